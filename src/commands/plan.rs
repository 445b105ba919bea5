//! `aacmm plan`: which poses to measure — `K` rows of a pool of candidate
//! poses chosen so that the calibration they feed predicts the probe's
//! position best over the workspace (see `aacmm_core::plan` for the
//! criterion and docs/plan.md for why).
//!
//! Without `--out` only the summary is printed (the ranking names the rows
//! of the candidates file); with `--out` the chosen rows are written too, as
//! a poses file in the order chosen (a sphere-surface file for `--measure
//! spheres`), so that a sampled pool's poses can be measured.

use std::path::{Path, PathBuf};

use aacmm_core::domain::{Arm, Poses, Spheres};
use aacmm_core::io::spheres::{read_spheres, write_spheres};
use aacmm_core::io::{AngleUnit, limit_warning, read_arm, read_poses_or_positions, source_name};
use aacmm_core::plan::{
    Criterion, DEFAULT_SOCKETS, Given, GivenNote, Measure, Plan, PlanError, PlanSettings, Pool,
    SampleError, SummaryContext, plan, sample_positions, sample_sphere_points,
    sample_touches_observed, sphere_candidates, summary,
};
use aacmm_core::report::REPORT_FILE;
use aacmm_core::session::CalibrationReport;
use aacmm_core::simulate::{DEFAULT_SPHERE_DIAMETER_MM, SimError, SocketPlan};
use anyhow::{Context, Result, anyhow, bail};
use clap::{ArgGroup, ValueEnum};

use super::report;
use crate::output::{Stdout, warn};
use crate::paths::{Input, check_output_file};

// The default quoted in --workspace-poses' help is the library's.
const _: () = assert!(aacmm_core::plan::WORKSPACE_POSES == 500);

/// Rows chosen with --given when --count is not given.
const DEFAULT_NEXT: usize = 10;

