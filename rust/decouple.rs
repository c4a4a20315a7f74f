//! Per-joint algebra of decoupling (Boehs et al.): the expressive component
//! `E = O * B^-1`, its activity index `A = clip((tanh(a) g)^b, 0, 1)` with `a` the angle of `E`,
//! the filtered component `E* = E^A` and the recovered body mechanics `B' = E*^-1 * O`, so that
//! `E* * B' = O` exactly; and recomposition `E*^s * B'` (modulation).

use glam::{DQuat, DVec3};
use rayon::prelude::*;

pub use crate::arms::Arms;
use crate::error::{positive, KernelError, Result};
use crate::rotations::PARALLEL_MIN_ITEMS;
use crate::smooth::{gaussian_weights, smooth_frames};

/// The angle of a unit quaternion's rotation, in `[0, pi]`.
#[must_use]
#[inline]
pub fn angle(q: DQuat) -> f64 {
    2.0 * q.xyz().length().atan2(q.w.abs())
}

/// `q^s`: the rotation about the same axis by `s` times its angle (shortest arc).
#[must_use]
#[inline]
pub fn power(q: DQuat, s: f64) -> DQuat {
    // Take the hemisphere w >= 0 so the angle is in [0, pi] and q^0 = identity, q^1 = q.
    let q = if q.w < 0.0 { -q } else { q };
    let sin_half = q.xyz().length();
    if sin_half < 1e-15 {
        return DQuat::IDENTITY;
    }
    let half = sin_half.atan2(q.w) * s;
    let axis = q.xyz() / sin_half;
    let (s, c) = half.sin_cos();
    DQuat::from_xyzw(axis.x * s, axis.y * s, axis.z * s, c)
}

/// Activity index of an expressive rotation of angle `a`: `clip((tanh(a) * gain)^exponent, 0, 1)`.
#[must_use]
#[inline]
pub fn activity(a: f64, gain: f64, exponent: f64) -> f64 {
    (a.tanh() * gain).powf(exponent).clamp(0.0, 1.0)
}

fn check_pair(name: &'static str, first: &[f64], second: &[f64]) -> Result<()> {
    if first.len() % 4 != 0 || first.len() != second.len() {
        return Err(KernelError::argument(
            name,
            format!(
                "expected two [F, J, 4] arrays of the same shape, got {} and {} values",
                first.len(),
                second.len()
            ),
        ));
    }
    Ok(())
}

/// Decouple original rotations `O` from body-mechanics rotations `B` (both `[F, J, 4]`), each
/// frame on its own: [`split`] unsmoothed and unscaled. Returns `(E*, B', A)` with `E*` and `B'`
/// `[F, J, 4]` and the activity `A` `[F, J]`.
///
/// # Errors
/// `KernelError::Argument` when the arrays differ in shape, are not quaternions, or `gain` or
/// `exponent` is not a finite positive number.
pub fn decouple(
    original: &[f64],
    body: &[f64],
    gain: f64,
    exponent: f64,
) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    // One "joint" a frame: with no smoothing and no scale, the joints need not be told apart.
    let per_frame = Smoothing {
        body_sigma: 0.0,
        activity_sigma: 0.0,
        scale: &[1.0],
        trunk: None,
        arms: None,
    };
    split(original, body, gain, exponent, &per_frame)
}

/// How a clip's split is smoothed in time and its activity read: the Gaussians' widths in frames
/// (0: none) over the predicted body mechanics and over the activity, per joint the angle
/// `E` is divided by before the activity index reads it (a calibrated model's thresholds), and
/// optionally the trunk read as one chain and the arms filtered in world axes.
pub struct Smoothing<'a> {
    pub body_sigma: f64,
    pub activity_sigma: f64,
    pub scale: &'a [f64],
    pub trunk: Option<Trunk<'a>>,
    pub arms: Option<Arms<'a>>,
}

/// The trunk read as one chain. A lean is spread over its joints, a few degrees each, which the
/// steep activity index reads as nothing; read as the chain's, it counts. `joints`: the chain
/// from the hips up, each the parent of the next; `bones[k]`: the bone that joint `k` carries
/// (the next joint's rest offset, the last one's: the neck's), so that the trunk line runs from
/// the chain's first joint to the neck; the angle between the trunk lines of `O` and `B` (a lean,
/// forward or sideways; a twist about the line does not count) divided by `scale` gives each
/// joint of the chain at least that activity.
pub struct Trunk<'a> {
    pub joints: &'a [usize],
    pub bones: &'a [DVec3],
    pub scale: f64,
}

