//! What a calibration session found: the schema of `calibration.json`.

use serde::{Deserialize, Serialize};

use crate::calibrate::Calibration;
use crate::calibrate::validate::{BeforeAfter, Fold};
use crate::corrections::Physics;
use crate::domain::Arm;
use crate::residuals::Noise;

use super::{Verdict, spheres, tools};

/// Units of the values in a [`CalibrationReport`] meant for people.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Units {
    /// `mm`.
    pub lengths: String,
    /// `deg`.
    pub angles: String,
}

/// Held-out validation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct HeldOut {
    /// Its poses file.
    pub data_file: String,
    /// Its lengths file.
    pub(crate) lengths_file: Option<String>,
    /// Before and after there.
    pub figures: BeforeAfter,
    /// Its frames the fit does not have, each registered on its own
    /// positions (closed form, for each arm) because the user asked
    /// (`--register-held-out`): their figures are optimistic.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub registered_on_itself: Vec<String>,
}

/// Cross-validation over points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct CrossValidation {
    /// One entry per fold.
    pub folds: Vec<Fold>,
    /// Seed of the fold assignment.
    pub seed: u64,
}

/// The figures of the start and calibrated arms on the data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Validation {
    /// On the fitted data.
    pub fitted: BeforeAfter,
    /// On held-out data.
    pub held_out: Option<HeldOut>,
    /// Cross-validation folds.
    pub cross_validation: Option<CrossValidation>,
    /// Points on reference spheres held out (`--validate-spheres`); absent
    /// without them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_out_spheres: Option<spheres::HeldOutSpheres>,
}

/// Everything a calibration session found: the schema of
/// `calibration.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct CalibrationReport {
    /// The start arm's name.
    pub arm: String,
    /// Its file.
    pub arm_file: String,
    /// The poses file.
    pub data_file: String,
    /// The lengths file.
    pub(crate) lengths_file: Option<String>,
    /// The fixed set: `auto` or the names fixed.
    pub fix: String,
    /// The noise (internal units: rad, mm).
    pub noise: Noise,
    /// Seed of every random draw.
    pub seed: u64,
    /// Units of the parameter tables.
    pub units: Units,
    /// Touches fitted.
    pub touches: usize,
    /// Points fitted.
    pub points: usize,
    /// Reference lengths fitted.
    pub reference_lengths: usize,
    /// The reference-positions file, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) positions_file: Option<String>,
    /// Reference positions fitted.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub positions: usize,
    /// The calibration.
    pub calibration: Calibration,
    /// Before and after.
    pub validation: Validation,
    /// The readers' warnings.
    pub warnings: Vec<String>,
    /// Whether the calibration may be used, and if not, why.
    pub verdict: Verdict,
    /// The predicted position uncertainty over a sampled workspace
    /// ([`crate::plan::map`]); absent when the covariance is not finite.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty_map: Option<crate::plan::UncertaintyMap>,
    /// Points probed on reference spheres, when given: per sphere its
    /// centre, diameter and radial residuals.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spheres: Option<spheres::SphereReport>,
    /// Several tool points, when rows name them: per tool its offset ± σ
    /// and its rows' 3-D errors.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tools: Option<tools::ToolReport>,
    /// Touches by several probes, when the poses name them: per probe its
    /// offset ± σ and its touches' distances from their points' centres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub touch_tools: Option<tools::ToolReport>,
    /// The same poses as each fitted frame's instrument sees the probe,
    /// that frame's registration included
    /// ([`crate::plan::uncertainty_map_in_frame`]); absent without frames.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub uncertainty_maps_in_frames: Vec<crate::plan::UncertaintyMap>,
    /// The same poses at each tool point whose offset was fitted, its
    /// offset's uncertainty included
    /// ([`crate::plan::uncertainty_map_at_tool`]); absent without one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub uncertainty_maps_at_tools: Vec<crate::plan::UncertaintyMap>,
    /// The start arm, for [`CalibrationReport::calibrated_arm`]: its name,
    /// limits, physics and tools are not in `calibration.json`, so a
    /// report read back has none.
    #[serde(skip)]
    pub(super) start: Option<Box<Arm>>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl CalibrationReport {
    /// Whether the calibration is usable: the solver reached a confirmed
    /// minimum, the arm is the nominal arm's kind of geometry, and (unless
    /// a poor fit was accepted) the χ² test and the fitted data agree.
    pub fn is_usable(&self) -> bool {
        self.verdict.usable
    }

    /// The calibrated arm: named `<start>-calibrated`, with the start arm's
    /// joint limits and no tolerances (those were the nominal's; the
    /// calibration's σ are in the report). `None` for a report read back
    /// from `calibration.json`, which does not carry the start arm: give it
    /// to [`CalibrationReport::calibrated_arm_from`] then.
    pub fn calibrated_arm(&self) -> Option<Arm> {
        self.start
            .as_deref()
            .map(|start| self.calibrated_arm_from(start))
    }

    /// [`CalibrationReport::calibrated_arm`] from the start arm `start`
    /// (that of a report read back from `calibration.json`).
    pub fn calibrated_arm_from(&self, start: &Arm) -> Arm {
        Arm {
            name: format!("{}-calibrated", start.name),
            params: self.calibration.params.clone(),
            limits: start.limits.clone(),
            prior: None,
            // Drift belongs to the session, not to the arm.
            physics: match &self.calibration.physics {
                Some(p) => Box::new(Physics {
                    drift_mm_per_h: None,
                    ..p.clone()
                }),
                None => start.physics.clone(),
            },
            ball_diameter_mm: start.ball_diameter_mm,
            tools: self.calibrated_tools(start),
        }
    }

    /// The start arm's tools, each fitted one at its fitted offset (a tool
    /// no row named keeps its own).
    fn calibrated_tools(&self, start: &Arm) -> Vec<crate::domain::Tool> {
        let fitted = self.calibration.tool_offsets();
        (start.tools.iter())
            .map(|t| crate::domain::Tool {
                name: t.name.clone(),
                offset: (fitted.iter().find(|(n, _)| *n == t.name)).map_or(t.offset, |(_, x)| *x),
                ball_diameter_mm: t.ball_diameter_mm,
            })
            .collect()
    }
}
