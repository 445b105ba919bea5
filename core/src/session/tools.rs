//! What a calibration with several tool points ([`crate::io::tools`])
//! reports of them: per tool its rows, its nominal and fitted offset ± σ
//! (mm, the last joint's frame) and the RMS of its rows' errors before
//! (the start arm, its frames in closed form, the nominal offsets) and
//! after (the calibrated arm, frames and offsets) — a reference
//! position's 3-D error, a touch's distance from its point's centre. One
//! report per file whose rows name tools (positions, poses); absent when
//! no row names a tool. Points on spheres have their own per-probe table
//! ([`super::spheres`]).

use serde::{Deserialize, Serialize};

use crate::calibrate::validate::{ArmView, pose_errors, seen_by};
use crate::calibrate::{Calibration, CalibrationError};
use crate::dataset::DataSet;

/// One tool point's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToolResult {
    /// Its name ([`crate::domain::DEFAULT_TOOL`] for the arm's probe).
    pub name: String,
    /// Rows that name it.
    pub rows: usize,
    /// Its nominal offset, mm.
    pub nominal: [f64; 3],
    /// Its fitted offset, mm (the probe's `Bx, By, Bz` for the default
    /// tool, fitted or held).
    pub offset: [f64; 3],
    /// Its σ per axis, mm, when determined (none when held).
    pub sigma: Option<[f64; 3]>,
    /// RMS of its rows' 3-D errors at the start arm, mm.
    pub rms_before: f64,
    /// The same at the calibrated arm, mm.
    pub rms_after: f64,
}

/// What a tool report's rows are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum ToolRows {
    /// Reference positions: the RMS is of their 3-D errors `|R p + t − y|`.
    #[default]
    Positions,
    /// Touches: the RMS is of each touch's distance from its point's
    /// centre (the mean of the point's touches as the arm sees them).
    Touches,
}

impl ToolRows {
    fn is_positions(&self) -> bool {
        *self == ToolRows::Positions
    }
}

/// The tool points of a calibration: `calibration.json`'s `tools` (the
/// positions') and `touch_tools` (the touches').
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToolReport {
    /// The file whose rows name them.
    pub file: String,
    /// What its rows are (absent in JSON for positions, as before touches
    /// could name tools).
    #[serde(default, skip_serializing_if = "ToolRows::is_positions")]
    pub(crate) of: ToolRows,
    /// Per tool with rows, the default tool first, then in order of first
    /// appearance.
    pub tools: Vec<ToolResult>,
}

/// Per row of `data`'s positions, its 3-D error as `arm` sees them.
fn row_errors(arm: ArmView<'_>, data: &DataSet) -> Result<Vec<f64>, CalibrationError> {
    let seen = seen_by(arm.params, arm.physics, data)?;
    match seen.positions() {
        Some(p) => Ok(pose_errors(arm.params, p, arm.frames)?.1),
        None => Ok(Vec::new()),
    }
}

/// The probe's fitted `B` and its σ from the parameter table.
pub(crate) fn probe_estimate(c: &Calibration) -> ([f64; 3], Option<[f64; 3]>) {
    let of = |k: usize| {
        (c.parameters.iter()).find(|e| {
            e.id.kind == crate::params::ParamKind::Probe && e.id.index == k && e.fixed.is_none()
        })
    };
    let sigma = match [of(0), of(1), of(2)].map(|e| e.and_then(|e| e.sigma)) {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    };
    (c.params.probe, sigma)
}

/// Per touch of `data`, its distance from its point's centre as `arm`
/// sees them (each touch through its tool, the tools at `arm`'s frames'
/// `tool.NAME` blocks when fitted, else nominal).
fn touch_errors(arm: ArmView<'_>, data: &DataSet) -> Result<Vec<f64>, CalibrationError> {
    let seen = seen_by(arm.params, arm.physics, data)?;
    let xyz = crate::residuals::tools::touch_positions_at(arm.params, &seen, arm.frames)?;
    let mut e = vec![0.0; xyz.len()];
    for point in seen.points() {
        let at = &xyz[point.touches.clone()];
        let c = crate::geometry::centroid(at);
        for (i, p) in point.touches.clone().zip(at) {
            e[i] = crate::geometry::distance(p, &c);
        }
    }
    Ok(e)
}

