//! The fixed set: which columns a calibration fits — the identifiability
//! analysis behind the automatic fixed set, or the user's fixed set checked
//! against what the data see; the weak directions held at nominal; the
//! corrections beyond geometry the data cannot separate; the tolerances
//! carried onto the free partners of redundant parameters.

use super::{CalibrationError, FixSpec, ModelOptions, Phase, assess, prior};
use crate::dataset::DataSet;
use crate::error::OptionError;
use crate::identify::{Identification, identify_from, open_directions_from};
use crate::objective::Objective;
use crate::params::{DhParams, ParamId};
use crate::residuals::{Elimination, Layout, Normal};
use crate::setting::Setting;

/// What the fixed set's stage leaves for the solver and the assessment.
pub(super) struct Settled {
    /// The columns fitted.
    pub(super) free: Vec<usize>,
    pub(super) identification: Option<Identification>,
    /// Why each fixed parameter is fixed.
    pub(super) reasons: Vec<(ParamId, String)>,
    /// Auxiliary columns held at their start, with why.
    pub(super) held: Vec<(usize, String)>,
    /// Tolerances carried onto free partners of redundant parameters.
    pub(super) carried: Vec<prior::CarriedTolerance>,
    /// The weak directions held at nominal, if any.
    pub(super) holds: Option<crate::residuals::HoldTerm>,
    pub(super) counts: assess::Counts,
    /// Whether every data term states its noise (else σ is estimated).
    pub(super) stated: bool,
    /// The normal equations at the start over `free`, prior included: the
    /// solver's first step.
    pub(super) start_normal: Normal,
    /// This stage's work.
    pub(super) phase: Phase,
}

/// The fixed set's stage at `x0`: one pass over the data (every column)
/// serves the identifiability analysis and, restricted to the free
/// columns, the solver's first step; then the corrections the data cannot
/// separate and the held blocks are taken out, and the prior completed
/// (tolerances carried, weak directions held). Refuses a fit with nothing
/// free, or with no more residuals than unknowns.
pub(super) fn settle_fixed_set(
    objective: &mut Objective<'_>,
    layout: &Layout,
    x0: &[f64],
    model: &ModelOptions,
    data: &DataSet,
) -> Result<Settled, CalibrationError> {
    let start = layout.geometry();
    let timer = std::time::Instant::now();
    let all: Vec<usize> = (0..layout.len()).collect();
    let full = objective.normal_of(x0, &all, |t| !t.is_prior())?;
    let FixedSet {
        free,
        identification,
        reasons,
        holds,
    } = fixed_set(start, objective, model, &full, data)?;
    let (mut free, mut held) = correction_columns(&full, layout, free)?;
    hold_blocks(layout, &mut free, &mut held);
    let (carried, holds) = complete_prior(objective, identification.as_ref(), holds, start, x0);
    if free.is_empty() {
        return Err(OptionError::new(
            Setting::Fix,
            model.fix.describe_for(start),
            "every parameter is fixed: nothing is left to calibrate",
        )
        .into());
    }
    // The fixed set is the data's own (see [`prior`]); the prior joins
    // every fit from here on.
    let counts = assess::Counts::of(objective, &free);
    let stated = objective.stated();
    if counts.residuals() <= counts.unknowns() {
        return Err(CalibrationError::TooFewResiduals {
            residuals: counts.residuals(),
            unknowns: counts.unknowns(),
            free: free.len(),
        });
    }
    let phase = Phase {
        jacobian_evaluations: 1,
        seconds: timer.elapsed().as_secs_f64(),
        ..Phase::new("identify")
    };
    let mut start_normal = full.restrict(&free).ok_or(CalibrationError::Shape)?;
    objective.add_terms(&mut start_normal, x0, |t| t.is_prior())?;
    Ok(Settled {
        free,
        identification,
        reasons,
        held,
        carried,
        holds,
        counts,
        stated,
        start_normal,
        phase,
    })
}

