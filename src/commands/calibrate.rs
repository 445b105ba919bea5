//! `aacmm calibrate`: the arm that makes the touches agree, with honest
//! uncertainties and validation on held-out data (see
//! `aacmm_core::calibrate`).

use std::path::PathBuf;
use std::time::Instant;

use aacmm_core::calibrate::{
    AnnealOptions, CalibrationError, Cancel, Context, GlobalOptions, Loss, SolverSettings,
    SwitchRule,
};
use aacmm_core::io::source_name;
use aacmm_core::report::{
    BEYOND_SVG, CALIBRATION_FILES, HTML_FILE, POSITIONS_SVG, UNCERTAINTY_MAP_SVG,
};
use aacmm_core::report::{CALIBRATED_FILE, REPORT_FILE, TIMING_FILE};
use aacmm_core::session::{self, Problem};
use anyhow::{Context as _, Result, bail};
use clap::ValueEnum;

use super::shared_flags::{FitInput, flag_error};
use crate::output::{Stdout, note, warn};
use crate::paths::check_output_dir;

/// Calibrate an arm from touches, reference lengths and/or reference positions.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    fit: FitInput,
    /// Parameters held at their nominal values: `auto` (identify's
    /// recommended set) or names such as `theta1,d1,theta6,alpha6,Bx,By`.
    #[arg(long, default_value = "auto", value_name = "auto|NAMES")]
    fix: String,
    /// The solver: `global` converges from encoder zeros unknown anywhere in
    /// ±180°; `lm` only from a near start; `sa` and `hybrid` are the
    /// paper's annealing alone and annealing then LM.
    #[arg(long, value_enum, default_value = "global")]
    method: Method,
    #[command(flatten)]
    solver: SolverFlags,
    /// Held-out poses to validate on (same CSV format as --data).
    #[arg(long, value_name = "POSES.csv")]
    validate: Option<PathBuf>,
    /// Reference lengths of the held-out points.
    #[arg(long, value_name = "L.csv", requires = "validate")]
    validate_lengths: Option<PathBuf>,
    /// Held-out reference positions to validate on (same CSV format as
    /// --positions): scored in the fitted frames of the same name; a frame the
    /// fit does not have is refused (see --register-held-out).
    #[arg(long, value_name = "P.csv")]
    validate_positions: Option<PathBuf>,
    /// Score held-out positions in a frame the fit does not have by
    /// registering that frame on its own positions (refused without this
    /// flag: such figures are optimistic, and every output then says so).
    #[arg(long, requires = "validate_positions")]
    register_held_out: bool,
    /// Held-out points on reference spheres to validate on (same CSV format
    /// as --spheres): each sphere's centre, and its diameter unless
    /// --sphere-diameter states it, refitted on its own points with the arm
    /// held fixed; scored by the points' radial error.
    #[arg(long, value_name = "S.csv")]
    validate_spheres: Option<PathBuf>,
    /// K-fold cross-validation over points (points joined by a reference
    /// length stay in one fold), reference positions (dealt per frame) and
    /// points on spheres (dealt per sphere, scored against the fold's
    /// spheres).
    #[arg(long, value_name = "K")]
    cross_validate: Option<usize>,
    /// The tool the rows that name none were measured with: `probe` (the
    /// arm's `[probe]`, the default) or one of the arm file's `[[tool]]` (a
    /// stylus, a marker), whose offset is then fitted and written to the
    /// calibrated arm's `[[tool]]`, the probe's held. For touches,
    /// positions and points on spheres in files without a `tool` column.
    #[arg(long, value_name = "NAME", default_value = "probe")]
    tool: String,
    /// Exit 0 even when the fit's χ² is far outside the stated noise or the
    /// calibrated arm is worse than the nominal on its own data (never for
    /// a mirror-image or collapsed arm).
    #[arg(long)]
    accept_poor_fit: bool,
    /// Robust fit after the solver: iteratively reweighted least squares
    /// with a Huber or Cauchy loss on each touch's standardised residual
    /// (in units of its σ); the weights go to calibration.json and the
    /// touches weighed below 0.25 are listed.
    #[arg(long, value_enum, value_name = "LOSS")]
    robust: Option<RobustLoss>,
    /// Tuning constant k of --robust, in robust-scale units of the
    /// standardised residual norm (default: 1.62 huber, 2.65 cauchy — 95 %
    /// efficiency under Gaussian noise).
    #[arg(long, value_name = "K", requires = "robust")]
    robust_scale: Option<f64>,
    /// Seed of every random draw (annealing moves, global starts,
    /// cross-validation folds): the same seed gives the same files.
    #[arg(long, default_value_t = 0, value_name = "S")]
    seed: u64,
    /// Output directory: calibrated.toml, calibration.json, timing.json and
    /// the report (report.html and one SVG per figure).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

