//! The objective every fit minimises: the residual terms, at fixed weights,
//! on the layout's columns — the least squares a solver (the library's or
//! a third party's) evaluates.
//!
//! A point is a vector `x` of every column (the geometry's first, in the
//! paper's order, then each auxiliary block's: [`Layout`]). The objective
//! gives the cost at `x` (positions only, what a trial step needs), the
//! normal equations over the free columns (`JᵀJ`, `Jᵀr`, each term's cost),
//! and the local update `x ⊞ δ`; it weighs its terms at an arm (the noise
//! carried through it) and says how far their weights would move. The
//! terms are evaluated in order — the data's (touches first: the others may
//! measure between their point centres), then the prior — and their sums
//! are added in that order, so the same inputs give the same bits on any
//! thread count.

pub(crate) mod check;

pub use check::{CheckOptions, GradientCheck, check_gradients};

use crate::dataset::DataSet;
use crate::kernel::ArmKernel;
use crate::residuals::{
    At, Layout, LengthTerm, Noise, Normal, OrientationTerm, Origin, PositionTerm, PriorTerm, Sees,
    Shared, Term, TermError, TouchTerm,
};
use crate::tolerances::Tolerances;

/// Every observation's standardised squared residual and its row count,
/// in [`Objective::observations`]' order: a `k`-row observation's value is
/// about `χ²_k` when it fits the noise model, so the robust loss weighs it
/// on its `k`-dimensional norm and the outlier test holds it against the
/// `χ²_k` quantile.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Observed {
    /// Per observation, `rᵀ A r / (1 − h)`.
    pub values: Vec<f64>,
    /// Per observation, its rows `k` ([`Observed::rows`]).
    pub(crate) rows: RowCounts,
}

/// Each observation's rows, in runs of one count (a term's observations
/// share theirs): a million touches' threes are one run, not 8 MB.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct RowCounts {
    /// (observations, rows each), in order.
    runs: Vec<(usize, usize)>,
}

impl RowCounts {
    /// Appends `n` observations of `k` rows each.
    fn push(&mut self, n: usize, k: usize) {
        match self.runs.last_mut() {
            Some((m, last)) if *last == k => *m += n,
            _ if n > 0 => self.runs.push((n, k)),
            _ => {}
        }
    }

    /// Observations.
    pub(crate) fn len(&self) -> usize {
        self.runs.iter().map(|&(n, _)| n).sum()
    }

    /// Each observation's rows, in order.
    pub(crate) fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        (self.runs.iter()).flat_map(|&(n, k)| std::iter::repeat_n(k, n))
    }

    /// The first observation's rows.
    pub(crate) fn first(&self) -> Option<usize> {
        self.runs.first().map(|&(_, k)| k)
    }
}

impl Observed {
    /// Per observation, its rows `k` (3 for a touch, 1 for a distance, 6
    /// for a pose), in [`Objective::observations`]' order.
    pub fn rows(&self) -> impl Iterator<Item = usize> + '_ {
        self.rows.iter()
    }

    /// Each value in the units of a three-row observation's law: times
    /// `m₃/m_k` (`m_k` the median of `χ²_k`; exactly 1 for three rows), so
    /// that one median serves observations of any row count.
    pub(crate) fn as_three_rows(&self) -> Vec<f64> {
        let mut factor: Vec<f64> = Vec::new();
        (self.values.iter().zip(self.rows.iter()))
            .map(|(&v, k)| {
                if k == 3 {
                    return v;
                }
                if factor.len() <= k {
                    factor.resize(k + 1, f64::NAN);
                }
                if factor[k].is_nan() {
                    factor[k] = crate::stats::CHI2_3_MEDIAN / crate::stats::chi_square_median(k);
                }
                v * factor[k]
            })
            .collect()
    }
}

