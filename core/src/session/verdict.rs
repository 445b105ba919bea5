//! Whether a calibration may be used, typed: each reason for a refusal
//! ([`Reason`]) and each note beside a verdict ([`Note`]) carries its data
//! (the χ² figures, the parameters and their corrections, the outliers'
//! `file:line`, the unconfirmed search's counts), and says itself in the
//! words of the front end that asks ([`Spelling`]): the command line's
//! flags, Python's keyword arguments or C's setters, each option named once
//! ([`Setting`]). A program matches on the variants; a person reads
//! [`Reason::describe`].
//!
//! `calibration.json`'s `/verdict` and `calibrated.toml`'s `[verdict]` keep
//! the command line's sentences ([`Verdict::words`]): read back, a reason is
//! the sentence it was written as ([`Reason::Recorded`]).

use serde::{Deserialize, Serialize};

use super::{BeforeAfter, Calibration, Problem, noun, outliers_noun};
use crate::calibrate::checks::{ChiSquare, ChiSquareVerdict, GrossCorrection, Outlier};
use crate::io::ArmVerdict;
use crate::residuals::Noise;
pub use crate::setting::{Setting, Spelling};

/// Whether a calibration may be used: exit 0 of the command line. Written
/// into `calibration.json` and `calibrated.toml` in the command line's
/// words ([`Verdict::words`], the [`ArmVerdict`] a reader of those files
/// gets back).
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct Verdict {
    /// Usable: no reason against it.
    pub usable: bool,
    /// Why not (empty when usable), the first cause first.
    pub reasons: Vec<Reason>,
    /// What a metrologist should know although the result is usable.
    pub notes: Vec<Note>,
}

impl Verdict {
    /// The verdict in `spelling`'s words: its reasons and notes as
    /// sentences.
    pub fn words(&self, spelling: Spelling) -> ArmVerdict {
        ArmVerdict {
            usable: self.usable,
            reasons: self.reasons.iter().map(|r| r.describe(spelling)).collect(),
            notes: self.notes.iter().map(|n| n.describe(spelling)).collect(),
        }
    }
}

impl Serialize for Verdict {
    /// The command line's words: `calibration.json`'s `/verdict`.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.words(Spelling::Cli).serialize(s)
    }
}

impl<'de> Deserialize<'de> for Verdict {
    /// A verdict read back from its sentences: each a [`Reason::Recorded`]
    /// or [`Note::Recorded`].
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Verdict, D::Error> {
        let words = ArmVerdict::deserialize(d)?;
        Ok(Verdict {
            usable: words.usable,
            reasons: (words.reasons.into_iter())
                .map(|text| Reason::Recorded { text })
                .collect(),
            notes: (words.notes.into_iter())
                .map(|text| Note::Recorded { text })
                .collect(),
        })
    }
}

/// One reason a calibration is refused, with its data. Said in a front
/// end's words by [`Reason::describe`].
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Reason {
    /// Every joint reading is within ±2π read as degrees: radians read as
    /// degrees, the cause of the reasons after it.
    RadiansAsDegrees {
        /// The poses file.
        poses_file: String,
    },
    /// The data and the arm disagree: the global search found no arm of
    /// the nominal's kind, or its best leaves residuals hundreds of times
    /// the stated noise.
    DataDisagreeWithArm {
        /// The minima the search found when none was of the nominal's
        /// kind.
        minima_of_other_kinds: Option<usize>,
        /// σ̂₀ of the best minimum when hundreds of times the noise.
        far_sigma0: Option<f64>,
        /// A touch's stated σ, mm.
        touch_sigma_mm: f64,
        /// The arm's joints.
        joints: usize,
    },
    /// A few outliers pull the fit: the likely cause.
    Outliers {
        /// How many.
        count: usize,
        /// The first five.
        named: Vec<Outlier>,
        /// What each is of: `touch`, `target`, `point on its sphere`,
        /// `orientation`, `observation`.
        what: String,
        /// A robust loss was in use (and is not recommended again).
        robust_in_use: bool,
    },
    /// The solver did not reach a confirmed minimum.
    Unconfirmed {
        /// How it stopped, in words.
        stop: String,
        /// A global search that spent its starts: how many it had and
        /// whether a prior was in use (the remedy).
        search: Option<UnconfirmedSearch>,
    },
    /// Parameters the data determine moved implausibly far: a mirror
    /// image, a collapse, a unit mistake.
    NotNominalGeometry {
        /// The moves.
        moves: Vec<GrossCorrection>,
    },
    /// Parameters the data barely determine moved implausibly far.
    Undetermined {
        /// The moves, each with its σ (in its unit).
        moves: Vec<(GrossCorrection, f64)>,
        /// A prior was in use.
        prior_in_use: bool,
    },
    /// An auxiliary block's values are physically impossible.
    ImplausibleBlocks {
        /// Each block's complaint.
        blocks: Vec<String>,
    },
    /// The χ² test refuses the fit.
    ChiSquare {
        /// The test.
        chi: ChiSquare,
        /// The noise stated, when the fit is otherwise sound (a
        /// misstated noise is then a possible cause: said with the Birge
        /// ratio).
        stated: Option<StatedNoise>,
    },
    /// The robust scale's test refuses the fit.
    RobustScale {
        /// The test, in words.
        description: String,
    },
    /// Worse than nominal at its own reference positions.
    WorseAtPositions {
        /// Mean 3-D error before, mm.
        before_mm: f64,
        /// After, mm.
        after_mm: f64,
    },
    /// Worse than nominal on its own data.
    WorseOnData {
        /// The headline figure's name.
        what: String,
        /// Before, mm.
        before_mm: f64,
        /// After, mm.
        after_mm: f64,
    },
    /// A reason read back from a file: its sentence.
    Recorded {
        /// The sentence.
        text: String,
    },
}

