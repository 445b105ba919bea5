//! `aacmm import`: a robot's URDF → the toolkit's arm file (D-H, mm and
//! degrees), for any serial chain of revolute, continuous and prismatic
//! joints, fixed joints folded into their neighbours.
//!
//! The conversion itself is `aacmm_core::urdf` (exact: the tip within 1 nm
//! and the tool frame's orientation at any reading, tested there); this
//! command rounds the values for the file (1e-9 mm and 1e-9°, so that 90° is
//! written `90.0` rather than `89.99999999999999`; masses to 1e-12 kg),
//! states the limits in the arm's units (a slide's metres as mm), and says
//! per joint what it converted — in the file's header comments and on
//! standard error.

use std::fmt::Write as _;
use std::path::PathBuf;

use aacmm_core::corrections::{Mass, Physics};
use aacmm_core::domain::Arm;
use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml, source_name};
use aacmm_core::params::{JointKind, JointModel};
use aacmm_core::urdf::{Carrier, Chain, DhConversion, DhMass, Urdf, UrdfOptions, parse_urdf};
use anyhow::{Context, Result, bail};

use crate::output::note;
use crate::paths::check_output_file;

/// Convert the chain of a URDF from `--base` to `--tip` into an arm file.
#[derive(clap::Args)]
pub struct Args {
    /// The robot's URDF.
    #[arg(long, value_name = "ROBOT.urdf")]
    urdf: PathBuf,
    /// The link the chain starts from (the robot's base; links above it
    /// load no joint).
    #[arg(long, value_name = "LINK")]
    base: String,
    /// The link the chain ends at: the probe's centre (or, with `--tool`,
    /// the link the tool is on).
    #[arg(long, value_name = "LINK")]
    tip: String,
    /// A tool point: its offset from the tip link's origin, mm, in the tip
    /// link's frame (`X,Y,Z`).
    #[arg(long, value_name = "X,Y,Z")]
    tool: Option<String>,
    /// Write the arm file here.
    #[arg(long, value_name = "ARM.toml")]
    out: PathBuf,
    /// The arm's name (default: the URDF robot's name).
    #[arg(long)]
    name: Option<String>,
    /// Leave out the URDF's joint limits (for a robot whose recorded
    /// readings exceed them).
    #[arg(long)]
    no_limits: bool,
    /// Round each `rpy` value within this many radians of a multiple of
    /// π/2 to it (published URDFs write 1.5708 for π/2); 0 keeps them as
    /// written.
    #[arg(long, value_name = "RAD", default_value_t = UrdfOptions::default().snap_rad)]
    snap_rad: f64,
    /// Write over an output file that exists.
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> Result<()> {
    check_output_file("--out", &args.out, &[("--urdf", &args.urdf)], args.force)?;
    if !(args.snap_rad.is_finite() && args.snap_rad >= 0.0) {
        bail!("--snap-rad {}: expected a number >= 0 (rad)", args.snap_rad);
    }
    let tool = args.tool.as_deref().map(tool_offset).transpose()?;
    let text = std::fs::read_to_string(&args.urdf)
        .with_context(|| format!("{}: cannot read", args.urdf.display()))?;
    let file = source_name(&args.urdf);
    let options = UrdfOptions {
        snap_rad: args.snap_rad,
    };
    let urdf = parse_urdf(&text, &file, options)?;
    let mut chain = urdf.chain(Some(&args.base), &args.tip)?;
    if let Some(offset) = tool {
        chain = chain.with_tool(offset.map(|v| v / 1000.0));
    }
    let dh = chain.to_dh()?;
    let arm = arm_of(&urdf, &chain, &dh, &args);
    let joints = joint_lines(&chain, &dh);
    let mut out = header(&file, &args, &urdf, &chain, &dh, &joints);
    out += &arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
    aacmm_core::io::write_atomic(&args.out, &out)
        .with_context(|| format!("{}: cannot write", args.out.display()))?;
    for line in &joints {
        note(line)?;
    }
    note(format_args!("wrote {}", args.out.display()))
}

/// `--tool X,Y,Z`: three finite numbers, mm.
fn tool_offset(text: &str) -> Result<[f64; 3]> {
    let parts: Vec<Option<f64>> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect();
    match parts.as_slice() {
        [Some(x), Some(y), Some(z)] => Ok([*x, *y, *z]),
        _ => bail!("--tool `{text}`: expected X,Y,Z, three numbers (mm, in the tip link's frame)"),
    }
}

/// The arm file's content: the conversion rounded, the limits in the
/// arm's units, the masses as the file states them.
fn arm_of(urdf: &Urdf, chain: &Chain, dh: &DhConversion, args: &Args) -> Arm {
    let mut params = dh.params.clone();
    for j in &mut params.joints {
        (j.a, j.d) = (tidy_mm(j.a), tidy_mm(j.d));
        (j.alpha, j.theta, j.beta) = (tidy_rad(j.alpha), tidy_rad(j.theta), tidy_rad(j.beta));
    }
    params.probe = params.probe.map(tidy_mm);
    let mass = |m: &DhMass| Mass {
        kg: (m.kg * 1e12).round() / 1e12,
        com_mm: Some(m.com_mm.map(tidy_mm)),
    };
    let physics = Physics {
        link_masses: dh
            .masses
            .links
            .iter()
            .map(|l| l.as_ref().map(mass))
            .collect(),
        probe_mass: dh.masses.tool.as_ref().map(mass),
        gravity: (dh.masses.gravity).map(|g| g.map(|v| (v * 1e12).round() / 1e12 + 0.0)),
        ..Physics::default()
    };
    let limits = (chain.limits.iter().zip(&chain.kinds))
        .map(|(l, kind)| match kind {
            _ if args.no_limits => None,
            JointKind::Revolute => *l,
            JointKind::Prismatic => l.map(|l| l.map(|m| tidy_mm(m * 1000.0))),
        })
        .collect();
    Arm {
        name: args.name.clone().unwrap_or_else(|| urdf.name.clone()),
        params,
        limits,
        prior: None,
        physics: physics.into(),
        ball_diameter_mm: None,
        tools: Vec::new(),
    }
}

/// One line per joint saying what it converted: the URDF joint, its type
/// and line, the D-H joint it became and its model, and the fixed joints
/// folded into the base, the links and the tool.
fn joint_lines(chain: &Chain, dh: &DhConversion) -> Vec<String> {
    let n = chain.joints.len();
    let folded = |k: usize| chain.folded[k].join(", ");
    let mut out = Vec::new();
    if !chain.folded[0].is_empty() {
        out.push(format!("fixed joints {} → folded into the base", folded(0)));
    }
    for (i, joint) in dh.params.joints.iter().enumerate() {
        let mut line = format!(
            "{} ({}, URDF line {}) → joint {}: ",
            chain.joints[i],
            chain.types[i],
            chain.lines[i],
            i + 1
        );
        line += match joint.kind {
            JointKind::Revolute => "revolute (q deg)",
            JointKind::Prismatic => "prismatic (q mm = the URDF's m × 1000)",
        };
        line += match joint.model {
            JointModel::Hayati => {
                ", Hayati: the next axis is nearly parallel, D-H's d would be over 10 m"
            }
            _ if i + 1 < n && joint.alpha.sin().abs() < 1e-9 => {
                ", D-H: the next axis is parallel, d = 0 by convention"
            }
            _ => ", D-H",
        };
        if i + 1 < n && !chain.folded[i + 1].is_empty() {
            let _ = write!(
                line,
                "; fixed joints {} folded into its link",
                folded(i + 1)
            );
        }
        out.push(line);
    }
    if !chain.folded[n].is_empty() {
        out.push(format!(
            "fixed joints {} → folded into the probe",
            folded(n)
        ));
    }
    out
}

/// The header comments: where the arm comes from, each joint's conversion,
/// the roundings, the base and tool frames, and where the masses went.
fn header(
    file: &str,
    args: &Args,
    urdf: &Urdf,
    chain: &Chain,
    dh: &DhConversion,
    joints: &[String],
) -> String {
    let mut s = format!(
        "# Converted from {file} by `aacmm import`\n# (aacmm_core::urdf), chain {} → {}{}.\n",
        args.base,
        args.tip,
        match &args.tool {
            Some(t) => format!(", tool point {t} mm in its frame"),
            None => String::new(),
        }
    );
    let _ = writeln!(
        s,
        "# q1..q{}: {}",
        chain.joints.len(),
        chain.joints.join(", ")
    );
    for j in joints {
        let _ = writeln!(s, "#   {j}");
    }
    if urdf.snapped.is_empty() {
        let _ = writeln!(s, "# No rpy value rounded (--snap-rad {}).", args.snap_rad);
    } else {
        let _ = writeln!(
            s,
            "# rpy values rounded to multiples of π/2 (--snap-rad {}):",
            args.snap_rad
        );
        for r in &urdf.snapped {
            let _ = writeln!(s, "#   {r}");
        }
    }
    let t = dh.base.translation.vector * 1000.0;
    let (r, p, y) = dh.base.rotation.euler_angles();
    let (tr, tp, ty) = dh.tool.euler_angles();
    let deg = |v: f64| v.to_degrees();
    let _ = writeln!(
        s,
        "# D-H base frame in the URDF root frame: xyz = [{:.6}, {:.6}, {:.6}] mm, \
         rpy = [{:.6}, {:.6}, {:.6}] deg\n\
         # Tip link's axes in the arm's tool frame (its last D-H frame): rpy = \
         [{:.6}, {:.6}, {:.6}] deg\n\
         # (not needed for calibration: spreads and distances do not depend on them).\n\
         # Values rounded to 1e-9 mm and 1e-9 deg (the probe moves by < 1e-7 mm).",
        t.x,
        t.y,
        t.z,
        deg(r),
        deg(p),
        deg(y),
        deg(tr),
        deg(tp),
        deg(ty)
    );
    for line in mass_notes(chain) {
        let _ = writeln!(s, "# {line}");
    }
    s
}

/// Where the URDF's masses went: one line per joint's link, the probe, the
/// base side, and each link behind a moving joint off the chain.
fn mass_notes(chain: &Chain) -> Vec<String> {
    if chain.masses.is_empty() {
        return vec!["No link of the chain has a mass (<inertial>).".into()];
    }
    let list = |carrier: Carrier| -> Option<String> {
        let of: Vec<String> = (chain.masses.iter())
            .filter(|m| m.carrier == carrier)
            .map(|m| format!("{} {} kg", m.link, m.kg))
            .collect();
        (!of.is_empty()).then(|| of.join(", "))
    };
    let mut out = vec![
        "Masses from the URDF's <inertial> (mass_kg; com_mm in the link's D-H frame):".to_string(),
    ];
    for (j, name) in chain.joints.iter().enumerate() {
        if let Some(l) = list(Carrier::Link(j)) {
            out.push(format!("  after q{} ({name}): {l}", j + 1));
        }
    }
    if let Some(l) = list(Carrier::Tool) {
        out.push(format!("  probe (after the last joint): {l}"));
    }
    if let Some(l) = list(Carrier::Base) {
        out.push(format!("  before q1, loading no joint (left out): {l}"));
    }
    for m in chain.masses.iter().filter(|m| !m.moving.is_empty()) {
        out.push(format!(
            "  {} is behind {} off the chain, taken at zero",
            m.link,
            m.moving.join(", ")
        ));
    }
    out
}

/// Rounds to 1e-9 mm: `279.99999999999994` (the rounding of the geometry)
/// is written `280.0`.
fn tidy_mm(x: f64) -> f64 {
    (x * 1e9).round() / 1e9 + 0.0
}

/// Rounds to 1e-9 degrees, so that right angles are written `90.0`.
fn tidy_rad(x: f64) -> f64 {
    ((x.to_degrees() * 1e9).round() / 1e9 + 0.0).to_radians()
}
