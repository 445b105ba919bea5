//! The subcommands, and what they share: reading an arm and its poses with
//! warnings printed, never dropped, and probe positions that are numbers.

pub mod calibrate;
pub mod calibration;
pub mod evaluate;
pub mod export;
pub mod identify;
pub mod import;
pub mod plan;
pub mod points;
pub mod probe;
pub mod progress;
pub mod report;
pub mod shared_flags;
pub mod simulate;
pub mod verify;

use std::path::PathBuf;

use aacmm_core::domain::{Arm, Poses};
use aacmm_core::error::short;
use aacmm_core::io::{
    AngleUnit, Rejected, Warning, limit_warning, read_arm_with, read_poses,
    read_poses_or_positions, source_name,
};
use aacmm_core::kernel::{ArmKernel, KernelError, NoiseOf, Pose, PreparedPoses};
use anyhow::{Context, Result, bail};

use crate::output::warn;

/// Prints warnings to stderr, where they cannot be mistaken for output.
pub fn report(warnings: &[Warning]) -> Result<()> {
    warnings.iter().try_for_each(warn)
}

/// Worker threads for a `--threads` flag (checked by
/// [`shared_flags::threads_flag`]): its value, or every core.
pub fn worker_threads(flag: Option<usize>) -> usize {
    flag.unwrap_or_else(aacmm_core::calibrate::available_threads)
}

/// The arm and the poses it is applied to: the flags `points` and
/// `evaluate` share.
#[derive(clap::Args)]
pub struct ArmAndPoses {
    /// Arm file (TOML) with 1 to 12 `[[joint]]` entries.
    #[arg(long)]
    pub arm: PathBuf,
    /// Poses file (CSV `point,q1,...,qn`); `-` reads standard input.
    #[arg(long, required = true)]
    pub data: Option<PathBuf>,
    /// Unit of the joint readings (q1..qn) in the poses file; the arm
    /// file states its own (`angle_unit`).
    #[arg(long, default_value = "deg", value_parser = angle_unit())]
    pub angle_unit: AngleUnit,
    /// The arm's temperature, °C, when its file states a thermal expansion
    /// (`cte_per_k`): its lengths are scaled from the reference temperature.
    #[arg(long, value_name = "CELSIUS")]
    pub temperature: Option<f64>,
    /// Read an arm file whose `[verdict]` says NOT usable (a refused
    /// calibration's calibrated.toml), with a warning, instead of refusing
    /// it.
    #[arg(long)]
    pub accept_rejected: bool,
}

/// The poses file as messages name it.
fn shown_data(data: &Option<PathBuf>) -> String {
    data.as_deref()
        .map_or("--data".to_string(), |d| d.display().to_string())
}

impl ArmAndPoses {
    /// The poses file (`--data`; optional only where a command says so,
    /// as `evaluate --positions`).
    pub fn data(&self) -> Result<&std::path::Path> {
        match &self.data {
            Some(path) => Ok(path),
            None => bail!("give --data: a poses file"),
        }
    }

    /// Reads both files; the poses must have the arm's joint count. Warns
    /// (stderr) about suspicious poses, readings outside the arm's joint
    /// limits included.
    pub fn read(&self) -> Result<(Arm, Poses)> {
        self.read_with(|path, unit, arm| {
            let (poses, warnings) = read_poses(path, unit, arm)?;
            Ok((poses, warnings))
        })
    }

    /// [`ArmAndPoses::read`] of a poses file or of a reference-positions
    /// file, whose readings are taken (`points`: the positions and frames
    /// are not needed to say where the arm puts its probe).
    pub fn read_readings(&self) -> Result<(Arm, Poses)> {
        self.read_with(|path, unit, arm| {
            let (poses, warnings, _) = read_poses_or_positions(path, unit, arm)?;
            Ok((poses, warnings))
        })
    }

    /// The arm alone (`evaluate --positions` without poses), its warnings
    /// printed.
    pub fn read_arm(&self) -> Result<Arm> {
        let (arm, warnings) = self.arm_and_warnings()?;
        report(&warnings)?;
        Ok(arm)
    }

    /// The arm file read (a rejected calibration's refused unless
    /// --accept-rejected), with its warnings.
    fn arm_and_warnings(&self) -> Result<(Arm, Vec<Warning>)> {
        let rejected = if self.accept_rejected {
            Rejected::Warn
        } else {
            Rejected::Refuse
        };
        Ok(read_arm_with(&self.arm, rejected)?)
    }

