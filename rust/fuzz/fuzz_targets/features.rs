//! Dynamic features, foot contacts, air time, the contact filters and the whole-clip gait kernel,
//! with arbitrary counts (including products that overflow), lengths, joint indices, flags and
//! parameters (NaN, infinities, 0).
#![no_main]
use _core::features::{dynamic_features, FeatureParams, N_FEATURES};
use _core::footsteps::{absorb_short_runs, air_time, foot_contacts, hold_filter, ContactParams};
use _core::gait::{clip_gait, BodyScale, FeatureRequest, GaitJoints, GaitParams};
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

        // Whole clips: positions and rotations of `joints` joints, roles anywhere (also out of range).
        let joints = count(&mut u)?;
        let positions = floats(&mut u, frames.saturating_mul(joints).saturating_mul(3))?;
        let rotations = floats(&mut u, frames.saturating_mul(joints).saturating_mul(4))?;
        let mut joint = || u.int_in_range(0..=joints.saturating_add(1));
        let roles = GaitJoints { hips: joint()?, upper_legs: [joint()?, joint()?], feet: [joint()?, joint()?], toes: [joint()?, joint()?] };
        let scale = BodyScale { height: u.arbitrary()?, hips_rest_height: u.arbitrary()? };
        let params = GaitParams {
            height_threshold: u.arbitrary()?,
            speed_threshold: u.arbitrary()?,
            min_duration: u.arbitrary()?,
            floor_percentile: u.arbitrary()?,
        };
        let reference: Option<[f64; 8]> = u.arbitrary()?;
        let request = FeatureRequest { floor: u.arbitrary()?, thigh_reference: reference };
        let want_features: bool = u.arbitrary()?;
        if let Ok(gait) = clip_gait(&positions, &rotations, joints, u.arbitrary()?, scale, &roles, &params, want_features.then_some(&request), u.arbitrary()?) {
            let frames = positions.len() / (3 * joints);
            assert!(gait.features.map_or(true, |f| f.len() == frames * N_FEATURES));
            assert!(gait.contacts.map_or(true, |c| c.len() == frames * 2));
        }
        Ok(())
    };
    let _ = run();
});
