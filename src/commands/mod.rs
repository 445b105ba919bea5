//! The subcommands, and what they share: reading an arm and its poses with
//! warnings printed, never dropped.

pub mod evaluate;
pub mod points;
pub mod simulate;

use std::path::Path;

use aacmm::io::{AngleUnit, Arm, Poses, Warning, read_arm, read_poses};
use anyhow::Result;

/// Prints warnings to stderr, where they cannot be mistaken for output.
pub fn report(warnings: &[Warning]) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

/// Reads an arm file and a poses file whose joint count must match it.
pub fn read_arm_and_poses(arm: &Path, data: &Path, unit: AngleUnit) -> Result<(Arm, Poses)> {
    let arm = read_arm(arm)?;
    let (poses, warnings) = read_poses(data, unit, Some(arm.params.joint_count()))?;
    report(&warnings);
    Ok((arm, poses))
}

/// Parses `--angle-unit` values with the library's own unit names.
pub fn angle_unit(s: &str) -> Result<AngleUnit, String> {
    s.parse().map_err(|e: aacmm::io::UnknownUnit| e.to_string())
}
