//! `aacmm evaluate`: the single-point and length figures of an arm on
//! measured poses — the paper's and the standards' (see `aacmm_core::metrics`
//! for every formula).

use std::path::PathBuf;

use aacmm_core::dataset::DataSet;
use aacmm_core::io::{read_lengths, source_name};
use aacmm_core::report::EVALUATION_FILES;
use aacmm_core::session::{EvaluationReport, Sources};
use anyhow::{Context, Result};

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
    /// Worker threads for the pairs of points, 1 to 1024 (default: every core);
    /// results do not depend on it.
    #[arg(long, value_name = "N", value_parser = super::shared_flags::threads_flag)]
    threads: Option<usize>,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> Result<()> {
    let mut inputs = vec![
        ("--arm", args.input.arm.as_path()),
        ("--data", &args.input.data),
    ];
    inputs.extend(args.lengths.as_deref().map(|l| ("--lengths", l)));
    if let Some(json) = &args.json {
        check_output_file("--json", json, &inputs, args.force)?;
    }
    if let Some(dir) = &args.report {
        check_output_dir("--report", dir, &EVALUATION_FILES, &inputs, args.force)?;
    }
    let (arm, poses) = args.input.read()?;
    let kernel = args.input.kernel(&arm)?;
    let mut data = DataSet::from_poses_owned(poses, &source_name(&args.input.data))?;
    // Rows counted once are said, with their lines, before any figure.
    super::report(data.repeat_warnings())?;
    if let Some(path) = &args.lengths {
        data = data.with_lengths(&read_lengths(path)?, &source_name(path))?;
        // As calibrate and identify check them: lengths in another unit
        // than the arm are refused, naming the input at fault.
        aacmm_core::session::check_units(&arm.params, &data, &source_name(&args.input.arm))?;
    }
    // The positions and the rows below are the evaluation's: room first.
    aacmm_core::metrics::room_to_evaluate(&data)?;
    let mut xyz = vec![[0.0; 3]; data.len()];
    args.input.check_conditions(&arm)?;
    let rows: Vec<&[f64]> = (0..data.len()).map(|i| data.reading(i)).collect();
    match args
        .input
        .corrected(&arm, &rows, data.conditions().approach)?
    {
        Some(poses) => kernel.positions(&poses, 0..data.len(), &mut xyz)?,
        None => kernel.positions(data.poses(), 0..data.len(), &mut xyz)?,
    }
    args.input
        .check_finite(&xyz, |i| data.source().touch(i).line)?;
    let sources = Sources {
        arm_file: source_name(&args.input.arm),
        data_file: source_name(&args.input.data),
        lengths_file: args.lengths.as_deref().map(source_name),
        warnings: Vec::new(),
    };
    let threads = super::worker_threads(args.threads);
    let report = EvaluationReport::new(&arm, &data, &xyz, &sources, threads)
        .with_context(|| {
            format!(
                "{}: on {}",
                args.input.arm.display(),
                args.input.data.display()
            )
        })?
        .with_pairs(args.pairs);

    // The JSON file is written even if stdout fails (e.g. `| head -1`).
    let printed = (|| {
        let mut out = Stdout::new();
        out.write_with(|w| report.write_summary(w))?;
        out.finish()
    })();
    if let Some(path) = &args.json {
        super::write_json(path, &report)?;
    }
    if let Some(dir) = &args.report {
        let json = args.json.as_deref().map(source_name);
        let page = report.html(json.as_deref()).context("--report")?;
        super::report::write("--report", dir, &page)?;
    }
    printed
}
