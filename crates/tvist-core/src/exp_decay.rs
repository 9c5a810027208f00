//! `exp(x)` for `x <= 0`, inline and branch-free: the decay `K = exp(−ζπ/√(1−ζ²))` of the
//! closed-form shapers ([`crate::shaper`]), designed every cycle in which `ζ` changes.
//!
//! Method (the table-driven reduction of the usual libm implementations): `x = (k/N) ln 2 + r`
//! with `k` the integer nearest `x N / ln 2` (`N` = 64) and `|r| <= ln 2 / 128`, so that
//! `exp(x) = 2^(k div N) · 2^((k mod N)/N) · exp(r)`. The table holds `2^(j/N)` rounded to a
//! double and the relative remainder of that rounding; `exp(r) − 1` is its Taylor polynomial to
//! `r⁵`, whose truncation error `r⁶/720 <= 3.5e-17` is a sixth of an ulp of 1. The result is
//! within about half an ulp of `exp(x)` (tested against the standard library's `exp`: at most
//! 1 ulp apart over the whole range). The power of two is applied as two factors, each a normal
//! double, so results in the subnormal range round once more (still within 1 ulp) and results
//! below half the smallest subnormal (`x < −745.13`) are 0, as `exp` gives.

/// Table size `N` (a power of two): `2^(j/N)` for `j < N`.
const N_BITS: u32 = 6;
const N: usize = 1 << N_BITS;
/// `N / ln 2`.
const INV_LN2_N: f64 = 92.33248261689366;
/// `ln 2 / N` split: the leading part has 35 significant bits, so `k · LN2_N_HI` is exact for
/// every `|k| < 2^17` (here `|k| <= 746 · N / ln 2 < 68 900`), and `x − k · LN2_N_HI` is exact.
const LN2_N_HI: f64 = 0.010830424696223417;
const LN2_N_LO: f64 = 2.572804622327669e-14;
/// `1.5 · 2^52`: `z + SHIFT − SHIFT` rounds `|z| < 2^51` to the nearest integer, and the low bits
/// of `z + SHIFT` are that integer.
const SHIFT: f64 = 6755399441055744.0;
/// The range of `k div N` applied: below `−1076` every result rounds to 0 (`exp(x) <
/// 2^−1075`), above `1023` every result overflows; the two halves of the power of two are
/// normal doubles (exponents in `[−539, 512]`).
const E_MIN: i64 = -1077;
const E_MAX: i64 = 1024;

/// `(2^(j/N) rounded to a double t_j, (2^(j/N) − t_j) / t_j rounded)` for `j < N`, computed to
/// 80 digits and rounded once.
const TWO_POW_J_N: [(f64, f64); N] = [
    (1.0, 0.0),
    (1.0108892860517005, -1.507066976926039e-17),
    (1.0218971486541166, 4.9997448722726326e-17),
    (1.0330248790212284, 7.357846871247418e-18),
    (1.0442737824274138, 8.189317638195515e-17),
    (1.0556451783605572, 1.6665881442326747e-18),
    (1.0671404006768237, -7.402825309426177e-17),
    (1.0787607977571199, -6.170654745608695e-17),
    (1.0905077326652577, -2.7939114859515733e-17),
    (1.102382583307841, 4.776959425256223e-17),
    (1.1143867425958924, 9.341710609905046e-17),
    (1.1265216186082418, 4.585670326662351e-17),
    (1.1387886347566916, 7.826573258636076e-17),
    (1.1511892299529827, 2.823784425951061e-17),
    (1.1637248587775775, 3.2904726646008416e-17),
    (1.1763969916502812, 4.721368121170128e-17),
    (1.189207115002721, 3.3484623336251524e-17),
    (1.202156731452703, 5.527550048505249e-17),
    (1.215247359980469, -6.346552106729483e-17),
    (1.22848053610687, -1.5456342819397733e-17),
    (1.241857812073484, 3.750854201303127e-17),
    (1.255380757024691, -5.346099009198751e-18),
    (1.2690509571917332, 2.1023049675215714e-18),
    (1.2828700160787783, 1.3357510088834541e-17),
    (1.2968395546510096, 1.9572585293112036e-17),
    (1.3109612115247644, -5.478069123926778e-17),
    (1.3252366431597413, -2.1571477251208752e-17),
    (1.339667524053303, 6.663804589232195e-17),
    (1.3542555469368927, 5.68648095791174e-17),
    (1.3690024229745905, 7.007875046906994e-17),
    (1.383909881963832, -4.8923067513522756e-17),
    (1.3989796725383112, -6.872303720902018e-17),
    (1.4142135623730951, -6.835808657661922e-17),
    (1.42961333839197, -8.416011634717156e-18),
    (1.4451808069770467, -2.092304381843353e-17),
    (1.460917794180647, -3.833464968654295e-17),
    (1.4768261459394993, -2.3591094770850053e-17),
    (1.4929077282912648, 9.50689710108796e-18),
    (1.5091644275934228, -6.735219232374683e-17),
    (1.5255981507445384, -7.226635472101257e-17),
    (1.5422108254079407, 5.1548301170786783e-17),
    (1.559004400237837, 2.4253985766689806e-17),
    (1.5759808451078865, -6.432131775424189e-18),
    (1.593142151342267, -6.336161863401293e-17),
    (1.6104903319492543, 1.5341410053603723e-17),
    (1.6280274218573478, -4.123367330661149e-17),
    (1.645755478153965, -6.152602891550265e-17),
    (1.6636765803267364, 3.540948262646183e-17),
    (1.681792830507429, 4.875160526227062e-17),
    (1.7001063537185235, -4.719539664590972e-18),
    (1.718619298122478, -1.0772487078934056e-17),
    (1.7373338352737062, 1.821405440362259e-17),
    (1.7562521603732995, 1.685487290628973e-17),
    (1.7753764925265212, 3.621615935336894e-17),
    (1.7947090750031072, 1.01562190116415e-17),
    (1.8142521755003989, -5.495118966122005e-17),
    (1.8340080864093424, 1.790126907604513e-17),
    (1.8539791250833855, 5.265370768556274e-17),
    (1.8741676341103, -3.266924100901318e-17),
    (1.8945759815869656, 1.7963932659833022e-17),
    (1.9152065613971474, -5.545065618639427e-17),
    (1.9360617934922943, 5.336805878514151e-17),
    (1.9571441241754002, 4.5784915277060095e-17),
    (1.978456026387951, 2.0414278897578303e-17),
];