/// Choose which poses to measure (experiment design): K rows of a pool of
/// candidates that make the calibration predict the probe's position best
/// over the workspace.
#[derive(clap::Args)]
#[command(group(ArgGroup::new("pool").required(true).args(["candidates", "sample"])))]
pub struct Args {
    /// Arm file (TOML): the arm the plan is for; its joint limits bound
    /// --sample (±180° for a joint without).
    #[arg(long, value_name = "ARM.toml")]
    arm: PathBuf,
    /// Candidate poses (CSV `point,q1,...,qn`), or a reference-positions
    /// file (`point,q1,...,qn,x,y,z[,frame][,uncertainty]`) whose readings
    /// are taken, its positions ignored; for touches the `point` labels are
    /// the sockets. For sphere points a sphere-surface file (`sphere,q1,...,
    /// qn`, as calibrate --spheres reads). `-` reads standard input.
    #[arg(long, value_name = "POOL.csv")]
    candidates: Option<PathBuf>,
    /// Draw N candidates instead: positions uniformly within the joint
    /// limits; touches of sockets placed as `aacmm simulate` places them,
    /// found on the arm itself by inverse kinematics (N rounded up to a
    /// multiple of the sockets); sphere points as `aacmm simulate
    /// --spheres` places and probes them, 25 a sphere (N rounded up).
    #[arg(long, value_name = "N")]
    sample: Option<usize>,
    /// The sockets of sampled touches (CSV `point,x,y,z`, mm).
    #[arg(
        long,
        value_name = "FILE",
        requires = "sample",
        conflicts_with = "socket_count"
    )]
    sockets: Option<PathBuf>,
    /// Sockets of sampled touches, spread over the reachable volume
    /// [default: 5].
    #[arg(long, value_name = "S", requires = "sample")]
    socket_count: Option<usize>,
    /// Rows to choose [default: 10 with --given].
    #[arg(long, value_name = "K", required_unless_present = "given")]
    count: Option<usize>,
    /// What the campaign measures: reference positions an instrument sees
    /// (its frame fitted with the arm), touches of sockets, or points
    /// probed on reference spheres (each one's centre fitted, and its
    /// diameter unless --sphere-diameter states it).
    #[arg(long, value_enum)]
    measure: MeasureFlag,
    /// Sphere points: the spheres' diameter, mm, as calibrate will be told
    /// it (each sphere's size then known, so the points fix the arm's
    /// scale); --sample draws spheres of this size [default: 25.4, the
    /// diameter fitted, unless the --given calibration stated one].
    #[arg(long, value_name = "MM")]
    sphere_diameter: Option<f64>,
    /// Unit of the joint readings (q1..qn) of the poses files read
    /// (--candidates, --workspace) and written (--out); the arm file states
    /// its own (`angle_unit`).
    #[arg(long, default_value = "deg", value_parser = super::angle_unit())]
    angle_unit: AngleUnit,
    /// A calibration's output directory (calibration.json): plan the next
    /// measurements at the calibrated arm, starting from what it knows
    /// (its covariance, its σ per row and σ̂₀).
    #[arg(long, value_name = "DIR", conflicts_with = "noise")]
    given: Option<PathBuf>,
    /// Where the arm will be used (a poses file, or a positions file's
    /// readings): the predicted uncertainty is averaged over these poses
    /// [default: the candidates].
    #[arg(long, value_name = "POSES.csv")]
    workspace: Option<PathBuf>,
    /// Workspace poses the criterion averages over at most: an even sample
    /// of a larger workspace (each pose adds to every step's work)
    /// [default: 500].
    #[arg(long, value_name = "N")]
    workspace_poses: Option<usize>,
    /// What is optimised: the mean predicted position variance over the
    /// workspace, one row from each of K strata of look-alike candidates
    /// (robust), over all candidates freely (i), or the determinant of the
    /// information (d, for comparison).
    #[arg(long, value_enum, default_value = "robust")]
    criterion: CriterionFlag,
    /// τ of the robust criterion: each candidate's rows count as noisier by
    /// 1 + τ²·(its leverage / the mean), τ the error no model explains at a
    /// pose of average leverage in units of the noise (with --given at least
    /// the calibration's sqrt(σ̂₀² − 1)) [default: 0].
    #[arg(long, value_name = "TAU")]
    hedge: Option<f64>,
    /// σ of one measured row per coordinate, mm: scales every predicted
    /// radius, not the choice (with --given the calibration's own σ).
    #[arg(long, value_name = "MM", default_value_t = 0.01)]
    noise: f64,
    /// The tool the campaign will measure with: `probe` (the arm's
    /// `[probe]`, the default) or one of the arm file's `[[tool]]` (a
    /// stylus, a marker): the plan is for its offset (sampled touches seat
    /// its ball), and the calibration it predicts fits that offset.
    #[arg(
        long,
        value_name = "NAME",
        default_value = "probe",
        conflicts_with = "given"
    )]
    tool: String,
    /// Seed of the sampled candidates and of the random subsets the plan is
    /// compared with.
    #[arg(long, value_name = "N", default_value_t = 1)]
    seed: u64,
    /// Write the chosen rows here, in the order chosen (a poses file in
    /// --angle-unit, the candidates' labels).
    #[arg(long, value_name = "CHOSEN.csv")]
    out: Option<PathBuf>,
    /// Also write the whole plan as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

/// Values of --measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum MeasureFlag {
    /// Positions an instrument sees (laser tracker, artefact).
    Positions,
    /// Touches of sockets.
    Touches,
    /// Points probed on reference spheres.
    Spheres,
}

/// Values of --criterion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum CriterionFlag {
    /// I-optimal, each candidate discounted by its leverage.
    Robust,
    /// I-optimal: the mean predicted position variance.
    #[value(name = "i", alias = "prediction")]
    Prediction,
    /// D-optimal: the determinant of the information.
    #[value(name = "d", alias = "determinant")]
    Determinant,
}

/// The candidates, and the name messages give them: the file, or the flag
/// that drew them.
struct Candidates {
    pool: Pool,
    name: String,
}

/// A calibration the plan adds to.
struct Start {
    report: CalibrationReport,
    given: Given,
    note: GivenNote,
}

