//! What `evaluate --positions` prints of a [`PositionEvaluation`]: how each
//! frame was registered, then the 3-D errors per frame and over all.

use crate::calibrate::validate::PositionErrors;
use crate::session::{FrameEvaluation, PositionEvaluation};

impl PositionEvaluation {
    /// The table `evaluate` prints: how each frame was registered, then the
    /// 3-D errors per frame and over all.
    pub fn summary(&self) -> String {
        let mut t = format!(
            "Reference positions {}: {} rows in {} frame{}\n",
            self.positions_file,
            self.errors.count,
            self.frames.len(),
            if self.frames.len() == 1 { "" } else { "s" }
        );
        for f in &self.frames {
            let how = if f.from_arm_file {
                "registered as the arm file states it ([[frame]])"
            } else {
                "registered to this arm in closed form on these positions (the arm file has no \
                 such [[frame]]): the registration absorbs a rigid motion of the arm's error, so \
                 these figures are optimistic"
            };
            let r = f.rotation_deg;
            let tr = f.translation_mm;
            t += &format!(
                "  frame `{}`: {how}; rotation vector ({:.6}, {:.6}, {:.6}) deg, translation \
                 ({:.4}, {:.4}, {:.4}) mm\n",
                f.name, r[0], r[1], r[2], tr[0], tr[1], tr[2]
            );
        }
        t += &self.table(
            "3-D error |R p + t - y| (mm)",
            |f| Some(&f.errors),
            &self.errors,
        );
        t + &self.orientation_summary()
    }

    /// A table of errors under `title`: per frame (`of` it, a frame
    /// without: no row), then over all (`all`) when there are several.
    fn table(
        &self,
        title: &str,
        of: impl Fn(&FrameEvaluation) -> Option<&PositionErrors>,
        all: &PositionErrors,
    ) -> String {
        let mut t = format!("{title}\n");
        t += &format!(
            "  {:<20} {:>8} {:>8} {:>8} {:>8} {:>8}\n",
            "frame", "poses", "mean", "RMS", "p95", "max"
        );
        let mut row = |name: &str, e: &PositionErrors| {
            t += &format!(
                "  {:<20} {:>8} {:>8.4} {:>8.4} {:>8.4} {:>8.4}\n",
                name, e.count, e.mean, e.rms, e.p95, e.max
            );
        };
        for f in &self.frames {
            if let Some(e) = of(f) {
                row(&f.name, e);
            }
        }
        if self.frames.len() > 1 {
            row("all", all);
        }
        t
    }

    /// The orientation part of [`PositionEvaluation::summary`]: how the
    /// mount was taken, then the errors per frame and over all (nothing
    /// without orientations).
    fn orientation_summary(&self) -> String {
        let (Some(all), Some(m)) = (&self.orientations, &self.mount) else {
            return String::new();
        };
        let how = if m.from_arm_file {
            "as the arm file states it ([mount])"
        } else {
            "in closed form on these orientations (the arm file has no [mount]): it absorbs a \
             constant turn of the arm's error, so these figures are optimistic"
        };
        let r = m.rotation_deg;
        let t = format!(
            "Tool orientations: {} rows; the 6-D target's mount {how}; rotation vector ({:.6}, \
             {:.6}, {:.6}) deg\n",
            all.count, r[0], r[1], r[2]
        );
        t + &self.table(
            "Orientation error (deg): angle of the turn from the arm's target frame to the one seen",
            |f| f.orientations.as_ref(),
            all,
        )
    }
}