/// `exp(x)` for `|x| <= 2^40` (within about half an ulp; see the module), NaN for NaN.
#[inline(always)]
pub(crate) fn exp_inline(x: f64) -> f64 {
    let kd = x * INV_LN2_N + SHIFT;
    // k = round(x N / ln 2), |k| < 2^47, from the low bits of kd.
    let k = kd.to_bits().wrapping_sub(SHIFT.to_bits()) as i64;
    let kd = kd - SHIFT;
    // Exact but for the last term while |k| < 2^17 (|x| < 1400); beyond, exp(x) is 0 or
    // infinite and r only has to stay small.
    let r = (x - kd * LN2_N_HI) - kd * LN2_N_LO;
    let (t, tail) = TWO_POW_J_N[(k as usize) & (N - 1)];
    // 2^(k div N) = 2^e1 · 2^e2, e1 and e2 normal doubles: with e limited to [−1077, 1024]
    // (off the floating-point chain), results beyond the range round to 0 or overflow to ∞.
    let e = (k >> N_BITS).clamp(E_MIN, E_MAX);
    let e1 = e >> 1;
    let pow2 = |e: i64| f64::from_bits(((e + 1023) as u64) << 52);
    let t_e1 = t * pow2(e1);
    // exp(r) − 1 and the table's remainder: r + r²/2 + r³/6 + r⁴/24 + r⁵/120.
    let r2 = r * r;
    let poly =
        (tail + r) + (r2 * (0.5 + r * (1.0 / 6.0)) + r2 * r2 * (1.0 / 24.0 + r * (1.0 / 120.0)));
    (t_e1 + t_e1 * poly) * pow2(e - e1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in ulps between two non-negative doubles (their bit patterns are ordered;
    /// infinity is one ulp beyond the largest finite double).
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn agrees_with_std_exp_within_one_ulp_over_the_whole_range() {
        // A dense grid over [−746, 0] that is not aligned with the table's nodes, a
        // pseudo-random sample, every table node exactly (x = −j ln 2 / N and its neighbours),
        // tiny arguments, and the subnormal and underflow range. std's exp is within half an
        // ulp-ish too, so 1 ulp between the two is what two good implementations leave.
        let mut xs: Vec<f64> = (0..2_000_000)
            .map(|i| -746.0 * (i as f64 + 0.37) / 2e6)
            .collect();
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        for _ in 0..1_000_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            xs.push(-((state >> 11) as f64) / (1u64 << 53) as f64 * 746.0);
        }
        for j in 0..4 * N as i64 {
            let node = -(j as f64) * core::f64::consts::LN_2 / N as f64;
            xs.extend([node, node.next_up(), node.next_down()]);
        }
        for p in 1..=1074 {
            xs.push(-(2f64.powi(-p)));
        }
        xs.extend((0..20_000).map(|i| -708.0 - 38.0 * i as f64 / 20_000.0));
        let mut worst = (0, 0.0);
        for &x in &xs {
            let (got, want) = (exp_inline(x), x.exp());
            let d = ulps(got, want);
            if d > worst.0 {
                worst = (d, x);
            }
        }
        assert!(worst.0 <= 1, "{} ulps at x = {:e}", worst.0, worst.1);
    }

    #[test]
    fn is_exact_at_zero_and_underflows_and_overflows_as_std_does() {
        assert_eq!(exp_inline(0.0), 1.0);
        assert_eq!(exp_inline(-0.0), 1.0);
        assert_eq!(exp_inline(-f64::MIN_POSITIVE), 1.0);
        // A subnormal result, then the underflow boundary and far beyond it, down to the
        // decay of the largest damping ratio below 1 (`−ζπ/√(1−ζ²)` ≈ −2e8) and the domain's
        // end.
        assert_eq!(exp_inline(-745.0), (-745.0f64).exp());
        assert!((-745.0f64).exp() > 0.0);
        let zeta = 1.0f64.next_down();
        let steepest = -zeta * core::f64::consts::PI / (1.0 - zeta * zeta).sqrt();
        assert!(steepest < -1e8);
        for x in [-745.14, -746.0, -800.0, -1e6, steepest, -(2f64.powi(40))] {
            assert_eq!(exp_inline(x), 0.0, "x = {x}");
        }
        // Positive arguments up to overflow, and NaN.
        for x in [1e-300, 0.5, 3.0, 700.0, 709.78] {
            assert!(ulps(exp_inline(x), x.exp()) <= 1, "x = {x}");
        }
        for x in [709.79, 800.0, 2f64.powi(40)] {
            assert_eq!(exp_inline(x), f64::INFINITY, "x = {x}");
        }
        assert!(exp_inline(f64::NAN).is_nan());
    }
}
