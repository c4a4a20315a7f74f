//! The whole per-clip work of `expressive-mocap preprocess` as one task: the MOTION block
//! parsed and decoded, forward kinematics, dynamic features and foot contacts. Run clip by clip
//! on a thread pool, each clip's intermediate arrays (channel values, local and world poses) are
//! made and dropped inside its task, so an archive never holds them all and the allocator reuses
//! the same memory clip after clip; only the arrays asked for leave the task. (Handed to NumPy
//! and kept for a whole batch instead, the intermediates made the two cores fight over fresh
//! pages and held `preprocess` to 1.6x the speed of one core.)

use crate::decode::{read_motion_block, ChannelLayout};
use crate::error::Result;
use crate::fk::forward_kinematics;
use crate::gait::{clip_gait, BodyScale, FeatureRequest, GaitJoints, GaitParams};

/// What to compute for every clip of one skeleton.
#[derive(Debug, Clone)]
pub struct ClipRequest<'a> {
    /// The skeleton's parent indices (-1 for the root), parents before children.
    pub parents: &'a [i64],
    pub roles: GaitJoints,
    pub params: GaitParams,
    /// Keep the world positions `[F, J, 3]`.
    pub positions: bool,
    /// Keep the local rotations `[F, J, 4]` (x, y, z, w).
    pub rotations: bool,
    /// One causal feature array `[F, 19]` per request (e.g. a dataset's and a model's).
    pub features: &'a [FeatureRequest],
    /// Keep the offline foot contacts `[F, 2]`.
    pub contacts: bool,
}

/// One clip: its MOTION block (the bytes after the `Frame Time` line), frame count, channel
/// layout, frame time (seconds) and body scale.
#[derive(Debug, Clone, Copy)]
pub struct ClipInput<'a> {
    pub block: &'a [u8],
    pub frames: usize,
    pub layout: ChannelLayout<'a>,
    pub frame_time: f64,
    pub scale: BodyScale,
}

/// The arrays a [`ClipRequest`] asked for, flattened row-major.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClipOutputs {
    pub positions: Option<Vec<f64>>,
    pub rotations: Option<Vec<f64>>,
    pub features: Vec<Vec<f64>>,
    pub contacts: Option<Vec<bool>>,
}

