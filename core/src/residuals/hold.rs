//! Weak directions held at the start value: a direction of the free
//! geometry that the data determine more than [`WEAK_RATIO`]⁻¹ times worse
//! than the best-determined one, and that no stated tolerance covers, is
//! held where the nominal arm puts it (a truncated step; see
//! `docs/calibration.md`, "Weak directions").
//!
//! Each held direction `v` (a unit vector in the identification's scaled
//! coordinates `y = x / d`: lengths in mm, angles as the arc they sweep at
//! the reach) adds the pseudo-observation
//!
//! ```text
//! r = √K · vᵀ (y − y0)        K = 100 · s_max²
//! ```
//!
//! `s_max` the largest singular value of the scaled data Jacobian. Along
//! `v` the data carry `s² < 10⁻⁶ s_max²` (that is what makes it weak), so
//! the hold outweighs them by more than 10⁸: the direction moves by less
//! than 10⁻⁸ of what the data would make of it — held, as a fixed
//! parameter is, while the normal equations stay as well conditioned as
//! the best-determined direction allows. Each row counts in the degrees of
//! freedom, as fixing a parameter removes an unknown. Angles are wrapped
//! to ±π before they enter, as the prior's are.

use serde::{Deserialize, Serialize};

use super::{At, Normal, Shared, Term, TermError};
use crate::params::wrap;

/// Relative singular value below which a direction of the free geometry is
/// weak: determined 1000 times worse than the best one (a condition number
/// above 1000 in the scaled metric). A model error of ε moves such a
/// direction by up to 1000 ε.
pub const WEAK_RATIO: f64 = 1e-3;

/// Stiffness of a hold relative to the best-determined direction's
/// information, `K = HOLD_STIFFNESS · s_max²`.
const HOLD_STIFFNESS: f64 = 100.0;

/// One held direction: over the columns `cols`, the unit vector `v` in
/// scaled coordinates, each column's scale `d` (1 for a length, 1/reach for
/// an angle), and its start values.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Hold {
    pub(crate) cols: Vec<usize>,
    pub(crate) v: Vec<f64>,
    pub(crate) d: Vec<f64>,
    pub(crate) circular: Vec<bool>,
    /// The direction's singular value relative to the largest.
    pub(crate) ratio: f64,
    /// The direction in words (its larger terms).
    pub(crate) text: String,
    /// Its terms above 0.05: `(name, coefficient)`.
    pub(crate) terms: Vec<(String, f64)>,
}

/// The held directions of one fit, around the start `x0`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct HoldTerm {
    holds: Vec<Hold>,
    x0: Vec<f64>,
    /// `√K`.
    root_stiffness: f64,
}

impl HoldTerm {
    /// Holds `holds` at `x0`, against data whose largest scaled singular
    /// value is `s_max`.
    pub(crate) fn new(holds: Vec<Hold>, x0: &[f64], s_max: f64) -> HoldTerm {
        HoldTerm {
            holds,
            x0: x0.to_vec(),
            root_stiffness: HOLD_STIFFNESS.sqrt() * s_max,
        }
    }

    /// The held directions.
    pub(crate) fn holds(&self) -> &[Hold] {
        &self.holds
    }

    /// The hold's own information along its direction, `K`.
    pub(crate) fn stiffness(&self) -> f64 {
        self.root_stiffness * self.root_stiffness
    }

    /// `∂r/∂x_c` of hold `h`, per column of `h.cols`.
    fn gradient<'h>(&self, h: &'h Hold) -> impl Iterator<Item = (usize, f64)> + 'h {
        let k = self.root_stiffness;
        (0..h.cols.len()).map(move |i| (h.cols[i], k * h.v[i] / h.d[i]))
    }

    /// `r` of hold `h` at `x`.
    fn residual(&self, h: &Hold, x: &[f64]) -> f64 {
        (0..h.cols.len())
            .map(|i| {
                let c = h.cols[i];
                let delta = x[c] - self.x0[c];
                let delta = if h.circular[i] { wrap(delta) } else { delta };
                self.root_stiffness * h.v[i] * delta / h.d[i]
            })
            .sum()
    }

    fn cost(&self, x: &[f64]) -> f64 {
        self.holds.iter().map(|h| self.residual(h, x).powi(2)).sum()
    }
}

impl Term for HoldTerm {
    fn name(&self) -> &str {
        "hold"
    }

    /// Not data: left out of what the data alone see, added where the
    /// prior is.
    fn role(&self) -> super::Role {
        super::Role::Held
    }

    /// A row per held direction (its columns are free by construction).
    fn rows(&self, free: &[usize]) -> usize {
        self.holds
            .iter()
            .filter(|h| h.cols.iter().any(|c| free.contains(c)))
            .count()
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let p = normal.free.len();
        let mut cost = 0.0;
        for h in &self.holds {
            let g: Vec<(usize, f64)> = self
                .gradient(h)
                .filter_map(|(c, g)| normal.free.iter().position(|&f| f == c).map(|a| (a, g)))
                .collect();
            if g.is_empty() {
                continue;
            }
            let r = self.residual(h, at.x);
            for &(a, ga) in &g {
                normal.jtr[a] += ga * r;
                for &(b, gb) in &g {
                    normal.jtj[a * p + b] += ga * gb;
                }
            }
            cost += r * r;
        }
        Ok(cost)
    }

    fn add_cost(
        &self,
        at: &At<'_>,
        _free: &[usize],
        _shared: &mut Shared,
        _scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        *total += self.cost(at.x);
        Ok(())
    }
}

/// A direction held at nominal, as reported.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldDirection {
    /// The direction in words: its larger terms, a unit vector in scaled
    /// units (angles as the arc they sweep at the reach).
    pub relation: String,
    /// `(parameter, coefficient)`, coefficients above 0.05.
    pub terms: Vec<(String, f64)>,
    /// Its singular value relative to the best-determined direction's
    /// (below [`WEAK_RATIO`]).
    pub ratio: f64,
    /// The standard uncertainty the data alone would give it at the fit's
    /// noise, mm at the reach: what fitting it would have risked (absent
    /// when the data carry no information along it at all).
    pub sigma_mm: Option<f64>,
}

impl HeldDirection {
    /// In words, for a summary line.
    pub fn describe(&self) -> String {
        let sigma = match self.sigma_mm {
            Some(s) => format!("σ {s:.3} mm at the reach"),
            None => "not determined at all".to_string(),
        };
        format!(
            "{} (the data alone: {sigma}; {:.1e} of the best direction's precision)",
            self.relation, self.ratio
        )
    }
}