/// The free columns, the identifiability analysis behind them (`fix =
/// auto`), why each fixed parameter is fixed and the weak directions to
/// hold; a user's fixed set that leaves a direction the data (and the
/// tolerances) cannot see is refused.
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn fixed_set(
    start: &DhParams,
    objective: &Objective<'_>,
    model: &ModelOptions,
    full: &Normal,
    data: &DataSet,
) -> Result<FixedSet, CalibrationError> {
    let layout = objective.layout();
    let geometry = layout.geometry_columns();
    // Every auxiliary column is free: the geometry is analysed with them
    // fitted too (their elimination, as the centres' is).
    let aux: Vec<usize> = (geometry..layout.len()).collect();
    let full = full.geometry_only(layout).map_err(|e| match e {
        Elimination::Shape => CalibrationError::Shape,
        Elimination::Undetermined(_) => CalibrationError::Unidentifiable {
            directions: vec![e.to_string()],
        },
    })?;
    let sees = objective.sees();
    let mut holds = Vec::new();
    let (mut free, identification, reasons) = match &model.fix {
        FixSpec::Auto => {
            let id = identify_from(start, sees, full.clone(), data);
            let free = id.free_columns();
            let reasons: Vec<(ParamId, String)> =
                id.fixed.iter().map(|f| (f.id, f.reason.clone())).collect();
            holds = weak_untoleranced(start, full, &free, model, &id);
            (free, Some(id), reasons)
        }
        FixSpec::Columns(fixed) => {
            let free: Vec<usize> = (0..start.param_count())
                .filter(|c| !fixed.contains(c))
                .collect();
            let unknown = untoleranced(start, model, &free);
            let directions = open_directions_from(start, sees, full, &unknown);
            if !directions.is_empty() {
                return Err(CalibrationError::Unidentifiable { directions });
            }
            let reasons = fixed
                .iter()
                .filter_map(|&c| start.param_id(c))
                .map(|id| (id, "fixed by the user".to_string()))
                .collect();
            (free, None, reasons)
        }
    };
    free.extend(aux);
    Ok(FixedSet {
        free,
        identification,
        reasons,
        holds,
    })
}

/// Takes the columns of the blocks the layout holds ([`Layout::hold`]) out
/// of `free`, each with why in `held`.
///
/// [`Layout::hold`]: crate::residuals::Layout::hold
pub(super) fn hold_blocks(
    layout: &crate::residuals::Layout,
    free: &mut Vec<usize>,
    held: &mut Vec<(usize, String)>,
) {
    for c in layout.held_columns() {
        if let Some(at) = free.iter().position(|&f| f == c) {
            free.remove(at);
            held.push((
                c,
                "held at its start: the problem holds its block".to_string(),
            ));
        }
    }
}

/// What the automatic fixed set adds to the prior: the tolerances of the
/// redundant fixed parameters carried onto their free partners, and the
/// weak directions `holds` held at `x0` (as a term of the objective).
#[inline(never)] // a stage of its own in profiles (README, "Measured speed")
pub(super) fn complete_prior(
    objective: &mut Objective<'_>,
    identification: Option<&Identification>,
    holds: Vec<crate::residuals::Hold>,
    start: &DhParams,
    x0: &[f64],
) -> (
    Vec<prior::CarriedTolerance>,
    Option<crate::residuals::HoldTerm>,
) {
    let Some(id) = identification else {
        return (Vec::new(), None);
    };
    let carried = prior::carry_redundant(objective, id, start);
    let s_max = id.analysed_singular_values.first().copied().unwrap_or(0.0);
    let holds = (!holds.is_empty()).then(|| crate::residuals::HoldTerm::new(holds, x0, s_max));
    if let Some(h) = &holds {
        objective.push_term(Box::new(h.clone()));
    }
    (carried, holds)
}

/// The free columns, the identifiability analysis behind them (`fix =
/// auto`), why each fixed parameter is fixed, and the weak directions held
/// at nominal.
pub(super) struct FixedSet {
    pub(super) free: Vec<usize>,
    pub(super) identification: Option<Identification>,
    pub(super) reasons: Vec<(ParamId, String)>,
    pub(super) holds: Vec<crate::residuals::Hold>,
}

