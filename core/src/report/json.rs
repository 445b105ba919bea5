//! The files a calibration writes: `calibration.json`, `timing.json` and
//! `calibrated.toml`.

use serde::Serialize;

use crate::io::{AngleUnit, LengthUnit, arm_to_toml};

use crate::session::{CalibrationReport, Problem, Spelling};

/// The calibrated arm, in the arm-file schema.
pub const CALIBRATED_FILE: &str = "calibrated.toml";
/// Everything the calibration found, as JSON ([`CalibrationReport`]).
pub const REPORT_FILE: &str = "calibration.json";
/// Wall times per phase (apart from [`REPORT_FILE`], which is the same
/// bytes for the same seed).
pub const TIMING_FILE: &str = "timing.json";

impl CalibrationReport {
    /// `calibration.json`: pretty JSON and a final newline, the same bytes
    /// for the same inputs and seed.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self)
            .expect("the report holds only strings, numbers, arrays and maps");
        s.push('\n');
        s
    }

    /// Reads a report back (the calibrated parameters are rebuilt from the
    /// estimates).
    ///
    /// # Errors
    ///
    /// The JSON error when `text` is not a report.
    pub fn from_json(text: &str) -> Result<CalibrationReport, serde_json::Error> {
        let mut r: CalibrationReport = serde_json::from_str(text)?;
        r.calibration.restore_params();
        Ok(r)
    }

    /// `timing.json`: the wall time of every phase, ms.
    pub(crate) fn timing_json(&self, total_seconds: f64) -> String {
        #[derive(Serialize)]
        struct PhaseTime<'a> {
            name: &'a str,
            ms: f64,
        }
        #[derive(Serialize)]
        struct Timing<'a> {
            fit_ms: f64,
            total_ms: f64,
            phases: Vec<PhaseTime<'a>>,
        }
        let phases = &self.calibration.solver.phases;
        let timing = Timing {
            fit_ms: phases.iter().map(|p| p.seconds).sum::<f64>() * 1e3,
            total_ms: total_seconds * 1e3,
            phases: phases
                .iter()
                .map(|p| PhaseTime {
                    name: &p.name,
                    ms: p.seconds * 1e3,
                })
                .collect(),
        };
        let mut s = serde_json::to_string_pretty(&timing).expect("numbers and strings");
        s.push('\n');
        s
    }

    /// `calibrated.toml`: the calibrated arm, its frames, and the verdict
    /// (`[verdict]`; a refused calibration's file also opens with a comment
    /// saying so), which every reader of arm files checks
    /// ([`crate::io::verdict`]).
    pub(crate) fn calibrated_toml(&self, problem: &Problem) -> String {
        let calibrated = self.calibrated_arm_from(problem.arm());
        let verdict = &self.verdict;
        let header = if verdict.usable {
            ""
        } else {
            crate::io::verdict::rejected_header()
        };
        let mount = (self.calibration.mount_record().as_ref())
            .map_or_else(String::new, crate::io::frames::mount_to_toml);
        format!(
            "{header}{}{}{mount}{}",
            arm_to_toml(&calibrated, LengthUnit::Mm, AngleUnit::Deg),
            crate::io::frames::frames_to_toml(&self.calibration.frame_records()),
            crate::io::verdict::verdict_to_toml(&verdict.words(Spelling::Cli))
        )
    }
}