/// The terms of a calibration on the columns of a layout, with the worker
/// threads their sums may use.
#[derive(Clone, Debug)]
pub struct Objective<'a> {
    layout: Layout,
    terms: Vec<Box<dyn Term + 'a>>,
    /// The prior of the stated tolerances, for its report, and its index
    /// among the terms (the one [`Objective::set_prior`] replaces).
    prior: Option<(PriorTerm, usize)>,
    threads: usize,
}

impl<'a> Objective<'a> {
    /// `terms` on the columns of `layout`, their sums on up to `threads`
    /// threads (results do not depend on it). The terms are not weighed
    /// yet: see [`Objective::weigh`].
    pub fn new(layout: Layout, terms: Vec<Box<dyn Term + 'a>>, threads: usize) -> Objective<'a> {
        Objective {
            layout,
            terms,
            prior: None,
            threads: threads.max(1),
        }
    }

    /// The data's built-in terms: `data`'s touches and its reference
    /// lengths if it has any, its reference positions if it has any (on
    /// the layout's frame blocks: [`crate::residuals::positions::layout_for`]),
    /// under `noise`; then `extra` terms; then the
    /// prior of `tolerances` and of the layout's blocks, if any applies.
    /// Weighed at the layout's start, touches as `unit_sigma` mm when no
    /// touch noise is stated.
    ///
    /// # Errors
    ///
    /// The kernel's, and noise that makes weights that are not finite.
    pub(crate) fn of_data(
        layout: Layout,
        data: &'a DataSet,
        noise: &Noise,
        extra: Vec<Box<dyn Term + 'a>>,
        tolerances: Option<&Tolerances>,
        unit_sigma: f64,
        threads: usize,
    ) -> Result<Objective<'a>, TermError> {
        let mut terms: Vec<Box<dyn Term + 'a>> = Vec::new();
        if !data.is_empty() {
            terms.push(Box::new(TouchTerm::new(data, *noise)));
        }
        if !data.references().is_empty() {
            terms.push(Box::new(LengthTerm::new(data, *noise)));
        }
        if let Some(positions) = data.positions() {
            terms.push(Box::new(PositionTerm::new(positions, &layout, noise)?));
            if let Some(o) = OrientationTerm::new(positions, &layout, noise)? {
                terms.push(Box::new(o));
            }
        }
        terms.extend(extra);
        let start = layout.start();
        let prior = PriorTerm::new(tolerances, &layout, &start).map(|prior| {
            terms.push(Box::new(prior.clone()));
            (prior, terms.len() - 1)
        });
        let mut objective = Objective::new(layout, terms, threads);
        objective.prior = prior;
        objective.weigh(&start, unit_sigma)?;
        Ok(objective)
    }

    /// The columns.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The terms, in the order they are evaluated.
    pub(crate) fn terms(&self) -> impl Iterator<Item = &(dyn Term + 'a)> {
        self.terms.iter().map(|t| &**t)
    }

    /// Whether stated tolerances (or an auxiliary block's) apply: a prior
    /// that weighs against the data. (Held weak directions are not one:
    /// they are stiff, whatever the data's weights.)
    pub(crate) fn has_prior(&self) -> bool {
        self.prior.is_some()
    }

    /// Replaces the prior of the stated tolerances by `prior` (the same
    /// columns, other tolerances): the term this objective put in for
    /// them, never another (an outside term of any name or role stays).
    /// Without one, nothing changes.
    pub(crate) fn set_prior(&mut self, prior: PriorTerm) {
        if let Some((old, at)) = &mut self.prior {
            self.terms[*at] = Box::new(prior.clone());
            *old = prior;
        }
    }

    /// Adds `term` after the others (a fit's held directions).
    pub(crate) fn push_term(&mut self, term: Box<dyn Term + 'a>) {
        self.terms.push(term);
    }

    /// The prior of the stated tolerances, if any applies.
    pub(crate) fn prior(&self) -> Option<&PriorTerm> {
        self.prior.as_ref().map(|(p, _)| p)
    }

