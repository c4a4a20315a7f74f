//! Sine and cosine of an angle in degrees, for the Euler -> quaternion kernel.
//!
//! Why not `degrees.to_radians().sin_cos()`: that is two libm calls (14-21 ns a pair measured
//! here; preprocessing an archive spent ~14% of its CPU in them, three half-angles per joint
//! per frame), and converting to radians first rounds away exactness: `sin(180 deg)` comes out
//! as 1.2e-16, and near the zeros of sin/cos the result is up to ~4e4 ulp off in relative terms.
//! Here the argument is reduced exactly in degrees (to [-45, 45] plus a quadrant), converted
//! once, and fed to two short Taylor polynomials: 8.8 ns a pair against libm's 14.0 in the same
//! loop, within 1.6 ulp of mpmath over random half-angles in [-180, 180] (libm path: 3.8e4),
//! and exact at every multiple of 90 degrees.

use std::f64::consts::PI;

/// `1.5 * 2^52`: adding and subtracting it rounds an `f64` below 2^51 to an integer (ties to
/// even) without a libm call (`f64::round` is one on baseline x86-64), and leaves that integer
/// plus 2^51 in the low mantissa bits, so `bits & 3` is the integer mod 4, negatives included.
const ROUND: f64 = 6_755_399_441_055_744.0;

/// Below this the reduction is exact with room to spare (|degrees / 90| < 2^51 for `ROUND`,
/// 90 n < 2^53); larger angles and non-finite ones take the libm path, so NaN and infinities
/// behave as they always did.
const REDUCE_LIMIT: f64 = 1e15;

/// Taylor coefficients of sin(x) / x - 1 and cos(x) - 1 in z = x^2: (-1)^k / (2k+1)! and
/// (-1)^k / (2k)!. On |x| <= pi/4 the first omitted terms (x^17 / 17!, x^18 / 18!) are below
/// half an ulp of the result.
const SIN: [f64; 7] = [
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
];
const COS: [f64; 8] = [
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
];

