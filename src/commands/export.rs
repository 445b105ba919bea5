//! `aacmm export`: a (calibrated) arm for a robot controller or a
//! simulator — URDF joint origins, or a plain D-H table.

use std::path::PathBuf;

use aacmm_core::io::{read_arm, source_name};
use aacmm_core::params::{DhParams, JointKind};
use aacmm_core::urdf::export::{UrdfNames, dh_table, template_chains, to_urdf};
use aacmm_core::urdf::{UrdfOptions, parse_urdf};
use anyhow::{Context, Result, bail};

use super::report;
use crate::output::note;
use crate::paths::check_output_file;

/// Export an arm file as URDF (joint origins; names, links and limits from
/// a template when given) or as a D-H table (CSV).
#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("what").required(true).multiple(true).args(["urdf", "dh_table"])))]
pub struct Args {
    /// The arm file (a calibrated.toml).
    #[arg(long)]
    arm: PathBuf,
    /// Write the arm as URDF here: one joint per joint, revolute or
    /// prismatic (its origin the previous link's D-H or Hayati transform,
    /// axis z), then a fixed joint to the link `probe`; metres and radians.
    #[arg(long, value_name = "OUT.urdf")]
    urdf: Option<PathBuf>,
    /// A URDF of the robot whose movable joints (in file order) name the
    /// joints, links and limits of the export; its revolute, continuous and
    /// prismatic joints must be the arm's joints, kind for kind.
    #[arg(long, value_name = "ROBOT.urdf", requires = "urdf")]
    template: Option<PathBuf>,
    /// Write the arm as a D-H table here: `link,model,theta_deg,d_mm,a_mm,
    /// alpha_deg,beta_deg,x_mm,y_mm,z_mm,type`, one row per joint (`type`:
    /// revolute or prismatic) and a `probe` row.
    #[arg(long, value_name = "OUT.csv")]
    dh_table: Option<PathBuf>,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> Result<()> {
    let inputs = [("--arm", args.arm.as_path())];
    for (flag, out) in [("--urdf", &args.urdf), ("--dh-table", &args.dh_table)] {
        if let Some(out) = out {
            check_output_file(flag, out, &inputs, args.force)?;
        }
    }
    let (arm, warnings) = read_arm(&args.arm)?;
    report(&warnings)?;
    let n = arm.params.joint_count();
    if let Some(out) = &args.urdf {
        let names = match &args.template {
            Some(path) => template_names(path, &arm.params)?,
            None => UrdfNames::defaults(&arm.name, n, &arm.limits),
        };
        write(out, &to_urdf(&arm.params, &names))?;
    }
    if let Some(out) = &args.dh_table {
        write(out, &dh_table(&arm.params))?;
    }
    Ok(())
}

/// The names of a template URDF whose movable joints are the arm's.
fn template_names(path: &std::path::Path, params: &DhParams) -> Result<UrdfNames> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let urdf = parse_urdf(&text, &source_name(path), UrdfOptions::default())?;
    let kinds: Vec<JointKind> = params.joints.iter().map(|j| j.kind).collect();
    match UrdfNames::from_template(&urdf, &kinds) {
        Some(names) => Ok(names),
        None => {
            let chains: Vec<String> = (template_chains(&urdf).iter())
                .map(|(leaf, path)| {
                    let shape: String = (path.iter())
                        .filter_map(|j| j.kind.movable())
                        .map(JointKind::letter)
                        .collect();
                    format!(
                        "{} to `{leaf}`",
                        if shape.is_empty() { "-" } else { &shape }
                    )
                })
                .collect();
            let arm: String = kinds.iter().map(|k| k.letter()).collect();
            bail!(
                "--template {}: no chain of it has the arm's joints ({arm}: {} joints; R \
                 revolute, P prismatic); its chains: {} — give the URDF of the same robot",
                path.display(),
                kinds.len(),
                if chains.is_empty() {
                    "none".to_string()
                } else {
                    chains.join(", ")
                }
            )
        }
    }
}

fn write(path: &std::path::Path, text: &str) -> Result<()> {
    aacmm_core::io::write_atomic(path, text)
        .with_context(|| format!("{}: cannot write", path.display()))?;
    note(format_args!("wrote {}", path.display()))
}