/// Everything `request` asks for of one clip, as `read_motion_block`, `forward_kinematics` and
/// `clip_gait` give it (the same numbers, bit for bit).
///
/// # Errors
/// `KernelError::Parse` for a malformed MOTION block (its line counted from the block's first);
/// `KernelError::Argument` when the layout, parents or roles do not fit together.
pub fn clip_outputs(clip: &ClipInput<'_>, request: &ClipRequest<'_>) -> Result<ClipOutputs> {
    let (rotations, translations) = read_motion_block(clip.block, clip.frames, &clip.layout)?;
    let (_, positions) = forward_kinematics(&rotations, &translations, request.parents)?;
    let joints = request.parents.len();
    let gait = |features: Option<&FeatureRequest>, contacts: bool| {
        clip_gait(
            &positions,
            &rotations,
            joints,
            clip.frame_time,
            clip.scale,
            &request.roles,
            &request.params,
            features,
            contacts,
        )
    };
    let mut out = ClipOutputs::default();
    // The contacts come with the first feature request (or alone): one contact pass per clip.
    let mut contacts_wanted = request.contacts;
    for feature_request in request.features {
        let computed = gait(Some(feature_request), contacts_wanted)?;
        out.features.push(computed.features.unwrap_or_default());
        if contacts_wanted {
            out.contacts = computed.contacts;
            contacts_wanted = false;
        }
    }
    if contacts_wanted {
        out.contacts = gait(None, true)?.contacts;
    }
    out.positions = request.positions.then_some(positions);
    out.rotations = request.rotations.then_some(rotations);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rotations::Order;

    // Two joints play every role: the kernels only need valid indices here.
    const ROLES: GaitJoints = GaitJoints {
        hips: 0,
        upper_legs: [0, 1],
        feet: [1, 1],
        toes: [1, 0],
    };
    const PARAMS: GaitParams = GaitParams {
        height_threshold: 0.05,
        speed_threshold: 0.5,
        min_duration: 0.1,
        floor_percentile: 5.0,
    };
    const SCALE: BodyScale = BodyScale {
        height: 170.0,
        hips_rest_height: 90.0,
    };
    const PARENTS: [i64; 2] = [-1, 0];
    const BLOCK: &[u8] =
        b"0 90 0 10 20 30 5 0 0\n1 90 2 12 18 33 -5 1 0\n2 91 4 14 16 36 -15 2 0\n";

    /// `f` given two joints in a chain, each with a ZXY rotation, the root with a position.
    fn with_layout<R>(f: impl FnOnce(ChannelLayout<'_>) -> R) -> R {
        let (rotation_columns, orders, position_columns, offsets): (
            Vec<i64>,
            Vec<Order>,
            Vec<i64>,
            Vec<f64>,
        ) = (
            vec![3, 4, 5, 6, 7, 8],
            vec![[2, 0, 1]; 2],
            vec![0, 1, 2, -1, -1, -1],
            vec![0.0, 90.0, 0.0, 0.0, 40.0, 0.0],
        );
        f(ChannelLayout {
            channels: 9,
            rotation_columns: &rotation_columns,
            orders: &orders,
            position_columns: &position_columns,
            offsets: &offsets,
        })
    }

    fn request(features: &[FeatureRequest]) -> ClipRequest<'_> {
        ClipRequest {
            parents: &PARENTS,
            roles: ROLES,
            params: PARAMS,
            positions: true,
            rotations: true,
            features,
            contacts: true,
        }
    }

    #[test]
    fn outputs_are_those_of_the_kernels_one_by_one() {
        with_layout(|layout| {
            let features = [
                FeatureRequest {
                    floor: Some(0.0),
                    thigh_reference: None,
                },
                FeatureRequest {
                    floor: None,
                    thigh_reference: None,
                },
            ];
            let clip = ClipInput {
                block: BLOCK,
                frames: 3,
                layout,
                frame_time: 1.0 / 30.0,
                scale: SCALE,
            };
            let out = clip_outputs(&clip, &request(&features)).unwrap();

            let (rotations, translations) = read_motion_block(BLOCK, 3, &layout).unwrap();
            let (_, positions) = forward_kinematics(&rotations, &translations, &PARENTS).unwrap();
            let alone = |f: Option<&FeatureRequest>, c| {
                clip_gait(
                    &positions,
                    &rotations,
                    2,
                    1.0 / 30.0,
                    SCALE,
                    &ROLES,
                    &PARAMS,
                    f,
                    c,
                )
                .unwrap()
            };
            assert_eq!(out.positions.as_ref(), Some(&positions));
            assert_eq!(out.rotations.as_ref(), Some(&rotations));
            let expected: Vec<_> = features
                .iter()
                .map(|f| alone(Some(f), false).features.unwrap())
                .collect();
            assert_eq!(out.features, expected);
            assert_eq!(out.contacts, alone(None, true).contacts);

            let only_contacts = ClipRequest {
                positions: false,
                rotations: false,
                ..request(&[])
            };
            let out = clip_outputs(&clip, &only_contacts).unwrap();
            assert_eq!(
                out,
                ClipOutputs {
                    contacts: alone(None, true).contacts,
                    ..ClipOutputs::default()
                }
            );
        });
    }

    #[test]
    fn a_bad_block_or_skeleton_is_an_error() {
        with_layout(|layout| {
            let short = ClipInput {
                block: b"0 90 0 10 20 30 5 0\n",
                frames: 1,
                layout,
                frame_time: 1.0 / 30.0,
                scale: SCALE,
            };
            assert!(matches!(
                clip_outputs(&short, &request(&[])),
                Err(crate::error::KernelError::Parse { line: 0, .. })
            ));
            let clip = ClipInput {
                block: b"0 90 0 10 20 30 5 0 0\n",
                ..short
            };
            assert!(clip_outputs(
                &clip,
                &ClipRequest {
                    parents: &[-1, 5],
                    ..request(&[])
                }
            )
            .is_err());
            let far = GaitJoints {
                toes: [1, 2],
                ..ROLES
            };
            assert!(clip_outputs(
                &clip,
                &ClipRequest {
                    roles: far,
                    ..request(&[])
                }
            )
            .is_err());
        });
    }
}
