//! `aacmm evaluate`: the single-point and length figures of an arm on
//! measured poses — the paper's and the standards' (see `aacmm_core::metrics`
//! for every formula).

use std::path::{Path, PathBuf};

use aacmm::io::{AngleUnit, Poses, ReferenceLength, check_lengths_against, read_lengths};
use aacmm::kernel::positions_dyn;
use aacmm::metrics::{Evaluation, MetricsError, ReferenceDistance, evaluate};
use anyhow::{Context, Result, anyhow};
use serde::Serialize;

/// Evaluate an arm on measured poses.
#[derive(clap::Args)]
pub struct Args {
    /// Arm file (TOML).
    #[arg(long)]
    arm: PathBuf,
    /// Poses file (CSV `point,q1,...,qn`); every point needs at least 3 touches.
    #[arg(long)]
    data: PathBuf,
    /// Unit of the angles in the poses file.
    #[arg(long, default_value = "deg", value_parser = super::angle_unit)]
    angle_unit: AngleUnit,
    /// Reference lengths (CSV `point_a,point_b,distance[,uncertainty]`, mm).
    #[arg(long)]
    lengths: Option<PathBuf>,
    /// Also write every figure as JSON (lengths in mm).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// The JSON report: what was evaluated, and the figures.
#[derive(Serialize)]
struct Report<'a> {
    arm: &'a str,
    arm_file: String,
    data_file: String,
    lengths_file: Option<String>,
    length_unit: &'static str,
    evaluation: &'a Evaluation,
}

pub fn run(args: Args) -> Result<()> {
    let (arm, poses) = super::read_arm_and_poses(&args.arm, &args.data, args.angle_unit)?;
    let lengths = match &args.lengths {
        Some(path) => {
            let lengths = read_lengths(path)?;
            check_lengths_against(&lengths, &poses.labels, &path.display().to_string())?;
            lengths
        }
        None => Vec::new(),
    };
    let xyz = positions_dyn(&arm.params, &poses.q)
        .with_context(|| format!("{}: {}", args.arm.display(), args.data.display()))?;
    let references: Vec<ReferenceDistance> = lengths
        .iter()
        .map(|l| ReferenceDistance {
            a: l.a.clone(),
            b: l.b.clone(),
            distance: l.distance,
        })
        .collect();
    let evaluation = evaluate(&poses.labels, &xyz, &references)
        .map_err(|e| locate(e, &args.data, &poses, args.lengths.as_deref(), &lengths))?;

    println!(
        "arm `{}` ({}) on {}",
        arm.name,
        args.arm.display(),
        args.data.display()
    );
    print!("{}", evaluation.to_table());
    if let Some(path) = &args.json {
        let report = Report {
            arm: &arm.name,
            arm_file: args.arm.display().to_string(),
            data_file: args.data.display().to_string(),
            lengths_file: args.lengths.as_ref().map(|p| p.display().to_string()),
            length_unit: "mm",
            evaluation: &evaluation,
        };
        let text = serde_json::to_string_pretty(&report)?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    Ok(())
}

/// Points a metrics error at the file and line it comes from.
fn locate(
    e: MetricsError,
    data: &Path,
    poses: &Poses,
    lengths_file: Option<&Path>,
    lengths: &[ReferenceLength],
) -> anyhow::Error {
    let first_line = |label: &str| {
        poses
            .labels
            .iter()
            .position(|l| l == label)
            .map(|i| poses.lines[i])
    };
    match &e {
        MetricsError::TooFewTouches { label, .. } => match first_line(label) {
            Some(line) => anyhow!("{}:{line}: field `point`: {e}", data.display()),
            None => anyhow!("{}: {e}", data.display()),
        },
        MetricsError::NonFinite { row, .. } => {
            let line = poses.lines.get(*row).copied().unwrap_or(0);
            anyhow!("{}:{line}: {e}", data.display())
        }
        MetricsError::UnknownLabel { label } | MetricsError::InvalidReference { a: label, .. } => {
            let file = lengths_file.map_or_else(String::new, |p| p.display().to_string());
            match lengths.iter().find(|l| &l.a == label || &l.b == label) {
                Some(l) => anyhow!("{file}:{}: {e}", l.line),
                None => anyhow!("{file}: {e}"),
            }
        }
        MetricsError::Empty | MetricsError::LengthMismatch { .. } => {
            anyhow!("{}: {e}", data.display())
        }
    }
}
