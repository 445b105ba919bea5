//! The files a command writes: a calibration's ([`CalibrationReport::files`],
//! [`CalibrationReport::write`]), and the one rule
//! of every command that writes: an output is never
//! overwritten silently. An output file that exists, or an output
//! directory that holds results of any aacmm command (a calibration's, a
//! campaign's, a report's — [`result_files`]), is refused unless the user
//! says to overwrite (`--force` on the command line, `force=True` in
//! Python); overwriting replaces the command's own files and deletes
//! nothing. A directory that holds other files only is written into.

use std::path::Path;

use super::{CALIBRATED_FILE, REPORT_FILE, TIMING_FILE};
use crate::session::{CalibrationReport, Problem};
use crate::simulate::{
    CAMPAIGN_FILE, LENGTHS_FILE, POSES_FILE, POSITIONS_FILE, SOCKETS_FILE, TRUE_ARM_FILE,
};

/// Every file an aacmm command writes into an output directory: a
/// calibration's (`calibrate --out`, Python's `Calibration.write`), a
/// campaign's (`simulate --out`, `Campaign.write`) and a report's
/// (`evaluate --report`, and the calibration's own).
pub fn result_files() -> Vec<&'static str> {
    let mut files = vec![
        CALIBRATED_FILE,
        REPORT_FILE,
        TIMING_FILE,
        POSES_FILE,
        LENGTHS_FILE,
        SOCKETS_FILE,
        TRUE_ARM_FILE,
        CAMPAIGN_FILE,
        POSITIONS_FILE,
    ];
    #[cfg(feature = "report")]
    {
        use crate::report::{
            BEYOND_SVG, CALIBRATION_FILES, EVALUATION_FILES, POSITIONS_SVG, UNCERTAINTY_MAP_SVG,
        };
        let report = CALIBRATION_FILES.iter().chain(&EVALUATION_FILES);
        for name in report.chain(&[POSITIONS_SVG, BEYOND_SVG, UNCERTAINTY_MAP_SVG]) {
            if !files.contains(name) {
                files.push(name);
            }
        }
    }
    files
}

/// The results of an earlier run of any aacmm command that `dir` holds
/// (the names of [`result_files`] present there), in that order; empty for
/// a directory that holds none, or does not exist.
///
/// ```
/// let dir = std::env::temp_dir().join(format!("aacmm-doc-earlier-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// assert!(aacmm_core::report::earlier_results(&dir).is_empty());
/// std::fs::write(dir.join("notes.txt"), "mine").unwrap();
/// assert!(aacmm_core::report::earlier_results(&dir).is_empty());
/// std::fs::write(dir.join("campaign.toml"), "").unwrap();
/// assert_eq!(aacmm_core::report::earlier_results(&dir), ["campaign.toml"]);
/// std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn earlier_results(dir: &Path) -> Vec<&'static str> {
    result_files()
        .into_iter()
        .filter(|name| dir.join(name).exists())
        .collect()
}

impl CalibrationReport {
    /// The files a session writes, by name: [`CALIBRATED_FILE`],
    /// [`REPORT_FILE`], [`TIMING_FILE`] and (with the `report` feature) the
    /// HTML report and its figures.
    ///
    /// # Errors
    ///
    /// [`WriteError::Report`], when a figure cannot be drawn.
    pub fn files(
        &self,
        problem: &Problem,
        total_seconds: f64,
    ) -> Result<Vec<(String, String)>, WriteError> {
        let mut files = vec![
            (CALIBRATED_FILE.to_string(), self.calibrated_toml(problem)),
            (REPORT_FILE.to_string(), self.to_json()),
            (TIMING_FILE.to_string(), self.timing_json(total_seconds)),
        ];
        #[cfg(feature = "report")]
        {
            let page = crate::report::session_report(self, problem)?;
            files.extend(
                page.files()
                    .map(|(name, text)| (name.to_string(), text.to_string())),
            );
        }
        Ok(files)
    }

    /// Writes [`CalibrationReport::files`] into `dir` (which must exist);
    /// returns the paths written.
    ///
    /// # Errors
    ///
    /// The first file that cannot be written, with its path.
    pub fn write(
        &self,
        problem: &Problem,
        dir: &Path,
        total_seconds: f64,
    ) -> Result<Vec<std::path::PathBuf>, WriteError> {
        let files = self.files(problem, total_seconds)?;
        let mut written = Vec::with_capacity(files.len());
        for (name, text) in files {
            let path = dir.join(name);
            crate::io::write_atomic(&path, text).map_err(|source| WriteError::Io {
                path: path.display().to_string(),
                source,
            })?;
            written.push(path);
        }
        Ok(written)
    }
}

/// Why a session's files could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    /// A file could not be written.
    #[error("{path}: cannot write: {source}")]
    Io {
        /// The file.
        path: String,
        /// The system's reason.
        source: std::io::Error,
    },
    /// The report could not be drawn.
    #[cfg(feature = "report")]
    #[error(transparent)]
    Report(#[from] crate::report::ReportError),
}
