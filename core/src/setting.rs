//! Every option a user sets, named once for every front end: the library's
//! path (what [`crate::error::OptionError::field`] says), the command
//! line's flag, the Python argument and the C setter's. A refused option
//! ([`crate::error::OptionError::setting`]) and a verdict's remedy
//! ([`crate::session::Reason`]) are said in the words of the front end that
//! asks ([`Spelling`]), from this one table.

use serde::{Deserialize, Serialize};

/// Whose words: the front end's own spelling of the options.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Spelling {
    /// `aacmm calibrate`'s flags (`--robust`).
    Cli,
    /// The Python module's keyword arguments (`robust="huber"`).
    Python,
    /// The C API's setters (`aacmm_calibrate_options_set_robust`).
    C,
}

/// An option a user sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Setting {
    /// The encoders' noise.
    EncoderNoise,
    /// The probe's noise.
    ProbeNoise,
    /// A reference length's default uncertainty.
    LengthUncertainty,
    /// The reference lengths' weight.
    LengthWeight,
    /// A reference position's noise (its constant part).
    PositionNoise,
    /// A reference position's noise growth with distance.
    PositionNoisePerMetre,
    /// A reference orientation's noise.
    OrientationNoise,
    /// A robust loss.
    Robust,
    /// The robust loss's tuning constant.
    RobustScale,
    /// Accepting a fit the χ² test refuses.
    AcceptPoorFit,
    /// The solver.
    Method,
    /// The seed.
    Seed,
    /// Worker threads.
    Threads,
    /// Cross-validation folds.
    CrossValidate,
    /// Tolerances for the parameters (a prior).
    Prior,
    /// The fixed set.
    Fix,
    /// Reference lengths.
    Lengths,
    /// The readings' angle unit, as radians.
    AngleUnitRad,
    /// Fitted joint compliances.
    Compliance,
    /// Fitted encoder harmonics.
    Harmonics,
    /// Fitted backlash.
    Backlash,
    /// A fitted thermal expansion.
    Thermal,
    /// A fitted drift.
    Drift,
    /// The reference spheres' stated diameter.
    SphereDiameter,
    /// The reference sphere's calibration uncertainty (`aacmm verify`).
    SphereUncertainty,
    /// The acceptance tests' maximum permissible errors (`aacmm verify`).
    Mpe,
    /// The probe (a `[[tool]]`) a command computes with.
    Tool,
    /// The draws of an acceptance test's prediction (`aacmm verify
    /// --calibration`).
    PredictionDraws,
    /// The global search's random starts.
    GlobalStarts,
    /// The global search's confirmations.
    GlobalConfirmations,
    /// LM's iterations per global start.
    GlobalStartIterations,
    /// LM's iteration limit.
    LmIterations,
    /// The annealer's start temperature.
    AnnealT0,
    /// The annealer's cooling factor.
    AnnealCooling,
    /// The annealer's chain length.
    AnnealChain,
    /// The annealer's end temperature.
    AnnealTMin,
    /// The annealer's target cost.
    AnnealTarget,
    /// The annealer's length step.
    AnnealStepMm,
    /// The annealer's twist step.
    AnnealTwistStep,
    /// The annealer's zero-offset step.
    AnnealZeroStep,
    /// The annealer's evaluation budget.
    AnnealMaxEvaluations,
    /// The hybrid's switching window.
    SwitchWindow,
    /// The hybrid's switching threshold.
    SwitchEpsilon,
    /// LM's relative cost tolerance (the library's only).
    LmFtol,
    /// LM's relative step tolerance (the library's only).
    LmXtol,
    /// LM's gradient tolerance (the library's only).
    LmGtol,
    /// The global search's grid cells per zero offset (the library's only).
    GlobalGridCells,
    /// The global search's noise floor, in stated σ (the library's only).
    GlobalNoiseFloorK,
    /// The arm's stated thermal expansion coefficient (its file's
    /// `cte_per_k`).
    CtePerK,
    /// The placements leave-one-placement-out validation deals (the
    /// points' labels).
    Placements,
    /// The probe's ball diameter the acceptance tests use.
    BallDiameter,
}