/// Solvers.
#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
enum Method {
    /// Levenberg–Marquardt from the nominal arm.
    Lm,
    /// The paper's simulated annealing alone.
    Sa,
    /// The paper's hybrid: annealing, then LM from its best point.
    Hybrid,
    /// Multi-start on the circles of the zero offsets, then LM.
    Global,
}

impl From<Method> for aacmm_core::calibrate::Method {
    fn from(m: Method) -> Self {
        use aacmm_core::calibrate::Method as M;
        match m {
            Method::Lm => M::Lm,
            Method::Sa => M::Sa,
            Method::Hybrid => M::Hybrid,
            Method::Global => M::Global,
        }
    }
}

/// Losses of `--robust`.
#[derive(Clone, Copy, Debug, PartialEq, ValueEnum)]
enum RobustLoss {
    /// Quadratic up to k, linear beyond.
    Huber,
    /// Far outliers weigh almost nothing.
    Cauchy,
}

impl From<RobustLoss> for Loss {
    fn from(l: RobustLoss) -> Self {
        match l {
            RobustLoss::Huber => Loss::Huber,
            RobustLoss::Cauchy => Loss::Cauchy,
        }
    }
}

/// The solvers' settings (defaults in docs/calibration.md).
#[derive(clap::Args)]
struct SolverFlags {
    /// Annealing: start temperature T0, mm of energy.
    #[arg(long, value_name = "MM", default_value_t = AnnealOptions::default().t0)]
    sa_t0: f64,
    /// Annealing: cooling factor alpha (T <- alpha T), between 0 and 1.
    #[arg(long, value_name = "A", default_value_t = AnnealOptions::default().cooling)]
    sa_cooling: f64,
    /// Annealing: moves per temperature L.
    #[arg(long, value_name = "L", default_value_t = AnnealOptions::default().chain)]
    sa_chain: usize,
    /// Annealing: stop below this temperature, mm.
    #[arg(long, value_name = "MM", default_value_t = AnnealOptions::default().t_min)]
    sa_t_min: f64,
    /// Annealing: stop below this energy epsilon, mm (0 = never).
    #[arg(long, value_name = "MM", default_value_t = AnnealOptions::default().target)]
    sa_target: f64,
    /// Annealing: move range of lengths, mm.
    #[arg(long, value_name = "MM", default_value_t = AnnealOptions::default().step_mm)]
    sa_step_mm: f64,
    /// Annealing: move range of twists, degrees.
    #[arg(long, value_name = "DEG", default_value_t = AnnealOptions::default().twist_step_deg)]
    sa_twist_step: f64,
    /// Annealing: move range of zero offsets, degrees.
    #[arg(long, value_name = "DEG", default_value_t = AnnealOptions::default().zero_step_deg)]
    sa_zero_step: f64,
    /// Annealing: energy evaluation budget.
    #[arg(long, value_name = "N", default_value_t = AnnealOptions::default().max_evaluations)]
    sa_max_evaluations: usize,
    /// Hybrid: window s0 of the switching rule, temperatures.
    #[arg(long, value_name = "S0", default_value_t = SwitchRule::default().window)]
    switch_window: usize,
    /// Hybrid: threshold epsilon1 of the switching rule.
    #[arg(long, value_name = "E1", default_value_t = SwitchRule::default().epsilon)]
    switch_epsilon: f64,
    /// Global: most starts.
    #[arg(long, value_name = "N", default_value_t = GlobalOptions::default().max_starts)]
    global_starts: usize,
    /// Global: starts that must reach the lowest cost.
    #[arg(long, value_name = "N", default_value_t = GlobalOptions::default().confirmations)]
    global_confirmations: usize,
}

