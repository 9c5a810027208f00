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
    // Round to nearest by adding and removing 1.5 · 2^52 (|x · 2/π| < 2^51): no libm call.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let j = (x * core::f64::consts::FRAC_2_PI + ROUND) - ROUND;
    let r = (x - j * PIO2_HI) - j * PIO2_LO;
    let z = r * r;
    let sin_r = r + z * r * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    let tail = z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    let half_z = 0.5 * z;
    let w = 1.0 - half_z;
    let cos_r = w + (((1.0 - w) - half_z) + tail);
    // Quadrant j mod 4: (sin, cos) = (s, c), (c, −s), (−s, −c), (−c, s).
    let quadrant = (j as i64) & 3;
    let (s, c) = if quadrant & 1 == 0 {
        (sin_r, cos_r)
    } else {
        (cos_r, -sin_r)
    };
    if quadrant & 2 == 0 {
        (s, c)
    } else {
        (-s, -c)
    }
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
}
