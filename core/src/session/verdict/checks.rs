//! The checks that decide a verdict: the reasons against a calibration and
//! the notes beside it, each from the figures it carries.

use crate::calibrate::checks::{ChiSquareVerdict, GrossCorrection, Outlier};
use crate::residuals::Noise;
use crate::session::{BeforeAfter, Calibration, Problem, noun, outliers_noun};

use super::{Note, Reason, StatedNoise, UnconfirmedSearch, Verdict};

impl Note {
    /// Without a reference length the size of the arm is the nominal's:
    /// what that leaves out of every uncertainty, per 0.1 mm the parameter
    /// held for scale is off (the data cannot say by how much it is), and
    /// the remedy.
    pub(crate) fn scale(c: &Calibration) -> Option<Note> {
        let e = (c.parameters.iter())
            .find(|e| e.fixed.as_deref().is_some_and(|r| r.starts_with("scale:")))?;
        let value = e.nominal.abs();
        if value.is_nan() || value <= 0.0 {
            return None;
        }
        Some(Note::ScaleUndetermined {
            parameter: e.id.to_string(),
            nominal_mm: value,
            reach_mm: c.params.reach(),
        })
    }
}

/// Most outliers, as a share of the observations, that can be the cause
/// of a refusal rather than a symptom of it (a wrong minimum or a wrong
/// model puts most observations beyond the threshold).
const FEW_OUTLIERS: f64 = 0.1;

/// The σ̂₀ from which the best minimum of a global search says the data
/// and the arm disagree: residuals hundreds of times the stated noise are
/// no noise misstatement, and a search that tried the whole torus of the
/// zero offsets is no wrong start.
const DISAGREE_SIGMA0: f64 = 100.0;

impl Verdict {
    /// The verdict on `calibration` and its validation on the fitted data.
    fn of(
        calibration: &Calibration,
        fitted: &BeforeAfter,
        noise: &Noise,
        accept_poor_fit: bool,
    ) -> Verdict {
        let (mut reasons, mut notes) = (Vec::new(), Vec::new());
        let solver = &calibration.solver;
        // The data and the arm disagree: no search can help, so the
        // solver's own failure is said last, without its remedy.
        let disagree = disagreement(calibration);
        let mut unconfirmed = None;
        if !solver.is_solution_usable() {
            let search = match solver.stop {
                crate::calibrate::Stop::Global { search, .. }
                    if !search.confirmed() && disagree.is_none() =>
                {
                    Some(UnconfirmedSearch {
                        starts: (calibration.solver.global.as_ref())
                            .map_or(0, |g| g.options.max_starts),
                        prior_in_use: calibration.prior.is_some(),
                    })
                }
                _ => None,
            };
            unconfirmed = Some(Reason::Unconfirmed {
                stop: solver.stop.describe(),
                search,
            });
        }
        if disagree.is_none() {
            reasons.extend(unconfirmed.take());
        }
        reasons.extend(gross_reasons(calibration));
        let blocks = &calibration.checks.implausible_blocks;
        if !blocks.is_empty() {
            reasons.push(Reason::ImplausibleBlocks {
                blocks: blocks.clone(),
            });
        }
        let mut poor = Vec::new();
        noise_checks(calibration, noise, &mut poor, &mut notes);
        if let Some(u) = calibration.checks.position_uncertainty.filter(|u| u.weak()) {
            notes.push(Note::WeakData {
                rms_mm: u.rms_mm,
                coverage: u.coverage,
                touch_mm: u.touch_mm,
            });
        }
        notes.extend(Note::scale(calibration));
        // Nearly parallel axes in the D-H model: say which joint suits Hayati.
        notes.extend(
            crate::hayati::recommendations(&calibration.params)
                .into_iter()
                .map(|text| Note::Hayati { text }),
        );
        poor.extend(worse_than_nominal(fitted));
        if accept_poor_fit {
            notes.extend(poor.into_iter().map(|p| Note::Accepted {
                reason: Box::new(p),
            }));
        } else {
            reasons.extend(poor);
        }
        // A few gross outliers explain every other symptom: said first;
        // else data that no arm of this kind fits (another arm's file,
        // columns in another order, another unit).
        reasons.extend(unconfirmed);
        if !reasons.is_empty() {
            if let Some(cause) = outlier_cause(calibration) {
                reasons.insert(0, cause);
            } else if let Some(cause) = disagree {
                reasons.insert(0, cause);
            }
        }
        Verdict {
            usable: reasons.is_empty(),
            reasons,
            notes,
        }
    }
}