/// One setting's names.
struct Names {
    /// The library's path ([`crate::error::OptionError::field`]).
    path: &'static str,
    /// The command line's flag (or its words for what no flag sets);
    /// `None` for a setting of the library's only.
    flag: Option<&'static str>,
    /// The Python argument, where Python exposes it.
    python: Option<&'static str>,
    /// The C argument (as its setter names it), where C exposes it.
    c: Option<&'static str>,
    /// As a remedy names it: a flag (with a placeholder value where the
    /// flag needs one), a keyword argument, a setter.
    remedy: [&'static str; 3],
}

/// A row of the table.
const fn row(
    path: &'static str,
    flag: &'static str,
    python: Option<&'static str>,
    c: Option<&'static str>,
    remedy: [&'static str; 3],
) -> Names {
    Names {
        path,
        flag: Some(flag),
        python,
        c,
        remedy,
    }
}

/// A setting only the command line sets: no Python or C name, its remedy
/// the flag everywhere but in the library's path.
const fn cli_only(path: &'static str, flag: &'static str) -> Names {
    row(path, flag, None, None, [flag, path, path])
}

/// A setting only the library's settings structs hold: no front end's
/// argument sets it, and a refusal of it names its path.
const fn library_only(path: &'static str) -> Names {
    const WORDS: &str = "(the library's only)";
    Names {
        path,
        flag: None,
        python: None,
        c: None,
        remedy: [WORDS; 3],
    }
}

/// Every front end's name of each setting, one row per setting.
const TABLE: [(Setting, Names); 51] = [
    (
        Setting::EncoderNoise,
        row(
            "noise.encoder_rad",
            "--encoder-noise",
            Some("encoder_deg"),
            Some("encoder_noise_rad"),
            [
                "--encoder-noise",
                "Noise(encoder_deg=…)",
                "aacmm_calibrate_options_set_encoder_noise_rad",
            ],
        ),
    ),
    (
        Setting::ProbeNoise,
        row(
            "noise.probe_mm",
            "--probe-noise",
            Some("probe_mm"),
            Some("probe_noise_mm"),
            [
                "--probe-noise",
                "Noise(probe_mm=…)",
                "aacmm_calibrate_options_set_probe_noise_mm",
            ],
        ),
    ),
    (
        Setting::LengthUncertainty,
        row(
            "noise.length_default_mm",
            "--length-uncertainty",
            Some("length_default_mm"),
            Some("length_uncertainty_mm"),
            [
                "--length-uncertainty",
                "Noise(length_default_mm=…)",
                "aacmm_calibrate_options_set_length_uncertainty_mm",
            ],
        ),
    ),
    (
        Setting::LengthWeight,
        row(
            "noise.length_weight",
            "--length-weight",
            Some("length_weight"),
            Some("length_weight"),
            [
                "--length-weight",
                "Noise(length_weight=…)",
                "aacmm_calibrate_options_set_length_weight",
            ],
        ),
    ),
    (
        Setting::PositionNoise,
        row(
            "noise.position_mm",
            "--position-noise",
            Some("position_mm"),
            Some("position_noise a_mm"),
            [
                "--position-noise",
                "Noise(position_mm=…)",
                "aacmm_calibrate_options_set_position_noise_mm",
            ],
        ),
    ),
    (
        Setting::PositionNoisePerMetre,
        row(
            "noise.position_mm_per_m",
            "--position-noise",
            Some("position_mm_per_m"),
            Some("position_noise b_mm_per_m"),
            [
                "--position-noise",
                "Noise(position_mm_per_m=…)",
                "aacmm_calibrate_options_set_position_noise_mm",
            ],
        ),
    ),
    (
        Setting::OrientationNoise,
        row(
            "noise.orientation_rad",
            "--orientation-noise",
            Some("orientation_deg"),
            Some("orientation_noise_rad"),
            [
                "--orientation-noise",
                "Noise(orientation_deg=…)",
                "aacmm_calibrate_options_set_orientation_noise_rad",
            ],
        ),
    ),
    (
        Setting::Robust,
        row(
            "robust.loss",
            "--robust",
            Some("robust"),
            None,
            [
                "--robust",
                "robust=\"huber\"",
                "aacmm_calibrate_options_set_robust",
            ],
        ),
    ),
    (
        Setting::RobustScale,
        row(
            "robust.scale_k",
            "--robust-scale",
            Some("robust_scale"),
            Some("robust scale"),
            [
                "--robust-scale",
                "robust_scale=…",
                "aacmm_calibrate_options_set_robust",
            ],
        ),
    ),
    (
        Setting::AcceptPoorFit,
        row(
            "accept_poor_fit",
            "--accept-poor-fit",
            Some("accept_poor_fit"),
            None,
            [
                "--accept-poor-fit",
                "accept_poor_fit=True",
                "aacmm_calibrate_options_set_accept_poor_fit",
            ],
        ),
    ),
    (
        Setting::Method,
        row(
            "method",
            "--method",
            Some("method"),
            None,
            ["--method", "method=…", "aacmm_calibrate_options_set_method"],
        ),
    ),
    (
        Setting::Seed,
        row(
            "seed",
            "--seed",
            Some("seed"),
            None,
            ["--seed", "seed=…", "aacmm_calibrate_options_set_seed"],
        ),
    ),
    (
        Setting::Threads,
        row(
            "threads",
            "--threads",
            Some("threads"),
            Some("threads"),
            [
                "--threads",
                "threads=…",
                "aacmm_calibrate_options_set_threads",
            ],
        ),
    ),
    (
        Setting::CrossValidate,
        row(
            "cross_validate",
            "--cross-validate",
            Some("cross_validate"),
            Some("cross_validate"),
            [
                "--cross-validate",
                "cross_validate=…",
                "aacmm_calibrate_options_set_cross_validate",
            ],
        ),
    ),
    (
        Setting::Prior,
        row(
            "prior",
            "--prior",
            Some("prior"),
            Some("prior"),
            ["--prior", "prior=…", "aacmm_calibrate_options_set_prior"],
        ),
    ),
    (
        Setting::Fix,
        row(
            "fix",
            "--fix",
            Some("fix"),
            Some("fix"),
            ["--fix", "fix=…", "aacmm_calibrate_options_set_fix"],
        ),
    ),
    (
        Setting::Lengths,
        row(
            "lengths",
            "--lengths",
            None,
            None,
            [
                "--lengths",
                "the data set's lengths",
                "the lengths file of aacmm_calibrate_files",
            ],
        ),
    ),
    (
        Setting::AngleUnitRad,
        row(
            "angle_unit",
            "--angle-unit",
            Some("angle_unit"),
            None,
            ["--angle-unit rad", "angle_unit=\"rad\"", "AACMM_ANGLE_RAD"],
        ),
    ),
    (
        Setting::Compliance,
        row(
            "compliance",
            "--compliance",
            Some("compliance"),
            Some("compliance"),
            [
                "--compliance",
                "compliance=…",
                "aacmm_calibrate_options_set_compliance",
            ],
        ),
    ),
    (
        Setting::Harmonics,
        row(
            "harmonics",
            "--harmonics",
            Some("harmonics"),
            Some("harmonics"),
            [
                "--harmonics",
                "harmonics=…",
                "aacmm_calibrate_options_set_harmonics",
            ],
        ),
    ),
    (
        Setting::Backlash,
        row(
            "backlash",
            "--backlash",
            Some("backlash"),
            Some("backlash"),
            [
                "--backlash",
                "backlash=…",
                "aacmm_calibrate_options_set_backlash",
            ],
        ),
    ),
    (
        Setting::Thermal,
        row(
            "thermal",
            "--thermal",
            Some("thermal"),
            Some("thermal"),
            [
                "--thermal",
                "thermal=True",
                "aacmm_calibrate_options_set_thermal",
            ],
        ),
    ),
    (
        Setting::Drift,
        row(
            "drift",
            "--drift",
            Some("drift"),
            Some("drift"),
            ["--drift", "drift=True", "aacmm_calibrate_options_set_drift"],
        ),
    ),
    (
        Setting::SphereDiameter,
        row(
            "sphere_diameter_mm",
            "--sphere-diameter",
            None,
            None,
            [
                "--sphere-diameter",
                "sphere_diameter=…",
                "aacmm_calibrate_options_set_sphere_diameter_mm",
            ],
        ),
    ),
    (
        Setting::SphereUncertainty,
        row(
            "sphere_uncertainty",
            "--sphere-uncertainty",
            None,
            None,
            [
                "--sphere-uncertainty U",
                "(the command line's verify only)",
                "(the command line's verify only)",
            ],
        ),
    ),
    (
        Setting::Mpe,
        row(
            "mpe",
            "--mpe",
            None,
            None,
            [
                "--mpe SPEC",
                "(the command line's verify only)",
                "(the command line's verify only)",
            ],
        ),
    ),
    (
        Setting::PredictionDraws,
        row(
            "prediction.draws",
            "--draws",
            None,
            None,
            [
                "--draws N",
                "(the command line's verify only)",
                "(the command line's verify only)",
            ],
        ),
    ),
    (
        Setting::Tool,
        row(
            "tool",
            "--tool",
            None,
            None,
            [
                "--tool NAME",
                "(the command line's only)",
                "(the command line's only)",
            ],
        ),
    ),
    (
        Setting::GlobalStarts,
        row(
            "global.max_starts",
            "--global-starts",
            Some("global_starts"),
            Some("global_starts"),
            [
                "--global-starts N",
                "global_starts=N",
                "aacmm_calibrate_options_set_global_starts",
            ],
        ),
    ),
    (
        Setting::GlobalConfirmations,
        cli_only("global.confirmations", "--global-confirmations"),
    ),
    (
        Setting::GlobalStartIterations,
        cli_only("global.start_iterations", "(LM iterations per start)"),
    ),
    (
        Setting::LmIterations,
        cli_only("lm.max_iterations", "(LM iteration limit)"),
    ),
    (Setting::AnnealT0, cli_only("anneal.t0", "--sa-t0")),
    (
        Setting::AnnealCooling,
        cli_only("anneal.cooling", "--sa-cooling"),
    ),
    (Setting::AnnealChain, cli_only("anneal.chain", "--sa-chain")),
    (Setting::AnnealTMin, cli_only("anneal.t_min", "--sa-t-min")),
    (
        Setting::AnnealTarget,
        cli_only("anneal.target", "--sa-target"),
    ),
    (
        Setting::AnnealStepMm,
        cli_only("anneal.step_mm", "--sa-step-mm"),
    ),
    (
        Setting::AnnealTwistStep,
        cli_only("anneal.twist_step_deg", "--sa-twist-step"),
    ),
    (
        Setting::AnnealZeroStep,
        cli_only("anneal.zero_step_deg", "--sa-zero-step"),
    ),
    (
        Setting::AnnealMaxEvaluations,
        cli_only("anneal.max_evaluations", "--sa-max-evaluations"),
    ),
    (
        Setting::SwitchWindow,
        cli_only("switch.window", "--switch-window"),
    ),
    (
        Setting::SwitchEpsilon,
        cli_only("switch.epsilon", "--switch-epsilon"),
    ),
    (Setting::LmFtol, library_only("lm.ftol")),
    (Setting::LmXtol, library_only("lm.xtol")),
    (Setting::LmGtol, library_only("lm.gtol")),
    (Setting::GlobalGridCells, library_only("global.grid_cells")),
    (
        Setting::GlobalNoiseFloorK,
        library_only("global.noise_floor_k"),
    ),
    (Setting::CtePerK, library_only("cte_per_k")),
    (Setting::Placements, library_only("placements")),
    (Setting::BallDiameter, library_only("ball_diameter_mm")),
];

impl Setting {
    /// Every setting.
    pub const ALL: [Setting; 51] = [
        Setting::EncoderNoise,
        Setting::ProbeNoise,
        Setting::LengthUncertainty,
        Setting::LengthWeight,
        Setting::PositionNoise,
        Setting::PositionNoisePerMetre,
        Setting::OrientationNoise,
        Setting::Robust,
        Setting::RobustScale,
        Setting::AcceptPoorFit,
        Setting::Method,
        Setting::Seed,
        Setting::Threads,
        Setting::CrossValidate,
        Setting::Prior,
        Setting::Fix,
        Setting::Lengths,
        Setting::AngleUnitRad,
        Setting::Compliance,
        Setting::Harmonics,
        Setting::Backlash,
        Setting::Thermal,
        Setting::Drift,
        Setting::SphereDiameter,
        Setting::SphereUncertainty,
        Setting::Mpe,
        Setting::Tool,
        Setting::PredictionDraws,
        Setting::GlobalStarts,
        Setting::GlobalConfirmations,
        Setting::GlobalStartIterations,
        Setting::LmIterations,
        Setting::AnnealT0,
        Setting::AnnealCooling,
        Setting::AnnealChain,
        Setting::AnnealTMin,
        Setting::AnnealTarget,
        Setting::AnnealStepMm,
        Setting::AnnealTwistStep,
        Setting::AnnealZeroStep,
        Setting::AnnealMaxEvaluations,
        Setting::SwitchWindow,
        Setting::SwitchEpsilon,
        Setting::LmFtol,
        Setting::LmXtol,
        Setting::LmGtol,
        Setting::GlobalGridCells,
        Setting::GlobalNoiseFloorK,
        Setting::CtePerK,
        Setting::Placements,
        Setting::BallDiameter,
    ];

    /// Its row of [`TABLE`].
    fn names(self) -> &'static Names {
        // Invariant: every setting has its row (tested).
        let row = TABLE.iter().find(|(s, _)| *s == self);
        &row.expect("a row for every setting").1
    }

    /// The option as `spelling` names it in a remedy: a flag (with a
    /// placeholder value where the flag needs one), a keyword argument, a
    /// setter.
    pub(crate) fn name(self, spelling: Spelling) -> &'static str {
        let [cli, python, c] = self.names().remedy;
        match spelling {
            Spelling::Cli => cli,
            Spelling::Python => python,
            Spelling::C => c,
        }
    }

