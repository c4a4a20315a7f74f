//! The decoupling algebra with arbitrary lengths, quaternions (zero, NaN, huge) and parameters.
#![no_main]
use _core::decouple::{compose, decouple};
use arbitrary::Unstructured;
use expressive_mocap_fuzz::floats;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut run = || -> arbitrary::Result<()> {
        let rotations = u.int_in_range(0..=32_usize)?;
        let (original, body) = (floats(&mut u, 4 * rotations)?, floats(&mut u, 4 * rotations)?);
        let (gain, exponent, scale): (f64, f64, f64) = (u.arbitrary()?, u.arbitrary()?, u.arbitrary()?);
        if let Ok((expressive, recovered, activity)) = decouple(&original, &body, gain, exponent) {
            assert_eq!((expressive.len(), recovered.len(), activity.len() * 4), (original.len(), original.len(), original.len()));
            let _ = compose(&expressive, &recovered, scale);
        }
        let _ = compose(&original, &body, scale);
        Ok(())
    };
    let _ = run();
});
