//! Dynamic features and foot contacts of whole clips straight from their forward kinematics:
//! the joints the two kernels need are gathered here, floors and window lengths derived as
//! `expressive_mocap.features` derives them. One call per clip instead of a dozen array
//! operations in Python is what lets `expressive-mocap preprocess` keep both cores busy on an
//! archive of short clips (the Python per-clip work holds the GIL).

use crate::error::{positive, KernelError, Result};
use crate::features::{dynamic_features, FeatureParams};
use crate::footsteps::{foot_contacts, ContactParams};

/// The joints gait is read from (indices into the skeleton), as `JointRoles` names them.
#[derive(Debug, Clone, Copy)]
pub struct GaitJoints {
    pub hips: usize,
    pub upper_legs: [usize; 2],
    pub feet: [usize; 2],
    pub toes: [usize; 2],
}

/// A clip's body scale, file units: the actor's height and the hips' rest height above the floor.
#[derive(Debug, Clone, Copy)]
pub struct BodyScale {
    pub height: f64,
    pub hips_rest_height: f64,
}

/// Contact thresholds (after Lee et al. 2002, as fractions of the actor's height, so one setting
/// fits any skeleton's units) and the floor rule.
#[derive(Debug, Clone, Copy)]
pub struct GaitParams {
    /// Contact height threshold x height.
    pub height_threshold: f64,
    /// Contact speed threshold x height per second.
    pub speed_threshold: f64,
    /// Contact and flight runs shorter than this many seconds are noise.
    pub min_duration: f64,
    /// The default floor is this percentile of both toes' heights over the clip.
    pub floor_percentile: f64,
}

/// The causal features wanted: `floor` `None` = the toe-height percentile, `thigh_reference`
/// `None` = the first frame's thigh rotations.
#[derive(Debug, Clone, Copy)]
pub struct FeatureRequest {
    pub floor: Option<f64>,
    pub thigh_reference: Option<[f64; 8]>,
}

/// Features `[F, 19]` (causal) and offline contacts `[F, 2]` (floor = toe percentile) of one clip,
/// each only when asked for.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClipGait {
    pub features: Option<Vec<f64>>,
    pub contacts: Option<Vec<bool>>,
}

/// `np.percentile(values, q)` with NumPy's linear interpolation and rounding (NaN if any is).
fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.iter().any(|v| v.is_nan()) {
        return f64::NAN;
    }
    let rank = (values.len() - 1) as f64 * (q / 100.0);
    let below = rank.floor() as usize;
    let above = (below + 1).min(values.len() - 1);
    let (_, &mut low, rest) = values.select_nth_unstable_by(below, f64::total_cmp);
    let high = if above == below {
        low
    } else {
        rest.iter().copied().min_by(f64::total_cmp).unwrap_or(low)
    };
    let t = rank - below as f64;
    if t >= 0.5 {
        high - (high - low) * (1.0 - t)
    } else {
        low + (high - low) * t
    }
}

/// At least 1 frame: Python's `max(1, round(x))` (ties to even), `x` computed as
/// `expressive_mocap.features` computes it, so both round the same float.
fn at_least_one_frame(x: f64) -> usize {
    (x.round_ties_even() as usize).max(1)
}

fn check_index(name: &'static str, index: usize, joints: usize) -> Result<()> {
    if index < joints {
        Ok(())
    } else {
        Err(KernelError::argument(
            name,
            format!("joint {index} out of range for {joints} joints"),
        ))
    }
}

