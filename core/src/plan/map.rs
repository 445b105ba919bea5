//! The uncertainty map: the predicted position uncertainty of an arm over a
//! sampled workspace, per band of reach.
//!
//! At a pose `q` the calibrated probe position's error has covariance
//! `Σ = J C Jᵀ` (`J` the position's Jacobian over the free geometry, `C`
//! their covariance). The map reports the radius that holds the error with
//! 95 % probability ([`super::coverage::radius`]: `2.80 σ` for an
//! isotropic error, `1.96 σ` for one along a line), pose by pose, over
//! poses drawn uniformly within the joint ranges — not only the poses the
//! campaign measured — and summarised per band of distance from the
//! shoulder (the base axis at the first joint's height), where the reach
//! decides how levers amplify an angle's error.

use nalgebra::DMatrix;
use rand::RngExt;
use serde::{Deserialize, Serialize};

use super::coverage::{COVERAGE, K_ISOTROPIC, eigenvalues, radius};
use super::rows::jacobians;
use crate::kernel::{KernelError, PreparedPoses};
use crate::params::DhParams;
use crate::residuals::Frame;

/// Bands of reach a map is summarised in.
pub(crate) const BANDS: usize = 5;

/// Poses a map's figure shows at most (an even sample of the workspace).
const FIGURE_POINTS: usize = 1000;

/// The predicted position uncertainty over a workspace.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UncertaintyMap {
    /// Probability each radius covers (0.95).
    pub coverage: f64,
    /// The radius of an isotropic error in units of its per-coordinate σ
    /// (2.80): what "k" is for a 3-D error.
    pub k_isotropic: f64,
    /// Where the poses come from, in words.
    pub workspace: String,
    /// The instrument's frame the radii are in, when not the arm's base:
    /// they then include that frame's registration
    /// ([`uncertainty_map_in_frame`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<String>,
    /// The tool point the radii are at, when not the arm's probe (a
    /// `[[tool]]` whose offset was fitted: [`uncertainty_map_at_tool`]);
    /// they then include its offset's uncertainty.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<String>,
    /// Poses sampled.
    pub poses: usize,
    /// RMS of the 95 % radius over the poses, mm.
    pub rms_mm: f64,
    /// Median of the radius, mm.
    pub median_mm: f64,
    /// Largest radius, mm.
    pub max_mm: f64,
    /// The same per band of distance from the shoulder, nearest first.
    pub regions: Vec<Region>,
    /// For the figure: an even sample of the poses.
    pub points: Vec<MapPoint>,
}

/// One band of reach.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Region {
    /// Distance from the shoulder, from (mm).
    pub reach_from_mm: f64,
    /// … to (mm).
    pub reach_to_mm: f64,
    /// Poses in the band.
    pub poses: usize,
    /// RMS of the 95 % radius, mm (0 for an empty band).
    pub rms_mm: f64,
    /// Largest radius, mm.
    pub max_mm: f64,
}

/// One pose of the map.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapPoint {
    /// Distance of the probe from the shoulder, mm.
    pub reach_mm: f64,
    /// Height of the probe above the shoulder, mm.
    pub height_mm: f64,
    /// The 95 % radius, mm.
    pub radius_mm: f64,
}

/// `n` poses of a chain of `prismatic` joints (bit `j` for joint `j`)
/// drawn uniformly within each joint's range (`None`: a full turn; a
/// prismatic joint without a range stays at 0 mm, its stroke unknown),
/// seeded.
pub fn sample_poses(
    ranges: &[Option<[f64; 2]>],
    prismatic: u16,
    n: usize,
    seed: u64,
) -> PreparedPoses {
    let mut rng = crate::random::rng(seed, crate::random::streams::WORKSPACE);
    let joints = ranges.len();
    let mut q = Vec::with_capacity(n * joints);
    for _ in 0..n {
        for (j, r) in ranges.iter().enumerate() {
            q.push(match r {
                Some([lo, hi]) if hi > lo => rng.random_range(*lo..=*hi),
                Some([lo, _]) => *lo,
                None if j < 16 && prismatic & (1 << j) != 0 => 0.0,
                None => rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
            });
        }
    }
    PreparedPoses::from_flat_with(joints, prismatic, n, &q)
}

/// Each joint's range of readings over `poses` (rad).
pub(crate) fn reading_ranges(poses: &[&[f64]], joints: usize) -> Vec<Option<[f64; 2]>> {
    (0..joints)
        .map(|j| {
            let mut r: Option<[f64; 2]> = None;
            for q in poses {
                let v = q[j];
                r = Some(r.map_or([v, v], |[lo, hi]| [lo.min(v), hi.max(v)]));
            }
            r
        })
        .collect()
}

/// The map of `params` over `poses` from the covariance `cov` (mm, rad) of
/// the geometry columns `free`.
///
/// # Errors
///
/// The kernel's.
pub fn uncertainty_map(
    params: &DhParams,
    poses: &PreparedPoses,
    free: &[usize],
    cov: &DMatrix<f64>,
    workspace: &str,
) -> Result<UncertaintyMap, KernelError> {
    let (blocks, positions) = jacobians(params, poses, free, false)?;
    let q = free.len();
    let radii: Vec<f64> = (0..blocks.len())
        .map(|i| radius(eigenvalues(sandwich(blocks.at(i), cov, q))))
        .collect();
    Ok(summarise(&radii, &places(params, &positions), workspace))
}

