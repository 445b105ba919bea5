//! The damping of damped least squares (Levenberg–Marquardt): how far a
//! solver leans from the Gauss–Newton step towards a short gradient step,
//! raised after a step that fails and lowered after one that succeeds.
//!
//! One strategy, two parameterisations:
//!
//! - [`Damping::nielsen`], the calibration's LM: λ relative to Marquardt's
//!   diagonal scale (the solver multiplies), λ₀ = 10⁻³. After an accepted
//!   step with gain ratio ρ (actual over predicted cost reduction),
//!   `λ ← λ·max(1/3, 1 − (2ρ − 1)³)` and `ν ← 2`; after a rejected one,
//!   `λ ← λ·ν`, `ν ← 2ν` (Nielsen's update, as in Madsen, Nielsen &
//!   Tingleff, *Methods for non-linear least squares problems*, 2004): a
//!   step that did as predicted relaxes the damping up to threefold, one
//!   that barely helped keeps it, and failures in a row raise it ever
//!   faster, so a stall is left in a few tries. Past λ > 10¹⁶ the damped
//!   step is a gradient step too short to move any parameter by a bit:
//!   the damping is exhausted.
//! - [`Damping::fixed_factors`], the inverse kinematics (a 3 × 3 system per
//!   step, where a finer rule buys nothing): μ divided by one factor after
//!   an accepted step and multiplied by another after a rejected one, never
//!   exhausted (the solver's iteration budget stops it).
//!
//! Ground floor: it knows nothing of what is being solved.

/// Nielsen's initial damping, relative to Marquardt's diagonal scale.
const NIELSEN_INITIAL: f64 = 1e-3;

/// The damping past which Nielsen's rule gives up.
const NIELSEN_CAP: f64 = 1e16;

/// A damping and the rule that updates it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Damping {
    value: f64,
    rule: Rule,
}

/// How [`Damping`] moves.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rule {
    /// Nielsen's update; `nu` grows with rejections in a row.
    Nielsen { nu: f64 },
    /// Divide by `shrink` on acceptance, multiply by `grow` on rejection.
    Fixed { shrink: f64, grow: f64 },
}

impl Damping {
    /// Nielsen's rule from λ₀ = 10⁻³ (relative to the diagonal scale), ν = 2.
    pub(crate) fn nielsen() -> Damping {
        Damping {
            value: NIELSEN_INITIAL,
            rule: Rule::Nielsen { nu: 2.0 },
        }
    }

    /// Fixed factors from `initial`: divided by `shrink` after an accepted
    /// step, `grow` times (plus the least positive number) after a
    /// rejected one.
    pub(crate) fn fixed_factors(initial: f64, shrink: f64, grow: f64) -> Damping {
        Damping {
            value: initial,
            rule: Rule::Fixed { shrink, grow },
        }
    }

    /// The damping to use for the next step.
    pub(crate) fn value(&self) -> f64 {
        self.value
    }

    /// After a step that was taken, with gain ratio `rho` (fixed factors do
    /// not look at it).
    pub(crate) fn accept(&mut self, rho: f64) {
        match &mut self.rule {
            Rule::Nielsen { nu } => {
                self.value *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                *nu = 2.0;
            }
            Rule::Fixed { shrink, .. } => self.value /= *shrink,
        }
    }

    /// After a step that was not taken (or could not be solved for).
    pub(crate) fn reject(&mut self) {
        match &mut self.rule {
            Rule::Nielsen { nu } => {
                self.value *= *nu;
                *nu *= 2.0;
            }
            // The least positive number lets a damping of zero (a start
            // where the Jacobian vanishes) grow.
            Rule::Fixed { grow, .. } => self.value = self.value * *grow + f64::MIN_POSITIVE,
        }
    }

