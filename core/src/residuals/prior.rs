//! Prior knowledge as residuals: a stated tolerance `σ_k` (1σ, what the
//! maker knows from machining and assembly) on a FREE column adds the
//! whitened pseudo-observation `r_k = (p_k − p0_k)/σ_k`, `p0` the start
//! (nominal) value, zero offsets and twists wrapped to ±π:
//!
//! ```text
//! JᵀJ += diag(1/σ²)      Jᵀr += (p − p0)/σ²      cost += Σ r_k²
//! ```
//!
//! Each such row counts in the degrees of freedom; see
//! [`crate::calibrate::prior`] for where the prior acts and why the fixed
//! set is the data's own.

use super::{At, Layout, Normal, Shared, Term, TermError};
use crate::params::wrap;
use crate::tolerances::Tolerances;

/// The resolved prior of one fit: start values and tolerances per column
/// (the geometry's from the stated [`Tolerances`], an auxiliary block's
/// from the block).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PriorTerm {
    nominal: Vec<f64>,
    sigma: Vec<Option<f64>>,
    /// Whether a column is an angle on a circle (a geometry angle), whose
    /// offset from nominal is wrapped to ±π.
    circular: Vec<bool>,
}

impl PriorTerm {
    /// The prior of `tolerances` (the geometry's) and of the auxiliary
    /// blocks' own tolerances around the start `x` of `layout`; `None` when
    /// no tolerance applies to any column.
    pub(crate) fn new(
        tolerances: Option<&Tolerances>,
        layout: &Layout,
        x: &[f64],
    ) -> Option<PriorTerm> {
        let geometry = layout.geometry();
        let mut sigma = match tolerances {
            Some(t) => t.sigmas_for(geometry),
            None => vec![None; geometry.param_count()],
        };
        let mut circular: Vec<bool> = geometry
            .param_ids()
            .map(|id| !id.kind.is_length())
            .collect();
        for block in layout.blocks() {
            for i in 0..block.len() {
                sigma.push(block.tolerance(i));
                circular.push(false);
            }
        }
        if sigma.iter().all(Option::is_none) {
            return None;
        }
        Some(PriorTerm {
            nominal: x.to_vec(),
            sigma,
            circular,
        })
    }

    /// Carries `extra` (1σ, the column's units) onto column `c`'s
    /// tolerance, in quadrature; a column without a tolerance stays
    /// without one (nothing bounds it, whatever its partner's tolerance).
    /// The new tolerance, if any.
    pub(crate) fn carry(&mut self, c: usize, extra: f64) -> Option<f64> {
        let s = self.sigma.get_mut(c)?.as_mut()?;
        *s = s.hypot(extra);
        Some(*s)
    }

    /// The tolerance of column `c`.
    pub(crate) fn sigma(&self, c: usize) -> Option<f64> {
        self.sigma.get(c).copied().flatten()
    }

    /// `(p_c − p0_c)/σ_c` at `x` (angles wrapped), if `c` has a tolerance.
    pub(crate) fn residual(&self, c: usize, x: &[f64]) -> Option<f64> {
        let s = self.sigma(c)?;
        let d = x[c] - self.nominal[c];
        Some(if self.circular[c] { wrap(d) } else { d } / s)
    }

    /// `Σ r_k²` at `x` over the columns `free`.
    pub(crate) fn cost(&self, free: &[usize], x: &[f64]) -> f64 {
        free.iter()
            .filter_map(|&c| self.residual(c, x))
            .map(|r| r * r)
            .sum()
    }
}

impl Term for PriorTerm {
    fn name(&self) -> &str {
        "prior"
    }

    fn role(&self) -> super::Role {
        super::Role::Prior
    }

    /// A row per free column with a tolerance.
    fn rows(&self, free: &[usize]) -> usize {
        free.iter().filter(|&&c| self.sigma(c).is_some()).count()
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let p = normal.free.len();
        let mut cost = 0.0;
        for (a, &c) in normal.free.iter().enumerate() {
            if let (Some(r), Some(s)) = (self.residual(c, at.x), self.sigma(c)) {
                normal.jtj[a * p + a] += 1.0 / (s * s);
                normal.jtr[a] += r / s;
                cost += r * r;
            }
        }
        Ok(cost)
    }

    /// Its sum, added to the data's at once (the order every fit's cost
    /// has always had: data, then prior).
    fn add_cost(
        &self,
        at: &At<'_>,
        free: &[usize],
        _shared: &mut Shared,
        _scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        *total += self.cost(free, at.x);
        Ok(())
    }
}