impl Trunk<'_> {
    pub(crate) fn check(&self, joints: usize) -> Result<()> {
        if let Some(&j) = self.joints.iter().find(|&&j| j >= joints) {
            return Err(KernelError::argument(
                "trunk_joints",
                format!("joint {j} is not one of the {joints} joints"),
            ));
        }
        let line: DVec3 = self.bones.iter().sum();
        if self.bones.len() != self.joints.len()
            || !self.bones.iter().all(|b| b.is_finite())
            || line.length() <= 1e-12
        {
            return Err(KernelError::argument(
                "trunk_bones",
                format!(
                    "expected one finite bone per trunk joint ({}), not all of zero length, got {:?}",
                    self.joints.len(),
                    self.bones
                ),
            ));
        }
        positive("trunk_scale", self.scale)
    }

    /// The trunk line of one frame's local rotations `[J, 4]`, in the chain's parent's frame.
    fn line(&self, rotations: &[f64]) -> DVec3 {
        let mut turn = DQuat::IDENTITY;
        let mut line = DVec3::ZERO;
        for (&j, &bone) in self.joints.iter().zip(self.bones) {
            turn *= DQuat::from_slice(&rotations[4 * j..4 * j + 4]);
            line += turn * bone;
        }
        line
    }

    /// The angle between the trunk lines of `original` and `body` in one frame `[J, 4]`.
    fn lean(&self, original: &[f64], body: &[f64]) -> f64 {
        let (o, b) = (self.line(original), self.line(body));
        o.cross(b).length().atan2(o.dot(b))
    }
}

/// [`decouple`] of one clip (`[F, J, 4]`, `J = scale.len()`) with `B` and `A` smoothed in time:
/// `B` (each joint's quaternions put on their predecessor's hemisphere) filtered over frames and
/// normalised, `A` read from `angle(O B^-1) / scale` (the trunk's joints at least their chain's,
/// see [`Trunk`]) and filtered, then `E* = (O B^-1)^A`,
/// `B' = E*^-1 O`. Returns `(E*, B', A)`; `E* B' = O` still holds exactly.
///
/// # Errors
/// `KernelError::Argument` when the arrays differ in shape or do not hold `J` joints a frame, or a
/// parameter is not a finite number (positive: `gain`, `exponent`, `scale`; at least 0: sigmas).
pub fn split(
    original: &[f64],
    body: &[f64],
    gain: f64,
    exponent: f64,
    smoothing: &Smoothing,
) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    check_pair("body", original, body)?;
    positive("gain", gain)?;
    positive("exponent", exponent)?;
    let joints = smoothing.scale.len();
    if joints == 0 || original.len() % (4 * joints) != 0 {
        return Err(KernelError::argument(
            "scale",
            format!(
                "expected one value per joint of [F, J, 4] rotations, got {joints} for {} values",
                original.len()
            ),
        ));
    }
    for &value in smoothing.scale {
        positive("scale", value)?;
    }
    if let Some(trunk) = &smoothing.trunk {
        trunk.check(joints)?;
    }
    if let Some(arms) = &smoothing.arms {
        arms.check(joints)?;
    }
    for (name, sigma) in [
        ("body_sigma", smoothing.body_sigma),
        ("activity_sigma", smoothing.activity_sigma),
    ] {
        if !(sigma.is_finite() && sigma >= 0.0) {
            return Err(KernelError::argument(
                name,
                format!("must be a number >= 0, got {sigma}"),
            ));
        }
    }
    let frames = original.len() / 4 / joints;
    let smoothed = if smoothing.body_sigma > 0.0 && frames > 1 {
        smoothed_rotations(body, joints, smoothing.body_sigma)
    } else {
        body.to_vec()
    };
    let mut activities: Vec<f64> = (0..frames * joints)
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            let o = DQuat::from_slice(&original[4 * i..4 * i + 4]);
            let b = DQuat::from_slice(&smoothed[4 * i..4 * i + 4]);
            activity(
                angle(o * b.conjugate()) / smoothing.scale[i % joints],
                gain,
                exponent,
            )
        })
        .collect();
    if let Some(trunk) = &smoothing.trunk {
        let width = 4 * joints;
        for (frame, row) in activities.chunks_mut(joints).enumerate() {
            let span = frame * width..(frame + 1) * width;
            let lean = trunk.lean(&original[span.clone()], &smoothed[span]);
            let chain = activity(lean / trunk.scale, gain, exponent);
            for &j in trunk.joints {
                row[j] = row[j].max(chain);
            }
        }
    }
    if smoothing.activity_sigma > 0.0 && frames > 1 {
        activities = smooth_frames(
            &activities,
            joints,
            &gaussian_weights(smoothing.activity_sigma),
        );
        for a in &mut activities {
            *a = a.clamp(0.0, 1.0);
        }
    }
    let (mut expressive, mut recovered) = filter(original, &smoothed, &activities);
    if let Some(arms) = &smoothing.arms {
        let width = 4 * joints;
        expressive
            .par_chunks_mut(width)
            .zip(recovered.par_chunks_mut(width))
            .enumerate()
            .with_min_len(64)
            .for_each(|(f, (e, b))| {
                let span = f * width..(f + 1) * width;
                let a = &activities[f * joints..(f + 1) * joints];
                arms.hang(&original[span.clone()], &smoothed[span], a, e, b);
            });
    }
    Ok((expressive, recovered, activities))
}