/// Gait arrays of one clip from world `positions` `[F, J, 3]` and local `rotations`
/// `[F, J, 4]` (x, y, z, w); a clip of no frames has empty ones.
///
/// # Errors
/// `KernelError::Argument` when the lengths disagree with `joints`, a joint index is out of
/// range, or a parameter is out of range (see the two kernels).
#[allow(clippy::too_many_arguments)]
#[allow(clippy::too_many_lines)] // one sequence: checks, floor, contacts, features of one clip
pub fn clip_gait(
    positions: &[f64],
    rotations: &[f64],
    joints: usize,
    frame_time: f64,
    scale: BodyScale,
    roles: &GaitJoints,
    params: &GaitParams,
    features: Option<&FeatureRequest>,
    contacts: bool,
) -> Result<ClipGait> {
    let per_frame = joints.checked_mul(3).filter(|&n| n > 0);
    let Some(per_frame) = per_frame.filter(|&n| positions.len() % n == 0) else {
        return Err(KernelError::argument(
            "positions",
            format!(
                "length {} is not frames x {joints} joints x 3",
                positions.len()
            ),
        ));
    };
    let n_frames = positions.len() / per_frame;
    if rotations.len() / 4 != n_frames * joints || rotations.len() % 4 != 0 {
        return Err(KernelError::argument(
            "rotations",
            format!(
                "expected {n_frames} x {joints} x 4 values, got {}",
                rotations.len()
            ),
        ));
    }
    for (name, index) in [
        ("hips", roles.hips),
        ("upper_legs", roles.upper_legs[0]),
        ("upper_legs", roles.upper_legs[1]),
    ] {
        check_index(name, index, joints)?;
    }
    for (name, index) in [
        ("feet", roles.feet[0]),
        ("feet", roles.feet[1]),
        ("toes", roles.toes[0]),
        ("toes", roles.toes[1]),
    ] {
        check_index(name, index, joints)?;
    }
    positive("frame_time", frame_time)?;
    if !(0.0..=100.0).contains(&params.floor_percentile) {
        return Err(KernelError::argument(
            "floor_percentile",
            format!("must be within 0 and 100, got {}", params.floor_percentile),
        ));
    }
    if n_frames == 0 {
        return Ok(ClipGait {
            features: features.map(|_| Vec::new()),
            contacts: contacts.then(Vec::new),
        });
    }
    let point = |t: usize, j: usize| &positions[(t * joints + j) * 3..][..3];
    let mut toe_floor = None;
    let mut floor_of = |wanted: Option<f64>| {
        wanted.unwrap_or_else(|| {
            *toe_floor.get_or_insert_with(|| {
                let mut heights: Vec<f64> = (0..n_frames)
                    .flat_map(|t| roles.toes.map(|j| point(t, j)[1]))
                    .collect();
                percentile(&mut heights, params.floor_percentile)
            })
        })
    };
    let feet: Vec<f64> = (0..n_frames)
        .flat_map(|t| {
            [roles.feet[0], roles.toes[0], roles.feet[1], roles.toes[1]].map(|j| point(t, j))
        })
        .flatten()
        .copied()
        .collect();
    let contact_params = |floor: f64, causal: bool| ContactParams {
        frame_time,
        floor,
        height_threshold: params.height_threshold * scale.height,
        speed_threshold: params.speed_threshold * scale.height,
        min_frames: at_least_one_frame(params.min_duration * (1.0 / frame_time)),
        causal,
    };

    let mut out = ClipGait::default();
    if contacts {
        out.contacts = Some(foot_contacts(
            &feet,
            2,
            2,
            &contact_params(floor_of(None), false),
        )?);
    }
    if let Some(request) = features {
        let floor = floor_of(request.floor);
        let causal_contacts = foot_contacts(&feet, 2, 2, &contact_params(floor, true))?;
        let points: Vec<f64> = (0..n_frames)
            .flat_map(|t| {
                [roles.hips, roles.upper_legs[0], roles.upper_legs[1]].map(|j| point(t, j))
            })
            .flatten()
            .copied()
            .collect();
        let thigh = |t: usize, j: usize| &rotations[(t * joints + j) * 4..][..4];
        let thighs: Vec<f64> = (0..n_frames)
            .flat_map(|t| roles.upper_legs.map(|j| thigh(t, j)))
            .flatten()
            .copied()
            .collect();
        let reference = request.thigh_reference.unwrap_or_else(|| {
            let mut first = [0.0; 8];
            first.copy_from_slice(&thighs[..8]);
            first
        });
        let feature_params = FeatureParams {
            frame_time,
            height: scale.height,
            hips_rest_height: scale.hips_rest_height,
            floor,
            window: at_least_one_frame(1.0 / frame_time / 3.0),
        };
        out.features = Some(dynamic_features(
            &points,
            &thighs,
            &causal_contacts,
            &reference,
            &feature_params,
        )?);
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // NumPy's exact results are the point
mod tests {
    use super::*;

    #[test]
    fn percentile_interpolates_like_numpy() {
        // np.percentile([3, 1, 2, 10], 5) = 1 + 0.15 * (2 - 1); at 50: 2.5; at 100: 10.
        assert!((percentile(&mut [3.0, 1.0, 2.0, 10.0], 5.0) - 1.15).abs() < 1e-15);
        assert_eq!(percentile(&mut [3.0, 1.0, 2.0, 10.0], 50.0), 2.5);
        assert_eq!(percentile(&mut [3.0, 1.0, 2.0, 10.0], 100.0), 10.0);
        assert_eq!(percentile(&mut [7.0], 5.0), 7.0);
        assert!(percentile(&mut [1.0, f64::NAN, 2.0], 5.0).is_nan());
    }

    #[test]
    fn frames_round_half_to_even_like_python() {
        assert_eq!(at_least_one_frame(0.1 * 30.0), 3);
        assert_eq!(at_least_one_frame(2.5), 2);
        assert_eq!(at_least_one_frame(0.01), 1);
    }

    #[test]
    fn bad_shapes_and_indices_are_errors() {
        let roles = GaitJoints {
            hips: 0,
            upper_legs: [1, 2],
            feet: [3, 4],
            toes: [5, 6],
        };
        let scale = BodyScale {
            height: 1.0,
            hips_rest_height: 0.5,
        };
        let params = GaitParams {
            height_threshold: 0.1,
            speed_threshold: 1.0,
            min_duration: 0.1,
            floor_percentile: 5.0,
        };
        let positions = vec![0.0; 2 * 7 * 3];
        let rotations = vec![0.0; 2 * 7 * 4];
        assert!(clip_gait(
            &positions,
            &rotations,
            7,
            1.0 / 30.0,
            scale,
            &roles,
            &params,
            None,
            true
        )
        .is_ok());
        assert!(clip_gait(
            &positions[..20],
            &rotations,
            7,
            1.0 / 30.0,
            scale,
            &roles,
            &params,
            None,
            true
        )
        .is_err());
        assert!(clip_gait(
            &positions,
            &rotations[..20],
            7,
            1.0 / 30.0,
            scale,
            &roles,
            &params,
            None,
            true
        )
        .is_err());
        let empty = clip_gait(&[], &[], 7, 1.0 / 30.0, scale, &roles, &params, None, true).unwrap();
        assert_eq!(
            empty,
            ClipGait {
                features: None,
                contacts: Some(Vec::new())
            }
        );
        let far = GaitJoints {
            toes: [5, 7],
            ..roles
        };
        assert!(clip_gait(
            &positions,
            &rotations,
            7,
            1.0 / 30.0,
            scale,
            &far,
            &params,
            None,
            true
        )
        .is_err());
        assert!(
            clip_gait(&positions, &rotations, 7, 0.0, scale, &roles, &params, None, true).is_err()
        );
        assert!(clip_gait(
            &positions,
            &rotations,
            usize::MAX,
            1.0 / 30.0,
            scale,
            &roles,
            &params,
            None,
            true
        )
        .is_err());
        for q in [f64::NAN, -1.0, 100.5] {
            let params = GaitParams {
                floor_percentile: q,
                ..params
            };
            assert!(clip_gait(
                &positions,
                &rotations,
                7,
                1.0 / 30.0,
                scale,
                &roles,
                &params,
                None,
                true
            )
            .is_err());
        }
    }
}