    /// Whether the damping is past use: a step that small moves nothing,
    /// so the solver should stop trying.
    pub(crate) fn exhausted(&self) -> bool {
        match self.rule {
            Rule::Nielsen { .. } => self.value > NIELSEN_CAP,
            Rule::Fixed { .. } => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nielsen_rejections_grow_ever_faster_and_an_acceptance_resets_them() {
        let mut d = Damping::nielsen();
        assert_eq!(d.value(), 1e-3);
        d.reject();
        d.reject();
        d.reject();
        // ×2, ×4, ×8
        assert_eq!(d.value(), 1e-3 * 2.0 * 4.0 * 8.0);
        d.accept(1.0);
        assert_eq!(d.value(), 1e-3 * 2.0 * 4.0 * 8.0 * (1.0 / 3.0));
        let before = d.value();
        d.reject();
        assert_eq!(d.value(), before * 2.0, "ν back to 2 after an acceptance");
    }

    #[test]
    fn nielsen_acceptance_follows_the_gain_ratio() {
        let after = |rho: f64| {
            let mut d = Damping::nielsen();
            d.accept(rho);
            d.value() / 1e-3
        };
        // As predicted or better: relaxed threefold.
        assert_eq!(after(1.0), 1.0 / 3.0);
        assert_eq!(after(5.0), 1.0 / 3.0);
        // Half the prediction: kept.
        assert_eq!(after(0.5), 1.0);
        // Barely any gain: almost doubled.
        assert!((after(1e-9) - 2.0).abs() < 1e-8);
    }

    #[test]
    fn nielsen_is_exhausted_only_past_the_cap() {
        let mut d = Damping::nielsen();
        let mut rejections = 0;
        while !d.exhausted() {
            assert!(d.value() <= NIELSEN_CAP);
            d.reject();
            rejections += 1;
        }
        assert!(d.value() > NIELSEN_CAP);
        // 10⁻³·2^(1+2+…+k) > 10¹⁶ first at k = 11 (k = 10 reaches 3.6·10¹³).
        assert_eq!(rejections, 11);
    }

    #[test]
    fn fixed_factors_divide_and_multiply_and_never_give_up() {
        let mut d = Damping::fixed_factors(0.0, 3.0, 4.0);
        d.reject();
        assert_eq!(d.value(), f64::MIN_POSITIVE, "a zero damping grows");
        let mut d = Damping::fixed_factors(1.5, 3.0, 4.0);
        d.accept(f64::NAN);
        assert_eq!(d.value(), 0.5);
        d.reject();
        assert_eq!(d.value(), 2.0 + f64::MIN_POSITIVE);
        let mut d = Damping::fixed_factors(f64::MAX, 3.0, 4.0);
        d.reject();
        assert_eq!(d.value(), f64::INFINITY);
        assert!(!d.exhausted());
    }

    /// The rules as the solvers wrote them inline before this module: the
    /// same operations in the same order, so the same bits.
    #[test]
    fn both_rules_give_the_bits_of_the_inline_updates() {
        let rhos = [0.9, -1.0, 0.3, 1.7, 0.01, -1.0, -1.0, 0.55, 0.999, 2.5e-3];
        let mut d = Damping::nielsen();
        let (mut lambda, mut nu) = (1e-3f64, 2.0f64);
        let mut mu = Damping::fixed_factors(1e-3 * 12.34 / 3.0, 3.0, 4.0);
        let mut m = 1e-3 * 12.34 / 3.0;
        for (i, &rho) in rhos.iter().cycle().take(200).enumerate() {
            if rho > 0.0 {
                d.accept(rho);
                lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                mu.accept(rho);
                m /= 3.0;
            } else {
                d.reject();
                lambda *= nu;
                nu *= 2.0;
                mu.reject();
                m = m * 4.0 + f64::MIN_POSITIVE;
            }
            assert_eq!(d.value().to_bits(), lambda.to_bits(), "step {i}");
            assert_eq!(d.exhausted(), lambda > 1e16, "step {i}");
            assert_eq!(mu.value().to_bits(), m.to_bits(), "step {i}");
        }
    }
}