/// Unit quaternions `[F, J, 4]` smoothed over frames by a Gaussian of `sigma` frames: each joint's
/// put on its predecessor's hemisphere, the components filtered, then normalised.
fn smoothed_rotations(quats: &[f64], joints: usize, sigma: f64) -> Vec<f64> {
    let mut aligned = quats.to_vec();
    let width = 4 * joints;
    for frame in 1..aligned.len() / width {
        let (before, now) = aligned.split_at_mut(frame * width);
        let previous = &before[(frame - 1) * width..];
        for (q, p) in now[..width].chunks_mut(4).zip(previous.chunks(4)) {
            if q.iter().zip(p).map(|(a, b)| a * b).sum::<f64>() < 0.0 {
                for v in q.iter_mut() {
                    *v = -*v;
                }
            }
        }
    }
    let mut out = smooth_frames(&aligned, width, &gaussian_weights(sigma));
    out.chunks_mut(4).for_each(|q| {
        let unit = DQuat::from_slice(q).normalize();
        unit.write_to_slice(q);
    });
    out
}

/// `E* = (O B^-1)^A` and `B' = E*^-1 O` per rotation.
fn filter(original: &[f64], body: &[f64], activities: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let mut expressive = vec![0.0; original.len()];
    let mut recovered = vec![0.0; original.len()];
    let per_rotation = |(i, (e_out, b_out)): (usize, (&mut [f64], &mut [f64]))| {
        let o = DQuat::from_slice(&original[4 * i..4 * i + 4]);
        let b = DQuat::from_slice(&body[4 * i..4 * i + 4]);
        let e_star = power(o * b.conjugate(), activities[i]);
        e_star.write_to_slice(e_out);
        (e_star.conjugate() * o).write_to_slice(b_out);
    };
    if activities.len() >= PARALLEL_MIN_ITEMS {
        expressive
            .par_chunks_mut(4)
            .zip(recovered.par_chunks_mut(4))
            .enumerate()
            .with_min_len(1024)
            .for_each(per_rotation);
    } else {
        expressive
            .chunks_mut(4)
            .zip(recovered.chunks_mut(4))
            .enumerate()
            .for_each(per_rotation);
    }
    (expressive, recovered)
}

