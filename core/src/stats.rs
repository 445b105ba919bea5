//! The statistics every stage shares, in one place: the regularised
//! incomplete gamma function, hence the χ² law's tails and quantiles and
//! the normal law's tails, exact to about 1e-15 relative in either tail
//! (each tail is computed directly, not as one minus the other, so a tail
//! of 1e-300 is not 0); and the radii that cover 95 % of a 3-D Gaussian
//! error ([`coverage`]).

pub mod coverage;

/// The `p` quantile of the χ² law with `nu > 0` degrees of freedom
/// (Newton on [`gamma_p`] inside a bisection bracket, to 1e-12 relative).
pub(crate) fn chi_square_quantile(p: f64, nu: f64) -> f64 {
    let a = nu / 2.0;
    quantile(nu, |x| (gamma_p(a, x / 2.0) - p, 1.0))
}

/// The value the χ² law with `nu > 0` degrees of freedom exceeds with
/// probability `alpha`, found on the upper tail itself: exact for an
/// `alpha` of 1e-300, where `1 − alpha` is 1. Above 10⁶ (an `alpha` of 0)
/// it stops.
pub(crate) fn chi_square_upper_quantile(alpha: f64, nu: usize) -> f64 {
    let nu = nu.max(1) as f64;
    let a = nu / 2.0;
    // On the logarithm of the tail, nearly straight in `x`: on the tail
    // itself, which falls as `exp(−x/2)`, Newton's steps from far below
    // the root are about 2 long.
    quantile(nu, |x| {
        let q = gamma_q(a, x / 2.0);
        (alpha.ln() - q.ln(), 1.0 / q)
    })
}

/// Median of `χ²₃` (the touches' law, kept as a constant so that their
/// figures are the same bits whatever the quantile's iteration does).
pub(crate) const CHI2_3_MEDIAN: f64 = 2.365_973_884_375_338;

/// The median of the χ² law with `k ≥ 1` degrees of freedom: the law of a
/// `k`-row observation's standardised squared residual.
pub(crate) fn chi_square_median(k: usize) -> f64 {
    if k == 3 {
        CHI2_3_MEDIAN
    } else {
        chi_square_quantile(0.5, k.max(1) as f64)
    }
}

/// The density of the χ² law with `k ≥ 1` degrees of freedom at `x > 0`.
pub(crate) fn chi_square_density(x: f64, k: usize) -> f64 {
    let a = k.max(1) as f64 / 2.0;
    ((a - 1.0) * x.ln() - x / 2.0 - a * std::f64::consts::LN_2 - ln_gamma(a)).exp()
}

/// The root of `f`, increasing in `x`: `f(x) = (value, s)`, the value of a
/// function of a tail of the χ² law with `nu` degrees of freedom, whose
/// derivative is `s` times the χ² density.
fn quantile(nu: f64, f: impl Fn(f64) -> (f64, f64)) -> f64 {
    let a = nu / 2.0;
    let (mut lo, mut hi) = (0.0, nu.max(1.0));
    while f(hi).0 < 0.0 && hi < 1e6 {
        hi *= 2.0;
    }
    // Newton's steps on the tail (the χ² density is its derivative),
    // inside the bracket, which halves whenever a step would leave it:
    // 4–6 evaluations where bisection took ~40 — a calibration asks for
    // one quantile per pose (the 95 % radii).
    let ln_front = -ln_gamma(a) - a * std::f64::consts::LN_2;
    let mut x = 0.5 * (lo + hi);
    for _ in 0..200 {
        let (f, s) = f(x);
        if f < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let slope = ((a - 1.0) * x.ln() - x / 2.0 + ln_front).exp() * s;
        let newton = x - f / slope;
        let next = if slope > 0.0 && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let done = (next - x).abs() <= 1e-12 * next || hi - lo <= 1e-12 * hi;
        x = next;
        if done {
            break;
        }
    }
    x
}

/// The regularised lower incomplete gamma function `P(a, x)`: its series
/// below `x < a + 1`, the continued fraction (Lentz) above (Numerical
/// Recipes §6.2).
pub(crate) fn gamma_p(a: f64, x: f64) -> f64 {
    gamma_pq(a, x).0
}