    /// The arm, and the poses `read` reads for it, with the warnings.
    fn read_with(
        &self,
        read: impl Fn(
            &std::path::Path,
            AngleUnit,
            &Arm,
        ) -> Result<(Poses, Vec<Warning>), aacmm_core::error::InputError>,
    ) -> Result<(Arm, Poses)> {
        let (arm, mut warnings) = self.arm_and_warnings()?;
        let (poses, more) = read(self.data()?, self.angle_unit, &arm)?;
        warnings.extend(more);
        let file = source_name(self.data()?);
        // Every command reading poses here computes each row with one
        // probe: rows of several tools are `calibrate`'s alone.
        poses.refuse_tools(&file, "this command")?;
        warnings.extend(limit_warning(&arm, &poses, &file, self.angle_unit));
        report(&warnings)?;
        Ok((arm, poses))
    }

    /// Refuses an arm whose stated thermal expansion has no temperature to
    /// act at.
    pub fn check_conditions(&self, arm: &Arm) -> Result<()> {
        if arm.physics.cte_per_k.is_some_and(|c| c != 0.0) && self.temperature.is_none() {
            bail!(
                "{}: the arm states a thermal expansion (cte_per_k): give --temperature, the \
                 arm's temperature in °C",
                source_name(&self.arm)
            );
        }
        Ok(())
    }

    /// `rows` as the arm's chain sees them through the corrections its file
    /// states (compliance, encoder harmonics, backlash, expansion at
    /// --temperature, a backlash on the flank of the rows' directions of
    /// `approach` where known, per row and joint);
    /// `None` when it states none.
    pub fn corrected(
        &self,
        arm: &Arm,
        rows: &[&[f64]],
        approach: Option<&[i8]>,
    ) -> Result<Option<PreparedPoses>> {
        use aacmm_core::corrections::{Beyond, Conditions, Effects};
        if !arm.physics.corrects() {
            return Ok(None);
        }
        let raw = PreparedPoses::for_shape(arm.params.shape()?, rows)?;
        let temperatures = self.temperature.map(|t| vec![t; rows.len()]);
        let conditions = Conditions {
            temperature_c: temperatures.as_deref(),
            time_s: None,
            approach,
        };
        let effects = Effects::new(
            &arm.params,
            &arm.physics,
            &Beyond::default(),
            &raw,
            conditions,
        )
        .map_err(|e| anyhow::anyhow!("{}: {e}", source_name(&self.arm)))?;
        Ok(Some(effects.poses))
    }

    /// The arm prepared for its generated kernel.
    pub fn kernel(&self, arm: &Arm) -> Result<ArmKernel> {
        ArmKernel::new(&arm.params).with_context(|| source_name(&self.arm))
    }

    /// Probe positions of every pose (mm), in row order, on every core. The
    /// sin/cos of the readings are prepared a chunk at a time, never for the
    /// whole file; the bits do not depend on the chunks.
    pub fn positions(&self, arm: &Arm, poses: &Poses) -> Result<Vec<[f64; 3]>> {
        let xyz = self.per_pose(arm, poses, |k, p, out| k.positions(p, 0..out.len(), out))?;
        self.check_finite(&xyz, |row| poses.line(row))?;
        Ok(xyz)
    }

    /// The tool's pose (probe position and the tool frame's orientation)
    /// of every pose, in row order: [`ArmAndPoses::positions`] with the
    /// orientation.
    pub fn tool_poses(&self, arm: &Arm, poses: &Poses) -> Result<Vec<Pose>> {
        let tools = self.per_pose(arm, poses, |k, p, out| k.poses(p, 0..out.len(), out))?;
        let finite = |t: &Pose| t.rotation.iter().flatten().all(|v| v.is_finite());
        let xyz: Vec<[f64; 3]> = (tools.iter())
            .map(|t| if finite(t) { t.position } else { [f64::NAN; 3] })
            .collect();
        self.check_finite(&xyz, |row| poses.line(row))?;
        Ok(tools)
    }

