//! `aacmm evaluate`: the single-point and length figures of an arm on
//! measured poses — the paper's and the standards' (see `aacmm_core::metrics`
//! for every formula).

use std::path::{Path, PathBuf};

use aacmm_core::calibrate::validate::FrameValues;
use aacmm_core::dataset::DataSet;
use aacmm_core::domain::Arm;
use aacmm_core::io::frames::parse_frames;
use aacmm_core::io::spheres::read_spheres;
use aacmm_core::io::{read_lengths, read_positions, source_name};
use aacmm_core::report::EVALUATION_FILES;
use aacmm_core::session::spheres::SphereEvaluation;
use aacmm_core::session::{EvaluationReport, PositionEvaluation, Sources};
use anyhow::{Context, Result, bail};

use crate::output::Stdout;
use crate::paths::{check_output_dir, check_output_file};

/// Evaluate an arm on measured poses, or at reference positions.
#[derive(clap::Args)]
#[command(mut_arg("data", |a| a
    .required(false)
    .required_unless_present_any(["positions", "spheres"])
    .help("Poses file (CSV `point,q1,...,qn`: touches of points); `-` reads standard input. \
           Optional with --positions or --spheres")))]
pub struct Args {
    #[command(flatten)]
    input: super::ArmAndPoses,
    /// Reference lengths (CSV `point_a,point_b,distance[,uncertainty]`, mm).
    #[arg(long, requires = "data")]
    lengths: Option<PathBuf>,
    /// Reference positions an instrument saw (a laser tracker): CSV
    /// `point,q1,...,qn,x,y,z[,frame][,tool][,uncertainty]`, as calibrate
    /// --positions reads (each tool at the arm file's `[[tool]]` offset). Prints the arm's 3-D errors there (mean, RMS,
    /// 95th percentile, max per frame), each frame registered as the arm
    /// file's `[[frame]]` of its name (a calibrated arm's), else to this
    /// arm in closed form on these positions (optimistic) — and says which.
    /// Rows with the tool's orientation (`qw,qx,qy,qz`) add its errors,
    /// per frame, the 6-D target's mount as the arm file's `[mount]` states
    /// it, else in closed form (said so too).
    /// Printed only: --json and --report are of the touches (--data).
    #[arg(long, value_name = "P.csv")]
    positions: Option<PathBuf>,
    /// Points probed on reference spheres: CSV `sphere,q1,...,qn`, as
    /// calibrate --spheres reads. Prints each sphere's diameter, RMS radial
    /// residual and form with its centre (and diameter, unless
    /// --sphere-diameter states it) fitted on its points, the arm held
    /// fixed, and every point's radial errors. Printed only.
    #[arg(long, value_name = "S.csv")]
    spheres: Option<PathBuf>,
    /// The spheres' stated diameter, mm (needs the arm file's `[probe]
    /// ball_diameter_mm`).
    #[arg(long, value_name = "MM", requires = "spheres")]
    sphere_diameter: Option<f64>,
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
    /// The probe that touched --data: one of the arm file's `[[tool]]` (a
    /// stylus) instead of its `[probe]` — its offset. (Positions and sphere
    /// files name their rows' tools in their own `tool` column.)
    #[arg(long, value_name = "NAME", requires = "data")]
    tool: Option<String>,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> Result<()> {
    let mut inputs = vec![("--arm", args.input.arm.as_path())];
    inputs.extend(args.input.data.as_deref().map(|d| ("--data", d)));
    inputs.extend(args.lengths.as_deref().map(|l| ("--lengths", l)));
    inputs.extend(args.positions.as_deref().map(|p| ("--positions", p)));
    inputs.extend(args.spheres.as_deref().map(|p| ("--spheres", p)));
    if args.input.data.is_none() {
        for (given, flag) in [
            (args.json.is_some(), "--json"),
            (args.report.is_some(), "--report"),
            (args.pairs, "--pairs"),
        ] {
            if given {
                bail!(
                    "{flag}: written for the touches of --data; the errors at --positions are \
                     printed"
                );
            }
        }
        let arm = args.input.read_arm()?;
        print_positions(&args, &arm)?;
        return print_spheres(&args, &arm);
    }
    if let Some(json) = &args.json {
        check_output_file("--json", json, &inputs, args.force)?;
    }
    if let Some(dir) = &args.report {
        check_output_dir("--report", dir, &EVALUATION_FILES, &inputs, args.force)?;
    }
    let (arm, poses) = args.input.read()?;
    let arm = match &args.tool {
        Some(name) => aacmm_core::domain::arm_with_tool(&arm, name)
            .map_err(super::shared_flags::flag_error)?,
        None => arm,
    };
    let kernel = args.input.kernel(&arm)?;
    let data_path = args.input.data()?;
    let mut data = DataSet::from_poses_owned(poses, &source_name(data_path))?;
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
        data_file: source_name(data_path),
        lengths_file: args.lengths.as_deref().map(source_name),
        warnings: Vec::new(),
    };
    let threads = super::worker_threads(args.threads);
    let report = EvaluationReport::new(&arm, &data, &xyz, &sources, threads)
        .with_context(|| format!("{}: on {}", args.input.arm.display(), data_path.display()))?
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
    printed?;
    print_positions(&args, &arm)?;
    print_spheres(&args, &arm)
}

