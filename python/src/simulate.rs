//! `aacmm.simulate`: a calibration campaign with a known true arm (`aacmm
//! simulate`), as arrays, a data set, and the campaign's files on request.

use std::path::PathBuf;

use aacmm_core::simulate::{
    Campaign as CoreCampaign, CampaignSettings, ErrorModel, SocketPlan, pair_count,
    simulate as core_simulate, write_campaign,
};
use numpy::PyArrayDyn;
use pyo3::prelude::*;

use crate::arm::{Arm, points_array, shaped};
use crate::data::DataSet;
use crate::error::{Error, Result, detached};

/// The command line's default number of reference lengths (fewer if the
/// sockets make fewer pairs).
const DEFAULT_REFERENCE_LENGTHS: usize = 3;

/// A simulated campaign: the true arm, the sockets, what the encoders read
/// and the reference lengths. Same settings and seed, same values.
#[pyclass(frozen, module = "aacmm")]
pub struct Campaign {
    campaign: CoreCampaign,
    settings: CampaignSettings,
    nominal_source: String,
}

#[pymethods]
impl Campaign {
    /// The nominal arm (what a calibration starts from).
    #[getter]
    fn nominal(&self) -> PyResult<Arm> {
        let a = &self.campaign.nominal;
        Ok(Arm::new(
            a.clone(),
            self.nominal_source.clone(),
            Vec::new(),
        )?)
    }

    /// The true arm (what a calibration should find).
    #[getter]
    fn true_arm(&self) -> PyResult<Arm> {
        Ok(Arm::new(
            self.campaign.true_arm.clone(),
            "<simulation>".to_string(),
            Vec::new(),
        )?)
    }

    /// Per touch (row of `poses.csv`), the socket's label.
    #[getter]
    fn labels(&self) -> Vec<String> {
        self.campaign.poses.labels().map(str::to_string).collect()
    }