    /// Every column's start value.
    pub(crate) fn start(&self) -> Vec<f64> {
        self.layout.start()
    }

    /// `x` moved by `delta` over the columns `free` (each block's local
    /// update).
    pub fn plus(&self, x: &[f64], free: &[usize], delta: &[f64]) -> Vec<f64> {
        self.layout.plus(x, free, delta)
    }

    /// What the data's terms let the identifiability rules assume.
    pub(crate) fn sees(&self) -> Sees {
        self.terms
            .iter()
            .filter(|t| !t.is_prior())
            .fold(Sees::default(), |s, t| {
                let t = t.sees();
                Sees {
                    base_rotation: s.base_rotation || t.base_rotation,
                    base_slide: s.base_slide || t.base_slide,
                    scale: s.scale || t.scale,
                }
            })
    }

    /// Whether every term with data states its noise (none is weighed by a
    /// σ the fit estimates): the χ² test applies, and the covariance is not
    /// rescaled by σ̂.
    pub(crate) fn stated(&self) -> bool {
        let data: Vec<_> = self
            .terms
            .iter()
            .filter(|t| !t.is_prior() && t.rows(&[]) > 0)
            .collect();
        !data.is_empty() && data.iter().all(|t| !t.unit_weighted())
    }

    /// Evaluates `f` with the point `x` prepared: its arm and kernel.
    fn at<R>(
        &self,
        x: &[f64],
        f: impl FnOnce(&At<'_>) -> Result<R, TermError>,
    ) -> Result<R, TermError> {
        let arm = self.layout.arm(x).ok_or_else(|| {
            TermError::invalid(
                "objective",
                "a point of the wrong length (a bug, not input)",
            )
        })?;
        let kernel = ArmKernel::new(&arm)?;
        f(&At {
            x,
            arm: &arm,
            kernel: &kernel,
            layout: &self.layout,
            threads: self.threads,
        })
    }

    /// Weighs every term at `x` (the touches as `unit_sigma` mm when their
    /// noise is not stated), in place.
    ///
    /// # Errors
    ///
    /// The kernel's, and weights that are not finite numbers.
    pub fn weigh(&mut self, x: &[f64], unit_sigma: f64) -> Result<(), TermError> {
        let layout = &self.layout;
        let threads = self.threads;
        let arm = layout.arm(x).ok_or_else(|| {
            TermError::invalid(
                "objective",
                "a point of the wrong length (a bug, not input)",
            )
        })?;
        let kernel = ArmKernel::new(&arm)?;
        let at = At {
            x,
            arm: &arm,
            kernel: &kernel,
            layout,
            threads,
        };
        let mut shared = Shared::default();
        for term in &mut self.terms {
            term.weigh(&at, &mut shared, unit_sigma)?;
        }
        Ok(())
    }

    /// Observations a robust loss may downweight, over every term that has
    /// them (in term order).
    pub fn observations(&self) -> usize {
        self.terms.iter().map(|t| t.observations()).sum()
    }

    /// The terms that have observations, with the first observation of
    /// each in [`Objective::observations`]' numbering.
    fn observing(&self) -> impl Iterator<Item = (usize, &(dyn Term + 'a))> {
        let mut first = 0;
        self.terms
            .iter()
            .filter(|t| t.observations() > 0)
            .map(move |t| {
                let at = first;
                first += t.observations();
                (at, &**t)
            })
    }

    /// The threads its sums may use.
    pub(crate) fn threads(&self) -> usize {
        self.threads
    }

    /// Every observation's standardised squared residual at `x` (each
    /// about `χ²_k` when it fits the noise model, `k` its rows: 3 for a
    /// touch, 1 for a distance, 6 for a pose), in
    /// [`Objective::observations`]' order; with `leverage` (the inverse of
    /// the normal matrix at these weights), corrected for the free
    /// parameters' share of each observation's leverage as well as for its
    /// eliminated unknowns' (a touch's point).
    ///
    /// # Errors
    ///
    /// The kernel's, and a term whose standardised residuals do not match
    /// its observations (their count, or no row).
    pub fn standardised(
        &self,
        x: &[f64],
        leverage: Option<&crate::residuals::ParameterLeverage>,
    ) -> Result<Observed, TermError> {
        self.at(x, |at| {
            let mut out = Observed::default();
            for (_, term) in self.observing() {
                let Some(s) = term.standardised(at, leverage)? else {
                    continue;
                };
                if s.rows == 0 || s.values.len() != term.observations() {
                    return Err(TermError::invalid(
                        term.name(),
                        format!(
                            "{} standardised residuals of {} rows for {} observations: one \
                             per observation, of at least one row",
                            s.values.len(),
                            s.rows,
                            term.observations()
                        ),
                    ));
                }
                out.rows.push(s.values.len(), s.rows);
                if out.values.is_empty() {
                    // The first term's values as they are: no second copy
                    // of every touch's at the peak of memory.
                    out.values = s.values;
                } else {
                    out.values.extend(s.values);
                }
            }
            Ok(out)
        })
    }

    /// Where observation `i` came from.
    pub fn origin(&self, i: usize) -> Origin {
        self.observing()
            .take_while(|(first, _)| *first <= i)
            .last()
            .map_or_else(
                || Origin {
                    at: format!("observation {}", i + 1),
                    group: String::new(),
                },
                |(first, term)| term.origin(i - first),
            )
    }

    /// The term of observation `i` ([`Objective::observations`]' order).
    pub(crate) fn term_of(&self, i: usize) -> Option<&(dyn Term + 'a)> {
        let (first, term) = self
            .observing()
            .take_while(|(first, _)| *first <= i)
            .last()?;
        (i - first < term.observations()).then_some(term)
    }

    /// A copy whose observations' weights are multiplied by `w` (the robust
    /// fit's), the terms with observations taking theirs in order.
    pub(crate) fn with_observation_weights(&self, w: &[f64]) -> Objective<'a> {
        let mut copy = self.clone();
        let mut rest = w;
        for term in &mut copy.terms {
            let n = term.observations().min(rest.len());
            if n > 0 {
                term.weigh_observations(&rest[..n]);
                rest = &rest[n..];
            }
        }
        copy
    }

    /// A copy weighed at `x`.
    ///
    /// # Errors
    ///
    /// As [`Objective::weigh`].
    pub(crate) fn reweighed(&self, x: &[f64], unit_sigma: f64) -> Result<Objective<'a>, TermError> {
        let mut copy = self.clone();
        copy.weigh(x, unit_sigma)?;
        Ok(copy)
    }

