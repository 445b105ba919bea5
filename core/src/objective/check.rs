//! A gradient checker, in the manner of Ceres' `GradientChecker`: the first
//! thing the author of a term needs to know is whether the derivatives it
//! writes are those of the residuals it computes.
//!
//! A term gives the fit its normal equations ([`crate::residuals::Term::accumulate`]) and its
//! cost ([`crate::residuals::Term::add_cost`]); the two agree when its gradient `Jᵀr` is half
//! the derivative of its cost `Σ r²`. The checker compares, per term and
//! per free column, the `Jᵀr` the term writes with central differences of
//! the cost it computes, stepping each column through its block's local
//! update ([`crate::residuals::Block::plus`]: a frame's rotation columns
//! turn the frame) by `h = step · max(1, |x_c|)` and by `h/2`, extrapolated
//! (Richardson) so that the differences' `h²` error goes:
//!
//! ```text
//! D(h)      = (cost(x ⊞ h e_c) − cost(x ⊞ −h e_c)) / 4h
//! numeric_c = (4 D(h/2) − D(h)) / 3
//! error_c   = |g_c − numeric_c| / max(|g_c|, |numeric_c|, floor · max_c' |·|)
//! ```
//!
//! The step is large (1e-3 by default) because the cost's rounding, not
//! its curvature, limits small ones: a cost of 10⁷ (a nominal arm against
//! touches of 0.01 mm) rounds by 10⁻⁹, which over a step of 10⁻⁶ is a
//! gradient error of 10⁻³ — as large as a column of small effect (a
//! compliance in µrad/(N·m)) has gradient. The extrapolation leaves an
//! error of order `h⁴`.
//!
//! — relative, with a floor relative to the term's largest gradient entry
//! so that a column the term barely depends on is judged against the
//! term's scale, not its own rounding. The worst column of each block (the
//! geometry's, then each auxiliary block) is reported. A wrong column of a
//! Jacobian (a sign, a forgotten factor, a correction not carried through)
//! moves the gradient wherever the residuals are not zero: check at a
//! point where they are not (a nominal arm against its data, not a perfect
//! fit). What the gradient does not see is the part of `J` orthogonal to
//! `r`; the terms' own tests compare `JᵀJ` where that matters.

use std::fmt;

use super::Objective;
use crate::residuals::{Layout, TermError};

/// How [`check_gradients`] differentiates and judges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckOptions {
    /// Relative step of the central differences (`h = step · max(1,
    /// |x_c|)`, in the column's own units: mm, rad), and half of it.
    pub step: f64,
    /// Largest relative error that passes.
    pub tolerance: f64,
    /// The error's floor, relative to the term's largest gradient entry.
    pub floor: f64,
}

impl Default for CheckOptions {
    /// A step of 1e-3, a tolerance of 1e-5, a floor of 1e-6: the built-in
    /// terms agree to better than 1e-6 there (their test: rounding of
    /// costs of 10⁷ leaves 1e-7); a wrong column is off by far more.
    fn default() -> Self {
        CheckOptions {
            step: 1e-3,
            tolerance: 1e-5,
            floor: 1e-6,
        }
    }
}

/// The worst column of one block for one term.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockCheck {
    /// The block: `geometry`, or an auxiliary block's name.
    pub block: String,
    /// Its worst column's name.
    pub column: String,
    /// The term's `Jᵀr` there.
    pub analytic: f64,
    /// Half the central difference of its cost there.
    pub numeric: f64,
    /// Their relative error (module documentation).
    pub relative_error: f64,
}

/// One term's check: its worst column per block.
#[derive(Clone, Debug, PartialEq)]
pub struct TermCheck {
    /// The term's name.
    pub term: String,
    /// Its index in the objective.
    pub index: usize,
    /// Per block with a free column, its worst column.
    pub blocks: Vec<BlockCheck>,
}

impl TermCheck {
    /// The worst relative error over the blocks (0 without any).
    #[cfg(test)]
    pub(crate) fn worst(&self) -> f64 {
        (self.blocks.iter()).fold(0.0, |w, b| w.max(b.relative_error))
    }
}

/// Every term's check, in the objective's order.
#[derive(Clone, Debug, PartialEq)]
pub struct GradientCheck {
    /// The tolerance it was judged by.
    pub tolerance: f64,
    /// Per term.
    pub terms: Vec<TermCheck>,
}

impl GradientCheck {
    /// Whether every term's every block is within the tolerance.
    pub fn passed(&self) -> bool {
        self.failures().is_empty()
    }

    /// The blocks beyond the tolerance (not a number counts), with their
    /// terms, in order.
    pub fn failures(&self) -> Vec<(&TermCheck, &BlockCheck)> {
        (self.terms.iter())
            .flat_map(|t| t.blocks.iter().map(move |b| (t, b)))
            .filter(|(_, b)| b.relative_error.is_nan() || b.relative_error > self.tolerance)
            .collect()
    }
}

