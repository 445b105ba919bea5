//! What `identify` and `calibrate` share: the arm, the touches and reference
//! lengths as a data set, and the stated noise.

use std::path::{Path, PathBuf};

use aacmm_core::calibrate::CalibrationError;
use aacmm_core::calibrate::DEFAULT_LENGTH_SIGMA_MM;
use aacmm_core::dataset::DataSet;
use aacmm_core::error::OptionError;
use aacmm_core::io::source_name;
use aacmm_core::io::{AngleUnit, Arm, read_lengths};
use aacmm_core::residuals::Noise;
use aacmm_core::tolerances::Tolerances;
use anyhow::{Result, anyhow};

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
    /// Tolerances of the nominal geometry (1σ prior; a MAP fit): `none`
    /// (ignore the arm file's prior table) or comma-separated TARGET=VALUEUNIT,
    /// e.g. `length=0.5mm,angle=0.1deg,theta5=0.05deg` (targets length,
    /// angle, a, d, alpha, theta, probe or a parameter; units mm, m, deg,
    /// rad); overrides the arm file's prior table entry by entry.
    #[arg(long, value_name = "none|SPEC")]
    pub prior: Option<String>,
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

    /// The noise flags in internal units (the library checks them:
    /// [`Noise::check`], with [`flag_error`] naming the flag).
    pub fn noise(&self) -> Noise {
        Noise {
            encoder_rad: self.encoder_noise.map(f64::to_radians),
            probe_mm: self.probe_noise,
            length_default_mm: self.length_uncertainty,
            length_weight: self.length_weight.filter(|&w| w != 0.0),
        }
    }

    /// The worker threads: `--threads`, or every core.
    pub fn threads(&self) -> usize {
        super::worker_threads(self.threads)
    }

    /// The arm, its prior (the arm file's `[prior]` overridden entry by
    /// entry by `--prior`; `--prior none`: none), the data set (touches
    /// grouped by point, lengths added) and the warnings printed, kept for
    /// the report.
    pub fn read_with_prior(&self) -> Result<(Arm, Option<Tolerances>, DataSet, Vec<String>)> {
        let (arm, file_prior, poses, warnings) = self.input.read_with_prior()?;
        self.input.kernel(&arm)?;
        let joints = arm.params.joint_count();
        let prior = match self.prior.as_deref() {
            None => file_prior,
            Some(spec) => Tolerances::parse(spec, joints)
                .map_err(flag_error)?
                .map(|flag| file_prior.unwrap_or_default().overridden_by(&flag)),
        };
        // The file's entries were checked against the arm where they are
        // written; this catches the flag's.
        if let Some(t) = &prior {
            t.check_for(&arm.params).map_err(flag_error)?;
        }
        let data = data_set(poses, &self.input.data, self.lengths.as_deref())?;
        Ok((arm, prior, data, warnings))
    }
}

/// A data set from poses (already read) and an optional lengths file.
pub fn data_set(
    poses: aacmm_core::io::Poses,
    data: &Path,
    lengths: Option<&Path>,
) -> Result<DataSet> {
    let mut set = DataSet::from_poses_owned(poses, &source_name(data))?;
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
    data_set(poses, data, lengths)
}

/// The command-line flag of each library setting ([`OptionError::field`]).
const FLAGS: [(&str, &str); 24] = [
    ("prior", "--prior"),
    ("noise.encoder_rad", "--encoder-noise"),
    ("noise.probe_mm", "--probe-noise"),
    ("noise.length_default_mm", "--length-uncertainty"),
    ("noise.length_weight", "--length-weight"),
    ("fix", "--fix"),
    ("robust.scale_k", "--robust-scale"),
    ("threads", "--threads"),
    ("cross_validate", "--cross-validate"),
    ("anneal.t0", "--sa-t0"),
    ("anneal.cooling", "--sa-cooling"),
    ("anneal.chain", "--sa-chain"),
    ("anneal.t_min", "--sa-t-min"),
    ("anneal.target", "--sa-target"),
    ("anneal.step_mm", "--sa-step-mm"),
    ("anneal.twist_step_deg", "--sa-twist-step"),
    ("anneal.zero_step_deg", "--sa-zero-step"),
    ("anneal.max_evaluations", "--sa-max-evaluations"),
    ("switch.window", "--switch-window"),
    ("switch.epsilon", "--switch-epsilon"),
    ("global.max_starts", "--global-starts"),
    ("global.confirmations", "--global-confirmations"),
    ("lm.max_iterations", "(LM iteration limit)"),
    ("global.start_iterations", "(LM iterations per start)"),
];

/// A library error in the command line's words: a refused setting names
/// its flag (the value as typed is on the command line; the library's may
/// be in internal units), anything else passes through.
pub fn flag_error(e: impl Into<CalibrationError>) -> anyhow::Error {
    match e.into() {
        CalibrationError::Option(o) => option_error(&o),
        other => anyhow::Error::new(other),
    }
}

fn option_error(o: &OptionError) -> anyhow::Error {
    match FLAGS.iter().find(|(field, _)| *field == o.field) {
        // The library holds the encoder noise in radians; the flag is in
        // degrees.
        Some((_, flag)) if o.field == "noise.encoder_rad" => match o.value.parse::<f64>() {
            Ok(rad) if rad.is_finite() => {
                let deg = (rad.to_degrees() * 1e12).round() / 1e12;
                anyhow!("{flag} {deg}: {}", o.reason)
            }
            _ => anyhow!("{flag} {}: {}", o.value, o.reason),
        },
        Some((_, flag)) => anyhow!("{flag} {}: {}", o.value, o.reason),
        None => anyhow!("{o}"),
    }
}
