//! `aacmm points`: what a measuring arm's software does with every touch.

use std::path::PathBuf;

use aacmm_core::error::{quoted, shown};
use aacmm_core::io::frames::parse_frames;
use aacmm_core::io::{source_name, write_points, write_tool_poses};
use aacmm_core::residuals::Frame;
use anyhow::{Context, Result, bail};

use crate::output::Stdout;
use crate::paths::check_output_file;

/// Forward kinematics for every row of a poses file, or of a positions file
/// (its readings; `--data` takes either).
#[derive(clap::Args)]
#[command(mut_arg("data", |a| a.help(
    "Poses file (CSV `point,q1,...,qn`), or a reference-positions file (CSV \
     `point,q1,...,qn,x,y,z[,frame][,uncertainty]`, as calibrate --positions reads) whose \
     readings are taken, its positions ignored; `-` reads standard input"
)))]
pub struct Args {
    #[command(flatten)]
    input: super::ArmAndPoses,
    /// Output CSV `point,x,y,z` (mm); stdout when absent.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the tool's orientation too: `point,x,y,z,qw,qx,qy,qz`, the
    /// last link's frame as a unit quaternion (w ≥ 0, 9 decimals) in the
    /// base frame (or the `--frame`).
    #[arg(long)]
    pose: bool,
    /// Positions in this frame of the arm file (a calibrated arm's
    /// `[[frame]]`, fitted to reference positions): what that instrument
    /// will see, for a verification run. Without it, the arm's base frame.
    #[arg(long, value_name = "NAME")]
    frame: Option<String>,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

/// The registration of the frame `name` in the arm file `path`.
fn frame(path: &std::path::Path, name: &str) -> Result<[f64; 6]> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let frames = parse_frames(&text, &source_name(path))?;
    match frames.iter().find(|f| f.name == name) {
        Some(f) => Ok(f.values()),
        None if frames.is_empty() => bail!(
            "--frame {}: {} has no `[[frame]]` table (a calibration against reference \
             positions writes one per frame into calibrated.toml)",
            shown(name),
            path.display()
        ),
        None => {
            // At most ten names, each bounded: a hostile file cannot make
            // the message long.
            let mut names: Vec<String> = frames.iter().take(10).map(|f| quoted(&f.name)).collect();
            if frames.len() > 10 {
                names.push(format!("and {} more", frames.len() - 10));
            }
            bail!(
                "--frame {}: no such frame in {}; it has {}",
                shown(name),
                path.display(),
                names.join(", ")
            )
        }
    }
}

pub fn run(args: Args) -> Result<()> {
    if let Some(out) = &args.out {
        let inputs = [
            ("--arm", args.input.arm.as_path()),
            ("--data", args.input.data()?),
        ];
        check_output_file("--out", out, &inputs, args.force)?;
    }
    let (arm, poses) = args.input.read_readings()?;
    let frame = match &args.frame {
        Some(name) => Some(frame(&args.input.arm, name)?),
        None => None,
    };
    if args.pose {
        let mut tools = args.input.tool_poses(&arm, &poses)?;
        if let Some(x) = frame {
            tools.iter_mut().for_each(|t| *t = Frame::apply_pose(&x, t));
        }
        return write(&args.out, |w| write_tool_poses(w, poses.labels(), &tools));
    }
    let mut xyz = args.input.positions(&arm, &poses)?;
    if let Some(x) = frame {
        xyz.iter_mut().for_each(|p| *p = Frame::apply(&x, *p));
    }
    write(&args.out, |w| write_points(w, poses.labels(), &xyz))
}

/// `write` into the file `out`, atomically, or to stdout.
fn write(
    out: &Option<PathBuf>,
    write: impl Fn(&mut dyn std::io::Write) -> std::io::Result<()>,
) -> Result<()> {
    match out {
        Some(path) => {
            aacmm_core::io::write_atomic_with(path, |w| write(w))
                .with_context(|| format!("{}: cannot write", path.display()))?;
        }
        None => {
            let mut out = Stdout::new();
            out.write_with(|w| write(w))?;
            out.finish()?;
        }
    }
    Ok(())
}