/// The calibrated arm worse than the nominal at its own reference
/// positions, or on its own data.
fn worse_than_nominal(fitted: &BeforeAfter) -> Vec<Reason> {
    let mut poor = Vec::new();
    if let (Some(b), Some(a)) = (fitted.before.positions, fitted.after.positions)
        && fitted.after.points > 0
        && (a.mean.is_nan() || a.mean > b.mean)
    {
        poor.push(Reason::WorseAtPositions {
            before_mm: b.mean,
            after_mm: a.mean,
        });
    }
    let (before, after) = (fitted.before.headline(), fitted.after.headline());
    if after.is_nan() || after > before {
        poor.push(Reason::WorseOnData {
            what: fitted.after.headline_name().to_string(),
            before_mm: before,
            after_mm: after,
        });
    }
    poor
}

/// The data and the arm disagree — the first cause of a refusal, when the
/// global search (which tries every basin of the zero offsets) ends on an
/// arm not of the nominal's kind (gross corrections the data determine)
/// having found no minimum of that kind, or leaving residuals hundreds of
/// times the stated noise ([`DISAGREE_SIGMA0`]), and a few outliers do not
/// explain it: the joint columns in another order, another arm's file, or
/// another unit.
fn disagreement(c: &Calibration) -> Option<Reason> {
    let trace = c.solver.global.as_ref()?;
    if !matches!(c.solver.stop, crate::calibrate::Stop::Global { .. }) {
        return None;
    }
    // An arm of the nominal's kind at the end (only its fit poor) is a
    // misstated noise or a model error: said by the χ² test.
    if classify_gross(c).0.is_empty() {
        return None;
    }
    let no_kind = trace.best_hits == 0;
    let s0 = c.dof.sigma0;
    let far = c.checks.chi_square.is_some() && s0 >= DISAGREE_SIGMA0;
    if !(no_kind || far) {
        return None;
    }
    Some(Reason::DataDisagreeWithArm {
        minima_of_other_kinds: no_kind.then_some(trace.minima.len()),
        far_sigma0: far.then_some(s0),
        touch_sigma_mm: c.dof.touch_sigma_mm,
        joints: c.params.joint_count(),
    })
}

/// A refused fit with a few outliers: they are the likely cause (a
/// mislabelled or displaced touch pulls the whole fit), named by
/// `file:line`, with the remedy. After a robust fit, the touches it
/// weighed down pull nothing — they are reported (the summary's robust
/// and outlier lines), not blamed — and a robust loss is not recommended:
/// it is in use.
fn outlier_cause(c: &Calibration) -> Option<Reason> {
    let weighed_out: Vec<&str> = (c.robust.iter())
        .flat_map(|r| r.downweighted())
        .map(|w| w.at.as_str())
        .collect();
    let o: Vec<&Outlier> = (c.checks.outliers.iter())
        .filter(|x| !weighed_out.contains(&x.at.as_str()))
        .collect();
    // Named as the cause only when, weighed down, they leave the rest of
    // the residuals small: not after a wrong minimum, whose residuals are
    // all large and whose screen singles out one touch all the same.
    let screen = c.checks.outlier_screen;
    if screen.is_some_and(|s| !s.explains(c.dof.sigma0)) {
        return None;
    }
    // Observations, not rows: a position or an orientation is three rows,
    // a point on a sphere one.
    let d = &c.dof;
    let observations = (d.touch_rows / 3
        + d.rows_of("positions") / 3
        + d.rows_of("orientations") / 3
        + d.rows_of("spheres"))
    .max(1);
    if o.is_empty() || o.len() as f64 > (FEW_OUTLIERS * observations as f64).max(1.0) {
        return None;
    }
    // Each kind of evidence named as what was displaced: a touch, the
    // tracker's target, a point on its sphere, an orientation.
    let what = match outliers_noun(&c.checks.outliers, noun(c)) {
        "sphere point" => "point on its sphere",
        "orientation" => "orientation",
        "position" => "target",
        "touch" => "touch",
        _ => "observation",
    };
    Some(Reason::Outliers {
        count: o.len(),
        named: o.iter().take(5).map(|x| (*x).clone()).collect(),
        what: what.to_string(),
        robust_in_use: c.robust.is_some(),
    })
}

