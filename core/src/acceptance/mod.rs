//! The measuring arm's acceptance tests — ISO 10360-12 / ASME B89.4.22 —
//! from points probed on reference spheres, reference lengths between
//! sphere placements and touches of cones, each decided against a stated
//! maximum permissible error (MPE) the way ISO 14253-1 decides.
//!
//! The points are probe-ball **centres** (the arm's forward kinematics of
//! each touch); a sphere fitted to them has radius `R + r_ball`, `R` the
//! reference sphere's and `r_ball` the probe ball's. Every fit is the
//! geometric least-squares sphere (`fit_sphere_ls`).
//!
//! | figure | value | expanded uncertainty `U` (k = 2) |
//! |---|---|---|
//! | `P_Size.Sph.1x25::Art` | `2 (R_fit − r_ball) − D_cal` | `2 sqrt(u_D² + σ_D²)`, `σ_D = 2 σ_R` the fit's |
//! | `P_Form.Sph.1x25::Art` | `max r_i − min r_i` (radial residuals of the same fit) | `2 sqrt(u_D² + σ̂² gᵀ(JᵀJ)⁻¹g)`, `g` the difference of the two extreme points' Jacobian rows |
//! | `L_Dia.5x5::Art` | diameter of the smallest sphere enclosing the five articulations' centres | `2 sqrt(∇ᵀ C ∇ + (∂L/∂D · u_D)²)`: `C` the centres' covariance (σ pooled over the 25 points), `∇` the figure's gradient in them; the second term only with the diameter held |
//! | `E_Uni::Art` | `|c_a − c_b| − L_cal`, the centres of two placements' free fits | `2 sqrt(u_L² + n̂ᵀ(C_a + C_b)n̂)`, `n̂` along the length |
//! | `SPAT` | the largest `δ_max` over the cones ([`crate::metrics::PointStats`]) | 0: no calibrated value enters it |
//!
//! `u_D` is the sphere's stated standard uncertainty (k = 1,
//! `--sphere-uncertainty`, standing for its form too), `u_L` the length
//! file's `uncertainty` column (k = 1). `σ̂` is the fit's own `sqrt(Σ r² /
//! (n − p))`. The points' noise is part of `U` by design: a test on 25
//! noisy points is itself uncertain, and a guard band that ignored it would
//! call a noise-driven value a proof.
//!
//! **Decision** (ISO 14253-1): PASS when `|value| ≤ MPE − U`, FAIL when
//! `|value| ≥ MPE + U`, else INCONCLUSIVE; a test without an MPE is not
//! decided. `P_Size` and `P_Form` are computed at every placement of 25 or
//! more points that is neither articulated nor named by a length; the
//! reported one is the worst (a FAIL before an INCONCLUSIVE before a PASS,
//! then the largest `|value|`), every placement is listed.
//!
//! **L_Dia**: a placement whose `articulation` column has more than one
//! value is an L_Dia placement and must have exactly 5. Each group's centre
//! is fitted with the calibrated diameter held by default
//! ([`LDiaRadius::Held`]): five points on the patch one articulation
//! reaches fix a sphere's radius poorly, and a free radius trades against
//! the centre along the probe's direction — the centre then wanders by many
//! times the points' noise and the figure measures the fit, not the arm.
//! [`LDiaRadius::Free`] fits it (as a reading of the standard that fits a
//! full least-squares sphere to each set).
//!
//! **Prediction** ([`predict`]): each test's expected value and spread
//! from a calibration — Monte Carlo through its covariance and the noise
//! it stated, at the placements measured — and whether the measured value
//! lies within two spreads of it.

mod compute;
mod enclosing;
mod fit;
mod mpe;
mod predict;
mod table;

use serde::{Deserialize, Serialize};

pub use compute::verify;
pub(crate) use enclosing::enclosing_ball;
pub(crate) use fit::{FitError, SphereFit, fit_sphere_ls};
pub use mpe::{Limit, Mpe, TestKind, parse_mpe};
pub use predict::PredictionInfo;
pub use predict::{
    Calibrated, DEFAULT_DRAWS, Draws, Measured, PredictError, ReadingNoise, predict,
};

use crate::domain::Spheres;
use crate::error::{InputError, OptionError};

/// Points a sphere placement needs for `P_Size` and `P_Form` (ISO
/// 10360-12's 25-point pattern).
pub(crate) const P_TEST_POINTS: usize = 25;
/// Articulations of an `L_Dia` placement.
pub(crate) const L_DIA_GROUPS: usize = 5;

