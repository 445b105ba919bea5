//! `aacmm points`: what a measuring arm's software does with every touch.

use std::path::{Path, PathBuf};

use aacmm_core::domain::{Arm, Poses};
use aacmm_core::error::{quoted, shown};
use aacmm_core::io::frames::parse_frames;
use aacmm_core::io::{source_name, write_points, write_points_u95, write_tool_poses};
use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::plan::{InFrame, position_covariances};
use aacmm_core::report::REPORT_FILE;
use aacmm_core::residuals::Frame;
use aacmm_core::stats::coverage::{eigenvalues, radius};
use anyhow::{Context, Result, anyhow, bail};

use crate::output::{Stdout, note};
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
    /// The directory `aacmm calibrate --out` wrote for this arm (its
    /// calibration.json): add a column `u95_mm`, the radius holding each
    /// position's error with 95 % probability, from the fit's covariance
    /// of the geometry. With `--frame`, in that frame and including the
    /// frame's registration (fitted with the arm, and correlated with it).
    #[arg(long, value_name = "DIR")]
    uncertainty: Option<PathBuf>,
    /// The tool whose positions to compute: `probe` (the arm's `[probe]`,
    /// the default) or one of the arm file's `[[tool]]` (a stylus, a
    /// marker): its offset instead of the probe's.
    #[arg(
        long,
        value_name = "NAME",
        default_value = "probe",
        conflicts_with = "uncertainty"
    )]
    tool: String,
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
        let report = args.uncertainty.as_ref().map(|d| d.join(REPORT_FILE));
        let mut inputs = vec![
            ("--arm", args.input.arm.as_path()),
            ("--data", args.input.data()?),
        ];
        inputs.extend(report.as_deref().map(|p| ("--uncertainty", p)));
        check_output_file("--out", out, &inputs, args.force)?;
    }
    let (arm, poses) = args.input.read_readings()?;
    let arm = aacmm_core::domain::arm_with_tool(&arm, &args.tool)
        .map_err(super::shared_flags::flag_error)?;
    let frame = match &args.frame {
        Some(name) => Some(frame(&args.input.arm, name)?),
        None => None,
    };
    let u95 = match &args.uncertainty {
        Some(dir) => {
            let named = args.frame.as_deref().zip(frame);
            Some(radii(dir, &arm, &poses, named)?)
        }
        None => None,
    };
    if args.pose {
        let mut tools = args.input.tool_poses(&arm, &poses)?;
        if let Some(x) = frame {
            tools.iter_mut().for_each(|t| *t = Frame::apply_pose(&x, t));
        }
        if let Some(u95) = &u95 {
            let xyz: Vec<[f64; 3]> = tools.iter().map(|t| t.position).collect();
            return write(&args.out, |w| {
                write_points_u95(w, poses.labels(), &xyz, Some(&tools), u95)
            });
        }
        return write(&args.out, |w| write_tool_poses(w, poses.labels(), &tools));
    }
    let mut xyz = args.input.positions(&arm, &poses)?;
    if let Some(x) = frame {
        xyz.iter_mut().for_each(|p| *p = Frame::apply(&x, *p));
    }
    match &u95 {
        Some(u95) => write(&args.out, |w| {
            write_points_u95(w, poses.labels(), &xyz, None, u95)
        }),
        None => write(&args.out, |w| write_points(w, poses.labels(), &xyz)),
    }
}

/// Each pose's 95 % radius from the calibration in `dir` (of `arm`): in
/// the base, or in `frame` (its name and the arm file's registration) with
/// its registration — and a note saying which.
fn radii(
    dir: &Path,
    arm: &Arm,
    poses: &Poses,
    frame: Option<(&str, [f64; 6])>,
) -> Result<Vec<f64>> {
    let (report, path) = super::calibration::read("--uncertainty", dir, arm)?;
    let cal = &report.calibration;
    let unknown = || {
        anyhow!(
            "{}: a free parameter's σ is not finite, so the positions' uncertainty is unknown",
            path.display()
        )
    };
    let rows: Vec<&[f64]> = (0..poses.len()).map(|i| poses.reading(i)).collect();
    let kernel = ArmKernel::new(&cal.params)?;
    let prepared = PreparedPoses::for_shape(kernel.shape(), &rows)?;
    let seen = match frame {
        None => {
            let (free, cov) = cal.geometry_covariance().ok_or_else(unknown)?;
            note(format_args!(
                "u95_mm: the 95 % radius of each position in the arm's base, from the \
                 covariance in {}",
                path.display()
            ))?;
            position_covariances(&cal.params, &prepared, &free, &cov, None)?
        }
        Some((name, stated)) => {
            if !cal.frames().iter().any(|(n, _)| n == name) {
                bail!(
                    "--frame {}: {} has no such frame",
                    shown(name),
                    path.display()
                );
            }
            let (free, x, cov) = cal.frame_covariance(name).ok_or_else(unknown)?;
            let q = free.len();
            let d = Frame::difference(&x, &stated);
            if (0..6).any(|k| d[k].abs() > 0.1 * cov[(q + k, q + k)].sqrt()) {
                bail!(
                    "--frame {}: the arm file's registration is not the one in {} (give the \
                     directory that wrote this calibrated.toml)",
                    shown(name),
                    path.display()
                );
            }
            note(format_args!(
                "u95_mm: the 95 % radius of each position in frame {0}, from the covariance in \
                 {1}; it includes the registration of frame {0}",
                quoted(name),
                path.display()
            ))?;
            let frame = InFrame { name, x };
            position_covariances(&cal.params, &prepared, &free, &cov, Some(&frame))?
        }
    };
    Ok(seen.iter().map(|(_, s)| radius(eigenvalues(*s))).collect())
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
