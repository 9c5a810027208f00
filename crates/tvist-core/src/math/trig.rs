//! `sin` and `cos` of one angle together, inline and branch-light, for the per-cycle robot
//! kinematics (joint angles, a few radians).
//!
//! Cody–Waite reduction by `π/2` in two parts (the first with 33 significant bits, so
//! `j · PIO2_HI` is exact for `|j| < 2^20`) and the minimax polynomials of fdlibm's
//! `__kernel_sin` / `__kernel_cos` on `[−π/4, π/4]` (error below 1 ulp there). For
//! `|x| <= FAST_RANGE_RAD` the result is within a few ulp of the correctly rounded value
//! (checked against the standard library below); larger or non-finite angles take
//! [`f64::sin_cos`].

// The constants are fdlibm's, digit for digit (rounded to f64 on reading).
#![allow(clippy::excessive_precision)]

/// Largest `|x|` (rad) reduced here: `j = round(x · 2/π) < 2^16`, far inside the exact range of
/// `j · PIO2_HI`, and the reduction error `|j| · 2^−53 · |PIO2_LO|` stays below 1e-21 rad.
pub const FAST_RANGE_RAD: f64 = 1.0e5;

/// First 33 bits of `π/2`.
const PIO2_HI: f64 = 1.570_796_326_734_125_614_17e+00;
/// `π/2 − PIO2_HI`.
const PIO2_LO: f64 = 6.077_100_506_506_192_249_32e-11;

const S1: f64 = -1.666_666_666_666_663_243_48e-01;
const S2: f64 = 8.333_333_333_322_489_461_24e-03;
const S3: f64 = -1.984_126_982_985_794_931_34e-04;
const S4: f64 = 2.755_731_370_707_006_767_89e-06;
const S5: f64 = -2.505_076_025_340_686_341_95e-08;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;

const C1: f64 = 4.166_666_666_666_660_190_37e-02;
const C2: f64 = -1.388_888_888_887_410_957_49e-03;
const C3: f64 = 2.480_158_728_947_672_941_78e-05;
const C4: f64 = -2.755_731_435_139_066_330_35e-07;
const C5: f64 = 2.087_572_321_298_174_827_90e-09;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    // NaN fails the comparison and takes the library path.
    let fast = x.abs() <= FAST_RANGE_RAD;
    if !fast {
        return x.sin_cos();
    }
    sin_cos_reduced(x)
}

/// `(sin x, cos x)` of every `x[k]` into `out[k]` (the shorter length counts), as
/// [`sin_cos`] does for each: the same arithmetic, written without branches for the usual
/// case so that the angles are evaluated side by side.
#[inline]
pub fn sin_cos_each(x: &[f64], out: &mut [(f64, f64)]) {
    if x.iter().all(|v| v.abs() <= FAST_RANGE_RAD) {
        for (o, &v) in out.iter_mut().zip(x) {
            *o = sin_cos_reduced(v);
        }
    } else {
        for (o, &v) in out.iter_mut().zip(x) {
            *o = sin_cos(v);
        }
    }
}

/// The reduction and polynomials for `|x| <= FAST_RANGE_RAD`, branch-free, with the
/// quadrant's signs and swap applied by bit masks (the form that suits a loop over angles).
#[inline(always)]
fn sin_cos_reduced(x: f64) -> (f64, f64) {
    let (quadrant, sin_r, cos_r) = reduced_parts(x);
    // Quadrant j mod 4: (sin, cos) = (s, c), (c, −s), (−s, −c), (−c, s): odd quadrants swap
    // the two, sin is negated in quadrants 2 and 3, cos in 1 and 2 (bit masks, no branches).
    let swap = 0u64.wrapping_sub(quadrant & 1);
    let (sb, cb) = (sin_r.to_bits(), cos_r.to_bits());
    let s = (sb & !swap) | (cb & swap);
    let c = (cb & !swap) | (sb & swap);
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = ((quadrant + 1) & 2) << 62;
    (f64::from_bits(s ^ sin_sign), f64::from_bits(c ^ cos_sign))
}

/// `(sin x, cos x)` for `|x| <= FAST_RANGE_RAD` (the caller checks the range, which also
/// excludes NaN and infinities): [`sin_cos_reduced`] bit for bit, with the quadrant applied
/// as an indexed read instead of bit masks (fewer instructions for a single angle).
#[inline(always)]
pub(crate) fn sin_cos_in_range(x: f64) -> (f64, f64) {
    let (quadrant, sin_r, cos_r) = reduced_parts(x);
    // (sin, cos) = entries j and j + 1 (mod 4) of the cycle [s, c, −s, −c].
    let cycle = [sin_r, cos_r, -sin_r, -cos_r];
    let j = quadrant as usize;
    (cycle[j & 3], cycle[(j + 1) & 3])
}