/// The reports of the tools `data`'s positions and touches name after
/// `calibration`, each arm seeing the data as `before` and `after` say:
/// (positions', touches'), each `None` when no row of its file names a
/// tool.
///
/// # Errors
///
/// The kernel's; a correction whose conditions the data lack.
pub(crate) fn tool_reports(
    data: &DataSet,
    calibration: &Calibration,
    (start, before, after): (&crate::params::DhParams, ArmView<'_>, ArmView<'_>),
) -> Result<(Option<ToolReport>, Option<ToolReport>), CalibrationError> {
    let positions = match data.positions().filter(|p| p.rows().has_tools()) {
        Some(p) => {
            let rows = p.rows();
            let of: Vec<usize> = (0..rows.len()).map(|i| rows.tool(i)).collect();
            let tools: Vec<(String, Option<[f64; 3]>)> = (0..rows.tools().len())
                .map(|k| (rows.tools()[k].clone(), rows.tool_offset(k)))
                .collect();
            let errors = (row_errors(before, data)?, row_errors(after, data)?);
            Some(ToolReport {
                file: p.file().to_string(),
                of: ToolRows::Positions,
                tools: per_tool(calibration, start, &tools, &of, errors),
            })
        }
        None => None,
    };
    let touches = match data.touch_tools() {
        Some(t) => {
            let mut of = vec![0; data.len()];
            for (p, point) in data.points().iter().enumerate() {
                of[point.touches.clone()].fill(t.of_point(p));
            }
            let tools: Vec<(String, Option<[f64; 3]>)> = (t.names().iter().enumerate())
                .map(|(k, n)| (n.clone(), t.offset(k)))
                .collect();
            let errors = (touch_errors(before, data)?, touch_errors(after, data)?);
            Some(ToolReport {
                file: data.source().poses_file().to_string(),
                of: ToolRows::Touches,
                tools: per_tool(calibration, start, &tools, &of, errors),
            })
        }
        None => None,
    };
    Ok((positions, touches))
}

/// Per tool of `tools` (name, nominal offset; the default tool first) with
/// rows (`of`: each row's tool), its result: its offset fitted in
/// `calibration` and the RMS of its rows' `(before, after)` errors.
fn per_tool(
    calibration: &Calibration,
    start: &crate::params::DhParams,
    tools: &[(String, Option<[f64; 3]>)],
    of: &[usize],
    (e0, e1): (Vec<f64>, Vec<f64>),
) -> Vec<ToolResult> {
    let fitted = calibration.tool_estimates();
    let rms = |e: &[f64], rows: &[usize]| {
        (rows.iter().map(|&i| e[i] * e[i]).sum::<f64>() / rows.len().max(1) as f64).sqrt()
    };
    let mut out = Vec::new();
    for (k, (name, nominal)) in tools.iter().enumerate() {
        let rows: Vec<usize> = (0..of.len()).filter(|&i| of[i] == k).collect();
        if rows.is_empty() {
            continue;
        }
        let nominal = nominal.unwrap_or(start.probe);
        let (offset, sigma) = match k {
            0 => probe_estimate(calibration),
            _ => (fitted.iter().find(|(n, _, _)| n == name))
                .map_or((nominal, None), |(_, x, s)| (*x, *s)),
        };
        out.push(ToolResult {
            name: name.clone(),
            rows: rows.len(),
            nominal,
            offset,
            sigma,
            rms_before: rms(&e0, &rows),
            rms_after: rms(&e1, &rows),
        });
    }
    out
}