    /// What the encoders read, rad, `n × joints`, in the rows of
    /// `poses.csv`.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let p = &self.campaign.poses;
        shaped(py, p.readings().to_vec(), &[p.len(), p.joints()])
    }

    /// The sockets' labels, in order.
    #[getter]
    fn socket_labels(&self) -> Vec<String> {
        self.campaign
            .sockets
            .iter()
            .map(|(l, _)| l.clone())
            .collect()
    }

    /// The true socket centres, mm, `k × 3`.
    #[getter]
    fn sockets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let xyz: Vec<[f64; 3]> = self.campaign.sockets.iter().map(|(_, p)| *p).collect();
        points_array(py, &xyz)
    }

    /// The reference lengths: `(point_a, point_b, distance_mm,
    /// uncertainty_mm or None)`.
    #[getter]
    fn lengths(&self) -> Vec<(String, String, f64, Option<f64>)> {
        self.campaign
            .lengths
            .iter()
            .map(|l| (l.a.clone(), l.b.clone(), l.distance, l.uncertainty))
            .collect()
    }

    /// The campaign as the data set a calibration reads (named as the
    /// campaign's files, `poses.csv` and `lengths.csv`).
    #[getter]
    fn data(&self) -> PyResult<DataSet> {
        let data = self.campaign.data_set().map_err(Error::from)?;
        let has_lengths = !data.references().is_empty();
        Ok(DataSet {
            data,
            poses_file: aacmm_core::simulate::POSES_FILE.to_string(),
            lengths_file: has_lengths.then(|| aacmm_core::simulate::LENGTHS_FILE.to_string()),
            warnings: Vec::new(),
            // As its poses file is written.
            unit: aacmm_core::io::AngleUnit::Deg,
        })
    }

    /// Writes the campaign's files into `dir` (created if missing):
    /// `poses.csv` (degrees), `lengths.csv`, `sockets.csv`, `true_arm.toml`,
    /// `campaign.toml` — the bytes `aacmm simulate` writes for the same
    /// settings. Returns the paths written.
    ///
    /// `OSError` when `dir` holds results of an earlier run (a campaign's, a
    /// calibration's, a report's) and `force` is not set;
    /// `ValueError` for an empty path.
    #[pyo3(signature = (dir, *, force = false))]
    fn write(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<Vec<PathBuf>> {
        detached(py, || {
            crate::error::check_out_dir(&dir, force)?;
            Ok(write_campaign(&dir, &self.campaign, &self.settings)?)
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Campaign({} sockets, {} touches, {} reference lengths, seed {})",
            self.campaign.sockets.len(),
            self.campaign.poses.len(),
            self.campaign.lengths.len(),
            self.settings.seed
        )
    }
}

/// The error model of `errors=` (or the given true arm).
fn error_model(errors: &str, true_arm: Option<&Arm>, scale: Option<f64>) -> Result<ErrorModel> {
    if let Some(arm) = true_arm {
        return Ok(ErrorModel::File {
            arm: arm.arm.clone(),
        });
    }
    match errors {
        "paper" => match scale {
            Some(_) => Err(Error::value(
                "error_scale: applies to errors='random'|'assembled', not to the paper's fixed \
                 errors",
            )),
            None => Ok(ErrorModel::Paper),
        },
        "random" | "assembled" => {
            let scale = scale.unwrap_or(1.0);
            if let Err(why) = ErrorModel::check_scale(scale) {
                return Err(Error::value(format!("error_scale: {why}")));
            }
            Ok(ErrorModel::random(scale, errors == "assembled"))
        }
        other => Err(Error::value(format!(
            "errors = \"{}\": one of 'paper', 'random', 'assembled' (or give true_arm)",
            aacmm_core::error::shown(other)
        ))),
    }
}

/// Simulates a calibration campaign (`aacmm simulate`): a true arm made
/// from `arm` (the nominal) by `errors` (`"paper"`: the paper's Table 2,
/// 6 joints; `"random"`; `"assembled"`: random with zero offsets anywhere in
/// ±180°; `error_scale` multiplies the random models' σ) or given as
/// `true_arm`, touches `sockets` spread sockets (or those of
/// `sockets_file`, CSV `point,x,y,z` mm) `poses` times each; encoder noise
/// σ `encoder_noise_deg` (degrees), probe seating σ `probe_noise_mm`;
/// `reference_lengths` distances between sockets (default 3) with standard
/// uncertainty `length_uncertainty_mm`. A setting out of range is a
/// `ValueError` naming the argument, as in `calibrate` (the same bounds:
/// `seed` at most 2⁶³ − 1, an encoder σ at most 180°); a campaign the arm
/// cannot perform is `aacmm.CalibrationError`. Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (arm, *, poses, seed, sockets = None, sockets_file = None, errors = "paper", true_arm = None, error_scale = None, encoder_noise_deg = 0.0, probe_noise_mm = 0.0, reference_lengths = None, length_uncertainty_mm = None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    py: Python<'_>,
    arm: &Arm,
    poses: usize,
    seed: u64,
    sockets: Option<usize>,
    sockets_file: Option<PathBuf>,
    errors: &str,
    true_arm: Option<&Arm>,
    error_scale: Option<f64>,
    encoder_noise_deg: f64,
    probe_noise_mm: f64,
    reference_lengths: Option<usize>,
    length_uncertainty_mm: Option<f64>,
) -> PyResult<Campaign> {
    let errors = error_model(errors, true_arm, error_scale)?;
    let sockets_file = sockets_file.map(crate::file_path);
    detached(py, || {
        let plan = match (sockets, &sockets_file) {
            (Some(_), Some(_)) => {
                return Err(Error::value("give sockets or sockets_file, not both"));
            }
            (Some(count), None) => SocketPlan::Spread { count },
            (None, Some(path)) => SocketPlan::from_file(path)?,
            (None, None) => return Err(Error::value("give sockets (a count) or sockets_file")),
        };
        let count = plan.count();
        let mut settings = CampaignSettings::new(seed, errors, count, poses);
        settings.nominal_file = (arm.source.as_str() != "<parameters>").then(|| arm.source.clone());
        settings.sockets = plan;
        settings.encoder_noise_deg = encoder_noise_deg;
        settings.probe_noise_mm = probe_noise_mm;
        settings.reference_lengths =
            reference_lengths.unwrap_or_else(|| DEFAULT_REFERENCE_LENGTHS.min(pair_count(count)));
        settings.length_uncertainty_mm = length_uncertainty_mm;
        let campaign = core_simulate(&arm.arm, &settings)?;
        Ok(Campaign {
            campaign,
            settings,
            nominal_source: arm.source.clone(),
        })
    })
}