/// `(sin, cos)` of an angle in degrees.
///
/// Exact at multiples of 90 degrees (`sin_cos_degrees(90.0) == (1.0, 0.0)`), within about
/// 1.5 ulp elsewhere; NaN or infinite in gives NaN out, as `f64::sin_cos`.
#[must_use]
#[inline]
pub fn sin_cos_degrees(degrees: f64) -> (f64, f64) {
    if degrees.is_nan() || degrees.abs() >= REDUCE_LIMIT {
        return degrees.to_radians().sin_cos();
    }
    // n = round(degrees / 90); r = degrees - 90 n is exact: both terms are multiples of
    // ulp(degrees) and |r| <= 45 (a hair more if the product rounds across a tie: harmless).
    let shifted = degrees * (1.0 / 90.0) + ROUND;
    let quadrant = shifted.to_bits() & 3;
    let n = shifted - ROUND;
    let x = (degrees - 90.0 * n) * (PI / 180.0);
    let z = x * x;
    // Horner, plain a * b + c: f64::mul_add without the fma target feature is a libm call.
    let [s1, s2, s3, s4, s5, s6, s7] = SIN;
    let s = s1 + z * (s2 + z * (s3 + z * (s4 + z * (s5 + z * (s6 + z * s7)))));
    // copysign: a no-op except for x = -0, which the sum would turn into +0 (sin(-0) = -0).
    let s = (x + x * z * s).copysign(x);
    let [c1, c2, c3, c4, c5, c6, c7, c8] = COS;
    let c =
        1.0 + z * (c1 + z * (c2 + z * (c3 + z * (c4 + z * (c5 + z * (c6 + z * (c7 + z * c8)))))));
    // Quadrant 0..3: (s, c), (c, -s), (-s, -c), (-c, s): swap on odd quadrants, then flip the
    // sine in quadrants 2 and 3 and the cosine in quadrants 1 and 2. On the bits, with masks:
    // the quadrant is random in real data, and a branch on it mispredicts half the time.
    let (s, c) = (s.to_bits(), c.to_bits());
    let swap = (s ^ c) & 0_u64.wrapping_sub(quadrant & 1);
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = ((quadrant + 1) & 2) << 62;
    (
        f64::from_bits(s ^ swap ^ sin_sign),
        f64::from_bits(c ^ swap ^ cos_sign),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn libm(degrees: f64) -> (f64, f64) {
        degrees.to_radians().sin_cos()
    }

    /// A deterministic pseudo-random stream in [-1, 1).
    fn noise(count: usize) -> impl Iterator<Item = f64> {
        let mut state = 12_345_u64;
        (0..count).map(move |_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
    }

    #[test]
    #[allow(clippy::float_cmp)] // exact on purpose
    fn exact_at_multiples_of_90_degrees() {
        let table = [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)];
        for k in -8_i32..=8 {
            let (sin, cos) = sin_cos_degrees(90.0 * f64::from(k));
            let (want_sin, want_cos) = table[k.rem_euclid(4) as usize];
            assert_eq!((sin, cos), (want_sin, want_cos), "k = {k}");
        }
        // Signed zeros as f64::sin: sin(+-0) = +-0, cos = 1.
        let (sin, cos) = sin_cos_degrees(-0.0);
        assert!(sin == 0.0 && sin.is_sign_negative() && cos == 1.0);
        let (sin, cos) = sin_cos_degrees(0.0);
        assert!(sin == 0.0 && sin.is_sign_positive() && cos == 1.0);
    }

    #[test]
    fn agrees_with_libm_over_a_dense_sweep_and_random_angles() {
        // The libm path's own error grows with the angle (to_radians rounds x, and pi/180, to
        // half an ulp each): at -716.091 deg it is off by 1.1e-15 where this function is within
        // 1 ulp of mpmath. Hence 4e-16 plus |x| eps / 2; on [-180, 180] the largest difference
        // measured is 3.3e-16.
        let steps = 1_440_000;
        let sweep = (0..=steps).map(|i| -720.0 + 1440.0 * f64::from(i) / f64::from(steps));
        let random = noise(100_000).map(|u| u * 720.0);
        let mut worst: f64 = 0.0;
        for d in sweep.chain(random) {
            let (sin, cos) = sin_cos_degrees(d);
            let (want_sin, want_cos) = libm(d);
            let err = (sin - want_sin).abs().max((cos - want_cos).abs());
            let allowed = 4e-16 + d.to_radians().abs() * f64::EPSILON / 2.0;
            assert!(err <= allowed, "{d}: {err:e} > {allowed:e}");
            worst = worst.max(err);
        }
        assert!(worst > 0.0); // the comparison is not vacuous
    }

    #[test]
    fn sin_squared_plus_cos_squared_is_one() {
        let mut worst: f64 = 0.0;
        for d in noise(200_000).map(|u| u * 1e4) {
            let (sin, cos) = sin_cos_degrees(d);
            worst = worst.max((sin * sin + cos * cos - 1.0).abs());
        }
        assert!(worst <= 2.0 * f64::EPSILON, "{worst:e}");
    }

    #[test]
    fn non_finite_in_is_nan_out_and_huge_angles_take_libm() {
        for d in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let (sin, cos) = sin_cos_degrees(d);
            assert!(sin.is_nan() && cos.is_nan(), "{d}");
        }
        for d in [1e300, -1e300, 1e15, 3.7e16] {
            let (sin, cos) = sin_cos_degrees(d);
            assert!(
                (-1.0..=1.0).contains(&sin) && (-1.0..=1.0).contains(&cos),
                "{d}"
            );
            assert_eq!(sin.to_bits(), libm(d).0.to_bits(), "{d}");
            assert_eq!(cos.to_bits(), libm(d).1.to_bits(), "{d}");
        }
    }
}
