//! `aacmm plan`: which poses to measure — `K` rows of a pool of candidate
//! poses chosen so that the calibration they feed predicts the probe's
//! position best over the workspace (see `aacmm_core::plan` for the
//! criterion and docs/plan.md for why).
//!
//! Without `--out` only the summary is printed (the ranking names the rows
//! of the candidates file); with `--out` the chosen rows are written too, as
//! a poses file in the order chosen, so that a sampled pool's poses can be
//! measured.

use std::path::{Path, PathBuf};

use aacmm_core::error::short;
use aacmm_core::io::{
    AngleUnit, Arm, Poses, limit_warning, read_arm, read_poses, source_name, write_poses,
};
use aacmm_core::plan::{
    Criterion, CurvePoint, Given, Measure, Plan, PlanError, PlanSettings, Spread,
    coverage::K_ISOTROPIC, plan,
};
use aacmm_core::session::{CalibrationReport, REPORT_FILE};
use aacmm_core::simulate::{
    CampaignSettings, ErrorModel, MIN_POSES_PER_SOCKET, PositionSettings, SimError, SocketPlan,
    simulate_observed, simulate_positions,
};
use anyhow::{Context, Result, anyhow, bail};
use clap::{ArgGroup, ValueEnum};

use super::report;
use crate::output::{Stdout, warn};
use crate::paths::{Input, check_output_file};

// The default quoted in --workspace-poses' help is the library's.
const _: () = assert!(aacmm_core::plan::WORKSPACE_POSES == 500);

/// Rows chosen with --given when --count is not given.
const DEFAULT_NEXT: usize = 10;

/// Sockets of a sampled touch pool when neither --sockets nor
/// --socket-count is given.
const DEFAULT_SOCKETS: usize = 5;

/// σ of the encoder noise of sampled touches, degrees (0.36″, 1.7 µm at a
/// metre): see [`sample_touches`].
const SAMPLE_ENCODER_NOISE_DEG: f64 = 1e-4;

/// More rows stop paying where doubling them lowers the RMS radius by less
/// than this fraction.
const KNEE: f64 = 0.10;

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
    /// Candidate poses (CSV `point,q1,...,qn`); for touches the `point`
    /// labels are the sockets. `-` reads standard input.
    #[arg(long, value_name = "POOL.csv")]
    candidates: Option<PathBuf>,
    /// Draw N candidates instead: positions uniformly within the joint
    /// limits; touches of sockets placed as `aacmm simulate` places them,
    /// found on the arm itself by inverse kinematics (N rounded up to a
    /// multiple of the sockets).
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
    /// (its frame fitted with the arm) or touches of sockets.
    #[arg(long, value_enum)]
    measure: MeasureFlag,
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
    /// Where the arm will be used (a poses file): the predicted
    /// uncertainty is averaged over these poses [default: the candidates].
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

/// The candidates, and where they come from.
struct Pool {
    poses: Poses,
    /// In words, for the summary.
    origin: String,
    /// For messages: the file, or the flag that drew them.
    name: String,
    /// Whether the rows are lines of a file (the ranking names them).
    from_file: bool,
}

/// A calibration the plan adds to.
struct Start {
    report: CalibrationReport,
    given: Given,
    dir: PathBuf,
}

