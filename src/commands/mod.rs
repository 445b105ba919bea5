//! The subcommands, and what they share: reading an arm and its poses with
//! warnings printed, never dropped.

pub mod evaluate;
pub mod points;
pub mod simulate;

use std::path::PathBuf;

use aacmm::io::{AngleUnit, Arm, Poses, Warning, read_arm, read_poses, source_name};
use aacmm::kernel::positions_dyn;
use anyhow::{Context, Result};

/// Prints warnings to stderr, where they cannot be mistaken for output.
pub fn report(warnings: &[Warning]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

/// The arm and the poses it is applied to: the flags `points` and
/// `evaluate` share.
#[derive(clap::Args)]
pub struct ArmAndPoses {
    /// Arm file (TOML) with 6 or 7 `[[joint]]` entries.
    #[arg(long)]
    pub arm: PathBuf,
    /// Poses file (CSV `point,q1,...,qn`); `-` reads standard input.
    #[arg(long)]
    pub data: PathBuf,
    /// Unit of the angles in the poses file.
    #[arg(long, default_value = "deg", value_parser = angle_unit)]
    pub angle_unit: AngleUnit,
}

impl ArmAndPoses {
    /// Reads both files, printing their warnings; the poses must have the
    /// arm's joint count.
    pub fn read(&self) -> Result<(Arm, Poses)> {
        let (arm, warnings) = read_arm(&self.arm)?;
        report(&warnings);
        let (poses, warnings) =
            read_poses(&self.data, self.angle_unit, Some(arm.params.joint_count()))?;
        report(&warnings);
        Ok((arm, poses))
    }

    /// Probe positions of every pose (mm), in row order.
    pub fn positions(&self, arm: &Arm, poses: &Poses) -> Result<Vec<[f64; 3]>> {
        positions_dyn(&arm.params, &poses.q)
            .with_context(|| format!("{}: {}", source_name(&self.arm), source_name(&self.data)))
    }
}

/// Parses `--angle-unit` values with the library's own unit names.
pub fn angle_unit(s: &str) -> Result<AngleUnit, String> {
    s.parse().map_err(|e: aacmm::io::UnknownUnit| e.to_string())
}