/// A global search that spent its starts without confirming a minimum.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct UnconfirmedSearch {
    /// The starts it had.
    pub starts: usize,
    /// A prior was in use.
    pub prior_in_use: bool,
}

/// The noise a fit stated, as it holds it (rad, mm).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StatedNoise {
    /// The encoders', rad.
    pub encoder_rad: Option<f64>,
    /// The probe's, mm.
    pub probe_mm: Option<f64>,
    /// A reference position's, mm.
    pub position_mm: Option<f64>,
    /// Its growth with distance, mm per m.
    pub position_mm_per_m: Option<f64>,
    /// A reference orientation's, rad.
    pub orientation_rad: Option<f64>,
}

impl StatedNoise {
    fn of(noise: &Noise) -> StatedNoise {
        StatedNoise {
            encoder_rad: noise.encoder_rad,
            probe_mm: noise.probe_mm,
            position_mm: noise.position_mm,
            position_mm_per_m: noise.position_mm_per_m,
            orientation_rad: noise.orientation_rad,
        }
    }
}

/// A note beside a verdict, with its data. Said in a front end's words by
/// [`Note::describe`].
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum Note {
    /// A χ² outside its range but not refused.
    ChiSquare {
        /// The test.
        chi: ChiSquare,
    },
    /// A robust scale outside its range but not refused, in words.
    RobustScale {
        /// The test, in words.
        description: String,
    },
    /// The robust weights had not settled.
    RobustUnsettled {
        /// The weights' tolerance.
        tolerance: f64,
        /// The refits.
        passes: usize,
    },
    /// The data determine the arm too weakly beside a touch's scatter.
    WeakData {
        /// RMS of the predicted radius, mm.
        rms_mm: f64,
        /// Its coverage.
        coverage: f64,
        /// A touch's own radius at that coverage, mm.
        touch_mm: f64,
    },
    /// No reference length: the scale is the nominal's.
    ScaleUndetermined {
        /// The parameter held for scale.
        parameter: String,
        /// Its nominal value, mm.
        nominal_mm: f64,
        /// The arm's reach, mm.
        reach_mm: f64,
    },
    /// Nearly parallel axes: a joint suits Hayati's model.
    Hayati {
        /// The recommendation, in words.
        text: String,
    },
    /// A reason for refusal, accepted on request.
    Accepted {
        /// The reason.
        reason: Box<Reason>,
    },
    /// A note read back from a file: its sentence.
    Recorded {
        /// The sentence.
        text: String,
    },
}

impl std::fmt::Display for Reason {
    /// The command line's words.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe(Spelling::Cli))
    }
}

impl std::fmt::Display for Note {
    /// The command line's words.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe(Spelling::Cli))
    }
}