impl SolverFlags {
    /// The settings as given; the library checks them.
    fn options(&self) -> (AnnealOptions, SwitchRule, GlobalOptions) {
        let anneal = AnnealOptions {
            t0: self.sa_t0,
            cooling: self.sa_cooling,
            chain: self.sa_chain,
            t_min: self.sa_t_min,
            target: self.sa_target,
            step_mm: self.sa_step_mm,
            twist_step_deg: self.sa_twist_step,
            zero_step_deg: self.sa_zero_step,
            max_evaluations: self.sa_max_evaluations,
        };
        let switch = SwitchRule {
            window: self.switch_window,
            epsilon: self.switch_epsilon,
        };
        let global = GlobalOptions {
            max_starts: self.global_starts,
            confirmations: self.global_confirmations,
            ..GlobalOptions::default()
        };
        (anneal, switch, global)
    }
}

pub fn run(args: Args) -> Result<()> {
    check_paths(&args)?;
    let (problem, settings) = problem(&args)?;
    let started = Instant::now();
    let report = solve(&problem, &settings, &args)?;
    let total = started.elapsed().as_secs_f64();
    let wrote = write_files(&report, &problem, &args.out, total)?;
    print_results(&report, wrote, total)
}

/// --out may not hold an input, nor (without --force) earlier results.
fn check_paths(args: &Args) -> Result<()> {
    let mut inputs = args.fit.paths();
    inputs.extend(args.validate.as_deref().map(|p| ("--validate", p)));
    inputs.extend(
        args.validate_lengths
            .as_deref()
            .map(|p| ("--validate-lengths", p)),
    );
    inputs.extend(
        args.validate_positions
            .as_deref()
            .map(|p| ("--validate-positions", p)),
    );
    inputs.extend(
        args.validate_spheres
            .as_deref()
            .map(|p| ("--validate-spheres", p)),
    );
    check_output_dir(
        "--out",
        &args.out,
        &[
            &[
                CALIBRATED_FILE,
                REPORT_FILE,
                TIMING_FILE,
                POSITIONS_SVG,
                BEYOND_SVG,
                UNCERTAINTY_MAP_SVG,
            ][..],
            &CALIBRATION_FILES,
        ]
        .concat(),
        &inputs,
        args.force,
    )
}

/// The problem and the solver's settings the flags give, built by the
/// library's request (which owns every check and warning); the held-out
/// data's warnings are shown as they are read.
fn problem(args: &Args) -> Result<(Problem, SolverSettings)> {
    let (anneal, switch, global) = args.solver.options();
    let mut request = (args.fit.request()?)
        .fix(&args.fix)
        .method(aacmm_core::calibrate::Method::from(args.method).name())
        .seed(args.seed)
        .anneal(anneal)
        .switch(switch)
        .global(global)
        .accept_poor_fit(args.accept_poor_fit)
        .tool(&args.tool)
        .robust(args.robust.map(|l| Loss::from(l).name()), args.robust_scale)
        .cross_validate(args.cross_validate)
        .register_held_out(args.register_held_out);
    if let Some(path) = &args.validate {
        let shown = request.warnings().len();
        request = request.validate_on_files(path, args.validate_lengths.as_deref())?;
        request.warnings()[shown..].iter().try_for_each(warn)?;
    }
    if let Some(path) = &args.validate_positions {
        request = request.validate_on_positions(path)?;
    }
    if let Some(path) = &args.validate_spheres {
        request = request.validate_on_spheres(path)?;
    }
    let arm_file = source_name(&args.fit.arm);
    request.build().map_err(|e| match e {
        // The arm's own refusal names its file, as a read error would.
        CalibrationError::Kernel(_) => anyhow::Error::new(e).context(arm_file),
        e => flag_error(e),
    })
}