impl fmt::Display for GradientCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for t in &self.terms {
            for b in &t.blocks {
                let verdict = if b.relative_error <= self.tolerance {
                    "ok"
                } else {
                    "WRONG"
                };
                writeln!(
                    f,
                    "{verdict}: term `{}` (#{}), block {}: worst column {} — Jᵀr {:.6e}, \
                     numeric {:.6e}, relative error {:.1e} (tolerance {:.0e})",
                    t.term,
                    t.index + 1,
                    b.block,
                    b.column,
                    b.analytic,
                    b.numeric,
                    b.relative_error,
                    self.tolerance
                )?;
            }
        }
        Ok(())
    }
}

/// Checks every term of `objective` at `x` over the columns `free`: each
/// term's `Jᵀr` against central differences of its cost through the
/// blocks' local updates (module documentation). The terms are weighed as
/// they are; a term that needs another's results (the lengths the touches'
/// centres) gets them as in a fit.
///
/// ```
/// use aacmm_core::objective::{CheckOptions, Objective, check_gradients};
/// use aacmm_core::residuals::Layout;
/// use aacmm_core::DhParams;
/// // An objective without terms has nothing to check.
/// let layout = Layout::new(DhParams::paper_nominal());
/// let x = layout.start();
/// let o = Objective::new(layout, Vec::new(), 1);
/// let check = check_gradients(&o, &x, &[0, 1], &CheckOptions::default()).unwrap();
/// assert!(check.passed() && check.terms.is_empty());
/// ```
///
/// # Errors
///
/// The kernel's, at `x` or at a step from it.
pub fn check_gradients(
    objective: &Objective<'_>,
    x: &[f64],
    free: &[usize],
    options: &CheckOptions,
) -> Result<GradientCheck, TermError> {
    let analytic = objective.term_gradients(x, free)?;
    let numeric = numeric_gradients(objective, x, free, options.step)?;
    let layout = objective.layout();
    let terms = (objective.terms().enumerate())
        .map(|(k, term)| TermCheck {
            term: term.name().to_string(),
            index: k,
            blocks: judge(layout, free, &analytic[k].0, &numeric[k], options.floor),
        })
        .collect();
    Ok(GradientCheck {
        tolerance: options.tolerance,
        terms,
    })
}

/// Per term, half the central difference of its cost along each free
/// column, extrapolated from the steps `h` and `h/2`.
fn numeric_gradients(
    objective: &Objective<'_>,
    x: &[f64],
    free: &[usize],
    step: f64,
) -> Result<Vec<Vec<f64>>, TermError> {
    let terms = objective.terms().count();
    let mut out = vec![vec![0.0; free.len()]; terms];
    let mut delta = vec![0.0; free.len()];
    for (a, &c) in free.iter().enumerate() {
        let h = step * x[c].abs().max(1.0);
        let mut at = |d: f64| -> Result<Vec<f64>, TermError> {
            delta[a] = d;
            let moved = objective.plus(x, free, &delta);
            delta[a] = 0.0;
            objective.term_costs(&moved, free)
        };
        let (up, down) = (at(h)?, at(-h)?);
        let (half_up, half_down) = (at(h / 2.0)?, at(-h / 2.0)?);
        for k in 0..terms {
            let coarse = (up[k] - down[k]) / (4.0 * h);
            let fine = (half_up[k] - half_down[k]) / (2.0 * h);
            out[k][a] = (4.0 * fine - coarse) / 3.0;
        }
    }
    Ok(out)
}