/// `(j mod 4, sin r, cos r)` with `x = j π/2 + r`, `|r| <= π/4`, for `|x| <= FAST_RANGE_RAD`.
#[inline(always)]
fn reduced_parts(x: f64) -> (u64, f64, f64) {
    // Round to nearest by adding and removing 1.5 · 2^52 (|x · 2/π| < 2^51): no libm call.
    // The sum's lowest mantissa bits are `j` modulo 4 (its unit in the last place is 1 and
    // 2^51 is a multiple of 4).
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let shifted = x * core::f64::consts::FRAC_2_PI + ROUND;
    let quadrant = shifted.to_bits() & 3;
    let j = shifted - ROUND;
    let r = (x - j * PIO2_HI) - j * PIO2_LO;
    let z = r * r;
    // The polynomials in Estrin's form (pairs of coefficients first, then z², z⁴): a third
    // of Horner's chain of dependent operations, so the angle's result is ready sooner.
    let z2 = z * z;
    let z4 = z2 * z2;
    let sin_p = (S1 + z * S2) + z2 * (S3 + z * S4) + z4 * (S5 + z * S6);
    let cos_p = (C1 + z * C2) + z2 * (C3 + z * C4) + z4 * (C5 + z * C6);
    let sin_r = r + z * r * sin_p;
    let tail = z2 * cos_p;
    let half_z = 0.5 * z;
    let w = 1.0 - half_z;
    let cos_r = w + (((1.0 - w) - half_z) + tail);
    (quadrant, sin_r, cos_r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_the_standard_library_to_a_few_ulp() {
        // Dense over the joint range, sparse out to the fast range's end, and the points
        // where the quadrant changes (x near multiples of π/4).
        let mut worst = 0.0f64;
        let mut check = |x: f64| {
            let (s, c) = sin_cos(x);
            let (s0, c0) = x.sin_cos();
            // Absolute error against |value| <= 1: 4 ulp of 1 (the library result is itself
            // within 1 ulp; the reduction adds |j| 2^-53 |PIO2_LO| < 1e-21).
            worst = worst.max((s - s0).abs()).max((c - c0).abs());
        };
        for k in -200_000..=200_000 {
            check(k as f64 * 1e-4 * core::f64::consts::PI);
        }
        for k in -4000..=4000 {
            check(k as f64 * core::f64::consts::FRAC_PI_4);
            check(k as f64 * 24.999_7);
        }
        assert!(worst <= 4.0 * f64::EPSILON, "worst {worst:e}");
        // Tiny angles keep full relative precision.
        for x in [1e-300, -3e-9, 2.5e-5] {
            let (s, c) = sin_cos(x);
            assert!(
                (s / x.sin() - 1.0).abs() <= 2.0 * f64::EPSILON && c == x.cos(),
                "{x}"
            );
        }
        assert!(sin_cos(f64::NAN).0.is_nan() && sin_cos(f64::INFINITY).1.is_nan());
        assert_eq!(sin_cos(2.0e5), 2.0e5f64.sin_cos());
    }

    #[test]
    fn both_quadrant_forms_give_the_same_bits() {
        // Every quadrant (and its boundaries), signed zeros, tiny angles, the range's ends.
        let mut angles: Vec<f64> = (-20_000..=20_000)
            .map(|k| k as f64 * 0.000_731 * core::f64::consts::PI)
            .collect();
        for k in -64..=64 {
            let edge = k as f64 * core::f64::consts::FRAC_PI_4;
            angles.extend([edge, edge.next_up(), edge.next_down()]);
        }
        angles.extend([0.0, -0.0, 1e-300, -2.5e-5, FAST_RANGE_RAD, -FAST_RANGE_RAD]);
        for x in angles {
            let (a, b) = (sin_cos_reduced(x), sin_cos_in_range(x));
            assert_eq!(
                (a.0.to_bits(), a.1.to_bits()),
                (b.0.to_bits(), b.1.to_bits()),
                "{x}"
            );
        }
    }

    #[test]
    fn each_angle_of_a_batch_is_the_single_evaluation_bit_for_bit() {
        // Every quadrant, signed zeros, tiny angles, and a batch with one angle beyond the
        // fast range (the whole batch then takes the per-angle path) or a NaN.
        let mut angles: Vec<f64> = (-400..=400)
            .map(|k| k as f64 * 0.0137 * core::f64::consts::PI)
            .collect();
        angles.extend([0.0, -0.0, 1e-300, -2.5e-5, FAST_RANGE_RAD, -FAST_RANGE_RAD]);
        let bits = |(s, c): (f64, f64)| (s.to_bits(), c.to_bits());
        let mut out = vec![(0.0, 0.0); angles.len()];
        sin_cos_each(&angles, &mut out);
        for (x, got) in angles.iter().zip(&out) {
            assert_eq!(bits(*got), bits(sin_cos(*x)), "{x}");
        }
        for odd in [3.0e5, f64::NAN] {
            let batch = [0.5, odd, -1.0];
            let mut out = [(0.0, 0.0); 3];
            sin_cos_each(&batch, &mut out);
            assert_eq!(bits(out[0]), bits(sin_cos(0.5)));
            assert_eq!(bits(out[2]), bits(sin_cos(-1.0)));
            assert_eq!(out[1].0.to_bits(), odd.sin().to_bits());
        }
    }
}
