//! `aacmm verify`: the measuring arm's acceptance tests (ISO 10360-12 /
//! ASME B89.4.22) — `P_Size`, `P_Form`, `L_Dia`, `E_Uni` and the SPAT —
//! decided against stated MPEs (see `aacmm_core::acceptance` for every
//! formula and uncertainty).

use std::path::{Path, PathBuf};

use aacmm_core::acceptance::{
    Acceptance, AcceptanceError, Calibrated, DEFAULT_DRAWS, Draws, LDiaRadius, Measured, Mpe,
    PredictError, ReadingNoise, Settings, SpherePoints, parse_mpe, predict, verify,
};
use aacmm_core::dataset::DataSet;
use aacmm_core::domain::Arm;
use aacmm_core::error::{quoted, short};
use aacmm_core::io::spheres::read_spheres;
use aacmm_core::io::{read_lengths, source_name};
use aacmm_core::kernel::PreparedPoses;
use aacmm_core::metrics::Evaluation;
use aacmm_core::report::{ACCEPTANCE_FILES, acceptance_report};
use aacmm_core::session::CalibrationReport;
use aacmm_core::setting::Spelling;
use anyhow::{Result, anyhow, bail};

use crate::output::{Stdout, note};
use crate::paths::{check_output_dir, check_output_file};

/// The acceptance tests of an arm: probing size and form, the articulated
/// location test, length errors and the SPAT, each PASS, FAIL or
/// INCONCLUSIVE against its MPE with the test's expanded uncertainty as
/// the guard band (ISO 14253-1).
#[derive(clap::Args)]
#[command(mut_arg("data", |a| a
    .required(false)
    .help("Cones touched in many articulations (a poses file, CSV `point,q1,...,qn`) for the \
           SPAT: per cone delta_max, 2s and the per-axis (max − min)/2; the test's value is the \
           largest delta_max")))]
pub struct Args {
    #[command(flatten)]
    input: super::ArmAndPoses,
    /// Points probed on reference spheres: CSV `sphere,q1,...,qn[,articulation]`.
    /// A placement of 25 points gives P_Size and P_Form; one whose
    /// `articulation` column has five values (five points each) gives
    /// L_Dia; one named by --lengths is a centre for E_Uni. The probe
    /// ball's diameter is the arm file's `[probe] ball_diameter_mm`.
    #[arg(long, value_name = "S.csv")]
    spheres: PathBuf,
    /// The reference sphere's calibrated diameter, mm.
    #[arg(long, value_name = "MM")]
    sphere_diameter: f64,
    /// Its standard uncertainty (k = 1), mm, as its certificate states it
    /// (a certificate's expanded U at k = 2, halved); part of the guard
    /// band of P_Size, P_Form and L_Dia.
    #[arg(long, value_name = "MM", default_value_t = 0.0)]
    sphere_uncertainty: f64,
    /// Calibrated lengths between sphere placements for E_Uni: CSV
    /// `point_a,point_b,distance[,uncertainty]` (mm; the uncertainty k = 1),
    /// `point_a` and `point_b` naming placements of --spheres.
    #[arg(long, value_name = "L.csv")]
    lengths: Option<PathBuf>,
    /// Maximum permissible errors, mm: `P_Size=0.008,P_Form=0.012,L_Dia=0.030,
    /// E_Uni=0.016+L/60000,SPAT=0.02` — any subset; E_Uni also
    /// `min(A+L/K,C)` (capped at C). Without it the figures are printed and
    /// nothing is decided.
    #[arg(long, value_name = "SPEC")]
    mpe: Option<String>,
    /// Fit each L_Dia articulation's radius too, instead of holding the
    /// calibrated diameter (five points on a patch fix a radius poorly: a
    /// free radius moves the centre along the probe's direction).
    #[arg(long)]
    l_dia_free: bool,
    /// Also write every figure as JSON (mm).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Also write a report into this directory: report.html (the tests'
    /// table and every placement) and sphere_residuals.svg (each
    /// placement's radial residuals).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this
    /// command's files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
    /// The probe verified: `probe` (the arm's `[probe]`, the default) or a
    /// `[[tool]]`'s name — its offset and ball. A sphere file whose `tool`
    /// column names another probe is refused: verify one probe at a time.
    #[arg(long, value_name = "NAME", default_value = "probe")]
    tool: String,
    /// The directory `aacmm calibrate --out` wrote for this arm (its
    /// calibration.json): predict each test from it — its expected value
    /// and spread (σ) by Monte Carlo through the calibration's covariance
    /// and the noise it stated — printed beside the measured value, which
    /// should lie within two spreads when the arm performs as its
    /// calibration says. A calibration of another arm, one whose
    /// covariance is unknown and one not usable are refused. The decisions
    /// and the exit status do not depend on it.
    #[arg(long, value_name = "DIR")]
    calibration: Option<PathBuf>,
    /// Draws of the prediction (2 to 100000; each verifies the placements
    /// once).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_DRAWS, requires = "calibration")]
    draws: usize,
    /// Seed of the prediction's draws: the same seed gives the same bytes
    /// on any number of cores.
    #[arg(long, value_name = "N", default_value_t = 0, requires = "calibration")]
    seed: u64,
}