/// `Q(a, x) = 1 − P(a, x)`, computed directly (the upper tail).
pub(crate) fn gamma_q(a: f64, x: f64) -> f64 {
    gamma_pq(a, x).1
}

/// `(P(a, x), Q(a, x))`, the one that is small computed directly.
fn gamma_pq(a: f64, x: f64) -> (f64, f64) {
    if x.is_nan() || a.is_nan() {
        return (f64::NAN, f64::NAN);
    }
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    if x.is_infinite() {
        return (1.0, 0.0);
    }
    let log_front = a * x.ln() - x - ln_gamma(a);
    // Near x = a both the series and the continued fraction need about
    // 8.6·√a terms to reach 1e-16 (the series' terms fall as
    // exp(−n²/2a)): a fixed 1000 stopped short from a ≈ 10⁴ on (the χ²
    // tails at x = dof were off by 8e-6 relative at 10⁵ dof, by 0.16 at
    // 10⁶).
    let most = 1000 + (20.0 * a.sqrt()) as usize;
    if x < a + 1.0 {
        let (mut term, mut sum, mut n) = (1.0 / a, 1.0 / a, a);
        for _ in 0..most {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() <= sum.abs() * f64::EPSILON {
                break;
            }
        }
        let p = (sum * log_front.exp()).clamp(0.0, 1.0);
        (p, 1.0 - p)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..most {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            // Within one rounding of 1: `delta` rarely lands on 1 exactly,
            // and a bound below f64's spacing there (2.2e-16) ran every
            // fraction to `most` terms — 1000 or more per call, most of a
            // small calibration's time in the per-pose 95 % radii.
            if (delta - 1.0).abs() <= 2.0 * f64::EPSILON {
                break;
            }
        }
        let q = (log_front.exp() * h).clamp(0.0, 1.0);
        (1.0 - q, q)
    }
}

/// `P(χ²_k ≥ x)`, the upper tail of the χ² law with `k` degrees of freedom.
pub(crate) fn chi_square_upper(x: f64, k: usize) -> f64 {
    gamma_q(k.max(1) as f64 / 2.0, x / 2.0)
}

/// `P(χ²_k ≤ x)`, the lower tail.
pub(crate) fn chi_square_lower(x: f64, k: usize) -> f64 {
    gamma_p(k.max(1) as f64 / 2.0, x / 2.0)
}

/// `P(Z ≥ z)`, the upper tail of the standard normal law: `Z²` is χ² with
/// one degree of freedom, so half its upper tail for `z ≥ 0` and one less
/// that (the lower χ² tail, computed directly) below.
pub(crate) fn normal_upper(z: f64) -> f64 {
    let (p, q) = gamma_pq(0.5, z * z / 2.0);
    if z.is_nan() {
        f64::NAN
    } else if z >= 0.0 {
        0.5 * q
    } else {
        0.5 + 0.5 * p
    }
}

/// The `k`-th smallest of `v` in [`f64::total_cmp`]'s order — what
/// `v[k]` is after sorting, found in linear time (10⁶ residuals: ~10 ms
/// where a sort took ~70); reorders `v`. `None` when `k` is out of range.
pub(crate) fn kth_smallest(v: &mut [f64], k: usize) -> Option<f64> {
    (k < v.len()).then(|| *v.select_nth_unstable_by(k, f64::total_cmp).1)
}