/// The figures' names, as the standards name them.
pub(crate) const P_SIZE: &str = "P_Size.Sph.1x25::Art";
/// See [`P_SIZE`].
pub(crate) const P_FORM: &str = "P_Form.Sph.1x25::Art";
/// See [`P_SIZE`].
pub(crate) const L_DIA: &str = "L_Dia.5x5::Art";
/// See [`P_SIZE`].
pub(crate) const E_UNI: &str = "E_Uni::Art";
/// See [`P_SIZE`].
pub(crate) const SPAT: &str = "SPAT";

/// How each articulation's centre of an `L_Dia` placement is fitted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum LDiaRadius {
    /// The calibrated diameter held (the default: see the module's
    /// documentation).
    #[default]
    Held,
    /// The radius fitted with the centre.
    Free,
}

/// ISO 14253-1's decision on one test.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Decision {
    /// `|value| ≤ MPE − U`: conformance proven.
    #[serde(rename = "PASS")]
    Pass,
    /// Neither proven.
    #[serde(rename = "INCONCLUSIVE")]
    Inconclusive,
    /// `|value| ≥ MPE + U`: non-conformance proven.
    #[serde(rename = "FAIL")]
    Fail,
}

impl Decision {
    /// The decision on `value` against `mpe` with the guard band `u`.
    ///
    /// ```
    /// use aacmm_core::acceptance::Decision;
    /// assert_eq!(Decision::of(0.005, 0.010, 0.004), Decision::Pass);
    /// assert_eq!(Decision::of(-0.008, 0.010, 0.004), Decision::Inconclusive);
    /// assert_eq!(Decision::of(0.014, 0.010, 0.004), Decision::Fail);
    /// ```
    pub fn of(value: f64, mpe: f64, u: f64) -> Decision {
        let v = value.abs();
        if v <= mpe - u {
            Decision::Pass
        } else if v >= mpe + u {
            Decision::Fail
        } else {
            Decision::Inconclusive
        }
    }

    /// As printed.
    pub(crate) fn word(self) -> &'static str {
        match self {
            Decision::Pass => "PASS",
            Decision::Inconclusive => "INCONCLUSIVE",
            Decision::Fail => "FAIL",
        }
    }
}

/// A value and spread a calibration predicts for a test ([`predict`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Predicted {
    /// The expected value, mm.
    pub value: f64,
    /// Its standard deviation, mm.
    pub spread: f64,
    /// Whether the measured value lies within two spreads of it:
    /// `|measured − value| ≤ 2 spread` (the arm performs as its
    /// calibration says).
    pub agrees: bool,
}

/// One test's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TestResult {
    /// The test.
    pub test: TestKind,
    /// Its figure's name as the standard names it.
    pub figure: String,
    /// Where: the placement(s), or the length's `file:line`.
    pub at: String,
    /// The value, mm.
    pub value: f64,
    /// The test length of `E_Uni`, mm.
    pub length: Option<f64>,
    /// The MPE, mm, when stated.
    pub mpe: Option<f64>,
    /// The expanded uncertainty (k = 2), mm.
    pub u: f64,
    /// The decision, when an MPE is stated.
    pub decision: Option<Decision>,
    /// The calibration's prediction, when made.
    pub predicted: Option<Predicted>,
}

impl TestResult {
    fn new(test: TestKind, figure: &str, at: String, value: f64, u: f64, mpe: &Mpe) -> TestResult {
        TestResult {
            test,
            figure: figure.to_string(),
            at,
            value,
            length: None,
            mpe: None,
            u,
            decision: None,
            predicted: None,
        }
        .decided(mpe, 0.0)
    }

    /// With the MPE of `mpe` at test length `l` and its decision.
    fn decided(mut self, mpe: &Mpe, l: f64) -> TestResult {
        self.mpe = mpe.of(self.test).map(|m| m.at(l));
        self.decision = self.mpe.map(|m| Decision::of(self.value, m, self.u));
        self
    }

    /// How bad, for picking the worst: the decision, then `|value|`.
    fn badness(&self) -> (Option<Decision>, f64) {
        (self.decision, self.value.abs())
    }
}

/// What each placement is used for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub(crate) enum Use {
    /// `P_Size` and `P_Form`.
    Probing,
    /// `L_Dia` (an articulation column with 5 groups).
    Articulated,
    /// A centre for `E_Uni` (named by a length).
    Length,
}