pub fn run(args: Args) -> Result<()> {
    check_paths(&args)?;
    let (arm, warnings) = read_arm(&args.arm)?;
    report(&warnings)?;
    let start = match &args.given {
        Some(dir) => Some(read_given(dir, &arm, &args.arm)?),
        None => None,
    };
    let params = start
        .as_ref()
        .map_or(&arm.params, |s| &s.report.calibration.params);
    // Bad settings are refused before a pool is drawn.
    let settings = settings(&args, start.is_some())?;
    let pool = candidates(&args, &arm)?;
    let workspace = match &args.workspace {
        Some(path) => Some(read_candidates("--workspace", path, &args, &arm)?),
        None => None,
    };
    let mut bar = super::progress::Bar::new();
    bar.busy("plan: choosing rows");
    let plan = plan(
        params,
        &pool.poses,
        workspace.as_ref(),
        start.as_ref().map(|s| &s.given),
        &settings,
    );
    drop(bar);
    let plan = plan.map_err(|e| match e {
        // The count's bounds: the library names the setting, the command
        // line its flag.
        PlanError::Invalid(m) if m.starts_with("count ") => anyhow!("--{m}"),
        e => anyhow!("{}: {e}", pool.name),
    })?;
    if plan.all.is_none() {
        bail!(
            "{}: even all {} candidates do not determine the {} parameters ({}): no subset \
             can; add candidates that turn the joints further{}",
            pool.name,
            plan.candidates,
            plan.parameters.len(),
            plan.parameters.join(", "),
            if plan.measure == Measure::Touches {
                ", or touches of more sockets"
            } else {
                ""
            }
        );
    }
    let mut text = summary(&plan, &pool, &args, start.as_ref());
    if let Some(path) = &args.out {
        write_chosen(path, &plan, &pool.poses, args.angle_unit)?;
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
        let enough = plan.curve.iter().find(|c| c.rms_mm.is_some());
        bail!(
            "no usable plan: the {} chosen rows do not determine every parameter{}",
            plan.count,
            enough.map_or(String::new(), |c| format!(
                "; {} rows do: give --count {} or more",
                c.rows, c.rows
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
    let report = CalibrationReport::from_json(&text)
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
            report.verdict.reasons.join("; ")
        ))?;
    }
    Ok(Start {
        report,
        given,
        dir: dir.to_path_buf(),
    })
}

/// The pool: read (--candidates) or drawn (--sample).
fn candidates(args: &Args, arm: &Arm) -> Result<Pool> {
    if let Some(path) = &args.candidates {
        return Ok(Pool {
            poses: read_candidates("--candidates", path, args, arm)?,
            origin: format!("from {}", source_name(path)),
            name: format!("--candidates {}", source_name(path)),
            from_file: true,
        });
    }
    let Some(n) = args.sample else {
        bail!("give --candidates POOL.csv or --sample N");
    };
    match args.measure {
        MeasureFlag::Positions => sample_positions(arm, n, args.seed, &args.arm),
        MeasureFlag::Touches => sample_touches(args, arm, n),
    }
}

/// A poses file of the arm's joint count, its warnings (readings outside
/// the joint limits included) printed.
fn read_candidates(flag: &str, path: &Path, args: &Args, arm: &Arm) -> Result<Poses> {
    let n = arm.params.joint_count();
    let (poses, mut warnings) = read_poses(path, args.angle_unit, Some(n))?;
    let file = source_name(path);
    if poses.is_empty() {
        bail!("{flag} {file}: no poses");
    }
    warnings.extend(limit_warning(arm, &poses, &file, args.angle_unit));
    report(&warnings)?;
    Ok(poses)
}

/// `n` poses uniformly within the arm's joint limits (±180° where none),
/// labelled `P1…Pn`: the poses `aacmm simulate --positions` draws.
fn sample_positions(arm: &Arm, n: usize, seed: u64, file: &Path) -> Result<Pool> {
    if n == 0 {
        bail!("--sample 0: draw at least one candidate");
    }
    let settings = PositionSettings {
        poses: n,
        frames: 1,
        // The instrument's readings are not used: only the poses.
        noise: aacmm_core::residuals::Noise {
            position_mm: Some(0.0),
            ..Default::default()
        },
        seed,
    };
    let drawn = simulate_positions(arm, &settings).map_err(|e| anyhow!("--sample {n}: {e}"))?;
    let rows = drawn.positions;
    let mut poses = Poses::with_capacity(rows.joints(), rows.len());
    for i in 0..rows.len() {
        poses.push(rows.label(i), rows.reading(i), i + 2);
    }
    let limits = arm.limits.iter().filter(|l| l.is_some()).count();
    let within = match limits {
        0 => "±180° on every joint".to_string(),
        l if l == rows.joints() => format!("the joint limits of {}", source_name(file)),
        _ => format!(
            "the joint limits of {} (±180° where none)",
            source_name(file)
        ),
    };
    Ok(Pool {
        poses,
        origin: format!("drawn uniformly within {within} (seed {seed})"),
        name: format!("--sample {n}"),
        from_file: false,
    })
}

/// About `n` touches of sockets spread as `aacmm simulate` spreads them
/// (or read from --sockets), each found by inverse kinematics on the arm
/// itself: the simulator with no error and no noise.
fn sample_touches(args: &Args, arm: &Arm, n: usize) -> Result<Pool> {
    let sockets = match &args.sockets {
        Some(path) => SocketPlan::from_file(path)?,
        None => SocketPlan::Spread {
            count: args.socket_count.unwrap_or(DEFAULT_SOCKETS),
        },
    };
    let count = sockets.count();
    if count == 0 {
        bail!("--socket-count 0: at least one socket");
    }
    let per = n.div_ceil(count);
    if per < MIN_POSES_PER_SOCKET {
        bail!(
            "--sample {n}: {count} sockets need at least {} touches ({MIN_POSES_PER_SOCKET} \
             per socket)",
            MIN_POSES_PER_SOCKET * count
        );
    }
    // The true arm is the arm itself: no error, no lengths, and an encoder
    // noise far below any encoder's resolution. Touches that fit the arm
    // exactly (zero residuals) make the identifiability analysis the plan
    // starts from leave the arm's scale free (its scale direction is then
    // an exact null direction, which it sets aside as redundant), and no
    // plan is determined; this noise keeps the residuals off zero.
    let errors = ErrorModel::File { arm: arm.clone() };
    let mut settings = CampaignSettings::new(args.seed, errors, count, per);
    settings.sockets = sockets;
    settings.reference_lengths = 0;
    settings.encoder_noise_deg = SAMPLE_ENCODER_NOISE_DEG;
    let mut bar = super::progress::Bar::new();
    let campaign = simulate_observed(arm, &settings, &mut |f| bar.show("sampling", f))
        .map_err(|e| sample_error(e, args, n))?;
    drop(bar);
    let placed = match &args.sockets {
        Some(path) => format!("from {}", source_name(path)),
        None => "spread over the reachable volume".to_string(),
    };
    Ok(Pool {
        origin: format!(
            "{count} sockets {placed}, {per} touches each found on the arm by inverse \
             kinematics (seed {})",
            args.seed
        ),
        poses: campaign.poses,
        name: format!("--sample {n}"),
        from_file: false,
    })
}

/// The simulator's refusal in terms of the flags.
fn sample_error(e: SimError, args: &Args, n: usize) -> anyhow::Error {
    let flag = match &e {
        SimError::Setting { name, .. } if name == "sockets" => "--socket-count".to_string(),
        SimError::Setting { name, .. } if name == "sockets.points" => match &args.sockets {
            Some(p) => format!("--sockets {}", p.display()),
            None => "--sockets".to_string(),
        },
        _ => format!("--sample {n}"),
    };
    match e {
        SimError::Setting { message, .. } => anyhow!("{flag}: {message}"),
        other => anyhow!("{flag}: {other}"),
    }
}

/// The library's settings from the flags.
fn settings(args: &Args, given: bool) -> Result<PlanSettings> {
    let count = args.count.unwrap_or(DEFAULT_NEXT);
    let measure = match args.measure {
        MeasureFlag::Positions => Measure::Positions,
        MeasureFlag::Touches => Measure::Touches,
    };
    let mut s = PlanSettings::new(count, measure);
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

/// How much of the workspace the criterion used: all of it, or an even
/// sample, with why and how to use more.
fn workspace_used(plan: &Plan) -> String {
    if plan.workspace_poses >= plan.workspace_total {
        return format!(" ({} poses)", plan.workspace_poses);
    }
    format!(
        ", an even sample of {} of its {} poses (each workspace pose adds to every step's \
         work; --workspace-poses N uses up to N)",
        plan.workspace_poses, plan.workspace_total
    )
}

/// The chosen rows of `pool` in the order chosen, as a poses file.
fn write_chosen(path: &Path, plan: &Plan, pool: &Poses, unit: AngleUnit) -> Result<()> {
    let mut chosen = Poses::with_capacity(pool.joints(), plan.count);
    for (rank, row) in plan.chosen().into_iter().enumerate() {
        chosen.push(pool.label(row), pool.reading(row), rank + 2);
    }
    aacmm_core::io::write_atomic_with(path, |w| write_poses(w, &chosen, unit))
        .with_context(|| format!("{}: cannot write", path.display()))
}

/// What the user reads: what was optimised, the predicted radius with the
/// chosen rows against all and against random ones, the curve, the ranking,
/// the sockets and the joint spans.
fn summary(plan: &Plan, pool: &Pool, args: &Args, start: Option<&Start>) -> String {
    let mut t = header(plan, pool, args, start);
    t += &spreads(plan);
    t += &curve(plan);
    t += &ranking(plan, pool, start.is_some());
    if !plan.sockets.is_empty() {
        let s: Vec<String> = (plan.sockets.iter())
            .map(|(label, n)| format!("{label} {n}"))
            .collect();
        t += &format!("Touches per socket: {}\n", s.join(", "));
    }
    let spans: Vec<String> = (plan.joints.iter())
        .map(|j| format!("q{} {:.0}/{:.0}", j.joint, j.chosen_deg, j.pool_deg))
        .collect();
    t += &format!(
        "Joint spans, chosen/candidates (deg): {}\n",
        spans.join(", ")
    );
    t
}

/// The plan's first lines: the pool, what was optimised, the noise.
fn header(plan: &Plan, pool: &Pool, args: &Args, start: Option<&Start>) -> String {
    let what = match plan.measure {
        Measure::Positions => "positions",
        Measure::Touches => "touches",
    };
    let mut t = format!(
        "Plan: {} of {} candidate {what}, {}\n",
        plan.count, plan.candidates, pool.origin
    );
    if let Some(s) = start {
        let c = &s.report.calibration;
        t += &format!(
            "Adding to the calibration in {} (its covariance the start; σ̂₀ {:.2})\n",
            s.dir.display(),
            c.dof.sigma0
        );
    }
    let workspace = format!(
        "{}{}",
        match &args.workspace {
            Some(p) => source_name(p),
            None => "the candidates".to_string(),
        },
        workspace_used(plan)
    );
    let criterion = match plan.criterion {
        Criterion::Robust if plan.hedge > 0.0 => format!(
            "the mean predicted variance of a probe position over the workspace, one row from \
             each of {} strata of look-alike candidates, each discounted by its leverage \
             (robust, τ = {:.2})",
            plan.strata, plan.hedge
        ),
        Criterion::Robust => format!(
            "the mean predicted variance of a probe position over the workspace, one row from \
             each of {} strata of look-alike candidates (robust)",
            plan.strata
        ),
        Criterion::Prediction => {
            "the mean predicted variance of a probe position over the workspace (I-optimal)"
                .to_string()
        }
        Criterion::Determinant => {
            "the determinant of the information (D-optimal, for comparison)".to_string()
        }
    };
    let frame = plan
        .parameters
        .iter()
        .filter(|p| p.starts_with("frame "))
        .count();
    let geometry = plan.parameters.len() - frame;
    let frame = if frame > 0 {
        format!(" and the instrument frame's {frame}")
    } else {
        String::new()
    };
    t += &format!(
        "Optimised: {criterion}\n  workspace: {workspace}; parameters: {geometry} of the \
         geometry{frame}; noise σ {} mm per coordinate of a row{}\n",
        match start {
            Some(_) => format!("{:.4}", plan.sigma_mm),
            None => short(plan.sigma_mm),
        },
        if start.is_some() {
            " (the calibration's)"
        } else {
            ""
        }
    );
    t
}

/// The predicted radius with the chosen rows, all candidates, and random
/// subsets of the same size.
fn spreads(plan: &Plan) -> String {
    let row = |name: &str, s: Option<Spread>| match s {
        Some(s) => format!("  {name:<30} {:>9.4} {:>9.4}\n", s.rms_mm, s.max_mm),
        None => format!("  {name:<30}  not determined\n"),
    };
    let r = &plan.random;
    let mut t = format!(
        "Predicted 95 % radius of a probe position over the workspace (mm; {K_ISOTROPIC:.2} σ \
         for an isotropic error):\n  {:<30} {:>9} {:>9}\n",
        "", "RMS", "max"
    );
    if plan.given {
        t += &row("the calibration alone", plan.start);
        t += &row(&format!("with the {} chosen", plan.count), plan.planned);
        t += &row(
            &format!("with all {} candidates", plan.candidates),
            plan.all,
        );
    } else {
        t += &row(&format!("the {} chosen", plan.count), plan.planned);
        t += &row(&format!("all {} candidates", plan.candidates), plan.all);
    }
    t += &row(
        &format!("{} at random (median of {})", plan.count, r.sets),
        r.median,
    );
    if r.determined < r.sets {
        t += &format!(
            "  ({} of the {} random subsets determine every parameter)\n",
            r.determined, r.sets
        );
    }
    t
}

/// Where more rows stop paying, read off the curve.
#[derive(Debug, PartialEq)]
enum Knee {
    /// Doubling from `rows` lowers the RMS by `gain` (< [`KNEE`]).
    At { rows: usize, gain: f64 },
    /// Every doubling the curve shows still gains [`KNEE`] or more; the
    /// last from `rows`, by `gain`.
    Beyond { rows: usize, gain: f64 },
    /// The curve shows no doubling of determined rows.
    Unknown,
}

/// The first determined point of the curve from which doubling the rows
/// lowers the RMS radius by less than [`KNEE`] (the RMS at twice the rows
/// interpolated between the curve's points).
fn knee(curve: &[CurvePoint]) -> Knee {
    let points: Vec<(usize, f64)> = curve
        .iter()
        .filter_map(|c| c.rms_mm.map(|r| (c.rows, r)))
        .collect();
    let at = |rows: usize| -> Option<f64> {
        let i = points.iter().position(|&(k, _)| k >= rows)?;
        let (k1, r1) = points[i];
        if k1 == rows || i == 0 {
            return (k1 == rows).then_some(r1);
        }
        let (k0, r0) = points[i - 1];
        Some(r0 + (r1 - r0) * (rows - k0) as f64 / (k1 - k0) as f64)
    };
    let mut last = Knee::Unknown;
    for &(k, r) in &points {
        let Some(r2) = at(2 * k) else { break };
        let gain = 1.0 - r2 / r;
        if gain < KNEE {
            return Knee::At { rows: k, gain };
        }
        last = Knee::Beyond { rows: k, gain };
    }
    last
}

/// The curve, rows → RMS radius, with the chosen count and the knee marked.
fn curve(plan: &Plan) -> String {
    let to = plan.curve.last().map_or(plan.count, |c| c.rows);
    let knee = knee(&plan.curve);
    let mut t = format!("RMS radius as rows are added (the greedy continued to {to}):\n");
    for c in &plan.curve {
        let value = c
            .rms_mm
            .map_or("not determined".to_string(), |r| format!("{r:.4} mm"));
        let mut marks = Vec::new();
        if c.rows == plan.count {
            marks.push("chosen");
        }
        if matches!(knee, Knee::At { rows, .. } if rows == c.rows) {
            marks.push("more stops paying");
        }
        let marks = if marks.is_empty() {
            String::new()
        } else {
            format!("  ← {}", marks.join(", "))
        };
        t += &format!("  {:>6}  {value}{marks}\n", c.rows);
    }
    t += &match knee {
        Knee::At { rows, gain } => format!(
            "  From {rows} rows, twice as many lower the RMS radius by {:.0} % only (< {:.0} %).\n",
            100.0 * gain,
            100.0 * KNEE
        ),
        Knee::Beyond { rows, gain } => format!(
            "  Twice {rows} rows still lower the RMS radius by {:.0} %: more rows still pay.\n",
            100.0 * gain
        ),
        Knee::Unknown => String::new(),
    };
    t
}

/// A step's criterion, `None` while the rows do not determine every
/// parameter. Generic over what [`aacmm_core::plan::Step::criterion_mm`]
/// holds, a value or an option: the library's plan is being reworked.
fn criterion_of(c: impl Into<Option<f64>>) -> Option<f64> {
    c.into()
}

/// The chosen rows in the order chosen: row of the pool (from 1), label,
/// line of the candidates file, and the criterion after each.
fn ranking(plan: &Plan, pool: &Pool, next: bool) -> String {
    let mut t = if next {
        format!("Measure these {} next, in this order", plan.count)
    } else {
        "Chosen, in order".to_string()
    };
    t += " (after each, the mean predicted variance over the workspace as an RMS radius, mm; \
          — until every parameter is determined):\n";
    let width = (plan.steps.iter().map(|s| s.label.len()))
        .max()
        .unwrap_or(0)
        .max(5);
    let line = |l: &str| {
        if pool.from_file {
            format!("  {l:>5}")
        } else {
            String::new()
        }
    };
    t += &format!(
        "  {:>4}  {:>5}  {:<width$}{}  criterion\n",
        "#",
        "row",
        "label",
        line("line")
    );
    for (rank, step) in plan.steps[..plan.count].iter().enumerate() {
        let criterion =
            criterion_of(step.criterion_mm).map_or("—".to_string(), |c| format!("{c:.4}"));
        t += &format!(
            "  {:>4}  {:>5}  {:<width$}{}  {criterion}\n",
            rank + 1,
            step.row + 1,
            step.label,
            line(&pool.poses.line(step.row).to_string())
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(points: &[(usize, Option<f64>)]) -> Vec<CurvePoint> {
        points
            .iter()
            .map(|&(rows, rms_mm)| CurvePoint { rows, rms_mm })
            .collect()
    }

    #[test]
    fn the_knee_is_the_first_doubling_that_gains_under_ten_percent() {
        let c = curve(&[
            (5, None),
            (10, Some(1.0)),
            (15, Some(0.7)),
            (20, Some(0.6)),
            (30, Some(0.57)),
            (40, Some(0.55)),
        ]);
        // 10 → 20: 40 %; 15 → 30: 18.6 %; 20 → 40: 8.3 %.
        match knee(&c) {
            Knee::At { rows, gain } => {
                assert_eq!(rows, 20);
                assert!((gain - (1.0 - 0.55 / 0.6)).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        // Interpolated: 10 → 20 between 15 and 30.
        let c = curve(&[(10, Some(1.0)), (15, Some(0.8)), (30, Some(0.5))]);
        match knee(&c) {
            Knee::Beyond { rows, gain } => {
                assert_eq!(rows, 15);
                assert!((gain - 0.375).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(knee(&curve(&[(5, None), (10, Some(1.0))])), Knee::Unknown);
    }
}
