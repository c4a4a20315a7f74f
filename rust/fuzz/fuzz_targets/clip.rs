//! The whole per-clip work of preprocessing (`clip::clip_outputs`): arbitrary MOTION text,
//! frame counts, layouts, parents (also out of order), gait joints (also out of range), body
//! scale, parameters and requests. What succeeds has the shapes asked for.
#![no_main]
use _core::clip::{clip_outputs, ClipInput, ClipRequest};
use _core::decode::ChannelLayout;
use _core::features::N_FEATURES;
use _core::gait::{BodyScale, FeatureRequest, GaitJoints, GaitParams};
use arbitrary::Unstructured;
use expressive_mocap_fuzz::{count, floats, values};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut run = || -> arbitrary::Result<()> {
        let (frames, channels, joints) = (count(&mut u)?, count(&mut u)?, u.int_in_range(0..=6_usize)?);
        let rotation_columns = values::<i64>(&mut u, 3 * joints)?;
        let orders = values::<[u8; 3]>(&mut u, joints)?;
        let position_columns = values::<i64>(&mut u, 3 * joints)?;
        let offsets = floats(&mut u, 3 * joints)?;
        let parents = values::<i64>(&mut u, joints)?;
        let mut joint = || u.int_in_range(0..=joints.saturating_add(1));
        let roles = GaitJoints { hips: joint()?, upper_legs: [joint()?, joint()?], feet: [joint()?, joint()?], toes: [joint()?, joint()?] };
        let params = GaitParams {
            height_threshold: u.arbitrary()?,
            speed_threshold: u.arbitrary()?,
            min_duration: u.arbitrary()?,
            floor_percentile: u.arbitrary()?,
        };
        let requests: Vec<FeatureRequest> = (0..u.int_in_range(0..=2_usize)?)
            .map(|_| Ok(FeatureRequest { floor: u.arbitrary()?, thigh_reference: u.arbitrary()? }))
            .collect::<arbitrary::Result<_>>()?;
        let request = ClipRequest {
            parents: &parents,
            roles,
            params,
            positions: u.arbitrary()?,
            rotations: u.arbitrary()?,
            rotation_columns: u.int_in_range(0..=3)?,
            velocities: u.arbitrary()?,
            features: &requests,
            contacts: u.arbitrary()?,
        };
        let scale = BodyScale { height: u.arbitrary()?, hips_rest_height: u.arbitrary()? };
        let frame_time: f64 = u.arbitrary()?;
        let block = u.peek_bytes(u.len()).unwrap_or_default();
        let layout = ChannelLayout { channels, rotation_columns: &rotation_columns, orders: &orders, position_columns: &position_columns, offsets: &offsets };
        let clip = ClipInput { block, frames, layout, frame_time, scale };
        if let Ok(out) = clip_outputs(&clip, &request) {
            let n = parents.len();
            assert!(out.positions.map_or(!request.positions, |p| p.len() == frames * n * 3));
            assert!(out.rotations.map_or(!request.rotations, |r| r.len() == frames * n * 4));
            assert_eq!(out.features.len(), requests.len());
            assert!(out.features.iter().all(|f| f.len() == frames * N_FEATURES));
            assert!(out.contacts.map_or(!request.contacts, |c| c.len() == frames * 2));
        }
        Ok(())
    };
    let _ = run();
});
