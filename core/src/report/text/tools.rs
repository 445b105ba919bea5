//! The calibration summary's lines of its tool points.

use crate::session::tools::{ToolReport, ToolRows};

impl ToolReport {
    /// The summary's lines: per tool its offset ± σ and its rows' error
    /// RMS before and after (3-D errors of positions; of touches, their
    /// distances from their points' centres).
    pub(crate) fn summary(&self) -> String {
        let mut t = format!(
            "\nTool points ({}): offsets in the last joint's frame (mm), sigma k = 1{}\n",
            self.file,
            match self.of {
                ToolRows::Positions => "",
                ToolRows::Touches => "; RMS of each touch's distance from its point's centre",
            }
        );
        t += &format!(
            "{:<12} {:>6} {:>38} {:>28} {:>21}\n",
            "tool",
            match self.of {
                ToolRows::Positions => "rows",
                ToolRows::Touches => "touches",
            },
            "offset x, y, z (mm)",
            "sigma x, y, z (mm)",
            match self.of {
                ToolRows::Positions => "RMS 3-D before/after",
                ToolRows::Touches => "RMS before/after",
            }
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
pub(super) fn offset_cells(o: [f64; 3], sigma: Option<[f64; 3]>) -> (String, String) {
    let three = |v: [f64; 3]| format!("{:.4}, {:.4}, {:.4}", v[0], v[1], v[2]);
    (three(o), sigma.map_or_else(|| "held".to_string(), three))
}