/// The weak directions among the free parameters that no tolerance covers
/// (a parameter with a tolerance is determined by it, as in the user's
/// fixed set): with them free, noise and model error would move the arm
/// along them by tens of millimetres, so they are held at nominal
/// ([`crate::residuals::HoldTerm`]).
fn weak_untoleranced(
    start: &DhParams,
    full: Normal,
    free: &[usize],
    model: &ModelOptions,
    id: &Identification,
) -> Vec<crate::residuals::Hold> {
    let s_max = id.analysed_singular_values.first().copied().unwrap_or(0.0);
    crate::identify::weak_holds(start, full, &untoleranced(start, model, free), s_max)
}

/// The columns of `free` without a stated tolerance. A tolerance
/// determines its parameter as a fixed value would (the prior sees every
/// direction that moves it): only directions among these are open.
fn untoleranced(start: &DhParams, model: &ModelOptions, free: &[usize]) -> Vec<usize> {
    let sigmas = model.prior.as_ref().map(|t| t.sigmas_for(start));
    free.iter()
        .copied()
        .filter(|&c| sigmas.as_ref().is_none_or(|s| s[c].is_none()))
        .collect()
}

/// A correction column whose information, once the free geometry, the
/// frames and the corrections accepted before it are fitted, is below this
/// share of its own is held at its stated value: its effect is (to one part
/// in 10⁶ of its variance) what the others already do, and fitting it
/// would only trade it against them.
pub(crate) const CORRECTION_SEPARATION: f64 = 1e-6;

/// The free columns with the correction columns beyond geometry judged one
/// at a time, in the block's order, against the `free` geometry, the frames
/// and the corrections kept before: kept when the data separate it
/// ([`CORRECTION_SEPARATION`]), else held with why (by column).
#[allow(clippy::type_complexity)] // the free columns and the held ones
pub(crate) fn correction_columns(
    full: &Normal,
    layout: &Layout,
    free: Vec<usize>,
) -> Result<(Vec<usize>, Vec<(usize, String)>), CalibrationError> {
    let Some((_, corrections)) = layout.corrections() else {
        return Ok((free, Vec::new()));
    };
    let mut base: Vec<usize> = free
        .iter()
        .copied()
        .filter(|c| !corrections.contains(c))
        .collect();
    let judged = judge_corrections(full, &mut base, corrections)?;
    let name = |c: usize| layout.parameter(c).map_or(String::new(), |p| p.name);
    let held = (judged.into_iter())
        .filter_map(|j| match j.share {
            None => Some((
                j.column,
                "moves no residual: these data do not see it".to_string(),
            )),
            Some(share) if share < CORRECTION_SEPARATION => {
                let like = (j.like)
                    .map(|(a, cos)| format!(" (most like {}: cos {cos:+.4})", name(a)))
                    .unwrap_or_default();
                Some((
                    j.column,
                    format!(
                        "not separable from the fitted parameters by these data: {:.1e} of \
                         its information is its own{like}",
                        share.max(0.0)
                    ),
                ))
            }
            Some(_) => None,
        })
        .collect();
    base.sort_unstable();
    Ok((base, held))
}

/// One correction column as [`judge_corrections`] found it.
#[derive(Debug)]
struct Judged {
    column: usize,
    /// Its information's own share; `None`: it moves nothing.
    share: Option<f64>,
    /// The column kept before it that it is most like, with their cosine.
    like: Option<(usize, f64)>,
}

