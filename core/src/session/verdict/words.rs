//! The verdict in each front end's words ([`Spelling`]): every reason and
//! note said, with its remedy in the options of the front end that asks.

use crate::calibrate::checks::{ChiSquare, GrossCorrection, Outlier};

use super::{Note, Reason, Setting, Spelling, StatedNoise};

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