/// The calibration, with a progress bar; an error in terms of the flags
/// where it can be.
fn solve(
    problem: &Problem,
    settings: &SolverSettings,
    args: &Args,
) -> Result<session::CalibrationReport> {
    let arm_file = &problem.sources().arm_file;
    let mut bar = super::progress::Bar::new();
    let mut show = |phase: &str, f: f64| bar.show(phase, f);
    let mut ctx = Context::new()
        .observed(&mut show)
        .cancelled_by(interrupt_cancels());
    let solver = settings.method.solver();
    session::run(problem, settings, &*solver, &mut ctx).map_err(|e| match e {
        CalibrationError::Option(_) => flag_error(e),
        CalibrationError::Cancelled => {
            anyhow::Error::new(e).context("interrupted (Ctrl-C): nothing was written")
        }
        other => super::noise_flags(
            anyhow::Error::new(other).context(arm_file.clone()),
            &args.fit,
        ),
    })
}

/// A token that Ctrl-C sets: the first stops the calibration at the
/// solver's next check (within milliseconds; nothing is written), a
/// second ends the process at once. Where no handler can be installed the
/// token is never set, and Ctrl-C ends the process as it always did.
fn interrupt_cancels() -> Cancel {
    let token = Cancel::new();
    let set = token.clone();
    let _ = ctrlc::set_handler(move || {
        if set.is_cancelled() {
            std::process::exit(130);
        }
        set.cancel();
    });
    token
}

/// Writes the calibration and its report into `out`; the lines that say
/// so.
fn write_files(
    report: &session::CalibrationReport,
    problem: &Problem,
    out: &std::path::Path,
    total: f64,
) -> Result<String> {
    std::fs::create_dir_all(out)
        .with_context(|| format!("--out {}: cannot create", out.display()))?;
    let written = report.write(problem, out, total)?;
    let figures = written.len() - 4;
    let mut wrote = String::new();
    for path in &written {
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if [CALIBRATED_FILE, REPORT_FILE, TIMING_FILE].contains(&&*name) {
            wrote += &format!("wrote {}\n", path.display());
        } else if name == HTML_FILE {
            wrote += &format!(
                "wrote {} (with {figures} figures, each also an .svg beside it)\n",
                path.display()
            );
        }
    }
    Ok(wrote)
}

/// The summary (with the verdict and its notes) and the files written on
/// stdout, the time on stderr; an error when the calibration is not usable
/// (its files are written all the same, for inspection).
fn print_results(report: &session::CalibrationReport, wrote: String, total: f64) -> Result<()> {
    let mut out = Stdout::new();
    out.print(report.summary())?;
    out.print(wrote)?;
    out.finish()?;
    let phases = &report.calibration.solver.phases;
    let times: Vec<String> = phases
        .iter()
        .map(|p| format!("{} {:.1} ms", p.name, p.seconds * 1e3))
        .collect();
    note(format_args!(
        "time: fit {:.1} ms ({}), with validation {:.1} ms",
        phases.iter().map(|p| p.seconds).sum::<f64>() * 1e3,
        times.join(", "),
        total * 1e3
    ))?;
    // The verdict's notes are in the summary, under the verdict.
    if !report.is_usable() {
        // The first line names the first cause; the files' marks last.
        bail!(
            "the calibration is not usable: {}\n  (the files were written for inspection, \
             marked so in calibration.json (/verdict), calibrated.toml ([verdict]: aacmm \
             refuses to read it unless asked) and report.html)",
            report
                .verdict
                .words(aacmm_core::session::Spelling::Cli)
                .reasons
                .join("\n  ")
        );
    }
    Ok(())
}
