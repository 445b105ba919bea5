//! A URDF robot description → the toolkit's arm file (D-H, mm and degrees).
//!
//! ```text
//! cargo run --example urdf_to_dh -- ROBOT.urdf TIP_LINK [ROOT_LINK] [--snap-rad R] [--name NAME] [--no-limits]
//! cargo run --example urdf_to_dh -- examples/mukca/urdf/gen3lite.urdf ball_link > arm.toml
//! ```
//!
//! `TIP_LINK` is the probe centre (for MUKCa, the ball); `ROOT_LINK` defaults
//! to the top of the chain above it. `--snap-rad` (default 1e-4) rounds `rpy`
//! values within that many radians of a multiple of π/2; `0` keeps them as
//! written. The arm's joints are the chain's revolute joints in order, so the
//! poses' `q1..qn` are the URDF joint positions (rad) in that order; limits
//! come from the URDF unless `--no-limits` (for a URDF whose limits the
//! robot's recorded readings exceed). The header comments give the joint names, the
//! roundings and the D-H base frame in the URDF root frame, which the arm
//! file does not need: touches' spreads and distances do not depend on it.
//! Values are rounded to 1e-9 mm and 1e-9 degrees, so that 90° is written
//! `90.0` rather than `89.99999999999999`.
//! Masses (`<inertial>` of the URDF's links): each joint's `mass_kg` is the
//! link after it (its child link and the links fixed to it), `com_mm` their
//! centre of mass in that link's D-H frame; after the last joint, its child
//! link is that joint's and the rest (gripper, fingers, ball) is the
//! probe's `mass_kg`, its centre in the last frame. The header lists which
//! links went where; the links before the first joint load no joint and are
//! left out. Gravity is the URDF root's −z (`gravity` is written only when
//! the D-H base's −z is not that). Masses are rounded to 1e-12 kg.
//! The conversion itself is `aacmm_core::urdf` (tested there to 1e-9 m, the
//! centres of mass to 1e-6 mm at any pose).

use std::io::Write;

use aacmm_core::corrections::{Mass, Physics};
use aacmm_core::io::{AngleUnit, Arm, LengthUnit, arm_to_toml};
use aacmm_core::urdf::{Carrier, Chain, DhMass, UrdfOptions, parse_urdf};
use anyhow::{Context, bail};

fn main() -> anyhow::Result<()> {
    let mut positional = Vec::new();
    let mut options = UrdfOptions::default();
    let mut name = None;
    let mut with_limits = true;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--snap-rad" => {
                let v = args.next().context("--snap-rad needs a value (rad)")?;
                options.snap_rad = v
                    .parse()
                    .ok()
                    .filter(|r: &f64| r.is_finite() && *r >= 0.0)
                    .with_context(|| format!("--snap-rad `{v}`: expected a number >= 0 (rad)"))?;
            }
            "--name" => name = Some(args.next().context("--name needs a value")?),
            "--no-limits" => with_limits = false,
            _ if a.starts_with("--") => bail!("unknown option `{a}`"),
            _ => positional.push(a),
        }
    }
    let (path, tip, root) = match positional.as_slice() {
        [p, t] => (p, t, None),
        [p, t, r] => (p, t, Some(r.as_str())),
        _ => bail!(
            "usage: urdf_to_dh ROBOT.urdf TIP_LINK [ROOT_LINK] [--snap-rad R] [--name NAME] [--no-limits]"
        ),
    };
    let text = std::fs::read_to_string(path).with_context(|| format!("{path}: cannot read"))?;
    let urdf = parse_urdf(&text, path, options)?;
    let chain = urdf.chain(root, tip)?;
    let dh = chain.to_dh()?;
    let mut params = dh.params.clone();
    for j in &mut params.joints {
        (j.a, j.d) = (tidy_mm(j.a), tidy_mm(j.d));
        (j.alpha, j.theta) = (tidy_rad(j.alpha), tidy_rad(j.theta));
    }
    params.probe = params.probe.map(tidy_mm);
    // The masses as the arm file states them, rounded.
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
    let arm = Arm {
        name: name.unwrap_or_else(|| urdf.name.clone()),
        params,
        limits: if with_limits {
            chain.limits.clone()
        } else {
            vec![None; chain.joints.len()]
        },
        prior: None,
        physics: physics.into(),
    };
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "# Converted from {path} by `cargo run --example urdf_to_dh`"
    )?;
    writeln!(
        out,
        "# (aacmm_core::urdf), chain {} → {tip}.",
        root.unwrap_or("(top)")
    )?;
    writeln!(
        out,
        "# q1..q{}: {}",
        chain.joints.len(),
        chain.joints.join(", ")
    )?;
    if urdf.snapped.is_empty() {
        writeln!(
            out,
            "# No rpy value rounded (--snap-rad {}).",
            options.snap_rad
        )?;
    } else {
        writeln!(
            out,
            "# rpy values rounded to multiples of π/2 (--snap-rad {}):",
            options.snap_rad
        )?;
        for s in &urdf.snapped {
            writeln!(out, "#   {s}")?;
        }
    }
    let t = dh.base.translation.vector * 1000.0;
    let (r, p, y) = dh.base.rotation.euler_angles();
    writeln!(
        out,
        "# D-H base frame in the URDF root frame: xyz = [{:.6}, {:.6}, {:.6}] mm, \
         rpy = [{:.6}, {:.6}, {:.6}] deg",
        t.x,
        t.y,
        t.z,
        r.to_degrees(),
        p.to_degrees(),
        y.to_degrees()
    )?;
    writeln!(
        out,
        "# (not needed for calibration: spreads and distances do not depend on it)."
    )?;
    writeln!(
        out,
        "# Values rounded to 1e-9 mm and 1e-9 deg (the probe moves by < 1e-7 mm)."
    )?;
    for line in mass_notes(&chain) {
        writeln!(out, "# {line}")?;
    }
    write!(out, "{}", arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg))?;
    Ok(())
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