    /// The argument that sets it, as `spelling` names it in an error
    /// (`--encoder-noise`, `encoder_deg`, `encoder_noise_rad`); `None`
    /// where that front end does not set it.
    pub fn argument(self, spelling: Spelling) -> Option<&'static str> {
        let n = self.names();
        match spelling {
            Spelling::Cli => n.flag,
            Spelling::Python => n.python,
            Spelling::C => n.c,
        }
    }

    /// The library's name of the setting: its path in the settings
    /// struct that holds it (`noise.encoder_rad`, `global.max_starts`,
    /// `accept_poor_fit`), or the input's that no struct holds (`lengths`,
    /// `angle_unit`). A refused option is named by it
    /// ([`crate::error::OptionError`]'s text).
    pub(crate) fn path(self) -> &'static str {
        self.names().path
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_path_names_one_setting_and_no_python_or_c_name_is_a_flag() {
        let mut paths = std::collections::BTreeSet::new();
        for s in Setting::ALL {
            // A refusal is named by its path: two settings must not share one.
            assert!(paths.insert(s.path()), "{s:?}: {} taken", s.path());
            for spelling in [Spelling::Python, Spelling::C] {
                assert!(!s.name(spelling).contains("--"), "{s:?}");
                assert!(!s.argument(spelling).unwrap_or("").contains("--"), "{s:?}");
            }
            let cli = s.name(Spelling::Cli);
            assert!(cli.starts_with("--") || cli.starts_with('('), "{s:?}");
        }
        assert_eq!(paths.len(), Setting::ALL.len());
        let distinct: std::collections::BTreeSet<String> =
            Setting::ALL.iter().map(|s| format!("{s:?}")).collect();
        assert_eq!(distinct.len(), Setting::ALL.len());
        let rows: std::collections::BTreeSet<String> =
            TABLE.iter().map(|(s, _)| format!("{s:?}")).collect();
        assert_eq!(rows.len(), TABLE.len(), "a setting with two rows");
    }

    /// A setting no front end's argument sets is refused by its path in
    /// every front end (none has its own word for it), and the library's
    /// text names it so.
    #[test]
    fn a_setting_of_the_librarys_only_is_named_by_its_path() {
        let library_only: Vec<Setting> = (Setting::ALL.into_iter())
            .filter(|s| s.argument(Spelling::Cli).is_none())
            .collect();
        assert_eq!(library_only.len(), 8, "{library_only:?}");
        for s in library_only {
            for spelling in [Spelling::Python, Spelling::C] {
                assert_eq!(s.argument(spelling), None, "{s:?}");
            }
            let e = crate::error::OptionError::new(s, 1, "why");
            assert_eq!(e.to_string(), format!("{} = 1: why", s.path()));
        }
        let e = crate::error::OptionError::new(Setting::LmFtol, -1, "must be ≥ 0");
        assert_eq!(e.field(), "lm.ftol");
        assert_eq!(e.to_string(), "lm.ftol = -1: must be ≥ 0");
        // A setting a front end sets keeps its argument there.
        assert_eq!(
            Setting::GlobalStarts.argument(Spelling::Cli),
            Some("--global-starts")
        );
        assert_eq!(Setting::GlobalConfirmations.argument(Spelling::C), None);
    }
}