/// The fit against the noise: the χ² test (with the ways out of a misstated
/// noise when the fit is otherwise sound) and the robust scale's test, as
/// refusals (`poor`, unless a poor fit is accepted) or notes.
fn noise_checks(
    calibration: &Calibration,
    noise: &Noise,
    poor: &mut Vec<Reason>,
    notes: &mut Vec<Note>,
) {
    if let Some(chi) = &calibration.checks.chi_square {
        if chi.far_outside() {
            // A misstated noise is the cause only of a fit otherwise
            // sound: not of a wrong minimum or a wrong geometry.
            let sound = calibration.solver.is_solution_usable()
                && calibration.checks.gross_corrections.is_empty();
            poor.push(Reason::ChiSquare {
                chi: *chi,
                stated: sound.then(|| StatedNoise::of(noise)),
            });
        } else if chi.verdict != ChiSquareVerdict::Consistent {
            notes.push(Note::ChiSquare { chi: *chi });
        }
    }
    if let Some(r) = &calibration.robust {
        if let Some(description) = r.describe_scale() {
            if r.far_outside() {
                poor.push(Reason::RobustScale { description });
            } else if r.verdict != Some(ChiSquareVerdict::Consistent) {
                notes.push(Note::RobustScale { description });
            }
        }
        if !r.converged {
            notes.push(Note::RobustUnsettled {
                tolerance: crate::calibrate::robust::WEIGHT_TOLERANCE,
                passes: r.passes,
            });
        }
    }
}

/// Why free parameters moved implausibly far. One whose σ is a third of
/// the move accepted or more was not determined by the data (a weak
/// direction the user left free, or that a tolerance did not cover): said
/// so, with the remedy. The rest are what the check exists for — a mirror
/// image, a collapsed arm or a unit mistake.
fn gross_reasons(c: &Calibration) -> Vec<Reason> {
    let (gross, weak) = classify_gross(c);
    let mut reasons = Vec::new();
    if !gross.is_empty() {
        reasons.push(Reason::NotNominalGeometry { moves: gross });
    }
    if !weak.is_empty() {
        reasons.push(Reason::Undetermined {
            moves: weak,
            prior_in_use: c.prior.is_some(),
        });
    }
    reasons
}

/// The implausible moves of [`gross_reasons`]: those the data determine
/// (gross: a mirror image, a collapse, a unit mistake), and those they
/// barely do (weak, each with its σ).
fn classify_gross(c: &Calibration) -> (Vec<GrossCorrection>, Vec<(GrossCorrection, f64)>) {
    let (mut weak, mut gross) = (Vec::new(), Vec::new());
    // The σ carry σ̂²: when the fit is far outside the stated noise (a wrong
    // minimum), they are inflated by it and tell nothing.
    let meaningful = (c.checks.chi_square.as_ref()).is_none_or(|chi| !chi.far_outside());
    for g in &c.checks.gross_corrections {
        let e = (c.params.parse_param(&g.name)).and_then(|id| c.estimate(id));
        let sigma = e.and_then(|e| e.sigma.map(|s| e.id.to_user(s)));
        match sigma {
            Some(s) if meaningful && s >= g.tolerance / 3.0 => weak.push((g.clone(), s)),
            _ => gross.push(g.clone()),
        }
    }
    (gross, weak)
}

/// The verdict on `calibration` of `problem` (its `fitted` figures), with
/// readings that look like radians read as degrees as the first cause of a
/// refusal: the reader warned, and the reasons that follow (no confirmed
/// minimum, χ²) are its consequences.
pub(in crate::session) fn verdict_of(
    problem: &Problem,
    calibration: &Calibration,
    fitted: &BeforeAfter,
) -> Verdict {
    let (data, model) = (&problem.data, &problem.model);
    let mut verdict = Verdict::of(calibration, fitted, &model.noise, model.accept_poor_fit);
    if !verdict.usable
        && crate::io::poses::look_like_radians(
            data.readings(),
            data.len(),
            (data.joints(), data.poses().prismatic_mask()),
            1f64.to_degrees(),
        )
    {
        verdict.reasons.insert(
            0,
            Reason::RadiansAsDegrees {
                poses_file: data.source().poses_file().to_string(),
            },
        );
    }
    verdict
}