    /// The largest relative change weighing at `x` would make to any term's
    /// weights, without keeping a second set; `∞` where a term would refuse
    /// the new weights (so that the caller weighs and reports why).
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub(crate) fn weight_change(&self, x: &[f64], unit_sigma: f64) -> Result<f64, TermError> {
        self.at(x, |at| {
            let mut shared = Shared::default();
            let mut change = 0.0_f64;
            for term in &self.terms {
                change = change.max(term.weight_change(at, &mut shared, unit_sigma)?);
            }
            Ok(change)
        })
    }

    /// The normal equations at `x` over the columns `free`, every term.
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub fn normal(&self, x: &[f64], free: &[usize]) -> Result<Normal, TermError> {
        self.normal_of(x, free, |_| true)
    }

    /// The normal equations at `x` over `free` of the terms `include`
    /// accepts; the others' costs are 0.
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub(crate) fn normal_of(
        &self,
        x: &[f64],
        free: &[usize],
        include: impl Fn(&dyn Term) -> bool,
    ) -> Result<Normal, TermError> {
        let mut normal = Normal::new(free);
        normal.costs = vec![0.0; self.terms.len()];
        self.add_terms(&mut normal, x, include)?;
        Ok(normal)
    }

    /// Adds the terms `include` accepts at `x` to `normal` (over its
    /// columns), each cost into its place.
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub(crate) fn add_terms(
        &self,
        normal: &mut Normal,
        x: &[f64],
        include: impl Fn(&dyn Term) -> bool,
    ) -> Result<(), TermError> {
        normal.costs.resize(self.terms.len(), 0.0);
        self.at(x, |at| {
            let mut shared = Shared {
                want_centre_jacobians: self
                    .terms
                    .iter()
                    .any(|t| include(&**t) && t.needs_centre_jacobians()),
                ..Shared::default()
            };
            for (k, term) in self.terms.iter().enumerate() {
                if include(&**term) {
                    normal.costs[k] = term.accumulate(at, &mut shared, normal)?;
                }
            }
            Ok(())
        })
    }

