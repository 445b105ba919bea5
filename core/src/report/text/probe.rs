//! What `aacmm probe` prints of a [`ProbeQualification`].

use crate::error::quoted;
use crate::session::probe::ProbeQualification;

impl ProbeQualification {
    /// What `aacmm probe` prints.
    pub fn summary(&self) -> String {
        let triple = |v: [f64; 3]| format!("{:.4}, {:.4}, {:.4}", v[0], v[1], v[2]);
        let mut t = format!(
            "Probe qualification of {} on sphere {} ({} points, {}; sphere diameter {} mm, the \
             arm's geometry held)\n",
            quoted(&self.tool),
            quoted(&self.sphere),
            self.points,
            self.file,
            crate::error::short(self.sphere_diameter_mm),
        );
        t += &format!(
            "  tip offset (mm):     {}  ± {}\n  stated (mm):         {}  moved {:.4} mm \
             (tolerance {} mm)\n",
            triple(self.offset),
            triple(self.offset_sigma),
            triple(self.nominal_offset),
            self.moved_mm,
            crate::error::short(self.tolerance_mm),
        );
        t += &format!(
            "  ball diameter (mm):  {:.4} ± {:.4} effective (stated {})\n  sphere form: {:.4} mm \
             ({}), radial RMS {:.4} mm\n",
            self.ball_diameter_mm,
            self.ball_sigma_mm,
            self.nominal_ball_mm
                .map_or("none".to_string(), |d| format!("{d} mm")),
            self.form_mm,
            self.max_form_mm.map_or(
                "no limit set: judged by the stated noise".to_string(),
                |m| { format!("limit {} mm", crate::error::short(m)) }
            ),
            self.rms_mm,
        );
        for w in &self.warnings {
            t += &format!("warning: {w}\n");
        }
        t += &if self.usable() {
            "Verdict: QUALIFIED\n".to_string()
        } else {
            format!(
                "Verdict: NOT QUALIFIED\n  - {}\n",
                self.refusals.join("\n  - ")
            )
        };
        t
    }
}
