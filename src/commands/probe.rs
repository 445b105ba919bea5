//! `aacmm probe`: qualify one probe of a measuring arm on a reference
//! sphere, the arm's geometry held (see `aacmm_core::session::probe`).

use std::path::PathBuf;

use aacmm_core::io::spheres::read_spheres;
use aacmm_core::io::{AngleUnit, LengthUnit, Rejected, arm_to_toml, read_arm_with, source_name};
use aacmm_core::session::probe::{DEFAULT_TOLERANCE_MM, ProbeSettings, qualify_probe};
use aacmm_core::session::user_noise;
use anyhow::{Context, Result, bail};

use crate::output::{Stdout, note};
use crate::paths::check_output_file;

/// Qualify a probe: its tip offset and effective ball diameter from points
/// on one reference sphere, the arm's geometry held.
#[derive(clap::Args)]
pub struct Args {
    /// Arm file (TOML): the arm, its `[probe]` and `[[tool]]` probes.
    #[arg(long)]
    arm: PathBuf,
    /// Points touched on one reference sphere (CSV
    /// `sphere,q1,...,qn[,articulation][,tool]`); rows of other probes
    /// are left out.
    #[arg(long)]
    spheres: PathBuf,
    /// The reference sphere's certified diameter, mm.
    #[arg(long, value_name = "MM")]
    sphere_diameter: f64,
    /// The probe qualified: `probe` (the arm's `[probe]`) or a `[[tool]]`'s
    /// name. Every row is this probe's when the file has no `tool` column.
    #[arg(long, value_name = "NAME", default_value = "probe")]
    tool: String,
    /// The arm file with the qualified probe (its offset and ball
    /// diameter), written only when the probe qualifies.
    #[arg(long, value_name = "ARM2.toml")]
    out: PathBuf,
    /// Unit of the joint readings in the sphere file.
    #[arg(long, default_value = "deg", value_parser = super::angle_unit())]
    angle_unit: AngleUnit,
    /// σ of each encoder reading, degrees (with --probe-noise: the points'
    /// weights and the χ² test that refuses a loose stylus; without
    /// either, the σ is estimated and nothing is judged by it).
    #[arg(long, value_name = "DEG")]
    encoder_noise: Option<f64>,
    /// σ of the probe seating per axis, mm.
    #[arg(long, value_name = "MM")]
    probe_noise: Option<f64>,
    /// Warn when the tip moved more than this from the arm file's offset, mm.
    #[arg(long, value_name = "MM", default_value_t = DEFAULT_TOLERANCE_MM)]
    tolerance: f64,
    /// Refuse when the sphere's form as the probe sees it (the range of
    /// the radial residuals) exceeds this, mm.
    #[arg(long, value_name = "MM")]
    max_form: Option<f64>,
    /// Write over an existing --out file.
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> Result<()> {
    let inputs = [
        ("--arm", args.arm.as_path()),
        ("--spheres", args.spheres.as_path()),
    ];
    check_output_file("--out", &args.out, &inputs, args.force)?;
    for (flag, v) in [
        ("--tolerance", Some(args.tolerance)),
        ("--max-form", args.max_form),
    ] {
        if let Some(v) = v.filter(|v| !(v.is_finite() && *v > 0.0)) {
            bail!("{flag} {v}: a positive number of mm");
        }
    }
    let (arm, warnings) = read_arm_with(&args.arm, Rejected::Refuse)?;
    super::report(&warnings)?;
    let (rows, warnings) = read_spheres(&args.spheres, args.angle_unit, &arm)?;
    super::report(&warnings)?;
    let settings = ProbeSettings {
        tool: args.tool.clone(),
        sphere_diameter_mm: args.sphere_diameter,
        noise: user_noise(args.encoder_noise, args.probe_noise, 0.0, None),
        tolerance_mm: args.tolerance,
        max_form_mm: args.max_form,
        spelling: aacmm_core::session::Spelling::Cli,
    };
    let q = qualify_probe(&arm, rows, &source_name(&args.spheres), &settings)
        .map_err(super::shared_flags::flag_error)?;
    // The qualified arm is written even if stdout fails (`> /dev/full`):
    // the summary's failure is reported after it.
    let printed = (|| {
        let mut out = Stdout::new();
        out.print(q.summary())?;
        out.finish()
    })();
    if !q.usable() {
        printed?;
        bail!(
            "{} is not qualified ({}): nothing was written",
            args.tool,
            q.refusals[0]
        );
    }
    let text = format!(
        "# {} qualified by aacmm probe on {} (sphere {}, {} mm)\n{}",
        args.tool,
        source_name(&args.spheres),
        q.sphere,
        args.sphere_diameter,
        arm_to_toml(&q.qualified_arm(&arm), LengthUnit::Mm, AngleUnit::Deg)
    );
    aacmm_core::io::write_atomic(&args.out, &text)
        .with_context(|| format!("{}: cannot write", args.out.display()))?;
    note(format_args!("wrote {}", args.out.display()))?;
    printed
}