    /// The cost `Σ r²` at `x` over the columns `free` (a prior's rows are
    /// the free columns'), positions only; `+∞` when it is not finite, never
    /// NaN. `scratch` is a buffer kept between calls.
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub fn cost(
        &self,
        x: &[f64],
        free: &[usize],
        scratch: &mut Vec<[f64; 3]>,
    ) -> Result<f64, TermError> {
        self.cost_of(x, free, scratch, |_| true)
    }

    /// The data's cost at `x` (no prior), as [`Objective::cost`].
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub(crate) fn data_cost(
        &self,
        x: &[f64],
        scratch: &mut Vec<[f64; 3]>,
    ) -> Result<f64, TermError> {
        self.cost_of(x, &[], scratch, |t| !t.is_prior())
    }

    /// Each term's gradient `Jᵀr` over `free` (as its
    /// [`Term::accumulate`] writes it, on normal equations of its own) and
    /// its cost at `x`, in order; the terms pass what they share as in a
    /// fit.
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub(crate) fn term_gradients(
        &self,
        x: &[f64],
        free: &[usize],
    ) -> Result<Vec<(Vec<f64>, f64)>, TermError> {
        self.at(x, |at| {
            let mut shared = Shared {
                want_centre_jacobians: self.terms.iter().any(|t| t.needs_centre_jacobians()),
                ..Shared::default()
            };
            (self.terms.iter())
                .map(|term| {
                    let mut normal = Normal::new(free);
                    let cost = term.accumulate(at, &mut shared, &mut normal)?;
                    Ok((normal.jtr, cost))
                })
                .collect()
        })
    }

    /// Each term's cost at `x` over `free` ([`Term::add_cost`]), in order.
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub(crate) fn term_costs(&self, x: &[f64], free: &[usize]) -> Result<Vec<f64>, TermError> {
        let mut scratch = Vec::new();
        self.at(x, |at| {
            let mut shared = Shared::default();
            (self.terms.iter())
                .map(|term| {
                    let mut total = 0.0;
                    term.add_cost(at, free, &mut shared, &mut scratch, &mut total)?;
                    Ok(total)
                })
                .collect()
        })
    }

    fn cost_of(
        &self,
        x: &[f64],
        free: &[usize],
        scratch: &mut Vec<[f64; 3]>,
        include: impl Fn(&dyn Term) -> bool,
    ) -> Result<f64, TermError> {
        let total = self.at(x, |at| {
            let mut shared = Shared::default();
            let mut total = 0.0;
            for term in self.terms.iter().filter(|t| include(&***t)) {
                term.add_cost(at, free, &mut shared, scratch, &mut total)?;
            }
            Ok(total)
        })?;
        Ok(if total.is_finite() {
            total
        } else {
            f64::INFINITY
        })
    }
}

