//! Leave-one-placement-out validation, for touch campaigns recorded the way
//! robot users record them: a small tool with a few sockets (MUKCa's: two,
//! 50 mm apart) set down at several places ("placements") in the arm's
//! workspace, every socket touched in many poses.
//!
//! A point's placement is its label up to the last `-` (`front-h0` and
//! `front-h1` are the two sockets of placement `front`; a label without `-`
//! is a placement of its own). Each placement in turn is held out: the arm is
//! calibrated on the touches and reference lengths of all the others, and
//! the held-out placement is scored with the start (nominal) arm and with the
//! calibrated one — its consistency (the paper's `e`: mean distance of a
//! socket's touches to their centroid, averaged over its sockets) and, where
//! it has a reference length, the distance error `|d − L|`. Both figures are
//! invariant under rigid motions of the arm's base, so the base frame of the
//! nominal arm does not matter.

use serde::{Deserialize, Serialize};

use super::{Figures, figures};
use crate::calibrate::{CalibrationError, ModelOptions, SolverSettings, calibrate};
use crate::dataset::DataSet;
use crate::error::OptionError;
use crate::params::DhParams;
use crate::setting::Setting;

/// The placement of a point label: up to the last `-`.
///
/// ```
/// use aacmm_core::calibrate::validate::placements::placement_of;
/// assert_eq!(placement_of("right-high-h1"), "right-high");
/// assert_eq!(placement_of("S1"), "S1");
/// ```
pub fn placement_of(label: &str) -> &str {
    label.rsplit_once('-').map_or(label, |(p, _)| p)
}

/// One held-out placement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacementFold {
    /// The placement held out.
    pub placement: String,
    /// Its sockets (point labels).
    pub sockets: Vec<String>,
    /// Its touches.
    pub touches: usize,
    /// Touches the arm was calibrated on (all other placements).
    pub trained_touches: usize,
    /// Reference lengths it was calibrated on.
    pub trained_lengths: usize,
    /// The held-out figures of the start arm.
    pub nominal: Figures,
    /// The held-out figures of the arm calibrated without this placement.
    pub calibrated: Figures,
    /// Whether that calibration converged.
    pub successful: bool,
    /// Parameters that calibration moved past the plausibility check
    /// ([`crate::calibrate::checks::gross_corrections`]): what would make
    /// the command line refuse it. Empty for a plausible arm.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub implausible: Vec<String>,
}

/// Means over the folds, and the relative change.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacementSummary {
    /// Mean held-out consistency (`e`), start arm, mm.
    pub consistency_nominal: f64,
    /// Mean held-out consistency, calibrated arms, mm.
    pub consistency_calibrated: f64,
    /// Mean held-out `|d − L|` over folds with a reference length, start
    /// arm, mm; `None` if no held-out placement has one.
    pub distance_nominal: Option<f64>,
    /// The same, calibrated arms.
    pub distance_calibrated: Option<f64>,
}

impl PlacementSummary {
    /// The means of `folds` (not empty).
    pub fn of(folds: &[PlacementFold]) -> PlacementSummary {
        let mean = |v: Vec<f64>| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let with_length: Vec<&PlacementFold> = folds
            .iter()
            .filter(|f| f.nominal.length_max.is_some() && f.calibrated.length_max.is_some())
            .collect();
        PlacementSummary {
            consistency_nominal: mean(folds.iter().map(|f| f.nominal.e_mean).collect())
                .unwrap_or(f64::NAN),
            consistency_calibrated: mean(folds.iter().map(|f| f.calibrated.e_mean).collect())
                .unwrap_or(f64::NAN),
            distance_nominal: mean(
                with_length
                    .iter()
                    .filter_map(|f| f.nominal.length_max)
                    .collect(),
            ),
            distance_calibrated: mean(
                with_length
                    .iter()
                    .filter_map(|f| f.calibrated.length_max)
                    .collect(),
            ),
        }
    }

    /// `(calibrated − nominal) / nominal`, percent, of the consistency.
    pub fn consistency_change_percent(&self) -> f64 {
        percent(self.consistency_nominal, self.consistency_calibrated)
    }

    /// The same for the distance error, where there is one.
    pub fn distance_change_percent(&self) -> Option<f64> {
        Some(percent(self.distance_nominal?, self.distance_calibrated?))
    }
}

fn percent(before: f64, after: f64) -> f64 {
    100.0 * (after - before) / before
}

/// Holds out each placement of `data` in turn (see the module docs).
///
/// # Errors
/// Fewer than two placements ([`CalibrationError::Option`] on `placements`); any error of a
/// fold's calibration, or of its figures.
pub fn leave_one_placement_out(
    start: &DhParams,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
) -> Result<Vec<PlacementFold>, CalibrationError> {
    let mut placements: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, p) in data.points().iter().enumerate() {
        let name = placement_of(&p.label);
        match placements.iter_mut().find(|(n, _)| n == name) {
            Some((_, points)) => points.push(i),
            None => placements.push((name.to_string(), vec![i])),
        }
    }
    if placements.len() < 2 {
        return Err(OptionError::new(
            Setting::Placements,
            placements.len(),
            "leave one placement out needs two placements or more (a point's placement is its \
             label up to the last `-`)",
        )
        .into());
    }
    placements
        .iter()
        .map(|(name, held)| {
            let train: Vec<usize> = (0..data.points().len())
                .filter(|p| !held.contains(p))
                .collect();
            let train_data = data.subset(&train);
            let test_data = data.subset(held);
            let fit = calibrate(start, &train_data, model, settings)?;
            Ok(PlacementFold {
                placement: name.clone(),
                sockets: held
                    .iter()
                    .map(|&p| data.points()[p].label.clone())
                    .collect(),
                touches: test_data.len(),
                trained_touches: train_data.len(),
                trained_lengths: train_data.references().len(),
                nominal: figures(start, &test_data)?,
                calibrated: figures(&fit.params, &test_data)?,
                successful: fit.solver.successful,
                implausible: (fit.checks.gross_corrections.iter())
                    .map(|g| g.name.clone())
                    .collect(),
            })
        })
        .collect()
}
