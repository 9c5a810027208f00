//! `e^x` inline and branch-light, for the per-cycle shaper designs (`K = exp(−ζπ/√(1−ζ²))`
//! of the closed forms, evaluated whenever a mode's damping changes).
//!
//! Reduction by `ln 2 / 32` in two parts (Cody–Waite: the first with 33 significant bits, so
//! `k · LN2_32_HI` is exact for `|k| < 2^20`), `x = k ln2/32 + r` with `|r| <= ln2/64`, and
//! `e^x = 2^(k div 32) · 2^((k mod 32)/32) · e^r`: the second factor from a table of the 32
//! correctly rounded values `2^(j/32)`, the first added to its exponent bits, and `e^r` by its
//! Taylor polynomial to `r⁶/720` (the next term is below `2.8e-18`, 1/40 ulp), its leading 1
//! added last (`scale + scale · (e^r − 1)`), so only the table value's rounding (half an ulp
//! of a value in `[1, 2)`) and the final sum's reach the result: within about an ulp of `e^x`,
//! and within 1 ulp of the standard library's value (checked below). Arguments outside `[−708, 709]` (where the scale would leave the
//! normal range) and NaN take [`f64::exp`].

// The table and constants are printed to full precision (rounded to f64 on reading).
#![allow(clippy::excessive_precision)]

/// `32 / ln 2`.
const INV_LN2_32: f64 = 46.166_241_308_446_83;
/// The first 33 significant bits of `ln 2 / 32`.
const LN2_32_HI: f64 = 0.021_660_849_390_173_098;
/// `ln 2 / 32 − LN2_32_HI`.
const LN2_32_LO: f64 = 2.325_192_846_878_874e-12;

/// `2^(j/32)`, `j = 0..32`, each correctly rounded.
const TWO_POW_J_32: [f64; 32] = [
    1.0,
    1.021_897_148_654_116_6,
    1.044_273_782_427_413_8,
    1.067_140_400_676_823_7,
    1.090_507_732_665_257_7,
    1.114_386_742_595_892_4,
    1.138_788_634_756_691_6,
    1.163_724_858_777_577_5,
    1.189_207_115_002_721,
    1.215_247_359_980_469,
    1.241_857_812_073_484,
    1.269_050_957_191_733_2,
    1.296_839_554_651_009_6,
    1.325_236_643_159_741_3,
    1.354_255_546_936_892_7,
    1.383_909_881_963_832,
    core::f64::consts::SQRT_2,
    1.445_180_806_977_046_7,
    1.476_826_145_939_499_3,
    1.509_164_427_593_422_8,
    1.542_210_825_407_940_7,
    1.575_980_845_107_886_5,
    1.610_490_331_949_254_3,
    1.645_755_478_153_965,
    1.681_792_830_507_429,
    1.718_619_298_122_478,
    1.756_252_160_373_299_5,
    1.794_709_075_003_107_2,
    1.834_008_086_409_342_4,
    1.874_167_634_110_3,
    1.915_206_561_397_147_4,
    1.957_144_124_175_400_2,
];

/// `e^x`, within about an ulp (see the module docs).
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    // NaN fails the comparison and takes the library path.
    if !(-708.0..=709.0).contains(&x) {
        return x.exp();
    }
    // Round to nearest by adding and removing 1.5 · 2^52 (|x · 32/ln 2| < 2^15).
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let k = (x * INV_LN2_32 + ROUND) - ROUND;
    let r = (x - k * LN2_32_HI) - k * LN2_32_LO;
    let r2 = r * r;
    let r4 = r2 * r2;
    // e^r − 1: the leading 1 is added last, to the scaled value, so it is not rounded with r.
    let poly = r
        + r2 * (0.5 + r * (1.0 / 6.0))
        + r4 * ((1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0));
    // k is an integer in [−32 768, 32 768]: the cast is exact.
    let k = k as i64;
    let table = TWO_POW_J_32[(k & 31) as usize];
    // 2^(k div 32) added to the table value's exponent: k div 32 is in [−1022, 1023] and the
    // table value in [1, 2), so the sum is a normal number.
    let scale = f64::from_bits(table.to_bits().wrapping_add(((k >> 5) as u64) << 52));
    scale + scale * poly
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(got: f64, want: f64) -> f64 {
        // One ulp of `want` (its spacing at its binade).
        let ulp = f64::from_bits(want.to_bits() + 1) - want;
        (got - want).abs() / ulp
    }

    #[test]
    fn agrees_with_the_standard_library_to_one_ulp() {
        // Dense where the designs evaluate it (ζπ/√(1−ζ²) up to a few tens), sparse out to
        // the end of the fast range, and the points where the table index changes.
        let mut worst = 0.0f64;
        let mut check = |x: f64| {
            let (got, want) = (exp(x), x.exp());
            // Both are within about an ulp of the exact value: the largest difference seen
            // is 1 ulp (of the library's result, at its binade's spacing).
            worst = worst.max(ulps(got, want));
        };
        for i in 0..=400_000 {
            check(-(i as f64) * 1e-4);
        }
        for i in -7080..=7090 {
            check(i as f64 * 0.1 + 0.012_345);
        }
        for k in -32_000..=32_000 {
            let x = k as f64 * core::f64::consts::LN_2 / 32.0;
            if (-708.0..=709.0).contains(&x) {
                check(x);
                check(x + 1e-9);
                check(x - 1e-9);
            }
        }
        assert!(worst <= 1.0, "worst {worst} ulp");
        // Exact where the value is: e^0 = 1, and the table's own points k ln2/32 stay close.
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
    }

    #[test]
    fn outside_the_fast_range_is_the_library() {
        for x in [-708.5, -745.2, -800.0, -1e300, 709.5, 1e300] {
            assert_eq!(exp(x).to_bits(), x.exp().to_bits(), "{x}");
        }
        assert!(exp(f64::NAN).is_nan());
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp(f64::INFINITY), f64::INFINITY);
        // The fast range's ends are normal numbers and agree with the library.
        for x in [-708.0, 709.0] {
            assert!(exp(x).is_normal());
            assert!(ulps(exp(x), x.exp()) <= 1.0, "{x}");
        }
    }
}