/// `ln Γ(x)`, `x > 0` (Lanczos, g = 7, 9 terms: 1e-15 relative).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut s = G[0];
    for (i, &g) in G.iter().enumerate().skip(1) {
        s += g / (x + i as f64);
    }
    let t = x + 7.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_and_densities_of_any_row_count() {
        // The constant for three rows is the quantile's own value.
        assert!((chi_square_median(3) - chi_square_quantile(0.5, 3.0)).abs() < 1e-12);
        for k in 1..=8 {
            let m = chi_square_median(k);
            assert!((chi_square_lower(m, k) - 0.5).abs() < 1e-12, "{k}");
        }
        // Two degrees of freedom: exp(−x/2)/2; one: exp(−x/2)/sqrt(2πx).
        for x in [0.1, 1.0, 4.0] {
            assert!((chi_square_density(x, 2) - (-x / 2.0).exp() / 2.0).abs() < 1e-14);
            let one = (-x / 2.0).exp() / (2.0 * std::f64::consts::PI * x).sqrt();
            assert!((chi_square_density(x, 1) / one - 1.0).abs() < 1e-13);
        }
    }

    /// Each tail against tables (and closed forms), far into the tails,
    /// where one minus the other would be 0 or 1.
    #[test]
    fn the_tails_match_closed_forms_far_out() {
        // χ²₂: P(χ² ≥ x) = exp(−x/2), exactly.
        for x in [0.1, 1.0, 10.0, 100.0, 1000.0] {
            let q = chi_square_upper(x, 2);
            let exact = (-x / 2.0).exp();
            assert!((q - exact).abs() <= 1e-13 * exact, "{x}: {q} vs {exact}");
            assert!(
                (chi_square_lower(x, 2) - (1.0 - exact)).abs() < 1e-14,
                "{x}"
            );
        }
        // χ²₂ lower tail near 0: 1 − exp(−x/2) ≈ x/2, relative.
        let x = 1e-12;
        assert!((chi_square_lower(x, 2) / (x / 2.0) - 1.0).abs() < 1e-9);
        // Tables: χ²₁₀ at 18.307 is the 5 % point, χ²₁₀₀ at 124.342 too,
        // and χ²₁₀₀ at 77.929 the 5 % lower point.
        assert!((chi_square_upper(18.307, 10) - 0.05).abs() < 2e-5);
        assert!((chi_square_upper(124.342, 100) - 0.05).abs() < 2e-5);
        assert!((chi_square_lower(77.929, 100) - 0.05).abs() < 2e-5);
        // Far tails stay positive, and the ends are the ends.
        assert!(chi_square_upper(1000.0, 100) > 0.0); // about 1e-145
        assert!(chi_square_lower(1.0, 100) > 0.0);
        assert_eq!(chi_square_upper(0.0, 5), 1.0);
        assert_eq!(chi_square_upper(f64::INFINITY, 5), 0.0);
    }

    /// The upper quantile against the closed form of χ²₂ (`−2 ln α`) and
    /// back through the tail at 1, 3, 10 and 1000 degrees of freedom, far
    /// into the tail; and the lower quantile where both apply.
    #[test]
    fn the_upper_quantile_is_exact_far_out() {
        for alpha in [0.5, 0.05, 1e-3, 1e-9, 1e-100, 1e-300] {
            let x = chi_square_upper_quantile(alpha, 2);
            let exact = -2.0 * alpha.ln();
            assert!(
                (x - exact).abs() <= 1e-12 * exact,
                "{alpha}: {x} vs {exact}"
            );
            for k in [1, 3, 10, 1000] {
                let x = chi_square_upper_quantile(alpha, k);
                let back = chi_square_upper(x, k);
                assert!(
                    (back / alpha - 1.0).abs() < 1e-9,
                    "{k} dof, {alpha}: {back}"
                );
            }
        }
        let (upper, lower) = (
            chi_square_upper_quantile(0.05, 3),
            chi_square_quantile(0.95, 3.0),
        );
        assert!((upper - lower).abs() < 1e-11 * lower, "{upper} vs {lower}");
        // The χ²₃ table: 7.8147 at 5 %, 16.266 at 0.1 %.
        assert!((upper - 7.814_728).abs() < 1e-6);
        assert!((chi_square_upper_quantile(1e-3, 3) - 16.266_24).abs() < 1e-4);
        // No probability: the bracket's end, not a loop without one.
        assert!(chi_square_upper_quantile(0.0, 3) >= 1e3);
    }

    /// The normal tails against mpmath (`ncdf`, 30 digits), to 1e-14
    /// relative, in both tails and far out.
    #[test]
    fn the_normal_tails_match_mpmath() {
        for (z, want) in [
            (0.0, 0.5),
            (1.0, 0.158_655_253_931_457_05),
            (-1.0, 0.841_344_746_068_542_9),
            (3.0, 1.349_898_031_630_094_6e-3),
            (5.0, 2.866_515_718_791_939e-7),
            (10.0, 7.619_853_024_160_527e-24),
            (30.0, 4.906_713_927_148_187e-198),
            (-8.0, 0.999_999_999_999_999_4),
        ] {
            let got = normal_upper(z);
            assert!(
                (got - want).abs() <= 1e-14 * want,
                "{z}: {got:e} vs {want:e}"
            );
        }
        assert!(normal_upper(f64::NAN).is_nan());
        assert_eq!(normal_upper(f64::INFINITY), 0.0);
        assert_eq!(normal_upper(f64::NEG_INFINITY), 1.0);
    }

    /// Both tails against mpmath at 30 digits, 1 to 10⁶ degrees of freedom,
    /// to 1e-6 relative. Generated by (Python, mpmath 1.3):
    ///
    /// ```text
    /// mp.mp.dps = 30
    /// for k in [1, 2, 3, 10, 100, 1000, 10000, 100000, 1000000]:
    ///     for f in ["0.5", "0.9", "1", "1.1", "2"]:
    ///         x = mp.mpf(k) * mp.mpf(f); a = mp.mpf(k) / 2; h = x / 2
    ///         up = mp.gammainc(a, h, mp.inf, regularized=True)
    ///         lo = 1 - up if up < 0.5 else mp.exp(a * mp.log(h) - h
    ///             - mp.loggamma(a + 1)) * mp.hyp1f1(1, a + 1, h, maxterms=10**7)
    /// ```
    ///
    /// (`1 − up` only where it is not a cancellation; the series of the
    /// lower tail elsewhere.) A reference below the smallest double is 0 in
    /// the table, and the tail must then be below 1e-300 too.
    #[test]
    fn the_tails_match_mpmath_from_1_to_a_million_dof() {
        // (dof, x / dof, P(χ² ≥ x), P(χ² ≤ x))
        const TABLE: [(usize, f64, &str, &str); 45] = [
            (1, 0.5, "4.7950012218695346e-1", "5.2049987781304654e-1"),
            (1, 0.9, "3.4278171114791139e-1", "6.5721828885208861e-1"),
            (1, 1.0, "3.173105078629141e-1", "6.826894921370859e-1"),
            (1, 1.1, "2.9426610430496289e-1", "7.0573389569503711e-1"),
            (1, 2.0, "1.5729920705028513e-1", "8.4270079294971487e-1"),
            (2, 0.5, "6.0653065971263342e-1", "3.9346934028736658e-1"),
            (2, 0.9, "4.0656965974059911e-1", "5.9343034025940089e-1"),
            (2, 1.0, "3.6787944117144232e-1", "6.3212055882855768e-1"),
            (2, 1.1, "3.3287108369807955e-1", "6.6712891630192045e-1"),
            (2, 2.0, "1.3533528323661269e-1", "8.6466471676338731e-1"),
            (3, 0.5, "6.8227033033621257e-1", "3.1772966966378743e-1"),
            (3, 0.9, "4.4022729436023108e-1", "5.5977270563976892e-1"),
            (3, 1.0, "3.9162517627108896e-1", "6.0837482372891104e-1"),
            (3, 1.1, "3.4764264473227456e-1", "6.5235735526772544e-1"),
            (3, 2.0, "1.1161022509471256e-1", "8.8838977490528744e-1"),
            (10, 0.5, "8.9117801891415124e-1", "1.0882198108584876e-1"),
            (10, 0.9, "5.3210357637471548e-1", "4.6789642362528452e-1"),
            (10, 1.0, "4.4049328506521241e-1", "5.5950671493478759e-1"),
            (10, 1.1, "3.5751800242792553e-1", "6.4248199757207447e-1"),
            (10, 2.0, "2.9252688076961073e-2", "9.7074731192303893e-1"),
            (100, 0.5, "9.9999304669475238e-1", "6.953305247616099e-6"),
            (100, 0.9, "7.5319796559982973e-1", "2.4680203440017027e-1"),
            (100, 1.0, "4.8119168452795672e-1", "5.1880831547204328e-1"),
            (100, 1.1, "2.3220478050085633e-1", "7.6779521949914367e-1"),
            (100, 2.0, "1.1784500720979422e-8", "9.9999998821549928e-1"),
            (1000, 0.5, "1.0", "4.0671656819990012e-44"),
            (1000, 0.9, "9.8928276190871026e-1", "1.0717238091289742e-2"),
            (1000, 1.0, "4.9405285382923964e-1", "5.0594714617076036e-1"),
            (1000, 1.1, "1.4614408126295194e-2", "9.8538559187370481e-1"),
            (1000, 2.0, "4.1436785914549917e-69", "1.0"),
            (10000, 0.5, "1.0", "4.3501154601743014e-422"),
            (
                10000,
                0.9,
                "9.9999999999987302e-1",
                "1.2697731705204421e-13",
            ),
            (10000, 1.0, "4.9811936596618264e-1", "5.0188063403381736e-1"),
            (
                10000,
                1.1,
                "3.6183295580964793e-12",
                "9.9999999999638167e-1",
            ),
            (10000, 2.0, "2.6841887389080571e-669", "1.0"),
            (100000, 0.5, "1.0", "2.5983721241013879e-4197"),
            (100000, 0.9, "1.0", "7.0554989738953195e-119"),
            (
                100000,
                1.0,
                "4.9940529189520669e-1",
                "5.0059470810479331e-1",
            ),
            (100000, 1.1, "2.5841772471796376e-104", "1.0"),
            (100000, 2.0, "1.0643758347493923e-6666", "1.0"),
            (1000000, 0.5, "1.0", "4.7325702806674127e-41945"),
            (1000000, 0.9, "1.0", "5.3723176083811064e-1167"),
            (1000000, 1.0, "4.998119368033945e-1", "5.001880631966055e-1"),
            (1000000, 1.1, "2.3432220583262172e-1021", "1.0"),
            (1000000, 2.0, "3.2233214539030538e-66636", "1.0"),
        ];
        let close = |got: f64, want: f64| {
            if want == 0.0 {
                got < 1e-300
            } else {
                ((got - want) / want).abs() <= 1e-6
            }
        };
        let mut bad = Vec::new();
        for (k, f, up, lo) in TABLE {
            // Parsed: a reference below the smallest double reads as 0.
            let (up, lo): (f64, f64) = (up.parse().unwrap(), lo.parse().unwrap());
            let x = k as f64 * f;
            let (u, l) = (chi_square_upper(x, k), chi_square_lower(x, k));
            if !close(u, up) || !close(l, lo) {
                bad.push(format!(
                    "dof {k}, x {x}: upper {u:e} vs {up:e}, lower {l:e} vs {lo:e}"
                ));
            }
        }
        assert!(bad.is_empty(), "{}", bad.join("\n"));
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn stats_chi_square_upper_quantile() {
        use crate::stats::{chi_square_upper, chi_square_upper_quantile};
        let x = chi_square_upper_quantile(1e-12, 3);
        assert!((chi_square_upper(x, 3) / 1e-12 - 1.0).abs() < 1e-10);
    }

    #[test]
    fn stats_chi_square_median() {
        use crate::stats::chi_square_median;
        assert!((chi_square_median(1) - 0.454_936_423_119_572_7).abs() < 1e-12);
        assert!((chi_square_median(3) - 2.365_973_884_375_338).abs() < 1e-15);
    }

    #[test]
    fn stats_normal_upper() {
        use crate::stats::normal_upper;
        assert_eq!(normal_upper(0.0), 0.5);
        assert!((normal_upper(1.959_963_984_540_054) - 0.025).abs() < 1e-15);
        assert!((normal_upper(-1.0) - 0.841_344_746_068_542_9).abs() < 1e-15);
    }
}