/// Recompose `E^scale * B` for rotations `[F, J, 4]`: `scale = 1` gives `E * B`, 0 the body
/// mechanics alone, 1.5 one and a half times the expressiveness.
///
/// # Errors
/// `KernelError::Argument` when the arrays differ in shape or `scale` is not finite.
pub fn compose(expressive: &[f64], body: &[f64], scale: f64) -> Result<Vec<f64>> {
    check_pair("body", expressive, body)?;
    if !scale.is_finite() {
        return Err(KernelError::argument(
            "scale",
            format!("must be a finite number, got {scale}"),
        ));
    }
    let mut out = vec![0.0; body.len()];
    let per_rotation = |(i, dst): (usize, &mut [f64])| {
        let e = DQuat::from_slice(&expressive[4 * i..4 * i + 4]);
        let b = DQuat::from_slice(&body[4 * i..4 * i + 4]);
        // Exactly E * B at scale 1 (no round trip through the angle).
        #[allow(clippy::float_cmp)]
        let e = if scale == 1.0 { e } else { power(e, scale) };
        (e * b).write_to_slice(dst);
    };
    if body.len() / 4 >= PARALLEL_MIN_ITEMS {
        out.par_chunks_mut(4)
            .enumerate()
            .with_min_len(1024)
            .for_each(per_rotation);
    } else {
        out.chunks_mut(4).enumerate().for_each(per_rotation);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn about(axis: DVec3, degrees: f64) -> DQuat {
        DQuat::from_axis_angle(axis.normalize(), degrees.to_radians())
    }

    #[test]
    fn power_scales_the_angle_about_the_same_axis() {
        let q = about(DVec3::new(1.0, 2.0, 3.0), 80.0);
        assert!((angle(power(q, 0.5)) - 40f64.to_radians()).abs() < 1e-12);
        assert!(power(q, 1.0).dot(q).abs() > 1.0 - 1e-15);
        assert!(power(-q, 1.0).dot(q).abs() > 1.0 - 1e-15);
        assert!((angle(power(q, 0.0))).abs() < 1e-12);
    }

    #[test]
    fn decouple_recomposes_exactly_and_filters_small_rotations() {
        let o = [about(DVec3::X, 30.0), about(DVec3::Y, 120.0)];
        let b = [about(DVec3::X, 28.0), about(DVec3::Z, 10.0)];
        let flat = |qs: &[DQuat]| qs.iter().flat_map(DQuat::to_array).collect::<Vec<f64>>();
        let (e, b2, a) = decouple(&flat(&o), &flat(&b), 2.0, 4.0).unwrap();
        let recomposed = compose(&e, &b2, 1.0).unwrap();
        for (r, o) in recomposed.chunks(4).zip(&o) {
            assert!(DQuat::from_slice(r).dot(*o).abs() > 1.0 - 1e-14);
        }
        // 2 degrees apart: (tanh(0.035) * 2)^4 ~ 2.4e-5; far apart: fully active.
        assert!(a[0] < 1e-4 && (a[1] - 1.0).abs() < 1e-12, "{a:?}");
        // Unsmoothed and unscaled, the split of one clip is the same.
        let plain = Smoothing {
            body_sigma: 0.0,
            activity_sigma: 0.0,
            scale: &[1.0, 1.0],
            trunk: None,
            arms: None,
        };
        let (e2, b3, a2) = split(&flat(&o), &flat(&b), 2.0, 4.0, &plain).unwrap();
        assert_eq!((e2, b3, a2), (e, b2, a));
    }

    #[test]
    fn a_lean_spread_over_the_trunk_reads_as_the_chains() {
        // Two trunk joints leaning 8 degrees each about X, the trunk line along Y (all of it in
        // the second joint's bone): each joint's
        // own activity is tiny, the chain's 16 degrees read with scale 0.5 as 32: fully active.
        // A twist about the trunk line (Y) does not count.
        let flat = |qs: &[DQuat]| qs.iter().flat_map(DQuat::to_array).collect::<Vec<f64>>();
        let lean = flat(&[
            about(DVec3::X, 8.0),
            about(DVec3::X, 8.0),
            about(DVec3::Z, 8.0),
        ]);
        let twist = flat(&[
            about(DVec3::Y, 30.0),
            about(DVec3::Y, 30.0),
            DQuat::IDENTITY,
        ]);
        let neutral = flat(&[DQuat::IDENTITY; 3]);
        let trunk = Smoothing {
            body_sigma: 0.0,
            activity_sigma: 0.0,
            scale: &[1.0; 3],
            trunk: Some(Trunk {
                joints: &[0, 1],
                bones: &[DVec3::ZERO, DVec3::Y],
                scale: 0.5,
            }),
            arms: None,
        };
        let (_, _, a) = split(&lean, &neutral, 2.0, 4.0, &trunk).unwrap();
        let own = activity(8f64.to_radians(), 2.0, 4.0);
        assert!(
            own < 0.01 && a[0] > 0.99 && a[1] > 0.99 && a[2] == own,
            "{a:?}"
        );
        let (_, _, a) = split(&twist, &neutral, 2.0, 4.0, &trunk).unwrap();
        let (_, _, own) = decouple(&twist, &neutral, 2.0, 4.0).unwrap();
        assert_eq!(a, own);
        let beyond = Smoothing {
            trunk: Some(Trunk {
                joints: &[0, 3],
                bones: &[DVec3::ZERO, DVec3::Y],
                scale: 0.5,
            }),
            ..trunk
        };
        assert!(split(&lean, &neutral, 2.0, 4.0, &beyond).is_err());
    }

    #[test]
    fn rejects_mismatched_shapes_and_bad_parameters() {
        assert!(decouple(&[0.0; 8], &[0.0; 4], 2.0, 4.0).is_err());
        assert!(decouple(&[0.0; 4], &[0.0; 4], 0.0, 4.0).is_err());
        assert!(compose(&[0.0; 4], &[0.0; 4], f64::NAN).is_err());
        let three = Smoothing {
            body_sigma: 1.0,
            activity_sigma: 1.0,
            scale: &[1.0; 3],
            trunk: None,
            arms: None,
        };
        assert!(split(&[0.0; 8], &[0.0; 8], 2.0, 4.0, &three).is_err());
        let bad = Smoothing {
            body_sigma: f64::NAN,
            activity_sigma: 1.0,
            scale: &[1.0],
            trunk: None,
            arms: None,
        };
        assert!(split(&[0.0; 4], &[0.0; 4], 2.0, 4.0, &bad).is_err());
        let zero = Smoothing {
            body_sigma: 1.0,
            activity_sigma: 1.0,
            scale: &[0.0],
            trunk: None,
            arms: None,
        };
        assert!(split(&[0.0; 4], &[0.0; 4], 2.0, 4.0, &zero).is_err());
    }
}