impl Reason {
    /// A short stable name of the variant: `chi_square`, `outliers`, …
    /// (the `kind` of its JSON).
    pub fn kind(&self) -> &'static str {
        match self {
            Reason::RadiansAsDegrees { .. } => "radians_as_degrees",
            Reason::DataDisagreeWithArm { .. } => "data_disagree_with_arm",
            Reason::Outliers { .. } => "outliers",
            Reason::Unconfirmed { .. } => "unconfirmed",
            Reason::NotNominalGeometry { .. } => "not_nominal_geometry",
            Reason::Undetermined { .. } => "undetermined",
            Reason::ImplausibleBlocks { .. } => "implausible_blocks",
            Reason::ChiSquare { .. } => "chi_square",
            Reason::RobustScale { .. } => "robust_scale",
            Reason::WorseAtPositions { .. } => "worse_at_positions",
            Reason::WorseOnData { .. } => "worse_on_data",
            Reason::Recorded { .. } => "recorded",
        }
    }

    /// The sentence, its remedies named as `spelling` names options.
    pub fn describe(&self, spelling: Spelling) -> String {
        let name = |s: Setting| s.name(spelling);
        match self {
            Reason::RadiansAsDegrees { poses_file } => format!(
                "every joint reading of {poses_file}, read as degrees, is within ±6.28°: these \
                 angles look like radians read as degrees, and the reasons after this one \
                 follow from it — {}",
                angle_units_remedy(spelling)
            ),
            Reason::DataDisagreeWithArm {
                minima_of_other_kinds,
                far_sigma0,
                touch_sigma_mm,
                joints,
            } => disagreement_words(
                *minima_of_other_kinds,
                *far_sigma0,
                *touch_sigma_mm,
                *joints,
            ),
            Reason::Outliers {
                count,
                named,
                what,
                robust_in_use,
            } => outliers_words(*count, named, what, *robust_in_use, spelling),
            Reason::Unconfirmed { stop, search } => {
                let remedy = search.map_or_else(String::new, |s| {
                    let tolerances = if s.prior_in_use {
                        "tighter tolerances for the parameters that differ between its minima \
                         (the prior in use lets them wander)"
                            .to_string()
                    } else {
                        format!(
                            "state tolerances (`[prior]`, {}) for the parameters that differ \
                             between its minima",
                            name(Setting::Prior)
                        )
                    };
                    format!(
                        ": give it more starts than its {} ({}), or {tolerances}",
                        s.starts,
                        name(Setting::GlobalStarts)
                    )
                });
                format!("the solver did not reach a confirmed minimum ({stop}){remedy}")
            }
            Reason::NotNominalGeometry { moves } => format!(
                "the calibrated arm is not the nominal arm's geometry — a mirror image, a \
                 collapsed arm or a unit mistake: {}",
                moves
                    .iter()
                    .map(|g| g.describe())
                    .collect::<Vec<_>>()
                    .join("; ")
            ),
            Reason::Undetermined {
                moves,
                prior_in_use,
            } => undetermined_words(moves, *prior_in_use, spelling),
            Reason::ImplausibleBlocks { blocks } => format!(
                "an auxiliary block has values no real instrument could have: {}",
                blocks.join("; ")
            ),
            Reason::ChiSquare { chi, stated } => match stated {
                Some(noise) => {
                    format!("{}; {}", chi.describe(), noise_remedy(noise, chi, spelling))
                }
                None => chi.describe(),
            },
            Reason::RobustScale { description } => description.clone(),
            Reason::WorseAtPositions {
                before_mm,
                after_mm,
            } => format!(
                "the calibrated arm is worse than the nominal at its own reference positions \
                 (mean 3-D error {before_mm:.4} → {after_mm:.4} mm): touches and positions \
                 disagree?"
            ),
            Reason::WorseOnData {
                what,
                before_mm,
                after_mm,
            } => format!(
                "the calibrated arm is worse than the nominal on its own data ({what} \
                 {before_mm:.4} → {after_mm:.4} mm): a mislabelled observation or a wrong \
                 minimum?"
            ),
            Reason::Recorded { text } => text.clone(),
        }
    }
}