pub fn run(args: Args) -> Result<()> {
    check_paths(&args)?;
    let (arm, warnings) = read_arm(&args.arm)?;
    report(&warnings)?;
    // A tool's plan is its offset's: the probe replaced by it, as `points`
    // and `evaluate` compute with a `--tool`.
    let arm = aacmm_core::domain::arm_with_tool(&arm, &args.tool)
        .map_err(super::shared_flags::flag_error)?;
    let start = match &args.given {
        Some(dir) => Some(read_given(dir, &arm, &args.arm)?),
        None => None,
    };
    let params = start
        .as_ref()
        .map_or(&arm.params, |s| &s.report.calibration.params);
    // Bad settings are refused before a pool is drawn.
    let mut settings = settings(&args, start.is_some())?;
    // Points added to a calibration that stated its spheres' diameter are
    // planned as its next campaign will be fitted: the diameter stated.
    if let Some(spheres) = start.as_ref().and_then(|s| s.report.spheres.as_ref()) {
        settings.sphere_diameter_stated |= spheres.stated_diameter.is_some();
    }
    let candidates = candidates(&args, &arm)?;
    let workspace = match &args.workspace {
        Some(path) => Some(read_candidates("--workspace", path, &args, &arm)?),
        None => None,
    };
    let mut bar = super::progress::Bar::new();
    bar.busy("plan: choosing rows");
    let plan = plan(
        params,
        &candidates.pool.poses,
        workspace.as_ref(),
        start.as_ref().map(|s| &s.given),
        &settings,
    );
    drop(bar);
    let plan = plan.map_err(|e| match e {
        // The count's bounds: the library names the setting, the command
        // line its flag.
        PlanError::Invalid(m) if m.starts_with("count ") => anyhow!("--{m}"),
        e => anyhow!("{}: {e}", candidates.name),
    })?;
    if let Some(why) = plan.pool_undetermined() {
        bail!("{}: {why}", candidates.name);
    }
    let workspace_file = args.workspace.as_deref().map(source_name);
    let context = SummaryContext {
        pool: &candidates.pool,
        workspace: workspace_file.as_deref(),
        given: start.as_ref().map(|s| &s.note),
    };
    let mut text = summary(&plan, context);
    if let Some(path) = &args.out {
        write_chosen(path, &plan, &candidates.pool.poses, args.angle_unit)?;
        text += &format!("wrote {}\n", path.display());
    }
    if let Some(path) = &args.json {
        super::write_json(path, &plan)?;
        text += &format!("wrote {}\n", path.display());
    }
    let mut out = Stdout::new();
    out.print(text)?;
    out.finish()?;
    plan.warnings.iter().try_for_each(warn)?;
    if plan.planned.is_none() {
        bail!(
            "no usable plan: the {} chosen rows do not determine every parameter{}",
            plan.count,
            plan.rows_needed().map_or(String::new(), |rows| format!(
                "; {rows} rows do: give --count {rows} or more"
            ))
        );
    }
    Ok(())
}

/// The outputs can be written, are no input, and (without --force) hold
/// nothing yet.
fn check_paths(args: &Args) -> Result<()> {
    let mut inputs: Vec<Input> = vec![("--arm", &args.arm)];
    inputs.extend(args.candidates.as_deref().map(|p| ("--candidates", p)));
    inputs.extend(args.sockets.as_deref().map(|p| ("--sockets", p)));
    inputs.extend(args.workspace.as_deref().map(|p| ("--workspace", p)));
    let report = args.given.as_ref().map(|d| d.join(REPORT_FILE));
    inputs.extend(report.as_deref().map(|p| ("--given", p)));
    let outputs = [("--out", &args.out), ("--json", &args.json)];
    for (flag, path) in outputs {
        let Some(path) = path else { continue };
        check_output_file(flag, path, &inputs, args.force)?;
    }
    if let (Some(out), Some(json)) = (&args.out, &args.json)
        && out == json
    {
        bail!(
            "--out and --json: both are {}; give two files",
            out.display()
        );
    }
    Ok(())
}