/// The map of `params` over `poses` at the tool point `tool` (its name and
/// fitted offset, mm): the probe replaced by the tool, `free` the geometry
/// columns with the probe's three last standing for the tool's offset and
/// `cov` their joint covariance ([`crate::Calibration::tool_covariance`]),
/// so each radius includes the offset's own uncertainty and its
/// correlation with the arm's.
///
/// # Errors
///
/// The kernel's.
pub fn uncertainty_map_at_tool(
    params: &DhParams,
    poses: &PreparedPoses,
    free: &[usize],
    cov: &DMatrix<f64>,
    tool: (&str, [f64; 3]),
    workspace: &str,
) -> Result<UncertaintyMap, KernelError> {
    let mut at = params.clone();
    at.probe = tool.1;
    let mut map = uncertainty_map(&at, poses, free, cov, workspace)?;
    map.tool = Some(tool.0.to_string());
    Ok(map)
}

/// An instrument's frame a prediction is expressed in: its name and its
/// fitted registration `y = R p + t` (`[rx, ry, rz, tx, ty, tz]`, rad, mm,
/// as [`crate::residuals::Frame::apply`] takes it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InFrame<'a> {
    /// The frame's name.
    pub name: &'a str,
    /// Its registration.
    pub x: [f64; 6],
}

/// A predicted probe position (mm) and its covariance (mm²).
pub type Prediction = ([f64; 3], [[f64; 3]; 3]);

/// The predicted probe position at each of `poses` and its covariance
/// (mm²): `Σ = J C Jᵀ`. In the arm's base frame (`frame` `None`) `J` is the
/// position's Jacobian over the geometry columns `free` and `cov` their
/// covariance (`q × q`, mm and rad). In an instrument's frame the position
/// is `p_f = R p(q; x) + t` and it also carries the frame's registration
/// error, correlated with the arm's (the two were fitted together): `J =
/// [R ∂p/∂x, ∂p_f/∂δ]` over the free columns and the frame's local step
/// `δ = [δω, δt]` (`R ← exp(δω) R`, the fit's), and `cov` is their joint
/// covariance, `(q + 6) × (q + 6)`, the frame's six columns last
/// ([`crate::Calibration::frame_covariance`]).
///
/// # Errors
///
/// The kernel's; [`KernelError::ParamCount`] when `cov` is not `q × q`
/// (`(q + 6)²` with a frame).
pub fn position_covariances(
    params: &DhParams,
    poses: &PreparedPoses,
    free: &[usize],
    cov: &DMatrix<f64>,
    frame: Option<&InFrame<'_>>,
) -> Result<Vec<Prediction>, KernelError> {
    let (blocks, positions) = jacobians(params, poses, free, false)?;
    let q = free.len();
    let width = q + if frame.is_some() { 6 } else { 0 };
    if cov.shape() != (width, width) {
        let got = if cov.nrows() == width {
            cov.ncols()
        } else {
            cov.nrows()
        };
        return Err(KernelError::ParamCount {
            expected: width,
            got,
        });
    }
    Ok((0..blocks.len())
        .map(|i| match frame {
            None => (positions[i], sandwich(blocks.at(i), cov, q)),
            Some(f) => {
                let j = in_frame(blocks.at(i), positions[i], &f.x, q);
                (Frame::apply(&f.x, positions[i]), sandwich(&j, cov, q + 6))
            }
        })
        .collect())
}

/// The 3 × (q + 6) Jacobian of `R p + t` over the arm's columns (the
/// base-frame block `j`, turned by `R`) and the frame's local step.
fn in_frame(j: &[f64], p: [f64; 3], x: &[f64; 6], q: usize) -> Vec<f64> {
    let r = Frame::rotation(x);
    let step = Frame::jacobian(x, p);
    let mut out = vec![0.0; 3 * (q + 6)];
    for k in 0..3 {
        let row = &mut out[k * (q + 6)..(k + 1) * (q + 6)];
        for (a, v) in row[..q].iter_mut().enumerate() {
            *v = (0..3).map(|m| r[(k, m)] * j[m * q + a]).sum();
        }
        row[q..].copy_from_slice(&step[k]);
    }
    out
}

