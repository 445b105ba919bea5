//! `aacmm points`: what a measuring arm's software does with every touch.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use aacmm::io::{AngleUnit, write_points};
use aacmm::kernel::positions_dyn;
use anyhow::{Context, Result};

/// Forward kinematics for every row of a poses file.
#[derive(clap::Args)]
pub struct Args {
    /// Arm file (TOML) with 6 or 7 `[[joint]]` entries.
    #[arg(long)]
    arm: PathBuf,
    /// Poses file (CSV `point,q1,...,qn`).
    #[arg(long)]
    data: PathBuf,
    /// Unit of the angles in the poses file.
    #[arg(long, default_value = "deg", value_parser = super::angle_unit)]
    angle_unit: AngleUnit,
    /// Output CSV `point,x,y,z` (mm); stdout when absent.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    let (arm, poses) = super::read_arm_and_poses(&args.arm, &args.data, args.angle_unit)?;
    let xyz = positions_dyn(&arm.params, &poses.q)
        .with_context(|| format!("{}: {}", args.arm.display(), args.data.display()))?;
    match &args.out {
        Some(path) => {
            let file =
                File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
            let mut w = BufWriter::new(file);
            write_points(&mut w, &poses.labels, &xyz)
                .and_then(|_| w.flush())
                .with_context(|| format!("{}: cannot write", path.display()))?;
        }
        None => {
            let mut w = BufWriter::new(std::io::stdout().lock());
            write_points(&mut w, &poses.labels, &xyz).and_then(|_| w.flush())?;
        }
    }
    Ok(())
}