/// The calibration in `dir`: its report, and what a plan starts from.
fn read_given(dir: &Path, arm: &Arm, arm_file: &Path) -> Result<Start> {
    let path = dir.join(REPORT_FILE);
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "--given {}: cannot read {REPORT_FILE} (give the directory `aacmm calibrate --out` \
             wrote)",
            dir.display()
        )
    })?;
    let mut report = CalibrationReport::from_json(&text)
        .map_err(|e| anyhow!("{}: not a calibration report: {e}", path.display()))?;
    let (theirs, ours) = (
        report.calibration.params.joint_count(),
        arm.params.joint_count(),
    );
    if theirs != ours {
        bail!(
            "--given {}: the calibration is of a {theirs}-joint arm, {} has {ours} joints",
            dir.display(),
            source_name(arm_file)
        );
    }
    // The report names parameters, not the joints' kinds: those of the
    // arm file, of the same chain.
    for (theirs, ours) in (report.calibration.params.joints.iter_mut()).zip(&arm.params.joints) {
        theirs.kind = ours.kind;
    }
    let given = report.plan_given().ok_or_else(|| {
        anyhow!(
            "{}: a free parameter's σ is not finite, so its covariance is unknown and no plan \
             can start from it",
            path.display()
        )
    })?;
    if !report.is_usable() {
        warn(format_args!(
            "{}: the calibration is not usable ({}); the plan starts from its covariance all \
             the same",
            path.display(),
            report
                .verdict
                .words(aacmm_core::session::Spelling::Cli)
                .reasons
                .join("; ")
        ))?;
    }
    let note = GivenNote {
        dir: dir.display().to_string(),
        sigma0: report.calibration.dof.sigma0,
    };
    Ok(Start {
        report,
        given,
        note,
    })
}

/// The pool: read (--candidates) or drawn (--sample).
fn candidates(args: &Args, arm: &Arm) -> Result<Candidates> {
    if let Some(path) = &args.candidates {
        let poses = match args.measure {
            MeasureFlag::Spheres => read_sphere_candidates(path, args, arm)?,
            _ => read_candidates("--candidates", path, args, arm)?,
        };
        return Ok(Candidates {
            pool: Pool::from_file(poses, &source_name(path)),
            name: format!("--candidates {}", source_name(path)),
        });
    }
    let Some(n) = args.sample else {
        bail!("give --candidates POOL.csv or --sample N");
    };
    let pool = match args.measure {
        MeasureFlag::Positions => sample_positions(arm, n, args.seed, &source_name(&args.arm))
            .map_err(|e| anyhow!("--sample {n}: {e}"))?,
        MeasureFlag::Spheres => {
            let d = args.sphere_diameter.unwrap_or(DEFAULT_SPHERE_DIAMETER_MM);
            sample_sphere_points(arm, n, d, args.seed).map_err(|e| anyhow!("--sample {n}: {e}"))?
        }
        MeasureFlag::Touches => {
            let sockets = match &args.sockets {
                Some(path) => SocketPlan::from_file(path)?,
                None => SocketPlan::Spread {
                    count: args.socket_count.unwrap_or(DEFAULT_SOCKETS),
                },
            };
            let mut bar = super::progress::Bar::new();
            let pool = sample_touches_observed(arm, sockets, n, args.seed, &mut |f| {
                bar.show("sampling", f)
            });
            drop(bar);
            pool.map_err(|e| sample_error(e, args, n))?
        }
    };
    Ok(Candidates {
        pool,
        name: format!("--sample {n}"),
    })
}

/// A poses file of the arm's joint count, or the readings of a positions
/// file, its warnings (readings outside the joint limits included)
/// printed.
fn read_candidates(flag: &str, path: &Path, args: &Args, arm: &Arm) -> Result<Poses> {
    let (poses, mut warnings, _) = read_poses_or_positions(path, args.angle_unit, arm)?;
    poses.refuse_tools(&source_name(path), "plan")?;
    let file = source_name(path);
    if poses.is_empty() {
        bail!("{flag} {file}: no poses");
    }
    warnings.extend(limit_warning(arm, &poses, &file, args.angle_unit));
    report(&warnings)?;
    Ok(poses)
}

/// A sphere-surface file's rows as candidates (each labelled by its
/// sphere), refused by file, line and field where its points fix no
/// sphere on the arm, its warnings printed.
fn read_sphere_candidates(path: &Path, args: &Args, arm: &Arm) -> Result<Poses> {
    let file = source_name(path);
    let (rows, warnings) = read_spheres(path, args.angle_unit, arm)?;
    report(&warnings)?;
    if (0..rows.len()).any(|i| rows.tool(i) != 0) {
        bail!(
            "--candidates {file}: its `tool` column names the probe of each row; plan for one \
             tool at a time with --tool NAME and a file without the column"
        );
    }
    aacmm_core::residuals::spheres::check_spheres(&rows, &file, &arm.params)?;
    let poses = sphere_candidates(&rows);
    let warnings: Vec<_> = limit_warning(arm, &poses, &file, args.angle_unit)
        .into_iter()
        .collect();
    report(&warnings)?;
    Ok(poses)
}

