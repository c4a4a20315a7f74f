//! Forward kinematics with an arbitrary parents array (unordered, out of range, negative) and
//! arbitrary rotation and translation lengths and values.
#![no_main]
use _core::fk::forward_kinematics;
use arbitrary::Unstructured;
use expressive_mocap_fuzz::{floats, values};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut run = || -> arbitrary::Result<()> {
        let (joints, frames) = (u.int_in_range(0..=12_usize)?, u.int_in_range(0..=6_usize)?);
        let mut parents: Vec<i64> = values(&mut u, joints)?;
        if u.ratio(1, 2)? {
            // Mostly valid trees, so the kinematics themselves run.
            for (j, p) in parents.iter_mut().enumerate() {
                *p = if j == 0 { -1 } else { p.rem_euclid(j as i64 + 1) - 1 };
            }
        }
        let rotations = floats(&mut u, frames * parents.len() * 4)?;
        let translations = floats(&mut u, frames * parents.len() * 3)?;
        if let Ok((world_rotations, world_positions)) = forward_kinematics(&rotations, &translations, &parents) {
            assert_eq!((world_rotations.len(), world_positions.len()), (rotations.len(), translations.len()));
        }
        Ok(())
    };
    let _ = run();
});