/// The arm on --spheres, if given, printed.
fn print_spheres(args: &Args, arm: &Arm) -> Result<()> {
    let Some(path) = &args.spheres else {
        return Ok(());
    };
    let file = source_name(path);
    let (rows, warnings) = read_spheres(path, args.input.angle_unit, arm)?;
    super::report(&warnings)?;
    let evaluation = SphereEvaluation::new(arm, rows, &file, args.sphere_diameter)
        .map_err(super::shared_flags::flag_error)?;
    let mut out = Stdout::new();
    out.write_with(|w| w.write_all(evaluation.summary().as_bytes()))?;
    out.finish()
}

/// The arm's 3-D errors at --positions, if given, printed.
fn print_positions(args: &Args, arm: &Arm) -> Result<()> {
    let Some(path) = &args.positions else {
        return Ok(());
    };
    let file = source_name(path);
    let rows = read_positions(path, args.input.angle_unit, arm)?;
    let data = DataSet::from_positions(rows, &file)?;
    let stated: Vec<FrameValues> = stated_frames(&args.input.arm)?;
    let evaluation = PositionEvaluation::new(arm, &data, &stated)
        .with_context(|| format!("{}: on {file}", args.input.arm.display()))?;
    let mut out = Stdout::new();
    out.write_with(|w| w.write_all(evaluation.summary().as_bytes()))?;
    out.finish()
}

/// The frames the arm file states (`[[frame]]`, a calibrated arm's), by
/// name; none for an arm read from standard input.
fn stated_frames(arm: &Path) -> Result<Vec<FrameValues>> {
    if arm.as_os_str() == "-" {
        return Ok(Vec::new());
    }
    let text =
        std::fs::read_to_string(arm).with_context(|| format!("{}: cannot read", arm.display()))?;
    let frames = parse_frames(&text, &source_name(arm))?;
    let mut values: Vec<FrameValues> = frames
        .iter()
        .map(|f| (f.name.clone(), f.values()))
        .collect();
    // A calibrated arm's mount of a 6-D target, where the orientations are
    // evaluated.
    if let Some(m) = aacmm_core::io::frames::parse_mount(&text, &source_name(arm))? {
        let r = m.rotation_deg.map(f64::to_radians);
        let name = aacmm_core::residuals::MOUNT_BLOCK.to_string();
        values.push((name, [r[0], r[1], r[2], 0.0, 0.0, 0.0]));
    }
    Ok(values)
}