    /// `compute`'s output for every pose, in row order, on every core, the
    /// readings prepared (and corrected) a chunk at a time.
    fn per_pose<T: Copy + Default + Send>(
        &self,
        arm: &Arm,
        poses: &Poses,
        compute: impl Fn(&ArmKernel, &PreparedPoses, &mut [T]) -> Result<(), KernelError> + Sync,
    ) -> Result<Vec<T>> {
        /// Poses per chunk: 4096 poses of 7 joints prepared are 448 KiB.
        const CHUNK: usize = 4096;
        let kernel = self.kernel(arm)?;
        let mut xyz = vec![T::default(); poses.len()];
        self.check_conditions(arm)?;
        let chunk = |(c, out): (usize, &mut [T])| -> Result<()> {
            let rows: Vec<&[f64]> = (c * CHUNK..c * CHUNK + out.len())
                .map(|row| poses.reading(row))
                .collect();
            let n = poses.joints();
            let approach =
                (poses.approaches()).map(|a| &a[c * CHUNK * n..(c * CHUNK + out.len()) * n]);
            let prepared = match self.corrected(arm, &rows, approach)? {
                Some(p) => p,
                None => PreparedPoses::for_shape(kernel.shape(), &rows)?,
            };
            Ok(compute(&kernel, &prepared, out)?)
        };
        let threads = worker_threads(None);
        let per_thread = poses.len().div_ceil(CHUNK).div_ceil(threads).max(1) * CHUNK;
        std::thread::scope(|s| {
            let parts: Vec<_> = (xyz.chunks_mut(per_thread).enumerate())
                .map(|(t, part)| {
                    let first = t * per_thread / CHUNK;
                    s.spawn(move || {
                        (part.chunks_mut(CHUNK).enumerate())
                            .try_for_each(|(c, out)| chunk((first + c, out)))
                    })
                })
                .collect();
            parts
                .into_iter()
                .try_for_each(|p| p.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
        })
        .with_context(|| format!("{}: {}", self.arm.display(), shown_data(&self.data)))?;
        Ok(xyz)
    }

    /// A position that is not a finite number is the arm's fault (the poses
    /// are finite when read): the error names the arm file and the first
    /// such pose (`line` maps an index of `xyz` to its line in the poses file).
    pub fn check_finite(&self, xyz: &[[f64; 3]], line: impl Fn(usize) -> usize) -> Result<()> {
        if let Some(i) = xyz.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            bail!(
                "{}: the arm's geometry gives a probe position that is not a finite number \
                 ({:?} mm) for the pose at {}:{}; check the arm's lengths and units",
                self.arm.display(),
                xyz[i],
                shown_data(&self.data),
                line(i)
            );
        }
        Ok(())
    }
}

/// Parses `--angle-unit` values with the library's own unit names, listed
/// as the flag's possible values so that `--help` shows them (a plain
/// function parser shows only the default).
pub fn angle_unit() -> impl clap::builder::TypedValueParser<Value = AngleUnit> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    let help = |u: AngleUnit| match u {
        AngleUnit::Deg => "degrees",
        AngleUnit::Rad => "radians",
    };
    let values = AngleUnit::ALL.map(|u| PossibleValue::new(u.name()).help(help(u)));
    PossibleValuesParser::new(values).try_map(|s| s.parse::<AngleUnit>())
}

/// Writes `value` as pretty JSON (and a final newline) to `path`.
pub fn write_json(path: &std::path::Path, value: &impl serde::Serialize) -> Result<()> {
    aacmm_core::io::write_atomic_with(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(std::io::Error::from)?;
        w.write_all(b"\n")
    })
    .with_context(|| format!("{}: cannot write", path.display()))
}

/// A library error about weights that are not finite (a
/// [`KernelError::Noise`], alone or inside a calibration error), restated
/// with the flags that set the noise — the library knows no flag names.
/// Other errors pass through.
pub fn noise_flags(e: impl Into<anyhow::Error>, fit: &shared_flags::FitInput) -> anyhow::Error {
    let e: anyhow::Error = e.into();
    let kernel = e
        .downcast_ref::<KernelError>()
        .or_else(
            || match e.downcast_ref::<aacmm_core::calibrate::CalibrationError>() {
                Some(aacmm_core::calibrate::CalibrationError::Kernel(k)) => Some(k),
                _ => None,
            },
        )
        .or_else(
            || match e.downcast_ref::<aacmm_core::residuals::TermError>() {
                Some(aacmm_core::residuals::TermError::Kernel(k)) => Some(k),
                _ => None,
            },
        );
    let Some(KernelError::Noise { of, message }) = kernel else {
        return e;
    };
    let show = |flag: &str, v: Option<f64>| v.map(|v| format!("{flag} {}", short(v)));
    let flags: Vec<String> = match of {
        NoiseOf::Touches => [
            show("--encoder-noise", fit.encoder_noise),
            show("--probe-noise", fit.probe_noise),
        ]
        .into_iter()
        .flatten()
        .collect(),
        NoiseOf::Lengths => [
            show("--length-uncertainty", Some(fit.length_uncertainty)),
            show("--length-weight", fit.length_weight),
        ]
        .into_iter()
        .flatten()
        .collect(),
    };
    if flags.is_empty() {
        e
    } else {
        anyhow::anyhow!("{}: {message}", flags.join(", "))
    }
}
