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
}

/// One setting's names.
struct Names {
    /// The library's path ([`crate::error::OptionError::field`]).
    path: Option<&'static str>,
    /// The command line's flag (or its words for what no flag sets).
    flag: &'static str,
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
    path: Option<&'static str>,
    flag: &'static str,
    python: Option<&'static str>,
    c: Option<&'static str>,
    remedy: [&'static str; 3],
) -> Names {
    Names {
        path,
        flag,
        python,
        c,
        remedy,
    }
}

/// A setting only the command line sets: no Python or C name, its remedy
/// the flag everywhere but in the library's path.
const fn cli_only(path: &'static str, flag: &'static str) -> Names {
    row(Some(path), flag, None, None, [flag, path, path])
}

/// Every front end's name of each setting, one row per setting.
const TABLE: [(Setting, Names); 43] = [
    (
        Setting::EncoderNoise,
        row(
            Some("noise.encoder_rad"),
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
            Some("noise.probe_mm"),
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
            Some("noise.length_default_mm"),
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
            Some("noise.length_weight"),
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
            Some("noise.position_mm"),
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
            Some("noise.position_mm_per_m"),
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
            Some("noise.orientation_rad"),
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
            Some("robust.loss"),
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
            Some("robust.scale_k"),
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
            None,
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
            Some("method"),
            "--method",
            Some("method"),
            None,
            ["--method", "method=…", "aacmm_calibrate_options_set_method"],
        ),
    ),
    (
        Setting::Seed,
        row(
            Some("seed"),
            "--seed",
            Some("seed"),
            None,
            ["--seed", "seed=…", "aacmm_calibrate_options_set_seed"],
        ),
    ),
    (
        Setting::Threads,
        row(
            Some("threads"),
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
            Some("cross_validate"),
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
            Some("prior"),
            "--prior",
            Some("prior"),
            Some("prior"),
            ["--prior", "prior=…", "aacmm_calibrate_options_set_prior"],
        ),
    ),
    (
        Setting::Fix,
        row(
            Some("fix"),
            "--fix",
            Some("fix"),
            Some("fix"),
            ["--fix", "fix=…", "aacmm_calibrate_options_set_fix"],
        ),
    ),
    (
        Setting::Lengths,
        row(
            None,
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
            None,
            "--angle-unit",
            Some("angle_unit"),
            None,
            ["--angle-unit rad", "angle_unit=\"rad\"", "AACMM_ANGLE_RAD"],
        ),
    ),
    (
        Setting::Compliance,
        row(
            Some("compliance"),
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
            Some("harmonics"),
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
            Some("backlash"),
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
            Some("thermal"),
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
            Some("drift"),
            "--drift",
            Some("drift"),
            Some("drift"),
            ["--drift", "drift=True", "aacmm_calibrate_options_set_drift"],
        ),
    ),
    (
        Setting::SphereDiameter,
        row(
            Some("sphere_diameter_mm"),
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
            Some("sphere_uncertainty"),
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
            Some("mpe"),
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
            Some("prediction.draws"),
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
            Some("tool"),
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
            Some("global.max_starts"),
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
];

impl Setting {
    /// Every setting.
    pub const ALL: [Setting; 43] = [
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
    pub fn name(self, spelling: Spelling) -> &'static str {
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
            Spelling::Cli => Some(n.flag),
            Spelling::Python => n.python,
            Spelling::C => n.c,
        }
    }

    /// The library's path of the setting (`noise.encoder_rad`,
    /// `global.max_starts`), where a settings struct holds it.
    pub fn path(self) -> Option<&'static str> {
        self.names().path
    }

    /// The setting at `path` ([`Setting::path`]).
    pub fn at_path(path: &str) -> Option<Setting> {
        Setting::ALL.into_iter().find(|s| s.path() == Some(path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_path_names_one_setting_and_no_python_or_c_name_is_a_flag() {
        let mut paths = std::collections::BTreeSet::new();
        for s in Setting::ALL {
            if let Some(p) = s.path() {
                assert_eq!(Setting::at_path(p), Some(s));
                paths.insert(p);
            }
            for spelling in [Spelling::Python, Spelling::C] {
                assert!(!s.name(spelling).contains("--"), "{s:?}");
                assert!(!s.argument(spelling).unwrap_or("").contains("--"), "{s:?}");
            }
            let cli = s.name(Spelling::Cli);
            assert!(cli.starts_with("--") || cli.starts_with('('), "{s:?}");
        }
        assert!(paths.len() >= 35, "{}", paths.len());
        let distinct: std::collections::BTreeSet<String> =
            Setting::ALL.iter().map(|s| format!("{s:?}")).collect();
        assert_eq!(distinct.len(), Setting::ALL.len());
    }
}