impl Note {
    /// A short stable name of the variant (the `kind` of its JSON).
    pub fn kind(&self) -> &'static str {
        match self {
            Note::ChiSquare { .. } => "chi_square",
            Note::RobustScale { .. } => "robust_scale",
            Note::RobustUnsettled { .. } => "robust_unsettled",
            Note::WeakData { .. } => "weak_data",
            Note::ScaleUndetermined { .. } => "scale_undetermined",
            Note::Hayati { .. } => "hayati",
            Note::Accepted { .. } => "accepted",
            Note::Recorded { .. } => "recorded",
        }
    }

    /// The sentence, its remedies named as `spelling` names options.
    pub fn describe(&self, spelling: Spelling) -> String {
        match self {
            Note::ChiSquare { chi } => chi.describe(),
            Note::RobustScale { description } | Note::Hayati { text: description } => {
                description.clone()
            }
            Note::RobustUnsettled { tolerance, passes } => format!(
                "the robust weights still moved by more than {tolerance} after {passes} refits"
            ),
            Note::WeakData {
                rms_mm,
                coverage,
                touch_mm,
            } => format!(
                "these data determine the arm to ±{rms_mm:.4} mm (RMS over the campaign's poses \
                 of the {:.0} % radius in 3-D), enough to add more than 5 % to a touch's own \
                 scatter (±{touch_mm:.4} mm at the same coverage): add sockets, poses or \
                 reference lengths",
                100.0 * coverage
            ),
            Note::ScaleUndetermined {
                parameter,
                nominal_mm,
                reach_mm,
            } => {
                let relative = 0.1 / nominal_mm;
                format!(
                    "positions are determined only up to scale: no reference length fixes the \
                     arm's size, so {parameter} is held at its nominal {nominal_mm:.3} mm and \
                     every length follows it; each 0.1 mm it is off scales the arm by \
                     {relative:.1e}, {:.3} mm at the reach ({reach_mm:.0} mm), an error no \
                     uncertainty here includes. Add a reference length ({}) to fix the scale",
                    relative * reach_mm,
                    Setting::Lengths.name(spelling)
                )
            }
            Note::Accepted { reason } => {
                format!("accepted on request: {}", reason.describe(spelling))
            }
            Note::Recorded { text } => text.clone(),
        }
    }

    /// Without a reference length the size of the arm is the nominal's:
    /// what that leaves out of every uncertainty, per 0.1 mm the parameter
    /// held for scale is off (the data cannot say by how much it is), and
    /// the remedy.
    pub(super) fn scale(c: &Calibration) -> Option<Note> {
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

/// How each front end reads the poses as radians.
fn angle_units_remedy(spelling: Spelling) -> String {
    match spelling {
        Spelling::Cli => crate::calibrate::ANGLE_UNITS_REMEDY.to_string(),
        _ => format!(
            "read the poses as radians ({})",
            Setting::AngleUnitRad.name(spelling)
        ),
    }
}

/// [`Reason::DataDisagreeWithArm`] in words: no remedy names an option.
fn disagreement_words(
    minima_of_other_kinds: Option<usize>,
    far_sigma0: Option<f64>,
    touch_sigma_mm: f64,
    joints: usize,
) -> String {
    let mut evidence = Vec::new();
    if let Some(minima) = minima_of_other_kinds {
        evidence.push(format!(
            "none of the {minima} minima the global search found, from starts all over the zero \
             offsets' circles, is an arm of the nominal's kind (each a mirror image, folded or \
             rescaled)"
        ));
    }
    if let Some(s0) = far_sigma0 {
        evidence.push(format!(
            "even the best minimum leaves residuals {s0:.0} times the stated noise (a touch \
             scatters {:.3} mm where the noise says {touch_sigma_mm:.4} mm)",
            s0 * touch_sigma_mm,
        ));
    }
    format!(
        "the data and the arm disagree: {} — check that the poses file's columns q1..q{joints} \
         are this arm's joints in its order, that the touches are of this arm (not another \
         robot's), and that readings and lengths are in the units stated (the readings' angle \
         unit; lengths in mm)",
        evidence.join("; "),
    )
}

/// [`Reason::Outliers`] in words.
fn outliers_words(
    count: usize,
    named: &[Outlier],
    what: &str,
    robust_in_use: bool,
    spelling: Spelling,
) -> String {
    let listed: Vec<String> = (named.iter())
        .map(|x| format!("{} (point {}, {:.1} σ)", x.at, x.point, x.standardised))
        .collect();
    let robust = if robust_in_use {
        String::new()
    } else {
        format!(
            ", or calibrate with {}, which weighs them down",
            Setting::Robust.name(spelling)
        )
    };
    format!(
        "{count} outlying observation{} pull{} the fit: {}{} — a mislabelled or displaced \
         {what}? Check {}: fix the label or remove the row{robust}",
        if count == 1 { "" } else { "s" },
        if count == 1 { "s" } else { "" },
        listed.join(", "),
        if count > listed.len() { ", …" } else { "" },
        if count == 1 { "it" } else { "them" }
    )
}

/// [`Reason::Undetermined`] in words.
fn undetermined_words(
    moves: &[(GrossCorrection, f64)],
    prior_in_use: bool,
    spelling: Spelling,
) -> String {
    let moves: Vec<String> = (moves.iter())
        .map(|(g, s)| format!("{} (σ {s:.4} {})", g.describe(), g.unit))
        .collect();
    // With a prior in use, what it lacks: no option in use recommended.
    let tolerances = if prior_in_use {
        "give them tolerances (or tighter ones) in the prior".to_string()
    } else {
        format!(
            "state tolerances for them (`[prior]` in the arm file, or {})",
            Setting::Prior.name(spelling)
        )
    };
    format!(
        "the data barely determine parameters that moved implausibly far, so they followed \
         noise and model error: {} — {tolerances} or fix them ({}), or add poses that turn the \
         joints involved",
        moves.join("; "),
        Setting::Fix.name(spelling)
    )
}

/// The χ² far outside the stated noise, as the Birge ratio σ̂₀ =
/// √(χ²/dof): how many times the noise stated the residuals scatter. Not
/// "state the noise σ̂₀ times larger": that makes the test pass by
/// construction. The ways out: for residuals too large, outliers or a
/// model error when the noise is right; leaving a guessed noise unstated
/// (σ is then estimated from the residuals, as the uncertainties printed
/// already are through σ̂₀, and nothing is tested); or accepting the fit.
fn noise_remedy(noise: &StatedNoise, chi: &ChiSquare, spelling: Spelling) -> String {
    let s0 = (chi.statistic / chi.dof.max(1) as f64).sqrt();
    let (stated, unstated) = stated_noise_words(noise, spelling);
    let stated = if stated.is_empty() {
        "the stated noise".to_string()
    } else {
        format!("the stated noise ({stated})")
    };
    let unstated = if unstated.is_empty() {
        String::new()
    } else {
        format!(" ({unstated})")
    };
    let (scatter, right) = if s0 > 1.0 {
        (
            format!("{s0:.2} times what {stated} explains"),
            format!(
                "If that noise is right, look for outliers ({} names them) or a model error; if \
                 it is a guess",
                Setting::Robust.name(spelling)
            ),
        )
    } else {
        (
            format!(
                "{:.2} times less than {stated} explains — an overstated noise, or a fit that \
                 follows it",
                1.0 / s0
            ),
            "If the noise is a guess".to_string(),
        )
    };
    format!(
        "the Birge ratio σ̂₀ = √(χ²/dof) = {s0:.2}: the residuals scatter {scatter}. {right}, \
         leave it unstated{unstated}: σ is then estimated from these residuals (as the \
         uncertainties printed here already are, through σ̂₀) and no χ² test is made; or \
         accept the fit as it is with {}.",
        Setting::AcceptPoorFit.name(spelling)
    )
}

/// The noise stated, as `spelling` sets it (in its units: degrees on the
/// command line and in Python, radians in C), and how it leaves it
/// unstated.
fn stated_noise_words(noise: &StatedNoise, spelling: Spelling) -> (String, String) {
    let deg = |r: f64| r.to_degrees();
    let b = noise.position_mm_per_m.unwrap_or(0.0);
    let mut set: Vec<String> = Vec::new();
    let mut names: Vec<&str> = Vec::new();
    match spelling {
        Spelling::Python => {
            let mut args = Vec::new();
            if let Some(e) = noise.encoder_rad {
                args.push(format!("encoder_deg={:.4}", deg(e)));
            }
            if let Some(p) = noise.probe_mm {
                args.push(format!("probe_mm={p:.4}"));
            }
            if let Some(a) = noise.position_mm {
                args.push(format!("position_mm={a:.4}"));
                if b > 0.0 {
                    args.push(format!("position_mm_per_m={b:.4}"));
                }
            }
            if let Some(o) = noise.orientation_rad {
                args.push(format!("orientation_deg={:.4}", deg(o)));
            }
            if !args.is_empty() {
                set.push(format!("Noise({})", args.join(", ")));
                names.push("noise=None");
            }
        }
        _ => {
            let c = spelling == Spelling::C;
            let value = |v: f64, rad: bool| match (c, rad) {
                (true, true) => format!("(o, {v:.4e})"),
                (true, false) => format!("(o, {v:.4})"),
                (false, true) => format!(" {:.4}", deg(v)),
                (false, false) => format!(" {v:.4}"),
            };
            let mut add = |setting: Setting, v: String| {
                set.push(format!("{}{v}", setting.name(spelling)));
                names.push(setting.name(spelling));
            };
            if let Some(e) = noise.encoder_rad {
                add(Setting::EncoderNoise, value(e, true));
            }
            if let Some(p) = noise.probe_mm {
                add(Setting::ProbeNoise, value(p, false));
            }
            if let Some(a) = noise.position_mm {
                add(
                    Setting::PositionNoise,
                    match (c, b > 0.0) {
                        (true, _) => format!("(o, {a:.4}, {b:.4})"),
                        (false, true) => format!(" {a:.4}+{b:.4}/m"),
                        (false, false) => format!(" {a:.4}"),
                    },
                );
            }
            if let Some(o) = noise.orientation_rad {
                add(Setting::OrientationNoise, value(o, true));
            }
        }
    }
    let unstated = match (spelling, names.is_empty()) {
        (_, true) => String::new(),
        (Spelling::C, false) => format!("0 in {}: not stated", names.join(", ")),
        (Spelling::Python, false) => names.join(""),
        (_, false) => format!("without {}", names.join(", ")),
    };
    let separator = if spelling == Spelling::C { ", " } else { " " };
    (set.join(separator), unstated)
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
        let e = c.parameters.iter().find(|e| e.id.to_string() == g.name);
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
pub(super) fn verdict_of(
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

/// The verdict, and the notes that come with it (the same as the JSON's
/// `/verdict`): a χ² outside its range that is not a refusal is said here,
/// not only in the file.
pub(super) fn verdict_line(v: &Verdict) -> String {
    let words = v.words(Spelling::Cli);
    let mut t = if v.usable {
        "Verdict: usable\n".to_string()
    } else {
        format!("Verdict: NOT usable — {}\n", words.reasons.join("; "))
    };
    for n in &words.notes {
        t += &format!("  note: {n}\n");
    }
    t + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chi(statistic: f64, dof: usize, p_upper: f64, p_lower: f64) -> ChiSquare {
        ChiSquare {
            statistic,
            dof,
            p_upper,
            p_lower,
            verdict: ChiSquareVerdict::from_tails(p_upper, p_lower),
        }
    }

    fn gross() -> GrossCorrection {
        GrossCorrection {
            name: "theta5".into(),
            unit: "deg".into(),
            nominal: 0.0,
            calibrated: 20.0,
            tolerance: 15.0,
        }
    }

    fn outlier() -> Outlier {
        Outlier {
            at: "poses.csv:12".into(),
            point: "P3".into(),
            standardised: 9.87,
            kind: None,
        }
    }

    fn noise() -> StatedNoise {
        StatedNoise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            position_mm: Some(0.015),
            position_mm_per_m: Some(0.006),
            orientation_rad: Some(0.01f64.to_radians()),
        }
    }

    /// Every reason, with sample data (each remedy's branches: an option
    /// in use and not).
    fn reasons() -> Vec<Reason> {
        let search = |prior_in_use| UnconfirmedSearch {
            starts: 100,
            prior_in_use,
        };
        vec![
            Reason::RadiansAsDegrees {
                poses_file: "poses.csv".into(),
            },
            Reason::DataDisagreeWithArm {
                minima_of_other_kinds: Some(7),
                far_sigma0: Some(512.0),
                touch_sigma_mm: 0.02,
                joints: 6,
            },
            Reason::Outliers {
                count: 1,
                named: vec![outlier()],
                what: "touch".into(),
                robust_in_use: false,
            },
            Reason::Outliers {
                count: 7,
                named: vec![outlier(); 5],
                what: "target".into(),
                robust_in_use: true,
            },
            Reason::Unconfirmed {
                stop: "no two starts agreed".into(),
                search: Some(search(false)),
            },
            Reason::Unconfirmed {
                stop: "no two starts agreed".into(),
                search: Some(search(true)),
            },
            Reason::Unconfirmed {
                stop: "iteration limit".into(),
                search: None,
            },
            Reason::NotNominalGeometry {
                moves: vec![gross()],
            },
            Reason::Undetermined {
                moves: vec![(gross(), 6.0)],
                prior_in_use: false,
            },
            Reason::Undetermined {
                moves: vec![(gross(), 6.0)],
                prior_in_use: true,
            },
            Reason::ImplausibleBlocks {
                blocks: vec!["thermal: 1 m/K".into()],
            },
            Reason::ChiSquare {
                chi: chi(9000.0, 1000, 1e-300, 1.0),
                stated: Some(noise()),
            },
            Reason::ChiSquare {
                chi: chi(100.0, 1000, 1.0, 1e-300),
                stated: Some(noise()),
            },
            Reason::ChiSquare {
                chi: chi(9000.0, 1000, 1e-300, 1.0),
                stated: None,
            },
            Reason::RobustScale {
                description: "robust cauchy fit, scale 3.000 of the stated noise".into(),
            },
            Reason::WorseAtPositions {
                before_mm: 0.1,
                after_mm: 0.2,
            },
            Reason::WorseOnData {
                what: "RMS touch scatter".into(),
                before_mm: 0.1,
                after_mm: 0.2,
            },
            Reason::Recorded {
                text: "read back".into(),
            },
        ]
    }

    /// Every note, with sample data.
    fn notes() -> Vec<Note> {
        let mut notes = vec![
            Note::ChiSquare {
                chi: chi(1150.0, 1000, 1e-4, 1.0),
            },
            Note::RobustScale {
                description: "robust huber fit, scale 1.300".into(),
            },
            Note::RobustUnsettled {
                tolerance: 1e-3,
                passes: 20,
            },
            Note::WeakData {
                rms_mm: 0.02,
                coverage: 0.95,
                touch_mm: 0.05,
            },
            Note::ScaleUndetermined {
                parameter: "d5".into(),
                nominal_mm: 270.0,
                reach_mm: 1000.0,
            },
            Note::Hayati {
                text: "joint 2: consider `model = \"hayati\"`".into(),
            },
            Note::Recorded {
                text: "read back".into(),
            },
        ];
        notes.extend(reasons().into_iter().map(|r| Note::Accepted {
            reason: Box::new(r),
        }));
        notes
    }

    #[test]
    fn no_text_for_python_or_c_names_a_command_line_flag() {
        for spelling in [Spelling::Python, Spelling::C] {
            let (reasons, notes) = (reasons(), notes());
            let texts = (reasons.iter().map(|r| r.describe(spelling)))
                .chain(notes.iter().map(|n| n.describe(spelling)));
            for text in texts {
                assert!(!text.contains("--"), "{spelling:?}: {text}");
            }
            for s in Setting::ALL {
                assert!(!s.name(spelling).contains("--"), "{s:?}");
            }
        }
        // The C words name the real setters of the header.
        let header = include_str!("../../../capi/include/aacmm.h");
        let c = reasons()
            .iter()
            .map(|r| r.describe(Spelling::C))
            .collect::<Vec<_>>();
        let named = (c
            .iter()
            .flat_map(|t| t.split(|ch: char| !ch.is_alphanumeric() && ch != '_')))
        .filter(|w| w.starts_with("aacmm_") || w.starts_with("AACMM_"));
        let mut count = 0;
        for word in named {
            assert!(header.contains(word), "{word} is not in aacmm.h");
            count += 1;
        }
        assert!(count >= 5, "{count}");
        for s in Setting::ALL {
            let name = s.name(Spelling::C);
            if name.starts_with("aacmm_") || name.starts_with("AACMM_") {
                assert!(header.contains(name), "{name} is not in aacmm.h");
            }
        }
    }

    /// The command line's words are the sentences the untyped verdict
    /// said (pinned here; `.ci/same-results` compares whole campaigns).
    #[test]
    fn the_command_line_words_are_todays_sentences() {
        let r = reasons();
        assert_eq!(
            r[2].to_string(),
            "1 outlying observation pulls the fit: poses.csv:12 (point P3, 9.9 σ) — a \
             mislabelled or displaced touch? Check it: fix the label or remove the row, or \
             calibrate with --robust, which weighs them down"
        );
        assert_eq!(
            r[3].to_string(),
            "7 outlying observations pull the fit: poses.csv:12 (point P3, 9.9 σ), poses.csv:12 \
             (point P3, 9.9 σ), poses.csv:12 (point P3, 9.9 σ), poses.csv:12 (point P3, 9.9 σ), \
             poses.csv:12 (point P3, 9.9 σ), … — a mislabelled or displaced target? Check them: \
             fix the label or remove the row"
        );
        assert_eq!(
            r[4].to_string(),
            "the solver did not reach a confirmed minimum (no two starts agreed): give it more \
             starts than its 100 (--global-starts N), or state tolerances (`[prior]`, --prior) \
             for the parameters that differ between its minima"
        );
        assert_eq!(
            r[8].to_string(),
            "the data barely determine parameters that moved implausibly far, so they followed \
             noise and model error: theta5 0.0000 → 20.0000 deg (more than ±15.0000) (σ 6.0000 \
             deg) — state tolerances for them (`[prior]` in the arm file, or --prior) or fix \
             them (--fix), or add poses that turn the joints involved"
        );
        assert_eq!(
            notes()[4].to_string(),
            "positions are determined only up to scale: no reference length fixes the arm's \
             size, so d5 is held at its nominal 270.000 mm and every length follows it; each 0.1 \
             mm it is off scales the arm by 3.7e-4, 0.370 mm at the reach (1000 mm), an error no \
             uncertainty here includes. Add a reference length (--lengths) to fix the scale"
        );
        assert!(
            r[0].to_string()
                .ends_with(crate::calibrate::ANGLE_UNITS_REMEDY)
        );
    }

    #[test]
    fn python_and_c_say_the_remedies_in_their_own_words() {
        let r = reasons();
        let py = r[2].describe(Spelling::Python);
        assert!(py.ends_with("or calibrate with robust=\"huber\", which weighs them down"));
        let c = r[4].describe(Spelling::C);
        assert!(
            c.contains("(aacmm_calibrate_options_set_global_starts)"),
            "{c}"
        );
        let chi = r[11].describe(Spelling::Python);
        assert!(
            chi.contains(
                "the stated noise (Noise(encoder_deg=0.0050, probe_mm=0.0100, \
                 position_mm=0.0150, position_mm_per_m=0.0060, orientation_deg=0.0100))"
            ),
            "{chi}"
        );
        assert!(chi.contains("leave it unstated (noise=None)"), "{chi}");
        assert!(chi.ends_with("accept_poor_fit=True."), "{chi}");
        let chi = r[11].describe(Spelling::C);
        assert!(
            chi.contains("aacmm_calibrate_options_set_encoder_noise_rad(o, 8.7266e-5)"),
            "{chi}"
        );
        assert!(
            chi.contains("aacmm_calibrate_options_set_position_noise_mm(o, 0.0150, 0.0060)"),
            "{chi}"
        );
    }

    /// The misstated-noise case is the Birge ratio, both ways, with what
    /// leaving the noise unstated does; never "state it σ̂₀ times larger".
    #[test]
    fn a_misstated_noise_is_the_birge_ratio() {
        let r = reasons();
        let large = r[11].to_string();
        assert!(
            large.contains(
                "the Birge ratio σ̂₀ = √(χ²/dof) = 3.00: the residuals scatter 3.00 times what \
                 the stated noise (--encoder-noise 0.0050 --probe-noise 0.0100 --position-noise \
                 0.0150+0.0060/m --orientation-noise 0.0100) explains. If that noise is right, \
                 look for outliers (--robust names them) or a model error; if it is a guess, \
                 leave it unstated (without --encoder-noise, --probe-noise, --position-noise, \
                 --orientation-noise): σ is then estimated from these residuals"
            ),
            "{large}"
        );
        let small = r[12].to_string();
        assert!(
            small.contains("= 0.32: the residuals scatter 3.16 times less than the stated noise"),
            "{small}"
        );
        for t in [&large, &small] {
            assert!(
                !t.contains("times larger") && !t.contains("consistent with the"),
                "{t}"
            );
            assert!(
                t.ends_with("or accept the fit as it is with --accept-poor-fit."),
                "{t}"
            );
        }
        // Not sound (a wrong minimum): the test alone, no remedy.
        assert!(!r[13].to_string().contains("Birge"));
    }

    /// `calibration.json` keeps the sentences; read back, each is a
    /// recorded reason that says the same.
    #[test]
    fn a_verdict_is_written_as_its_sentences_and_read_back_as_them() {
        let v = Verdict {
            usable: false,
            reasons: reasons(),
            notes: notes(),
        };
        let json = serde_json::to_value(&v).unwrap();
        assert_eq!(json["usable"], false);
        assert_eq!(json["reasons"][2], reasons()[2].to_string());
        let back: Verdict = serde_json::from_value(json).unwrap();
        assert_eq!(back.words(Spelling::Cli), v.words(Spelling::Cli));
        assert!(back.reasons.iter().all(|r| r.kind() == "recorded"));
        // The kinds are the variants' JSON tags.
        for r in reasons() {
            assert_eq!(serde_json::to_value(&r).unwrap()["kind"], r.kind());
        }
        for n in notes() {
            assert_eq!(serde_json::to_value(&n).unwrap()["kind"], n.kind());
        }
    }
}
