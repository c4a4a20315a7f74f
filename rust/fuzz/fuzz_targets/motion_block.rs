//! The MOTION number parser and the one-pass parse + decode, on arbitrary bytes with arbitrary
//! frame and channel counts and layouts. What parses must format and parse back the same.
#![no_main]
use _core::decode::{read_motion_block, ChannelLayout};
use _core::format::format_motion_block;
use _core::parse::parse_motion_block;
use arbitrary::Unstructured;
use expressive_mocap_fuzz::{count, floats, values};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let (Ok(frames), Ok(channels), Ok(split)) = (count(&mut u), count(&mut u), u.int_in_range(0..=3_u8)) else { return };
    let block = u.peek_bytes(u.len()).unwrap_or_default();
    // Most inputs: the block is the rest. Some: also a layout taken from the front of it.
    if let Ok(values) = parse_motion_block(block, frames, channels) {
        assert_eq!(values.len(), frames * channels);
        assert!(values.iter().all(|v| v.is_finite()));
        if channels > 0 {
            let text = format_motion_block(&values, channels, None).expect("parsed values format");
            assert_eq!(parse_motion_block(text.as_bytes(), frames, channels).expect("formatted text parses"), values);
        }
    }
    if split == 0 {
        let Ok(joints) = u.int_in_range(0..=6_usize) else { return };
        let (Ok(rotation_columns), Ok(orders), Ok(position_columns), Ok(offsets)) =
            (values::<i64>(&mut u, 3 * joints), values::<[u8; 3]>(&mut u, joints), values::<i64>(&mut u, 3 * joints), floats(&mut u, 3 * joints))
        else {
            return;
        };
        let rest = u.peek_bytes(u.len()).unwrap_or_default();
        let layout = ChannelLayout { channels, rotation_columns: &rotation_columns, orders: &orders, position_columns: &position_columns, offsets: &offsets };
        if let Ok((rotations, translations)) = read_motion_block(rest, frames, &layout) {
            assert_eq!((rotations.len(), translations.len()), (frames * 4 * orders.len(), frames * 3 * orders.len()));
        }
    }
});
