//! A calibration's output directory read back for a command that uses its
//! covariance (`points --uncertainty DIR`, `verify --calibration DIR`):
//! its `calibration.json`, checked to be the arm file's calibration.

use std::path::{Path, PathBuf};

use aacmm_core::domain::Arm;
use aacmm_core::report::REPORT_FILE;
use aacmm_core::session::CalibrationReport;
use anyhow::{Context, Result, anyhow, bail};

/// The report in `dir` (given as `flag`) and its file's path; refused, by
/// file and cause, when it cannot be read, is no report, or is another
/// arm's calibration than `arm`'s ([`same_arm`]). The calibrated joints
/// take the arm file's kinds (a report of a revolute arm does not write
/// them).
pub fn read(flag: &str, dir: &Path, arm: &Arm) -> Result<(CalibrationReport, PathBuf)> {
    let path = dir.join(REPORT_FILE);
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "{flag} {}: cannot read {REPORT_FILE} (give the directory `aacmm calibrate --out` \
             wrote)",
            dir.display()
        )
    })?;
    let mut report = CalibrationReport::from_json(&text)
        .map_err(|e| anyhow!("{}: not a calibration report: {e}", path.display()))?;
    let cal = &mut report.calibration;
    same_arm(flag, cal, arm, &path)?;
    for (theirs, ours) in cal.params.joints.iter_mut().zip(&arm.params.joints) {
        theirs.kind = ours.kind;
    }
    Ok((report, path))
}

/// Refuses a calibration of another arm than the arm file's: another
/// joint count, or a free parameter a tenth of its σ away (the arm file
/// is that calibration's calibrated.toml, written to far finer decimals).
fn same_arm(flag: &str, cal: &aacmm_core::Calibration, arm: &Arm, path: &Path) -> Result<()> {
    let (theirs, ours) = (cal.params.joint_count(), arm.params.joint_count());
    if theirs != ours {
        bail!(
            "{flag}: {} is of a {theirs}-joint arm, the arm file has {ours} joints",
            path.display()
        );
    }
    for e in cal.parameters.iter().filter(|e| e.fixed.is_none()) {
        let mut d = arm.params.get(e.id) - e.calibrated;
        if !e.id.kind.is_length() {
            d = aacmm_core::simulate::wrap(d);
        }
        if let Some(sigma) = e.sigma
            && d.abs() > 0.1 * sigma
        {
            bail!(
                "{flag}: {} is not this arm file's calibration: its {} differs from the arm \
                 file's by {:.3} σ (give the directory that wrote this calibrated.toml)",
                path.display(),
                e.id,
                d / sigma
            );
        }
    }
    Ok(())
}