/// The weighted cost `Σ r²` of the arm `params` on `data`, with every
/// residual weighed from `noise` at the arm `weighed_at` (so that two arms
/// compare under the same weights). Without stated touch noise a touch
/// weighs as a 1 mm σ.
///
/// ```
/// use aacmm_core::{DhParams, objective::weighted_cost, residuals::Noise, simulate::*, Arm};
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let c = simulate(&nominal, &CampaignSettings::new(2, ErrorModel::Paper, 4, 6)).unwrap();
/// let data = c.data_set().unwrap();
/// let noise = Noise { probe_mm: Some(0.01), ..Noise::default() };
/// let truth = &c.true_arm.params;
/// let at_truth = weighted_cost(truth, truth, &data, &noise).unwrap();
/// let at_nominal = weighted_cost(&nominal.params, truth, &data, &noise).unwrap();
/// assert!(at_truth < at_nominal);
/// ```
///
/// # Errors
///
/// The kernel's, for an arm it cannot evaluate.
pub fn weighted_cost(
    params: &crate::params::DhParams,
    weighed_at: &crate::params::DhParams,
    data: &DataSet,
    noise: &Noise,
) -> Result<f64, TermError> {
    let layout = crate::residuals::positions::layout_for(weighed_at, data)?;
    let objective = Objective::of_data(layout, data, noise, Vec::new(), None, 1.0, 1)?;
    objective.data_cost(&params.to_vec(), &mut Vec::new())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::residuals::Role;

    /// An outside term that happens to be named `prior`.
    #[derive(Clone, Debug)]
    struct NamedPrior;

    impl Term for NamedPrior {
        fn name(&self) -> &str {
            "prior"
        }
        fn rows(&self, _free: &[usize]) -> usize {
            1
        }
        fn accumulate(&self, _: &At<'_>, _: &mut Shared, _: &mut Normal) -> Result<f64, TermError> {
            Ok(0.0)
        }
        fn add_cost(
            &self,
            _: &At<'_>,
            _: &[usize],
            _: &mut Shared,
            _: &mut Vec<[f64; 3]>,
            _: &mut f64,
        ) -> Result<(), TermError> {
            Ok(())
        }
    }

    #[test]
    fn set_prior_replaces_its_own_term_not_one_named_prior() {
        use crate::simulate::{CampaignSettings, ErrorModel, simulate};
        let nominal = crate::Arm::without_limits("n", crate::params::DhParams::paper_nominal());
        let c = simulate(&nominal, &CampaignSettings::new(2, ErrorModel::Paper, 4, 6)).unwrap();
        let data = c.data_set().unwrap();
        let layout = crate::residuals::positions::layout_for(&nominal.params, &data).unwrap();
        let tolerances = |s| Tolerances::parse(s, 6).unwrap().unwrap();
        let (few, more) = (
            tolerances("length=0.5mm"),
            tolerances("length=0.5mm,angle=0.1deg"),
        );
        let extra: Vec<Box<dyn Term>> = vec![Box::new(NamedPrior)];
        let noise = Noise::default();
        let mut objective =
            Objective::of_data(layout.clone(), &data, &noise, extra, Some(&few), 1.0, 1).unwrap();
        let free: Vec<usize> = (0..layout.len()).collect();
        let rows_of =
            |o: &Objective<'_>, role| o.terms().find(|t| t.role() == role).unwrap().rows(&free);
        let before = rows_of(&objective, Role::Prior);
        let wider = PriorTerm::new(Some(&more), &layout, &layout.start()).unwrap();
        let wider_rows = wider.rows(&free);
        assert!(wider_rows > before);
        objective.set_prior(wider);
        assert_eq!(rows_of(&objective, Role::Prior), wider_rows);
        assert_eq!(rows_of(&objective, Role::Other), 1);
        let other = objective.terms().find(|t| t.role() == Role::Other).unwrap();
        assert_eq!(other.name(), "prior");
        assert_eq!(objective.terms().filter(|t| t.name() == "prior").count(), 2);
    }
}