/// The map of `params` over `poses` as the instrument of `frame` sees the
/// probe: each pose's radius from [`position_covariances`] in that frame
/// (`cov` the joint covariance of the free columns and the frame's six),
/// so it includes the frame's registration; the bands of reach stay the
/// arm's own (distance from the shoulder), where the levers are.
///
/// # Errors
///
/// The kernel's.
pub fn uncertainty_map_in_frame(
    params: &DhParams,
    poses: &PreparedPoses,
    free: &[usize],
    cov: &DMatrix<f64>,
    frame: &InFrame<'_>,
    workspace: &str,
) -> Result<UncertaintyMap, KernelError> {
    let seen = position_covariances(params, poses, free, cov, Some(frame))?;
    let radii: Vec<f64> = seen.iter().map(|(_, s)| radius(eigenvalues(*s))).collect();
    // Back in the base: `p = Rᵀ (p_f − t)`.
    let r = Frame::rotation(&frame.x);
    let t = nalgebra::Vector3::new(frame.x[3], frame.x[4], frame.x[5]);
    let base: Vec<[f64; 3]> = (seen.iter())
        .map(|(p, _)| (r.inverse() * (nalgebra::Vector3::from(*p) - t)).into())
        .collect();
    let mut map = summarise(&radii, &places(params, &base), workspace);
    map.frame = Some(frame.name.to_string());
    Ok(map)
}

/// Each position's distance from the shoulder (the base axis at the first
/// joint's height) and height above it.
fn places(params: &DhParams, positions: &[[f64; 3]]) -> Vec<(f64, f64)> {
    let shoulder = params.joints.first().map_or(0.0, |j| j.d);
    positions
        .iter()
        .map(|p| {
            let h = p[2] - shoulder;
            ((p[0] * p[0] + p[1] * p[1] + h * h).sqrt(), h)
        })
        .collect()
}

/// `J C Jᵀ` of one 3 × q block.
pub(crate) fn sandwich(j: &[f64], cov: &DMatrix<f64>, q: usize) -> [[f64; 3]; 3] {
    let jc: [Vec<f64>; 3] = std::array::from_fn(|k| {
        (0..q)
            .map(|b| (0..q).map(|a| j[k * q + a] * cov[(a, b)]).sum())
            .collect()
    });
    std::array::from_fn(|k| std::array::from_fn(|l| (0..q).map(|b| jc[k][b] * j[l * q + b]).sum()))
}

/// The map of per-pose radii at `(reach, height)` places.
pub(crate) fn summarise(radii: &[f64], places: &[(f64, f64)], workspace: &str) -> UncertaintyMap {
    let n = radii.len();
    let rms = |r: &[f64]| {
        if r.is_empty() {
            0.0
        } else {
            (r.iter().map(|v| v * v).sum::<f64>() / r.len() as f64).sqrt()
        }
    };
    let max = |r: &[f64]| r.iter().copied().fold(0.0, f64::max);
    let mut sorted = radii.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(n / 2).copied().unwrap_or(0.0);
    let lo = places.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = places.iter().map(|p| p.0).fold(0.0, f64::max);
    let width = ((hi - lo) / BANDS as f64).max(f64::MIN_POSITIVE);
    let regions = (0..if n == 0 { 0 } else { BANDS })
        .map(|b| {
            let in_band: Vec<f64> = radii
                .iter()
                .zip(places)
                .filter(|(_, p)| ((p.0 - lo) / width).floor().min(BANDS as f64 - 1.0) as usize == b)
                .map(|(r, _)| *r)
                .collect();
            Region {
                reach_from_mm: lo + b as f64 * width,
                reach_to_mm: lo + (b + 1) as f64 * width,
                poses: in_band.len(),
                rms_mm: rms(&in_band),
                max_mm: max(&in_band),
            }
        })
        .collect();
    let step = n.div_ceil(FIGURE_POINTS).max(1);
    let points = (0..n)
        .step_by(step)
        .map(|i| MapPoint {
            reach_mm: places[i].0,
            height_mm: places[i].1,
            radius_mm: radii[i],
        })
        .collect();
    UncertaintyMap {
        coverage: COVERAGE,
        k_isotropic: K_ISOTROPIC,
        workspace: workspace.to_string(),
        frame: None,
        tool: None,
        poses: n,
        rms_mm: rms(radii),
        median_mm: median,
        max_mm: max(radii),
        regions,
        points,
    }
}

impl UncertaintyMap {
    /// The map in words: one line, then one per band.
    pub fn describe(&self) -> String {
        let seen = match (&self.frame, &self.tool) {
            (Some(name), _) => {
                let name = crate::error::quoted(name);
                format!(" in frame {name}, which includes the registration of frame {name},")
            }
            (None, Some(tool)) => {
                let tool = crate::error::quoted(tool);
                format!(" at tool point {tool}, which includes the uncertainty of its offset,")
            }
            (None, None) => String::new(),
        };
        let mut s = format!(
            "predicted position uncertainty{seen} over {} poses of {} (radius holding the \
             error with {:.0} % probability; {:.2} σ for an isotropic 3-D error): RMS {:.4} \
             mm, median {:.4} mm, max {:.4} mm",
            self.poses,
            self.workspace,
            100.0 * self.coverage,
            self.k_isotropic,
            self.rms_mm,
            self.median_mm,
            self.max_mm
        );
        for r in &self.regions {
            s.push_str(&format!(
                "\n  reach {:>13} mm  {:>5} poses  RMS {:.4} mm  max {:.4} mm",
                format!("{:.0}–{:.0}", r.reach_from_mm, r.reach_to_mm),
                r.poses,
                r.rms_mm,
                r.max_mm
            ));
        }
        s
    }
}