/// The worst column of each block, judged against the term's scale.
fn judge(
    layout: &Layout,
    free: &[usize],
    analytic: &[f64],
    numeric: &[f64],
    floor: f64,
) -> Vec<BlockCheck> {
    let scale = (analytic.iter().chain(numeric))
        .fold(0.0_f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let mut blocks: Vec<BlockCheck> = Vec::new();
    for (a, &c) in free.iter().enumerate() {
        let (g, n) = (analytic[a], numeric[a]);
        let error = (g - n).abs() / g.abs().max(n.abs()).max(floor * scale);
        let block = block_of(layout, c);
        let check = BlockCheck {
            block: block.clone(),
            column: layout
                .parameter(c)
                .map_or_else(|| c.to_string(), |p| p.name),
            analytic: g,
            numeric: n,
            relative_error: error,
        };
        match blocks.iter_mut().find(|b| b.block == block) {
            // Not a number is the worst of all.
            Some(b) if error.is_nan() || error > b.relative_error => *b = check,
            Some(_) => {}
            None => blocks.push(check),
        }
    }
    blocks
}

/// The name of the block column `c` belongs to.
fn block_of(layout: &Layout, c: usize) -> String {
    let mut end = layout.geometry_columns();
    if c < end {
        return "geometry".to_string();
    }
    for block in layout.blocks() {
        end += block.len();
        if c < end {
            return block.name().to_string();
        }
    }
    format!("column {c}")
}

/// A point off `start` in every free column (a thousandth, each column by
/// another amount), where the gradient checks of the terms' tests look:
/// at the start some columns' derivatives vanish by symmetry.
#[cfg(test)]
pub(crate) fn off_start(o: &Objective<'_>, start: &[f64], free: &[usize]) -> Vec<f64> {
    let delta: Vec<f64> = (0..free.len())
        .map(|a| 1e-3 * ((a as f64) * 0.7).sin())
        .collect();
    o.plus(start, free, &delta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corrections::{Beyond, Mass, Physics};
    use crate::residuals::positions::layout_with;
    use crate::residuals::{Hold, HoldTerm, Noise, Role};
    use crate::simulate::{
        CampaignSettings, ErrorModel, PositionSettings, simulate, simulate_positions,
    };

    /// Every built-in term on one objective — touches, lengths, positions
    /// in two frames, the prior, a held direction — on a layout with the
    /// corrections beyond geometry (compliance, a harmonic) and two frame
    /// blocks, at a point off the start in every column.
    fn every_builtin(check: impl FnOnce(&Objective<'_>, &[f64], &[usize])) {
        let nominal = crate::Arm::without_limits("n", crate::DhParams::paper_nominal());
        let mut s = CampaignSettings::new(3, ErrorModel::Paper, 5, 6);
        s.reference_lengths = 3;
        let c = simulate(&nominal, &s).unwrap();
        let noise = Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            position_mm: Some(0.015),
            position_mm_per_m: Some(0.006),
            ..Noise::default()
        };
        let tracker = PositionSettings {
            poses: 12,
            frames: 2,
            noise,
            seed: 9,
        };
        let positions = simulate_positions(&c.true_arm, &tracker).unwrap().positions;
        let data = (c.data_set().unwrap())
            .with_positions(positions, "p.csv")
            .unwrap();
        let physics = Physics {
            link_masses: vec![Some(Mass::at_middle(2.0)); 6],
            probe_mass: Some(Mass::at_middle(0.5)),
            ..Physics::default()
        };
        let beyond = Beyond {
            compliance: vec![1, 2],
            harmonics: vec![(0, 1)],
            ..Beyond::default()
        };
        let layout = layout_with(&nominal.params, &data, &physics, &beyond).unwrap();
        let tolerances =
            crate::tolerances::Tolerances::parse("length=0.5mm,angle=0.1deg", 6).unwrap();
        let start = layout.start();
        let free: Vec<usize> = (0..layout.len()).collect();
        let mut o = Objective::of_data(
            layout,
            &data,
            &noise,
            Vec::new(),
            tolerances.as_ref(),
            1.0,
            1,
        )
        .unwrap();
        let hold = Hold {
            cols: vec![1, 7],
            v: vec![0.6, 0.8],
            d: vec![1.0, 1.0],
            circular: vec![false, false],
            ratio: 1e-4,
            text: String::new(),
            terms: Vec::new(),
        };
        o.push_term(Box::new(HoldTerm::new(vec![hold], &start, 1.0)));
        let x = off_start(&o, &start, &free);
        check(&o, &x, &free);
    }

    #[test]
    fn every_builtin_term_passes_on_every_block() {
        every_builtin(|o, x, free| {
            let roles: Vec<Role> = o.terms().map(|t| t.role()).collect();
            assert_eq!(
                roles,
                [
                    Role::Touches,
                    Role::Lengths,
                    Role::Positions,
                    Role::Prior,
                    Role::Held
                ]
            );
            let check = check_gradients(o, x, free, &CheckOptions::default()).unwrap();
            assert!(check.passed(), "{check}");
            // Each term was judged on the blocks it depends on.
            let blocks = |k: usize| -> Vec<&str> {
                (check.terms[k].blocks.iter())
                    .map(|b| b.block.as_str())
                    .collect()
            };
            assert_eq!(blocks(2), ["geometry", "beyond", "station1", "station2"]);
            assert!(check.terms.iter().all(|t| t.worst() < 1e-6));
            // The touches and positions depend on the corrections: their
            // gradient there is not zero (the check saw something).
            for k in [0, 2] {
                let beyond = &check.terms[k].blocks[1];
                assert!(beyond.analytic.abs() > 0.0, "{check}");
            }
        });
    }

    #[test]
    fn a_wrong_step_size_is_seen() {
        // The same check with a step so large the differences are not
        // derivatives: the checker can fail.
        every_builtin(|o, x, free| {
            let coarse = CheckOptions {
                step: 0.5,
                ..CheckOptions::default()
            };
            let check = check_gradients(o, x, free, &coarse).unwrap();
            assert!(!check.passed(), "{check}");
            assert!(check.to_string().contains("WRONG"));
        });
    }
}
