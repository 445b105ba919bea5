//! `aacmm evaluate`: the single-point and length figures of an arm on
//! measured poses — the paper's and the standards' (see `aacmm_core::metrics`
//! for every formula).

use std::path::{Path, PathBuf};

use aacmm::io::{Poses, ReferenceLength, check_lengths_against, read_lengths};
use aacmm::metrics::{Evaluation, MetricsError, ReferenceDistance, evaluate};
use anyhow::{Context, Result, anyhow, bail};
use serde::Serialize;

use crate::finite::first_non_finite;
use crate::output::Stdout;
use crate::paths::check_output_file;

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
    if let Some(json) = &args.json {
        let mut inputs = vec![
            ("--arm", args.input.arm.as_path()),
            ("--data", &args.input.data),
        ];
        inputs.extend(args.lengths.as_deref().map(|l| ("--lengths", l)));
        check_output_file("--json", json, &inputs)?;
    }
    let (arm, poses) = args.input.read()?;
    let lengths = match &args.lengths {
        Some(path) => {
            let lengths = read_lengths(path)?;
            check_lengths_against(&lengths, &poses.labels, &path.display().to_string())?;
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
    if let Some(figure) = first_non_finite(&evaluation) {
        bail!(
            "{}: on {}, the figure `{figure}` overflows (not a finite number): the probe \
             positions are too large for the statistics; check the arm's lengths and units",
            args.input.arm.display(),
            args.input.data.display()
        );
    }

    // The JSON file is written even if stdout fails (e.g. `| head -1`).
    let printed = (|| {
        let mut out = Stdout::new();
        out.print(format_args!(
            "arm `{}` ({}) on {}\n",
            arm.name,
            args.input.arm.display(),
            args.input.data.display()
        ))?;
        out.print(evaluation.to_table())?;
        out.finish()
    })();
    if let Some(path) = &args.json {
        let report = Report {
            arm: &arm.name,
            arm_file: args.input.arm.display().to_string(),
            data_file: args.input.data.display().to_string(),
            lengths_file: args.lengths.as_ref().map(|p| p.display().to_string()),
            length_unit: "mm",
            evaluation: &evaluation,
        };
        let text = serde_json::to_string_pretty(&report)?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("{}: cannot write", path.display()))?;
    }
    printed
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
