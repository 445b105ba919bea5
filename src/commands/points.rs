//! `aacmm points`: what a measuring arm's software does with every touch.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use aacmm_core::io::write_points;
use anyhow::{Context, Result};

use crate::output::Stdout;
use crate::paths::check_output_file;

/// Forward kinematics for every row of a poses file.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    input: super::ArmAndPoses,
    /// Output CSV `point,x,y,z` (mm); stdout when absent.
    #[arg(long)]
    out: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(out) = &args.out {
        let inputs = [
            ("--arm", args.input.arm.as_path()),
            ("--data", &args.input.data),
        ];
        check_output_file("--out", out, &inputs)?;
    }
    let (arm, poses) = args.input.read()?;
    let xyz = args.input.positions(&arm, &poses)?;
    match &args.out {
        Some(path) => {
            let file =
                File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
            let mut w = BufWriter::with_capacity(1 << 16, file);
            write_points(&mut w, poses.labels(), &xyz)
                .and_then(|_| w.flush())
                .with_context(|| format!("{}: cannot write", path.display()))?;
        }
        None => {
            let mut out = Stdout::new();
            out.write_with(|w| write_points(w, poses.labels(), &xyz))?;
            out.finish()?;
        }
    }
    Ok(())
}
