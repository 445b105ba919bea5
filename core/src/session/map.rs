//! A calibration's uncertainty map over its workspace, and what a next
//! plan starts from.

use crate::calibrate::Calibration;
use crate::dataset::DataSet;
use crate::domain::Arm;
use crate::kernel::PreparedPoses;
use crate::plan::{
    Given, InFrame, UncertaintyMap, reading_ranges, sample_poses, uncertainty_map,
    uncertainty_map_at_tool, uncertainty_map_in_frame,
};

use super::CalibrationReport;

/// Poses an uncertainty map samples.
pub(crate) const MAP_POSES: usize = 1000;

/// The predicted position uncertainty of `calibration` over [`MAP_POSES`]
/// poses drawn uniformly within the arm's joint limits — or, for a joint
/// without, within the range the campaign turned it through — seeded by
/// `seed`, in the arm's base; and over the same poses as each fitted frame
/// sees the probe, the frame's registration included
/// ([`crate::plan::uncertainty_map_in_frame`]); and at each tool point
/// whose offset was fitted ([`crate::plan::uncertainty_map_at_tool`]).
/// `None` (and no frame's or tool's) when the free geometry's covariance is
/// not finite; a frame's or tool's is left out when its own columns' is
/// not.
pub(crate) fn workspace_maps(
    arm: &Arm,
    data: &DataSet,
    calibration: &Calibration,
    seed: u64,
) -> (
    Option<UncertaintyMap>,
    Vec<UncertaintyMap>,
    Vec<UncertaintyMap>,
) {
    let Some((free, cov)) = calibration.geometry_covariance() else {
        return (None, Vec::new(), Vec::new());
    };
    let (poses, workspace) = workspace(arm, data, seed);
    let params = &calibration.params;
    let Ok(base) = uncertainty_map(params, &poses, &free, &cov, &workspace) else {
        return (None, Vec::new(), Vec::new());
    };
    let tools = (calibration.tool_offsets().iter())
        .filter_map(|(name, _)| {
            let (free, x, cov) = calibration.tool_covariance(name)?;
            uncertainty_map_at_tool(params, &poses, &free, &cov, (name, x), &workspace).ok()
        })
        .collect();
    let frames = (calibration.frames().iter())
        .filter_map(|(name, _)| {
            let (free, x, cov) = calibration.frame_covariance(name)?;
            let frame = InFrame { name, x };
            uncertainty_map_in_frame(params, &poses, &free, &cov, &frame, &workspace).ok()
        })
        .collect();
    (Some(base), frames, tools)
}

/// The map's poses, seeded by `seed`, and where they come from in words.
fn workspace(arm: &Arm, data: &DataSet, seed: u64) -> (PreparedPoses, String) {
    let n = arm.params.joint_count();
    let mut readings: Vec<&[f64]> = (0..data.len()).map(|i| data.reading(i)).collect();
    if let Some(p) = data.positions() {
        readings.extend((0..p.len()).map(|i| p.rows().reading(i)));
    }
    let seen = reading_ranges(&readings, n);
    let mut limits = arm.limits.clone();
    limits.resize(n, None);
    let stated = limits.iter().filter(|l| l.is_some()).count();
    let ranges: Vec<Option<[f64; 2]>> = limits.iter().zip(&seen).map(|(l, s)| l.or(*s)).collect();
    let workspace = match stated {
        0 => "the joint ranges the campaign turned through".to_string(),
        s if s == n => "the joint limits".to_string(),
        _ => "the joint limits (the campaign's ranges where none is stated)".to_string(),
    };
    let prismatic = arm.params.shape().map_or(0, |s| s.prismatic_mask());
    (sample_poses(&ranges, prismatic, MAP_POSES, seed), workspace)
}

impl CalibrationReport {
    /// What a plan of the next measurements starts from: this
    /// calibration's free geometry and covariance, its σ per row and
    /// `σ̂₀`. `None` when its covariance is not finite.
    pub fn plan_given(&self) -> Option<Given> {
        let c = &self.calibration;
        let (free, cov) = c.geometry_covariance()?;
        let stated = !c.dof.touch_sigma_estimated;
        Some(Given {
            free,
            cov,
            sigma_mm: c.dof.touch_sigma_mm,
            sigma0: stated.then_some(c.dof.sigma0),
            frame_known: !c.frames().is_empty(),
        })
    }
}
