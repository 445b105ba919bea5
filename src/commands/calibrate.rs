//! `aacmm calibrate`: the arm that makes the touches agree, with honest
//! uncertainties and validation on held-out data (see
//! `aacmm_core::calibrate`).

use std::path::PathBuf;
use std::time::Instant;

use aacmm_core::calibrate::validate::{BeforeAfter, Figures, Fold, before_after, cross_validate};
use aacmm_core::calibrate::{
    AnnealOptions, CalibrateOptions, Calibration, FixSpec, GlobalOptions, LmOptions, SwitchRule,
    calibrate_observed,
};
use aacmm_core::io::source_name;
use aacmm_core::io::{AngleUnit, Arm, LengthUnit, arm_to_toml};
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use serde::Serialize;

use super::fit::{FitInput, read_other};
use crate::output::{Stdout, note, warn};
use crate::paths::check_output_dir;

mod report;

/// The calibrated arm, in the arm-file schema.
pub const CALIBRATED_FILE: &str = "calibrated.toml";
/// Everything the calibration found, as JSON.
pub const REPORT_FILE: &str = "calibration.json";
/// σ̂ above which a fit under stated noise is flagged.
const SIGMA0_WARNING: f64 = 3.0;

/// Wall times per phase (apart from calibration.json, which is the same
/// bytes for the same seed).
pub const TIMING_FILE: &str = "timing.json";

/// Calibrate an arm from touches (and reference lengths).
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
    /// K-fold cross-validation over points (points joined by a reference
    /// length stay in one fold).
    #[arg(long, value_name = "K")]
    cross_validate: Option<usize>,
    /// Seed of every random draw (annealing moves, global starts,
    /// cross-validation folds): the same seed gives the same files.
    #[arg(long, default_value_t = 0, value_name = "S")]
    seed: u64,
    /// Output directory: calibrated.toml, calibration.json, timing.json and
    /// the report (report.html and one SVG per figure).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Overwrite an earlier calibration in --out (without it, a directory
    /// that holds calibrated.toml or calibration.json is refused).
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
    fn options(&self) -> Result<(AnnealOptions, SwitchRule, GlobalOptions)> {
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
        anneal.check().map_err(|e| anyhow::anyhow!("--sa-…: {e}"))?;
        let switch = SwitchRule {
            window: self.switch_window,
            epsilon: self.switch_epsilon,
        };
        switch.check().map_err(|e| {
            anyhow::anyhow!(
                "--switch-window {} --switch-epsilon {}: {e}",
                self.switch_window,
                self.switch_epsilon
            )
        })?;
        let global = GlobalOptions {
            max_starts: self.global_starts,
            confirmations: self.global_confirmations,
            ..GlobalOptions::default()
        };
        global
            .check()
            .map_err(|e| anyhow::anyhow!("--global-starts and --global-confirmations: {e}"))?;
        Ok((anneal, switch, global))
    }
}

#[derive(Serialize)]
struct Report<'a> {
    arm: &'a str,
    arm_file: String,
    data_file: String,
    lengths_file: Option<String>,
    fix: &'a str,
    noise: &'a aacmm_core::residuals::Noise,
    units: Units,
    touches: usize,
    points: usize,
    reference_lengths: usize,
    calibration: &'a Calibration,
    validation: Validation<'a>,
}

#[derive(Serialize)]
struct Timing<'a> {
    fit_ms: f64,
    total_ms: f64,
    phases: Vec<PhaseTime<'a>>,
}

#[derive(Serialize)]
struct PhaseTime<'a> {
    name: &'a str,
    ms: f64,
}

#[derive(Serialize)]
struct Units {
    lengths: &'static str,
    angles: &'static str,
}

#[derive(Serialize)]
struct Validation<'a> {
    fitted: BeforeAfter,
    held_out: Option<HeldOut>,
    cross_validation: Option<CrossValidation<'a>>,
}

#[derive(Serialize)]
struct HeldOut {
    data_file: String,
    lengths_file: Option<String>,
    figures: BeforeAfter,
}

#[derive(Serialize)]
struct CrossValidation<'a> {
    folds: &'a [Fold],
    seed: u64,
}

