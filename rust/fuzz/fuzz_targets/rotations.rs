//! Euler angles <-> quaternions and the decoding of channel values, with arbitrary orders
//! (valid or not), lengths and values.
#![no_main]
use _core::decode::{decode_channels, ChannelLayout};
use _core::rotations::{euler_to_quat, quat_to_euler};
use arbitrary::Unstructured;
use expressive_mocap_fuzz::{count, floats, values};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let mut run = || -> arbitrary::Result<()> {
        let (joints, frames) = (u.int_in_range(0..=8_usize)?, u.int_in_range(0..=8_usize)?);
        let orders: Vec<[u8; 3]> = values(&mut u, joints)?;
        let angles = floats(&mut u, frames * joints * 3)?;
        if let Ok(q) = euler_to_quat(&angles, &orders) {
            assert_eq!(q.len(), angles.len() / 3 * 4);
            let back = quat_to_euler(&q, &orders).expect("the quaternions of valid angles convert back");
            assert_eq!(back.len(), angles.len());
        }
        let quats = floats(&mut u, frames * joints * 4)?;
        if let Ok(e) = quat_to_euler(&quats, &orders) {
            assert_eq!(e.len(), quats.len() / 4 * 3);
        }
        let (channels, frames) = (count(&mut u)?, count(&mut u)?);
        let (rotation_columns, position_columns, offsets) = (values::<i64>(&mut u, 3 * joints)?, values::<i64>(&mut u, 3 * joints)?, floats(&mut u, 3 * joints)?);
        let values = floats(&mut u, frames.saturating_mul(channels))?;
        let layout = ChannelLayout { channels, rotation_columns: &rotation_columns, orders: &orders, position_columns: &position_columns, offsets: &offsets };
        if let Ok((rotations, translations)) = decode_channels(&values, frames, &layout) {
            assert_eq!((rotations.len(), translations.len()), (frames * 4 * joints, frames * 3 * joints));
        }
        Ok(())
    };
    let _ = run();
});
