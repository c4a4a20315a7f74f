//! Euler angles <-> unit quaternions (x, y, z, w), for the six intrinsic Tait-Bryan orders.
//!
//! An order is three distinct axes `[a, b, c]` (0 = X, 1 = Y, 2 = Z) as written in a BVH
//! CHANNELS line; the rotation is `R_a(angle0) * R_b(angle1) * R_c(angle2)` (intrinsic, the
//! first channel outermost), matching SciPy's `Rotation.from_euler("ABC", ..)` with upper case.

use glam::{DMat3, DQuat};
use rayon::prelude::*;

use crate::error::{KernelError, Result};
use crate::trig::sin_cos_degrees;

/// Below this many joint-frames a kernel runs on the calling thread.
pub(crate) const PARALLEL_MIN_ITEMS: usize = 1 << 14;

pub type Order = [u8; 3];

/// Check that every order is a permutation of the three axes.
///
/// # Errors
/// `KernelError::Argument` naming `orders` when one is not.
pub fn check_orders(orders: &[Order]) -> Result<()> {
    for (joint, order) in orders.iter().enumerate() {
        let mut seen = [false; 3];
        for &axis in order {
            if axis > 2 || seen[axis as usize] {
                return Err(KernelError::argument(
                    "orders",
                    format!("joint {joint}: {order:?} is not a permutation of the axes 0, 1, 2"),
                ));
            }
            seen[axis as usize] = true;
        }
    }
    Ok(())
}

/// One rotation from three angles in degrees: `R_a(angle0) * R_b(angle1) * R_c(angle2)` for
/// the order `[a, b, c]`.
///
/// Each factor is `cos(h) + sin(h) e_axis` with `h` half its angle (`degrees * 0.5`, exact);
/// the sines and cosines come from [`sin_cos_degrees`] (faster than libm, exact at multiples of
/// 90). The two products are written out over the non-zero terms only: 16 multiplications
/// where two general quaternion products take 32 and as many additions, each component a sum
/// of the same two products as the general one gives (equal to it but for the sign of a zero).
#[must_use]
#[inline]
pub fn euler_to_quat_one(degrees: [f64; 3], order: Order) -> DQuat {
    let [a, b, c] = order.map(usize::from);
    let (sa, ca) = sin_cos_degrees(degrees[0] * 0.5);
    let (sb, cb) = sin_cos_degrees(degrees[1] * 0.5);
    let (sc, cc) = sin_cos_degrees(degrees[2] * 0.5);
    // e_a e_b = s e_c, e_b e_c = s e_a, e_a e_c = -s e_b: s = 1 for the cyclic orders.
    let s = if (b + 3 - a) % 3 == 1 { 1.0 } else { -1.0 };
    // R_a R_b = w + p_a e_a + p_b e_b + p_c e_c.
    let (w, p_a, p_b, p_c) = (ca * cb, sa * cb, ca * sb, s * sa * sb);
    // Times R_c = cc + sc e_c.
    let mut v = [0.0; 3];
    v[a] = p_a * cc + s * p_b * sc;
    v[b] = p_b * cc - s * p_a * sc;
    v[c] = w * sc + p_c * cc;
    DQuat::from_xyzw(v[0], v[1], v[2], w * cc - p_c * sc)
}

/// Three angles in degrees from one unit rotation, the middle one in [-90, 90].
///
/// At gimbal lock (middle angle +-90) the third angle is set to 0 and the first takes the
/// whole remaining rotation, so the result still composes back to the same rotation.
#[must_use]
#[inline]
pub fn quat_to_euler_one(q: DQuat, order: Order) -> [f64; 3] {
    if !q.is_finite() {
        return [f64::NAN; 3]; // all three angles, as the NumPy twin (not a rotation at all)
    }
    let m = DMat3::from_quat(q);
    // r(row, col) of the rotation matrix.
    let r = |row: u8, col: u8| m.col(col as usize)[row as usize];
    let [i, j, k] = order;
    // +1 for the cyclic orders XYZ, YZX, ZXY, -1 for the others.
    let sign = if (j + 3 - i) % 3 == 1 { 1.0 } else { -1.0 };
    let sin_b = (sign * r(i, k)).clamp(-1.0, 1.0);
    let cos_b = r(i, i).hypot(r(i, j));
    let (a, b, c);
    if cos_b > 1e-9 {
        a = (-sign * r(j, k)).atan2(r(k, k));
        b = sin_b.atan2(cos_b);
        c = (-sign * r(i, j)).atan2(r(i, i));
    } else {
        // Gimbal lock: only a +- c is defined; put it all in a.
        a = (sign * r(k, j)).atan2(r(j, j));
        b = sin_b.signum() * std::f64::consts::FRAC_PI_2;
        c = 0.0;
    }
    [a.to_degrees(), b.to_degrees(), c.to_degrees()]
}

