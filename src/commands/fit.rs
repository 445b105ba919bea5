//! What `identify` and `calibrate` share: the arm, the touches and reference
//! lengths as a data set, and the stated noise.

use std::path::{Path, PathBuf};

use aacmm_core::calibrate::DEFAULT_LENGTH_SIGMA_MM;
use aacmm_core::dataset::DataSet;
use aacmm_core::io::source_name;
use aacmm_core::io::{AngleUnit, Arm, read_lengths};
use aacmm_core::residuals::Noise;
use anyhow::{Result, bail};

use super::ArmAndPoses;

/// The flags of a fit: arm, poses, reference lengths, noise.
#[derive(clap::Args)]
pub struct FitInput {
    #[command(flatten)]
    pub input: ArmAndPoses,
    /// Reference lengths (CSV `point_a,point_b,distance[,uncertainty]`, mm).
    #[arg(long, value_name = "L.csv")]
    pub lengths: Option<PathBuf>,
    /// σ of each encoder reading, degrees (with --probe-noise: the touch
    /// weights; without either, the touch σ is estimated from the fit).
    #[arg(long, value_name = "DEG")]
    pub encoder_noise: Option<f64>,
    /// σ of the probe seating per axis, mm.
    #[arg(long, value_name = "MM")]
    pub probe_noise: Option<f64>,
    /// σ of a reference length whose file gives no uncertainty, mm.
    #[arg(long, value_name = "MM", default_value_t = DEFAULT_LENGTH_SIGMA_MM)]
    pub length_uncertainty: f64,
    /// Weight of every reference-length residual, 1/mm (overrides the
    /// uncertainties).
    #[arg(long, value_name = "W")]
    pub length_weight: Option<f64>,
    /// Worker threads (default: every core); results do not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,
}

impl FitInput {
    /// The input files, for output-path checks.
    pub fn paths(&self) -> Vec<(&'static str, &Path)> {
        let mut v = vec![
            ("--arm", self.input.arm.as_path()),
            ("--data", &self.input.data),
        ];
        v.extend(self.lengths.as_deref().map(|l| ("--lengths", l)));
        v
    }

    /// The noise flags, checked and in internal units.
    pub fn noise(&self) -> Result<Noise> {
        for (flag, v) in [
            ("--encoder-noise", self.encoder_noise),
            ("--probe-noise", self.probe_noise),
            ("--length-uncertainty", Some(self.length_uncertainty)),
            ("--length-weight", self.length_weight),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v >= 0.0)
            {
                bail!("{flag} {v}: must be a finite number ≥ 0");
            }
        }
        if self.encoder_noise.unwrap_or(0.0) == 0.0
            && self.probe_noise.unwrap_or(0.0) == 0.0
            && (self.encoder_noise.is_some() || self.probe_noise.is_some())
        {
            bail!("--encoder-noise and --probe-noise are both 0: a touch needs some uncertainty");
        }
        Ok(Noise {
            encoder_rad: self.encoder_noise.map(f64::to_radians),
            probe_mm: self.probe_noise,
            length_default_mm: self.length_uncertainty,
            length_weight: self.length_weight.filter(|&w| w > 0.0),
        })
    }

    /// The worker threads: `--threads`, or every core.
    pub fn threads(&self) -> usize {
        super::worker_threads(self.threads)
    }

    /// The arm and the data set (touches grouped by point, lengths added).
    pub fn read(&self) -> Result<(Arm, DataSet)> {
        let (arm, poses) = self.input.read()?;
        self.input.kernel(&arm)?;
        let data = data_set(&poses, &self.input.data, self.lengths.as_deref())?;
        Ok((arm, data))
    }
}

/// A data set from poses (already read) and an optional lengths file.
pub fn data_set(
    poses: &aacmm_core::io::Poses,
    data: &Path,
    lengths: Option<&Path>,
) -> Result<DataSet> {
    let mut set = DataSet::from_poses(poses, &source_name(data))?;
    if let Some(path) = lengths {
        set = set.with_lengths(&read_lengths(path)?, &source_name(path))?;
    }
    Ok(set)
}

/// Reads another poses file (held-out data) for `arm`.
pub fn read_other(
    arm: &Arm,
    data: &Path,
    lengths: Option<&Path>,
    unit: AngleUnit,
) -> Result<DataSet> {
    let (poses, warnings) = aacmm_core::io::read_poses(data, unit, Some(arm.params.joint_count()))?;
    super::report(&warnings)?;
    data_set(&poses, data, lengths)
}