/// The library's refusal to draw touches, in terms of the flags.
fn sample_error(e: SampleError, args: &Args, n: usize) -> anyhow::Error {
    let flag = match &e {
        SampleError::NoSocket => "--socket-count 0".to_string(),
        SampleError::Simulate(SimError::Setting { name, .. }) if name == "sockets" => {
            "--socket-count".to_string()
        }
        SampleError::Simulate(SimError::Setting { name, .. }) if name == "sockets.points" => {
            match &args.sockets {
                Some(p) => format!("--sockets {}", p.display()),
                None => "--sockets".to_string(),
            }
        }
        _ => format!("--sample {n}"),
    };
    match e {
        SampleError::Simulate(SimError::Setting { message, .. }) => anyhow!("{flag}: {message}"),
        other => anyhow!("{flag}: {other}"),
    }
}

/// The library's settings from the flags.
fn settings(args: &Args, given: bool) -> Result<PlanSettings> {
    let count = args.count.unwrap_or(DEFAULT_NEXT);
    let measure = match args.measure {
        MeasureFlag::Positions => Measure::Positions,
        MeasureFlag::Touches => Measure::Touches,
        MeasureFlag::Spheres => Measure::Spheres,
    };
    let mut s = PlanSettings::new(count, measure);
    if let Some(d) = args.sphere_diameter {
        if measure != Measure::Spheres {
            bail!("--sphere-diameter {d}: applies to --measure spheres only");
        }
        aacmm_core::residuals::spheres::check_sphere_diameter(d)
            .map_err(super::shared_flags::flag_error)?;
        s.sphere_diameter_stated = true;
    }
    s.criterion = match args.criterion {
        CriterionFlag::Robust => Criterion::Robust,
        CriterionFlag::Prediction => Criterion::Prediction,
        CriterionFlag::Determinant => Criterion::Determinant,
    };
    if let Some(tau) = args.hedge {
        if s.criterion != Criterion::Robust {
            bail!("--hedge {tau}: applies to --criterion robust only");
        }
        if !(tau.is_finite() && tau >= 0.0) {
            bail!("--hedge {tau}: τ must be finite and not negative");
        }
        s.hedge = tau;
    }
    let noise_ok = args.noise.is_finite() && args.noise > 0.0;
    // With --given the calibration's σ is used (and --noise refused).
    if !given && !noise_ok {
        bail!("--noise {}: must be positive and finite, mm", args.noise);
    }
    s.sigma_mm = args.noise;
    s.seed = args.seed;
    if let Some(n) = args.workspace_poses {
        if n == 0 {
            bail!("--workspace-poses 0: at least 1");
        }
        s.workspace_limit = n;
    }
    Ok(s)
}

/// The chosen rows of `pool` in the order chosen, as a poses file (a
/// sphere-surface file for sphere points).
fn write_chosen(path: &Path, plan: &Plan, pool: &Poses, unit: AngleUnit) -> Result<()> {
    // The pool's prismatic joints are written as read: mm.
    let written = if plan.measure() == Measure::Spheres {
        let mut chosen = Spheres::new(pool.joints(), pool.prismatic_mask());
        for (rank, row) in plan.chosen().into_iter().enumerate() {
            chosen.push(pool.label(row), pool.reading(row), rank + 2, None);
        }
        aacmm_core::io::write_atomic_with(path, |w| write_spheres(w, &chosen, unit))
    } else {
        let mut chosen = pool.empty_like(plan.count);
        for (rank, row) in plan.chosen().into_iter().enumerate() {
            chosen.push(pool.label(row), pool.reading(row), rank + 2);
        }
        aacmm_core::io::write_atomic_with(path, |w| aacmm_core::io::write_poses(w, &chosen, unit))
    };
    written.with_context(|| format!("{}: cannot write", path.display()))
}
