//! What a calibration with several tool points ([`crate::io::tools`])
//! reports of them: per tool its rows, its nominal and fitted offset ± σ
//! (mm, the last joint's frame) and the RMS of its rows' 3-D errors before
//! (the start arm, its frames in closed form, the nominal offsets) and
//! after (the calibrated arm, frames and offsets). Absent when no row
//! names a tool.

use serde::{Deserialize, Serialize};

use crate::calibrate::validate::{ArmView, pose_errors, seen_by};
use crate::calibrate::{Calibration, CalibrationError};
use crate::dataset::DataSet;

/// One tool point's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToolResult {
    /// Its name ([`crate::io::DEFAULT_TOOL`] for the arm's probe).
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
    pub(crate) rms_before: f64,
    /// The same at the calibrated arm, mm.
    pub(crate) rms_after: f64,
}

/// The tool points of a calibration: `calibration.json`'s `tools`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ToolReport {
    /// The positions file whose rows name them.
    pub file: String,
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

/// The report of the tools `data`'s positions name after `calibration`,
/// each arm seeing the data as `before` and `after` say; `None` when no
/// row names a tool.
///
/// # Errors
///
/// The kernel's; a correction whose conditions the data lack.
pub(crate) fn tool_report(
    data: &DataSet,
    calibration: &Calibration,
    (start, before, after): (&crate::params::DhParams, ArmView<'_>, ArmView<'_>),
) -> Result<Option<ToolReport>, CalibrationError> {
    let Some(p) = data.positions().filter(|p| p.rows().has_tools()) else {
        return Ok(None);
    };
    let (e0, e1) = (row_errors(before, data)?, row_errors(after, data)?);
    let rows = p.rows();
    let fitted = calibration.tool_estimates();
    let rms = |e: &[f64], of: &[usize]| {
        (of.iter().map(|&i| e[i] * e[i]).sum::<f64>() / of.len().max(1) as f64).sqrt()
    };
    let mut tools = Vec::new();
    for (k, name) in rows.tools().iter().enumerate() {
        let of: Vec<usize> = (0..rows.len()).filter(|&i| rows.tool(i) == k).collect();
        if of.is_empty() {
            continue;
        }
        let nominal = rows.tool_offset(k).unwrap_or(start.probe);
        let (offset, sigma) = match k {
            0 => probe_estimate(calibration),
            _ => (fitted.iter().find(|(n, _, _)| n == name))
                .map_or((nominal, None), |(_, x, s)| (*x, *s)),
        };
        tools.push(ToolResult {
            name: name.clone(),
            rows: of.len(),
            nominal,
            offset,
            sigma,
            rms_before: rms(&e0, &of),
            rms_after: rms(&e1, &of),
        });
    }
    Ok(Some(ToolReport {
        file: p.file().to_string(),
        tools,
    }))
}

impl ToolReport {
    /// The summary's lines: per tool its offset ± σ and its rows' 3-D
    /// error RMS before and after.
    pub fn summary(&self) -> String {
        let mut t = format!(
            "\nTool points ({}): offsets in the last joint's frame (mm), sigma k = 1\n",
            self.file
        );
        t += &format!(
            "{:<12} {:>6} {:>38} {:>28} {:>21}\n",
            "tool", "rows", "offset x, y, z (mm)", "sigma x, y, z (mm)", "RMS 3-D before/after"
        );
        for r in &self.tools {
            let (o, s) = offset_cells(r.offset, r.sigma);
            t += &format!(
                "{:<12} {:>6} {:>38} {:>28} {:>10.4} / {:<8.4}\n",
                r.name, r.rows, o, s, r.rms_before, r.rms_after
            );
        }
        t
    }
}

/// A tool's offset and its σ as the summaries' cells (mm, 4 decimals; the
/// σ `held` when not fitted).
pub(crate) fn offset_cells(o: [f64; 3], sigma: Option<[f64; 3]>) -> (String, String) {
    let three = |v: [f64; 3]| format!("{:.4}, {:.4}, {:.4}", v[0], v[1], v[2]);
    (three(o), sigma.map_or_else(|| "held".to_string(), three))
}