/// Each column of `corrections` judged in order against `base` (the free
/// columns beside them), each kept one pushed onto `base`.
///
/// The kept columns' block of the normal matrix is scaled once, grown by
/// each kept column and factored once per growth: every candidate is
/// judged against the same factor of the same matrix as a restricted,
/// scaled and factored copy per candidate gave (the same bits, tested),
/// without that copy, its square root per entry and its factor.
fn judge_corrections(
    full: &Normal,
    base: &mut Vec<usize>,
    corrections: std::ops::Range<usize>,
) -> Result<Vec<Judged>, CalibrationError> {
    let p = full.free.len();
    let index = |c: usize| (full.free.iter().position(|f| *f == c)).ok_or(CalibrationError::Shape);
    // Entry (a, b) of the normal matrix scaled to a unit diagonal, from its
    // rows `a` and `b` and their diagonal entries.
    let scaled = |(a, da): (usize, f64), (b, db): (usize, f64)| {
        let d = (da * db).sqrt();
        if d > 0.0 {
            full.jtj[a * p + b] / d
        } else {
            0.0
        }
    };
    let mut judged = Vec::with_capacity(corrections.len());
    if corrections.is_empty() {
        return Ok(judged);
    }
    // The kept columns: their rows in `full` with their diagonal entries.
    let mut kept: Vec<(usize, f64)> = (base.iter())
        .map(|&c| index(c).map(|a| (a, full.jtj[a * p + a])))
        .collect::<Result<_, _>>()?;
    let mut bb =
        nalgebra::DMatrix::from_fn(kept.len(), kept.len(), |i, j| scaled(kept[i], kept[j]));
    let mut factor = None;
    for column in corrections {
        let a = index(column)?;
        let col = (a, full.jtj[a * p + a]);
        // Round-off of a column that is nil (a joint's turn that moves no
        // probe) is not information: judged against the largest column.
        let largest = (kept.iter().map(|k| k.1))
            .chain([col.1])
            .fold(0.0, f64::max);
        if !(col.1 > 1e-20 * largest && col.1.is_finite()) {
            judged.push(Judged {
                column,
                share: None,
                like: None,
            });
            continue;
        }
        let k = kept.len() + 1;
        let bc = nalgebra::DMatrix::from_fn(k - 1, 1, |i, _| scaled(kept[i], col));
        let share = match factor.get_or_insert_with(|| bb.clone().cholesky()) {
            Some(ch) => 1.0 - (bc.transpose() * ch.solve(&bc))[(0, 0)],
            None => 0.0,
        };
        // The column it is most like, by the cosine of their columns.
        let like = (0..k - 1)
            .max_by(|&a, &b| bc[(a, 0)].abs().total_cmp(&bc[(b, 0)].abs()))
            .map(|a| (base[a], bc[(a, 0)]));
        judged.push(Judged {
            column,
            share: Some(share),
            like,
        });
        if share >= CORRECTION_SEPARATION {
            bb = bb.resize(k, k, 0.0);
            for i in 0..k - 1 {
                bb[(i, k - 1)] = bc[(i, 0)];
                bb[(k - 1, i)] = scaled(col, kept[i]);
            }
            bb[(k - 1, k - 1)] = scaled(col, col);
            factor = None;
            kept.push(col);
            base.push(column);
        }
    }
    Ok(judged)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corrections::{Beyond, Physics};
    use crate::residuals::CorrectionBlock;

    /// The judgement as it was: each candidate against a restricted copy of
    /// the normal matrix, scaled and factored afresh. The reference the
    /// grown, once-factored block must match bit for bit. Per candidate:
    /// its share (`None`: moves nothing) and the column it is most like.
    #[allow(clippy::type_complexity)]
    fn one_at_a_time(
        full: &Normal,
        corrections: std::ops::Range<usize>,
        base: &mut Vec<usize>,
    ) -> Vec<(usize, Option<u64>, Option<(usize, u64)>)> {
        let mut out = Vec::new();
        for c in corrections {
            let cols: Vec<usize> = base.iter().copied().chain([c]).collect();
            let n = full.restrict(&cols).unwrap();
            let k = cols.len();
            let m = nalgebra::DMatrix::from_row_slice(k, k, &n.jtj);
            let diag: Vec<f64> = (0..k).map(|i| m[(i, i)]).collect();
            let largest = diag.iter().copied().fold(0.0, f64::max);
            if !(diag[k - 1] > 1e-20 * largest && diag[k - 1].is_finite()) {
                out.push((c, None, None));
                continue;
            }
            let s = nalgebra::DMatrix::from_fn(k, k, |i, j| {
                let d = (diag[i] * diag[j]).sqrt();
                if d > 0.0 { m[(i, j)] / d } else { 0.0 }
            });
            let bb = s.view((0, 0), (k - 1, k - 1)).into_owned();
            let bc = s.view((0, k - 1), (k - 1, 1)).into_owned();
            let share = match bb.cholesky() {
                Some(ch) => 1.0 - (bc.transpose() * ch.solve(&bc))[(0, 0)],
                None => 0.0,
            };
            let like = (0..k - 1)
                .max_by(|&a, &b| bc[(a, 0)].abs().total_cmp(&bc[(b, 0)].abs()))
                .map(|a| (cols[a], bc[(a, 0)].to_bits()));
            out.push((c, Some(share.to_bits()), like));
            if share >= CORRECTION_SEPARATION {
                base.push(c);
            }
        }
        out
    }

    /// A normal matrix of correlated columns where some corrections repeat
    /// geometry columns (exactly or nearly) and one moves nothing, with a
    /// geometry column fixed: every candidate's share and likeness are the
    /// bits of a fresh copy's, and some are kept, some held for each cause.
    #[test]
    fn the_grown_block_judges_with_a_fresh_copys_bits() {
        let mut layout = Layout::new(DhParams::paper_nominal());
        let fit = Beyond {
            harmonics: vec![(0, 1), (1, 1), (2, 2), (3, 1), (4, 1)],
            ..Default::default()
        };
        layout
            .add_corrections(CorrectionBlock {
                fit,
                physics: Physics::default(),
                joints: 6,
                prismatic: 0,
            })
            .unwrap();
        let (_, corrections) = layout.corrections().unwrap();
        let p = layout.len();
        assert!(corrections.len() >= 8, "{corrections:?}");
        let first = corrections.start;
        let value =
            |r: usize, c: usize| (((r + 1) * (c + 3)) as f64 * 0.7137 + (c * c) as f64).sin();
        let column = |c: usize, r: usize| match c.wrapping_sub(first) {
            0 => 0.0,
            2 => value(r, first + 7),
            4 => value(r, first + 9) * 3.0 + 1e-9 * value(r, c),
            _ => value(r, c),
        };
        let all: Vec<usize> = (0..p).collect();
        let mut full = Normal::new(&all);
        for a in 0..p {
            for b in 0..p {
                full.jtj[a * p + b] = (0..3 * p).map(|r| column(a, r) * column(b, r)).sum();
            }
        }
        let free: Vec<usize> = all.iter().copied().filter(|&c| c != 5).collect();
        let start: Vec<usize> = (free.iter().copied())
            .filter(|c| !corrections.contains(c))
            .collect();
        let (mut grown, mut fresh) = (start.clone(), start);
        let judged = judge_corrections(&full, &mut grown, corrections.clone()).unwrap();
        let want = one_at_a_time(&full, corrections.clone(), &mut fresh);
        assert_eq!(grown, fresh);
        let got: Vec<_> = (judged.iter())
            .map(|j| {
                let like = j.like.map(|(a, cos)| (a, cos.to_bits()));
                (j.column, j.share.map(f64::to_bits), like)
            })
            .collect();
        assert_eq!(got, want);
        let (kept, held) = correction_columns(&full, &layout, free).unwrap();
        let nil = held.iter().filter(|h| h.1.contains("moves no residual"));
        let alike = held.iter().filter(|h| h.1.contains("not separable"));
        assert_eq!((nil.count(), alike.count()), (1, 2), "{held:?}");
        assert!(kept.iter().any(|c| corrections.contains(c)), "{kept:?}");
        assert!(!kept.contains(&5));
    }
}
