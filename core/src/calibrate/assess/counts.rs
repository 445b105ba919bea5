//! How many residuals and unknowns each term brings: the degrees of
//! freedom, and the unit-σ terms' share of them.

use crate::calibrate::{Dof, TermRows};
use crate::objective::Objective;
use crate::residuals::Role;

/// One term's share of the residuals and unknowns.
#[derive(Clone, Debug)]
struct TermCount {
    name: String,
    role: Role,
    rows: usize,
    eliminated: usize,
    /// Its weights are in units of an estimated σ.
    unit: bool,
    /// It has observations a robust loss weighs.
    observed: bool,
}

/// Residual rows and unknowns of a fit, per term.
#[derive(Clone, Debug)]
pub(crate) struct Counts {
    terms: Vec<TermCount>,
    free: usize,
}

impl Counts {
    /// The counts of `objective`'s terms over the columns `free`.
    pub(crate) fn of(objective: &Objective<'_>, free: &[usize]) -> Counts {
        Counts {
            terms: objective
                .terms()
                .map(|t| TermCount {
                    name: t.name().to_string(),
                    role: t.role(),
                    rows: t.rows(free),
                    eliminated: t.eliminated(),
                    unit: t.unit_weighted(),
                    observed: t.observations() > 0,
                })
                .collect(),
            free: free.len(),
        }
    }

    /// Residual rows: every term's (the prior's pseudo-observations too).
    pub(crate) fn residuals(&self) -> usize {
        self.terms.iter().map(|t| t.rows).sum()
    }

    /// The free columns and every unknown eliminated inside the terms.
    pub(crate) fn unknowns(&self) -> usize {
        self.free + self.eliminated()
    }

    fn eliminated(&self) -> usize {
        self.terms.iter().map(|t| t.eliminated).sum()
    }

    /// `m − p` (at least 1 once [`crate::calibrate::calibrate_with`] checked it).
    pub(crate) fn dof(&self) -> usize {
        self.residuals().saturating_sub(self.unknowns()).max(1)
    }

    /// The rows of the terms of role `role`.
    fn rows_of(&self, role: Role) -> usize {
        self.terms
            .iter()
            .filter(|t| t.role == role)
            .map(|t| t.rows)
            .sum()
    }

    /// Rows and eliminated unknowns of the terms `which` accepts.
    fn sum(&self, which: impl Fn(&TermCount) -> bool) -> (usize, usize) {
        self.terms
            .iter()
            .filter(|t| which(t))
            .fold((0, 0), |(r, e), t| (r + t.rows, e + t.eliminated))
    }

    /// The unit-weighted terms' own degrees of freedom, for a σ estimated
    /// from their residuals.
    pub(super) fn unit_dof(&self) -> usize {
        let (rows, eliminated) = self.sum(|t| t.unit);
        rows.saturating_sub(eliminated + self.free).max(1)
    }

    /// `(e_o + p) / m_o` over the observed terms (rows `m_o`, eliminated
    /// unknowns `e_o`): the unknowns per residual row, Huber's `p/n` of
    /// the robust covariance's small-sample factor ([`crate::calibrate::robust`]).
    pub(super) fn unknowns_per_row(&self) -> f64 {
        let (rows, eliminated) = self.sum(|t| t.observed);
        ((eliminated + self.free) as f64 / rows.max(1) as f64).min(1.0)
    }

    /// Whether every term's weights are in units of the estimated σ: the
    /// normal equations can then be rescaled by it instead of reweighed.
    pub(super) fn all_unit(&self) -> bool {
        self.terms.iter().all(|t| t.unit)
    }

    /// The counts as reported, with the variance factor `sigma0` and the
    /// touch σ `unit_sigma` (from the stated noise when `stated`).
    pub(super) fn report(&self, sigma0: f64, unit_sigma: f64, stated: bool) -> Dof {
        Dof {
            touch_rows: self.rows_of(Role::Touches),
            length_rows: self.rows_of(Role::Lengths),
            free_parameters: self.free,
            centre_coordinates: self.eliminated(),
            degrees_of_freedom: self.dof(),
            sigma0,
            touch_sigma_mm: unit_sigma,
            touch_sigma_estimated: !stated,
            prior_rows: self.rows_of(Role::Prior),
            other_rows: self.other_rows(),
        }
    }

    /// The rows of the terms that are neither touches, lengths nor the
    /// prior (by role), by name.
    fn other_rows(&self) -> Vec<TermRows> {
        self.terms
            .iter()
            .filter(|t| ![Role::Touches, Role::Lengths, Role::Prior].contains(&t.role))
            .map(|t| TermRows {
                term: t.name.clone(),
                rows: t.rows,
                eliminated: t.eliminated,
            })
            .collect()
    }
}