pub fn run(args: Args) -> Result<()> {
    let mut inputs = args.fit.paths();
    inputs.extend(args.validate.as_deref().map(|p| ("--validate", p)));
    inputs.extend(
        args.validate_lengths
            .as_deref()
            .map(|p| ("--validate-lengths", p)),
    );
    check_output_dir(
        "--out",
        &args.out,
        &[
            &[CALIBRATED_FILE, REPORT_FILE, TIMING_FILE][..],
            &aacmm_core::report::CALIBRATION_FILES,
        ]
        .concat(),
        &inputs,
    )?;
    crate::paths::keep_earlier_results(
        "--out",
        &args.out,
        &[CALIBRATED_FILE, REPORT_FILE],
        args.force,
    )?;
    let noise = args.fit.noise()?;
    let (arm, data) = args.fit.read()?;
    let fix = FixSpec::parse(&args.fix, arm.params.joint_count()).context("--fix")?;
    let held_out = match &args.validate {
        Some(path) => Some(read_other(
            &arm,
            path,
            args.validate_lengths.as_deref(),
            args.fit.input.angle_unit,
        )?),
        None => None,
    };
    let (anneal, switch, global) = args.solver.options()?;
    let options = CalibrateOptions {
        fix,
        noise,
        method: args.method.into(),
        lm: LmOptions::default().threads(args.fit.threads()),
        anneal,
        switch,
        global,
        seed: args.seed,
    };
    let arm_file = source_name(&args.fit.input.arm);
    let started = Instant::now();
    let cal = {
        let mut bar = super::progress::Bar::new();
        calibrate_observed(&arm.params, &data, &options, &mut |phase, f| {
            bar.show(phase, f)
        })
        .with_context(|| arm_file.clone())?
    };
    let fit_time = started.elapsed();
    let fitted = before_after(&arm.params, &cal.params, &data)?;
    let held = match (&held_out, &args.validate) {
        (Some(h), Some(path)) => Some(HeldOut {
            data_file: source_name(path),
            lengths_file: args.validate_lengths.as_ref().map(|p| source_name(p)),
            figures: before_after(&arm.params, &cal.params, h)?,
        }),
        _ => None,
    };
    let folds = match args.cross_validate {
        Some(k) => Some(cross_validate(&arm.params, &data, &options, k, args.seed)?),
        None => None,
    };
    let total_time = started.elapsed();

    let calibrated = Arm {
        name: format!("{}-calibrated", arm.name),
        params: cal.params.clone(),
        limits: arm.limits.clone(),
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out {}: cannot create", args.out.display()))?;
    let toml_path = args.out.join(CALIBRATED_FILE);
    std::fs::write(
        &toml_path,
        arm_to_toml(&calibrated, LengthUnit::Mm, AngleUnit::Deg),
    )
    .with_context(|| format!("{}: cannot write", toml_path.display()))?;
    let report = Report {
        arm: &arm.name,
        arm_file: arm_file.clone(),
        data_file: source_name(&args.fit.input.data),
        lengths_file: args.fit.lengths.as_deref().map(source_name),
        fix: &args.fix,
        noise: &options.noise,
        units: Units {
            lengths: "mm",
            angles: "deg",
        },
        touches: data.len(),
        points: data.points().len(),
        reference_lengths: data.references().len(),
        calibration: &cal,
        validation: Validation {
            fitted,
            held_out: held,
            cross_validation: folds.as_deref().map(|f| CrossValidation {
                folds: f,
                seed: args.seed,
            }),
        },
    };
    let json_path = args.out.join(REPORT_FILE);
    super::write_json(&json_path, &report)?;

    let timing = Timing {
        fit_ms: fit_time.as_secs_f64() * 1e3,
        total_ms: total_time.as_secs_f64() * 1e3,
        phases: cal
            .solver
            .phases
            .iter()
            .map(|p| PhaseTime {
                name: &p.name,
                ms: p.seconds * 1e3,
            })
            .collect(),
    };
    let timing_path = args.out.join(TIMING_FILE);
    super::write_json(&timing_path, &timing)?;
    let wrote_report = report::write(&args, &arm, &data, held_out.as_ref(), &report)?;

    let mut out = Stdout::new();
    out.print(summary(&report))?;
    out.print(format_args!(
        "wrote {}\nwrote {}\nwrote {}\n",
        toml_path.display(),
        json_path.display(),
        timing_path.display()
    ))?;
    out.print(wrote_report)?;
    out.finish()?;
    let phases: Vec<String> = timing
        .phases
        .iter()
        .map(|p| format!("{} {:.1} ms", p.name, p.ms))
        .collect();
    note(format_args!(
        "time: fit {:.1} ms ({}), with validation {:.1} ms",
        timing.fit_ms,
        phases.join(", "),
        timing.total_ms
    ))?;
    // χ²/dof far above 1 under stated noise: the model does not explain the
    // data — a wrong basin, or noise stated too small.
    if !cal.dof.touch_sigma_estimated && cal.dof.sigma0 > SIGMA0_WARNING {
        warn(format_args!(
            "sigma0 = {:.1}: the fit leaves residuals {:.1} times the stated noise; a wrong \
             minimum (method {} from far-off zeros? try --method global) or noise stated too \
             small",
            cal.dof.sigma0,
            cal.dof.sigma0,
            cal.solver.method.name()
        ))?;
    }
    if !cal.solver.successful {
        bail!(
            "the solver did not converge ({}); the files were written for inspection",
            cal.solver.termination.describe()
        );
    }
    Ok(())
}

fn summary(r: &Report) -> String {
    let c = r.calibration;
    let s = &c.solver;
    let d = &c.dof;
    let mut t = format!(
        "calibrated `{}` ({}) on {}: {} touches of {} points, {} reference lengths\n\n",
        r.arm, r.arm_file, r.data_file, r.touches, r.points, r.reference_lengths
    );
    t += &method_lines(s);
    t += &format!(
        "Solver: {} — {} after {} iterations ({} cost and {} Jacobian evaluations); \
         cost {:.6e} -> {:.6e}\n",
        s.method.name(),
        s.termination.describe(),
        s.iterations,
        s.cost_evaluations,
        s.jacobian_evaluations,
        s.initial_cost,
        s.final_cost
    );
    t += &format!(
        "Residuals: {} touch rows + {} length rows; unknowns: {} parameters + {} centre \
         coordinates; {} degrees of freedom\n",
        d.touch_rows, d.length_rows, d.free_parameters, d.centre_coordinates, d.degrees_of_freedom
    );
    t += &format!(
        "sigma0 = sqrt(cost/dof) = {:.4} (1 when the weights are right); touch sigma {:.4} mm{}\n\n",
        d.sigma0,
        d.touch_sigma_mm,
        if d.touch_sigma_estimated {
            " (estimated from the fit)"
        } else {
            " (from the stated noise)"
        }
    );
    t += "Parameters (mm, deg; sigma = standard uncertainty, k = 1):\n";
    t += &format!(
        "  {:<8} {:<4} {:>14} {:>14} {:>12} {:>10}  {}\n",
        "name", "unit", "nominal", "calibrated", "correction", "sigma", "fixed because"
    );
    for p in &c.parameters {
        t += &format!(
            "  {:<8} {:<4} {:>14.6} {:>14.6} {:>12.6} {:>10}  {}\n",
            p.name,
            p.unit,
            p.nominal,
            p.calibrated,
            p.correction,
            p.sigma.map_or("-".to_string(), |s| format!("{s:.6}")),
            p.fixed.as_deref().unwrap_or("")
        );
    }
    if c.correlations.is_empty() {
        t += "No pair of free parameters correlates with |rho| > 0.9.\n";
    } else {
        t += "Correlations |rho| > 0.9:";
        for x in &c.correlations {
            t += &format!("  {}/{} {:+.3}", x.a, x.b, x.rho);
        }
        t += "\n";
    }
    t +=
        "\nValidation (mm): e = mean single-point error, 2s and delta_max (SPAT), length RMS/max\n";
    t += &format!(
        "  {:<28} {:>8} {:>8} {:>9} {:>10} {:>10}\n",
        "data", "e", "2s", "delta_max", "len RMS", "len max"
    );
    let mut row = |name: &str, f: &Figures| {
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
        t += &format!(
            "  {:<28} {:>8.4} {:>8.4} {:>9.4} {:>10} {:>10}\n",
            name,
            f.e_mean,
            f.two_s_mean,
            f.delta_max,
            opt(f.length_rms),
            opt(f.length_max)
        );
    };
    let v = &r.validation;
    row("fitted, before", &v.fitted.before);
    row("fitted, after", &v.fitted.after);
    if let Some(h) = &v.held_out {
        row("held out, before", &h.figures.before);
        row("held out, after", &h.figures.after);
    }
    if let Some(cv) = &v.cross_validation {
        for (i, f) in cv.folds.iter().enumerate() {
            row(
                &format!("fold {} ({} pts), before", i + 1, f.held_out.len()),
                &f.figures.before,
            );
            row(
                &format!("fold {} ({} pts), after", i + 1, f.held_out.len()),
                &f.figures.after,
            );
        }
    }
    t += "\n";
    t
}

/// What the method did, before the final LM's line.
fn method_lines(s: &aacmm_core::calibrate::SolverSummary) -> String {
    let mut t = String::new();
    if let Some(a) = &s.anneal {
        let o = &a.options;
        t += &format!(
            "Annealing: T0 {} mm, alpha {}, L {}, T_min {} mm, epsilon {} mm, ranges {} mm / {} deg \
             (twists) / {} deg (zeros); {} temperatures, {} energy evaluations; energy {:.4} -> \
             {:.4} mm; stopped: {}\n",
            o.t0,
            o.cooling,
            o.chain,
            o.t_min,
            o.target,
            o.step_mm,
            o.twist_step_deg,
            o.zero_step_deg,
            a.temperatures.len(),
            a.evaluations,
            a.start_energy,
            a.best_energy,
            a.stop.describe()
        );
        if let (Some(rule), Some(last)) = (&a.switch_rule, a.temperatures.last()) {
            t += &format!(
                "Switch (s0 {}, epsilon1 {}): at T = {:.3e} mm, energy {:.4} mm, after {} \
                 evaluations\n",
                rule.window, rule.epsilon, last.temperature, last.best, a.evaluations
            );
        }
    }
    if let Some(g) = &s.global {
        t += &format!(
            "Global: {} start(s) on the circles of {}; lowest cost reached {} time(s); stopped: {}{}\n",
            g.minima.len(),
            g.circles.join(", "),
            g.best_hits,
            g.stop.describe(),
            if g.sign_changes.is_empty() {
                String::new()
            } else {
                format!(
                    "; signs put in the nominal convention: {}",
                    g.sign_changes.join(", ")
                )
            }
        );
    }
    let phases: Vec<String> = s
        .phases
        .iter()
        .map(|p| {
            format!(
                "{} ({} cost, {} Jacobian)",
                p.name, p.cost_evaluations, p.jacobian_evaluations
            )
        })
        .collect();
    t += &format!("Phases: {}\n", phases.join("; "));
    t
}
