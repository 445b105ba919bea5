//! `aacmm calibrate`: the arm that makes the touches agree, with honest
//! uncertainties and validation on held-out data (see
//! `aacmm_core::calibrate`).

use std::path::PathBuf;
use std::time::Instant;

use aacmm_core::calibrate::validate::{BeforeAfter, Figures, Fold, before_after, cross_validate};
use aacmm_core::calibrate::{CalibrateOptions, Calibration, FixSpec, LmOptions, calibrate};
use aacmm_core::io::source_name;
use aacmm_core::io::{AngleUnit, Arm, LengthUnit, arm_to_toml};
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use serde::Serialize;

use super::fit::{FitInput, read_other};
use crate::output::{Stdout, note};
use crate::paths::check_output_dir;

/// The calibrated arm, in the arm-file schema.
pub const CALIBRATED_FILE: &str = "calibrated.toml";
/// Everything the calibration found, as JSON.
pub const REPORT_FILE: &str = "calibration.json";

/// Calibrate an arm from touches (and reference lengths).
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    fit: FitInput,
    /// Parameters held at their nominal values: `auto` (identify's
    /// recommended set) or names such as `theta1,d1,theta6,alpha6,Bx,By`.
    #[arg(long, default_value = "auto", value_name = "auto|NAMES")]
    fix: String,
    /// The solver.
    #[arg(long, value_enum, default_value = "lm")]
    method: Method,
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
    /// Seed of the fold assignment.
    #[arg(long, default_value_t = 0, value_name = "S")]
    seed: u64,
    /// Output directory: calibrated.toml and calibration.json.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Solvers.
#[derive(Clone, Copy, Debug, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
enum Method {
    /// Levenberg–Marquardt from the nominal arm.
    Lm,
}

#[derive(Serialize)]
struct Report<'a> {
    arm: &'a str,
    arm_file: String,
    data_file: String,
    lengths_file: Option<String>,
    method: Method,
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
    check_output_dir("--out", &args.out, &[CALIBRATED_FILE, REPORT_FILE], &inputs)?;
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
    let options = CalibrateOptions {
        fix,
        noise,
        lm: LmOptions::default().threads(super::identify::threads()),
    };
    let arm_file = source_name(&args.fit.input.arm);
    let started = Instant::now();
    let cal = calibrate(&arm.params, &data, &options).with_context(|| arm_file.clone())?;
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
        method: args.method,
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

    let mut out = Stdout::new();
    out.print(summary(&report))?;
    out.print(format_args!(
        "wrote {}\nwrote {}\n",
        toml_path.display(),
        json_path.display()
    ))?;
    out.finish()?;
    note(format_args!(
        "time: fit {:.1} ms, with validation {:.1} ms",
        fit_time.as_secs_f64() * 1e3,
        total_time.as_secs_f64() * 1e3
    ))?;
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
    t += &format!(
        "Solver: {} — {} after {} iterations ({} cost and {} Jacobian evaluations); \
         cost {:.6e} -> {:.6e}\n",
        s.method,
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