pub fn run(args: Args) -> Result<()> {
    let mut inputs = vec![
        ("--arm", args.input.arm.as_path()),
        ("--spheres", args.spheres.as_path()),
    ];
    inputs.extend(args.input.data.as_deref().map(|d| ("--data", d)));
    inputs.extend(args.lengths.as_deref().map(|l| ("--lengths", l)));
    let report_file = (args.calibration.as_ref()).map(|d| d.join(aacmm_core::report::REPORT_FILE));
    inputs.extend(report_file.as_deref().map(|p| ("--calibration", p)));
    if let Some(json) = &args.json {
        check_output_file("--json", json, &inputs, args.force)?;
    }
    if let Some(dir) = &args.report {
        check_output_dir("--report", dir, &ACCEPTANCE_FILES, &inputs, args.force)?;
    }
    let mpe = match &args.mpe {
        Some(spec) => parse_mpe(spec).map_err(super::shared_flags::flag_error)?,
        None => Mpe::default(),
    };
    let arm = args.input.read_arm()?;
    let calibration = match &args.calibration {
        Some(dir) => Some(calibration(&args, dir, &arm)?),
        None => None,
    };
    let arm = aacmm_core::domain::arm_with_tool(&arm, &args.tool)
        .map_err(super::shared_flags::flag_error)?;
    let Some(ball) = arm.ball_diameter_mm else {
        bail!(
            "{}: field `ball_diameter_mm`: the arm file states no probe ball ([probe] \
             ball_diameter_mm): the sphere points are ball centres, and P_Size needs the ball",
            source_name(&args.input.arm)
        );
    };
    let settings = Settings {
        sphere_diameter: args.sphere_diameter,
        sphere_uncertainty: args.sphere_uncertainty,
        ball_diameter: ball,
        l_dia_radius: if args.l_dia_free {
            LDiaRadius::Free
        } else {
            LDiaRadius::Held
        },
        mpe,
    };
    let acceptance = acceptance(&args, &arm, &settings, calibration.as_ref())?;
    // The JSON is written even if stdout fails (e.g. `| head -1`).
    let printed = (|| {
        let mut out = Stdout::new();
        out.write_with(|w| w.write_all(acceptance.summary().as_bytes()))?;
        out.finish()
    })();
    if let Some(path) = &args.json {
        super::write_json(path, &acceptance)?;
    }
    if let Some(dir) = &args.report {
        let listed: Vec<(String, String)> = (inputs.iter())
            .map(|(flag, path)| (flag.trim_start_matches('-').to_string(), source_name(path)))
            .collect();
        super::report::write("--report", dir, &acceptance_report(&acceptance, &listed))?;
    }
    printed?;
    let not = acceptance.not_passed();
    if !not.is_empty() {
        bail!("not accepted: {}", not.join("; "));
    }
    Ok(())
}

/// A calibration read for the prediction: its file, report and noise.
struct ForPrediction {
    path: PathBuf,
    report: CalibrationReport,
    noise: ReadingNoise,
}

/// Why the calibration in `path` has no covariance.
fn unknown(path: &Path) -> anyhow::Error {
    anyhow!(
        "{}: the calibration's covariance is unknown (no free parameter, or one whose σ is not \
         finite): nothing to predict from",
        path.display()
    )
}

/// The calibration in `dir` for `arm`, refused when it is another arm's,
/// not usable, or of unknown covariance, or when another probe than the
/// one it fitted is verified.
fn calibration(args: &Args, dir: &Path, arm: &Arm) -> Result<ForPrediction> {
    let (report, path) = super::calibration::read("--calibration", dir, arm)?;
    if args.tool != aacmm_core::domain::DEFAULT_TOOL {
        bail!(
            "--calibration with --tool {}: the calibration's covariance is of the probe's offset \
             (`probe`), not of this tool's; predict the probe it calibrated",
            quoted(&args.tool)
        );
    }
    if !report.is_usable() {
        let reasons = report.verdict.words(Spelling::Cli).reasons;
        let why = if reasons.is_empty() {
            String::new()
        } else {
            format!(" ({})", reasons.join("; "))
        };
        bail!(
            "{}: the calibration is not usable{why}: it predicts nothing",
            path.display()
        );
    }
    report
        .calibration
        .geometry_covariance()
        .ok_or_else(|| unknown(&path))?;
    let dof = &report.calibration.dof;
    let noise = ReadingNoise::of_calibration(&report.noise, dof.touch_sigma_mm);
    Ok(ForPrediction {
        path,
        report,
        noise,
    })
}

