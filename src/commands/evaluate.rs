//! `aacmm evaluate`: the single-point and length figures of an arm on
//! measured poses — the paper's and the standards' (see `aacmm_core::metrics`
//! for every formula).

use std::path::{Path, PathBuf};

use aacmm::io::{Poses, ReferenceLength, check_lengths_against, read_lengths, source_name};
use aacmm::metrics::{Evaluation, MetricsError, ReferenceDistance, evaluate};
use anyhow::{Context, Result, anyhow};
use serde::Serialize;

/// Evaluate an arm on measured poses.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    input: super::ArmAndPoses,
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
    let (arm, poses) = args.input.read()?;
    let lengths = match &args.lengths {
        Some(path) => {
            let lengths = read_lengths(path)?;
            check_lengths_against(&lengths, &poses.labels, &source_name(path))?;
            lengths
        }
        None => Vec::new(),
    };
    let xyz = args.input.positions(&arm, &poses)?;
    let references: Vec<ReferenceDistance> = lengths
        .iter()
        .map(|l| ReferenceDistance {
            a: l.a.clone(),
            b: l.b.clone(),
            distance: l.distance,
        })
        .collect();
    let evaluation = evaluate(&poses.labels, &xyz, &references).map_err(|e| {
        locate(
            e,
            &args.input.data,
            &poses,
            args.lengths.as_deref(),
            &lengths,
        )
    })?;

    println!(
        "arm `{}` ({}) on {}",
        arm.name,
        source_name(&args.input.arm),
        source_name(&args.input.data)
    );
    print!("{}", evaluation.to_table());
    if let Some(path) = &args.json {
        let report = Report {
            arm: &arm.name,
            arm_file: source_name(&args.input.arm),
            data_file: source_name(&args.input.data),
            lengths_file: args.lengths.as_deref().map(source_name),
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
            Some(line) => anyhow!("{}:{line}: field `point`: {e}", source_name(data)),
            None => anyhow!("{}: {e}", source_name(data)),
        },
        MetricsError::NonFinite { row, .. } => {
            let line = poses.lines.get(*row).copied().unwrap_or(0);
            anyhow!("{}:{line}: {e}", source_name(data))
        }
        MetricsError::UnknownLabel { label } | MetricsError::InvalidReference { a: label, .. } => {
            let file = lengths_file.map_or_else(String::new, source_name);
            match lengths.iter().find(|l| &l.a == label || &l.b == label) {
                Some(l) => anyhow!("{file}:{}: {e}", l.line),
                None => anyhow!("{file}: {e}"),
            }
        }
        MetricsError::Empty | MetricsError::LengthMismatch { .. } => {
            anyhow!("{}: {e}", source_name(data))
        }
    }
}