/// One placement's least-squares sphere (every point, radius free).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// Its label.
    pub name: String,
    /// Its first line in the sphere file.
    pub line: usize,
    /// What it is used for.
    pub(crate) used_for: Use,
    /// Points.
    pub points: usize,
    /// The fit.
    pub(crate) fit: SphereFit,
    /// The sphere's diameter seen, `2 (R_fit − r_ball)`, mm.
    pub(crate) diameter: f64,
    /// `P_Size` and `P_Form` here (a probing placement's).
    pub tests: Vec<TestResult>,
}

/// One `L_Dia` placement's articulations.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LDiaPlacement {
    /// Its label.
    pub name: String,
    /// Per articulation (in increasing order): its number and fitted
    /// centre, mm.
    pub centres: Vec<(u32, [f64; 3])>,
    /// The smallest sphere enclosing them: centre, mm.
    pub(crate) enclosing_centre: [f64; 3],
    /// σ̂ pooled over the placement's points, mm.
    pub sigma: f64,
}

/// One cone of the SPAT.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpatPoint {
    /// The cone's label.
    pub label: String,
    /// Touches.
    pub touches: usize,
    /// `δ_max`, mm.
    pub delta_max: f64,
    /// `2s`, mm.
    pub two_s: f64,
    /// `(max − min)/2` of X, Y and Z, mm.
    pub half_range: [f64; 3],
}

/// The acceptance tests' results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Acceptance {
    /// The sphere file.
    pub sphere_file: String,
    /// The calibrated sphere diameter, mm.
    pub sphere_diameter: f64,
    /// Its standard uncertainty (k = 1), mm.
    pub sphere_uncertainty: f64,
    /// The probe ball's diameter, mm.
    pub ball_diameter: f64,
    /// How `L_Dia` fitted each articulation.
    pub l_dia_radius: LDiaRadius,
    /// The MPEs stated.
    pub mpe: Mpe,
    /// The tests: the worst `P_Size` and `P_Form`, every `L_Dia`, every
    /// `E_Uni`, the SPAT.
    pub tests: Vec<TestResult>,
    /// Tests an MPE is stated for that no data tested.
    pub untested: Vec<TestKind>,
    /// Every placement's fit.
    pub placements: Vec<Placement>,
    /// Every `L_Dia` placement's centres.
    pub l_dia: Vec<LDiaPlacement>,
    /// Every cone of the SPAT.
    pub spat: Vec<SpatPoint>,
    /// What the predictions were made from; absent without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prediction: Option<PredictionInfo>,
}

impl Acceptance {
    /// Whether any MPE was stated (else nothing is decided).
    pub(crate) fn decided(&self) -> bool {
        !self.mpe.is_empty()
    }

    /// The tests with an MPE that did not pass, and the tests an MPE is
    /// stated for that nothing tested: empty when the arm is accepted.
    pub fn not_passed(&self) -> Vec<String> {
        let mut out: Vec<String> = (self.tests.iter())
            .filter(|t| t.decision.is_some_and(|d| d != Decision::Pass))
            .map(|t| {
                format!(
                    "{} at {}: {}",
                    t.figure,
                    t.at,
                    t.decision.map_or("", Decision::word)
                )
            })
            .collect();
        out.extend(
            (self.untested.iter())
                .map(|t| format!("{}: an MPE is stated, no data tested it", t.key())),
        );
        out
    }
}

/// What the tests are computed from: the settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The calibrated sphere diameter, mm.
    pub sphere_diameter: f64,
    /// Its standard uncertainty (k = 1), mm.
    pub sphere_uncertainty: f64,
    /// The probe ball's diameter, mm.
    pub ball_diameter: f64,
    /// How `L_Dia` fits each articulation.
    pub l_dia_radius: LDiaRadius,
    /// The MPEs.
    pub mpe: Mpe,
}

/// The sphere points: rows, their file, and each row's probe centre (mm).
#[derive(Clone, Copy, Debug)]
pub struct SpherePoints<'a> {
    /// The rows.
    pub rows: &'a Spheres,
    /// Their file, as messages name it.
    pub file: &'a str,
    /// Per row, the probe centre the arm computes, mm.
    pub centres: &'a [[f64; 3]],
}

/// Why the tests cannot be computed.
#[derive(Debug, thiserror::Error)]
pub enum AcceptanceError {
    /// An input file's fault, by file, line and field.
    #[error(transparent)]
    Input(#[from] InputError),
    /// A setting's.
    #[error(transparent)]
    Option(#[from] OptionError),
}