/// The tests computed from the files of `args`, predicted from
/// `calibration` when given.
fn acceptance(
    args: &Args,
    arm: &Arm,
    settings: &Settings,
    calibration: Option<&ForPrediction>,
) -> Result<Acceptance> {
    let file = source_name(&args.spheres);
    let (rows, warnings) = read_spheres(&args.spheres, args.input.angle_unit, arm)?;
    super::report(&warnings)?;
    if let Some(i) = (0..rows.len()).find(|&i| rows.tools()[rows.tool(i)].name != args.tool) {
        bail!(
            "{file}:{}: field `tool`: a point of {} while verifying {} (--tool): verify one probe \
             at a time — its rows alone, or --tool naming it",
            rows.line(i),
            quoted(&rows.tools()[rows.tool(i)].name),
            quoted(&args.tool)
        );
    }
    let readings: Vec<&[f64]> = (0..rows.len()).map(|i| rows.reading(i)).collect();
    let kernel = args.input.kernel(arm)?;
    args.input.check_conditions(arm)?;
    let prepared = match args.input.corrected(arm, &readings, None)? {
        Some(p) => p,
        None => PreparedPoses::for_shape(kernel.shape(), &readings)?,
    };
    let mut centres = vec![[0.0; 3]; rows.len()];
    kernel.positions(&prepared, 0..rows.len(), &mut centres)?;
    if let Some(i) = centres
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        bail!(
            "{}: the arm's geometry gives a probe position that is not a finite number for the \
             point at {file}:{}",
            args.input.arm.display(),
            rows.line(i)
        );
    }
    let lengths = match &args.lengths {
        Some(path) => Some((read_lengths(path)?, source_name(path))),
        None => None,
    };
    let cones = cones(args, arm)?;
    let points = SpherePoints {
        rows: &rows,
        file: &file,
        centres: &centres,
    };
    let lengths = lengths.as_ref().map(|(l, f)| (l.as_slice(), f.as_str()));
    let mut acceptance =
        verify(settings, points, lengths, cones.as_ref()).map_err(|e| match e {
            AcceptanceError::Option(o) => super::shared_flags::flag_error(o),
            other => anyhow!(other),
        })?;
    if let Some(c) = calibration {
        let measured = Measured {
            points,
            poses: &prepared,
            lengths,
        };
        predicted(args, &mut acceptance, settings, measured, arm, c)?;
    }
    Ok(acceptance)
}

/// `acceptance` with each test's prediction from `c`, and a note on what
/// it was drawn from.
fn predicted(
    args: &Args,
    acceptance: &mut Acceptance,
    settings: &Settings,
    measured: Measured<'_>,
    arm: &Arm,
    c: &ForPrediction,
) -> Result<()> {
    let (free, covariance) =
        (c.report.calibration.geometry_covariance()).ok_or_else(|| unknown(&c.path))?;
    let cal = Calibrated {
        params: &arm.params,
        free: &free,
        covariance: &covariance,
        noise: c.noise,
    };
    let draws = Draws {
        count: args.draws,
        seed: args.seed,
        threads: aacmm_core::calibrate::available_threads(),
    };
    let source = c.path.display().to_string();
    predict(acceptance, settings, measured, cal, draws, &source).map_err(|e| match e {
        PredictError::Option(o) => super::shared_flags::flag_error(o),
        other => anyhow!("--calibration {source}: {other}"),
    })?;
    let noise = if c.noise.stated {
        format!(
            "the noise it stated (encoders {}°, probe {} mm)",
            short(c.noise.encoder_rad.to_degrees()),
            short(c.noise.probe_mm)
        )
    } else {
        format!(
            "the touch σ its fit estimated, {} mm, as the probe's (it stated no noise)",
            short(c.noise.probe_mm)
        )
    };
    note(format_args!(
        "predicted: {} draws (seed {}) through the covariance of {} free parameters in {source} \
         and {noise}",
        args.draws,
        args.seed,
        free.len()
    ))
}

/// The cones of --data evaluated as `evaluate` does, if given.
fn cones(args: &Args, arm: &Arm) -> Result<Option<Evaluation>> {
    let Some(path) = &args.input.data else {
        return Ok(None);
    };
    let (_, poses) = args.input.read()?;
    let data = DataSet::from_poses_owned(poses, &source_name(path))?;
    super::report(data.repeat_warnings())?;
    let kernel = args.input.kernel(arm)?;
    let mut xyz = vec![[0.0; 3]; data.len()];
    let rows: Vec<&[f64]> = (0..data.len()).map(|i| data.reading(i)).collect();
    match args
        .input
        .corrected(arm, &rows, data.conditions().approach)?
    {
        Some(poses) => kernel.positions(&poses, 0..data.len(), &mut xyz)?,
        None => kernel.positions(data.poses(), 0..data.len(), &mut xyz)?,
    }
    args.input
        .check_finite(&xyz, |i| data.source().touch(i).line)?;
    Ok(Some(aacmm_core::metrics::evaluate(&data, &xyz)?))
}