/// `angles` is `[F, J, 3]` degrees, `orders` one per joint; returns `[F, J, 4]` (x, y, z, w).
///
/// # Errors
/// `KernelError::Argument` when `angles` is not a multiple of `3 * orders.len()` long or an
/// order is not a permutation of the axes.
pub fn euler_to_quat(angles: &[f64], orders: &[Order]) -> Result<Vec<f64>> {
    check_orders(orders)?;
    let joints = orders.len();
    if joints == 0 || angles.len() % (3 * joints) != 0 {
        return Err(KernelError::argument(
            "angles",
            format!(
                "length {} is not frames x {joints} joints x 3",
                angles.len()
            ),
        ));
    }
    let mut out = vec![0.0; angles.len() / 3 * 4];
    let frame = |(src, dst): (&[f64], &mut [f64])| {
        for (jo, order) in orders.iter().enumerate() {
            let q = euler_to_quat_one([src[3 * jo], src[3 * jo + 1], src[3 * jo + 2]], *order);
            q.write_to_slice(&mut dst[4 * jo..4 * jo + 4]);
        }
    };
    zip_frames(angles, 3 * joints, &mut out, 4 * joints, frame);
    Ok(out)
}

/// `quats` is `[F, J, 4]` (x, y, z, w), `orders` one per joint; returns `[F, J, 3]` degrees.
///
/// # Errors
/// As [`euler_to_quat`], for `quats`.
pub fn quat_to_euler(quats: &[f64], orders: &[Order]) -> Result<Vec<f64>> {
    check_orders(orders)?;
    let joints = orders.len();
    if joints == 0 || quats.len() % (4 * joints) != 0 {
        return Err(KernelError::argument(
            "quats",
            format!("length {} is not frames x {joints} joints x 4", quats.len()),
        ));
    }
    let mut out = vec![0.0; quats.len() / 4 * 3];
    let frame = |(src, dst): (&[f64], &mut [f64])| {
        for (jo, order) in orders.iter().enumerate() {
            let q = DQuat::from_slice(&src[4 * jo..4 * jo + 4]).normalize();
            dst[3 * jo..3 * jo + 3].copy_from_slice(&quat_to_euler_one(q, *order));
        }
    };
    zip_frames(quats, 4 * joints, &mut out, 3 * joints, frame);
    Ok(out)
}

/// Run `per_frame` over matching frame slices of `src` and `dst`, in parallel when large.
pub(crate) fn zip_frames<F>(
    src: &[f64],
    src_stride: usize,
    dst: &mut [f64],
    dst_stride: usize,
    per_frame: F,
) where
    F: Fn((&[f64], &mut [f64])) + Sync + Send,
{
    // About three values a joint: parallel once there are PARALLEL_MIN_ITEMS joint-frames.
    if src.len() >= 3 * PARALLEL_MIN_ITEMS {
        src.par_chunks(src_stride)
            .zip(dst.par_chunks_mut(dst_stride))
            .with_min_len(64)
            .for_each(per_frame);
    } else {
        src.chunks(src_stride)
            .zip(dst.chunks_mut(dst_stride))
            .for_each(per_frame);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    const ORDERS: [Order; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];

    #[test]
    fn euler_round_trips_for_every_order_including_gimbal_lock() {
        for order in ORDERS {
            for angles in [
                [10.0, 20.0, 30.0],
                [-170.0, 89.0, 45.0],
                [33.0, 90.0, 12.0],
                [5.0, -90.0, -60.0],
            ] {
                let q = euler_to_quat_one(angles, order);
                let back = euler_to_quat_one(quat_to_euler_one(q, order), order);
                assert!(q.dot(back).abs() > 1.0 - 1e-12, "{order:?} {angles:?}");
            }
        }
    }

    /// The rotation about one axis, as a general quaternion.
    fn about(axis: u8, degrees: f64) -> DQuat {
        let (s, c) = sin_cos_degrees(degrees * 0.5);
        let mut v = [0.0; 3];
        v[axis as usize] = s;
        DQuat::from_xyzw(v[0], v[1], v[2], c)
    }

    #[test]
    fn written_out_products_equal_general_quaternion_products() {
        let mut state = 7_u64;
        let mut angle = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 720.0 - 360.0
        };
        for order in ORDERS {
            for round in 0..20_000 {
                // Some angles at multiples of 90, where terms are exactly zero.
                let mut angles = [angle(), angle(), angle()];
                if round % 4 == 0 {
                    angles[round % 3] = 90.0 * (angles[round % 3] / 90.0).round();
                }
                let general = about(order[0], angles[0])
                    * about(order[1], angles[1])
                    * about(order[2], angles[2]);
                let written = euler_to_quat_one(angles, order);
                // Equal, bit for bit but for the sign of a zero.
                let (g, w) = (general.to_array(), written.to_array());
                assert!(
                    g.iter().zip(&w).all(|(x, y)| x == y),
                    "{order:?} {angles:?}: {g:?} {w:?}"
                );
            }
        }
    }

    #[test]
    fn intrinsic_order_is_first_channel_outermost() {
        // Z 90 then (in the rotated frame) X 90: maps the x axis to y.
        let q = euler_to_quat_one([90.0, 90.0, 0.0], [2, 0, 1]);
        assert!((q * DVec3::X - DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn a_non_finite_quaternion_gives_three_nans() {
        let e = quat_to_euler(
            &[f64::NAN, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, f64::INFINITY],
            &[[2, 0, 1]],
        )
        .unwrap();
        assert!(e.iter().all(|v| v.is_nan()), "{e:?}");
    }

    #[test]
    fn rejects_bad_orders_and_lengths() {
        assert!(euler_to_quat(&[0.0; 6], &[[0, 0, 1]]).is_err());
        assert!(euler_to_quat(&[0.0; 5], &[[0, 1, 2]]).is_err());
        assert!(quat_to_euler(&[0.0; 6], &[[0, 1, 2]]).is_err());
    }
}
