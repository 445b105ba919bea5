//! `aacmm evaluate`: the single-point and length figures of an arm on
//! measured poses — the paper's and the standards' (see `aacmm_core::metrics`
//! for every formula).

use std::path::PathBuf;

use aacmm_core::dataset::DataSet;
use aacmm_core::io::{read_lengths, source_name};
use aacmm_core::metrics::{Evaluation, PairLengthError, evaluate_threads, pair_length_errors};
use aacmm_core::report::{EVALUATION_FILES, EvaluationInput, Measured, evaluation_report};
use anyhow::{Context, Result};
use serde::{Serialize, Serializer};

use crate::output::Stdout;
use crate::paths::{check_output_dir, check_output_file};

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
    /// Also list the paper's eq. 19 for every pair of points (table and
    /// JSON). Pairs grow as the square of the points; they are streamed.
    #[arg(long)]
    pairs: bool,
    /// Also write a report into this directory: report.html (one
    /// self-contained page) and each figure as an SVG — single-point
    /// errors, length errors, residuals.
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Worker threads for the pairs of points (default: every core);
    /// results do not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    threads: Option<u16>,
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
    #[serde(skip_serializing_if = "Option::is_none")]
    pair_length: Option<Pairs<'a>>,
}

/// Eq. 19 rows serialised as they are computed, never collected.
struct Pairs<'a> {
    data: &'a DataSet,
    xyz: &'a [[f64; 3]],
    evaluation: &'a Evaluation,
}

impl Pairs<'_> {
    fn rows(&self) -> impl Iterator<Item = PairLengthError> + '_ {
        pair_length_errors(self.data, self.xyz, &self.evaluation.points)
    }
}

impl Serialize for Pairs<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.rows())
    }
}

pub fn run(args: Args) -> Result<()> {
    let mut inputs = vec![
        ("--arm", args.input.arm.as_path()),
        ("--data", &args.input.data),
    ];
    inputs.extend(args.lengths.as_deref().map(|l| ("--lengths", l)));
    if let Some(json) = &args.json {
        check_output_file("--json", json, &inputs)?;
    }
    if let Some(dir) = &args.report {
        check_output_dir("--report", dir, &EVALUATION_FILES, &inputs)?;
    }
    let (arm, poses) = args.input.read()?;
    let kernel = args.input.kernel(&arm)?;
    let mut data = DataSet::from_poses_owned(poses, &source_name(&args.input.data))?;
    if let Some(path) = &args.lengths {
        data = data.with_lengths(&read_lengths(path)?, &source_name(path))?;
    }
    let mut xyz = vec![[0.0; 3]; data.len()];
    kernel.positions(data.poses(), 0..data.len(), &mut xyz)?;
    args.input
        .check_finite(&xyz, |i| data.source().touch(i).line)?;
    let threads = super::worker_threads(args.threads);
    let evaluation = evaluate_threads(&data, &xyz, threads).with_context(|| {
        format!(
            "{}: on {}",
            args.input.arm.display(),
            args.input.data.display()
        )
    })?;
    let pairs = Pairs {
        data: &data,
        xyz: &xyz,
        evaluation: &evaluation,
    };

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
        if args.pairs {
            out.write_with(|w| {
                aacmm_core::metrics::write_pair_table(w, pairs.rows(), data.points())
            })?;
        }
        out.finish()
    })();
    if let Some(path) = &args.json {
        let report = Report {
            arm: &arm.name,
            arm_file: source_name(&args.input.arm),
            data_file: source_name(&args.input.data),
            lengths_file: args.lengths.as_deref().map(source_name),
            length_unit: "mm",
            evaluation: &evaluation,
            pair_length: args.pairs.then_some(pairs),
        };
        super::write_json(path, &report)?;
    }
    if let Some(dir) = &args.report {
        let input = EvaluationInput {
            title: format!("Evaluation of arm `{}`", arm.name),
            inputs: report_inputs(&args, &arm.name, &data),
            measured: Measured {
                data: &data,
                held_out: false,
                before: None,
                after: &xyz,
            },
            arm: arm.name.clone(),
            evaluation_json: args.json.as_ref().map(|_| "/evaluation".to_string()),
        };
        let page = evaluation_report(&input).context("--report")?;
        super::report::write("--report", dir, &page)?;
    }
    printed
}

/// What went in, for the report's heading.
fn report_inputs(args: &Args, arm: &str, data: &DataSet) -> Vec<(String, String)> {
    let mut lines = vec![
        (
            "arm".to_string(),
            format!("`{arm}` ({})", source_name(&args.input.arm)),
        ),
        (
            "touches".to_string(),
            format!(
                "{}: {} touches of {} points",
                source_name(&args.input.data),
                data.len(),
                data.points().len()
            ),
        ),
        (
            "reference lengths".to_string(),
            match &args.lengths {
                Some(l) => format!("{}: {}", source_name(l), data.references().len()),
                None => "none (scale is not tested)".to_string(),
            },
        ),
    ];
    if let Some(json) = &args.json {
        lines.push((
            "written beside".to_string(),
            format!(
                "{} (every number of the tables that is also there is marked with its place)",
                source_name(json)
            ),
        ));
    }
    lines
}
