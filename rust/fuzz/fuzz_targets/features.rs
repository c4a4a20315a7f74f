//! Dynamic features, foot contacts, air time and the contact filters, with arbitrary counts
//! (including products that overflow), lengths, flags and parameters (NaN, infinities, 0).
#![no_main]
use _core::features::{dynamic_features, FeatureParams, N_FEATURES};
use _core::footsteps::{absorb_short_runs, air_time, foot_contacts, hold_filter, ContactParams};
use arbitrary::Unstructured;
use expressive_mocap_fuzz::{count, floats, values};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut run = || -> arbitrary::Result<()> {
        let frames = u.int_in_range(0..=16_usize)?;
        let (feet, points) = (count(&mut u)?, count(&mut u)?);
        let positions = floats(&mut u, frames.saturating_mul(feet).saturating_mul(points).saturating_mul(3))?;
        let params = ContactParams {
            frame_time: u.arbitrary()?,
            floor: u.arbitrary()?,
            height_threshold: u.arbitrary()?,
            speed_threshold: u.arbitrary()?,
            min_frames: count(&mut u)?,
            causal: u.arbitrary()?,
        };
        if let Ok(contacts) = foot_contacts(&positions, feet, points, &params) {
            assert_eq!(contacts.len() * points * 3, positions.len());
        }
        let flags: Vec<bool> = values(&mut u, frames.saturating_mul(feet))?;
        if let Ok(times) = air_time(&flags, feet, params.frame_time) {
            assert_eq!(times.len(), flags.len());
        }
        let mut signal = flags.clone();
        absorb_short_runs(&mut signal, params.min_frames);
        hold_filter(&mut signal, params.min_frames);

        let points = floats(&mut u, frames * 9)?;
        let (thighs, contacts, reference) = (floats(&mut u, frames * 8)?, values::<bool>(&mut u, frames * 2)?, floats(&mut u, 8)?);
        let params = FeatureParams {
            frame_time: u.arbitrary()?,
            height: u.arbitrary()?,
            hips_rest_height: u.arbitrary()?,
            floor: u.arbitrary()?,
            window: count(&mut u)?,
        };
        if let Ok(features) = dynamic_features(&points, &thighs, &contacts, &reference, &params) {
            assert_eq!(features.len(), points.len() / 9 * N_FEATURES);
        }
        Ok(())
    };
    let _ = run();
});
