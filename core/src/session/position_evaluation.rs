//! What `evaluate --positions` reports: the 3-D errors of one arm at
//! reference positions (a laser tracker's), each frame registered — as the
//! arm file states it (a calibrated arm's `[[frame]]` of the same name), or
//! else to this arm in closed form on these very positions — and which of
//! the two, said with every figure: a frame registered on the positions it
//! scores absorbs a rigid motion of the arm's error, so its figures are a
//! lower bound of what a fixed registration would show.

use serde::Serialize;

use crate::calibrate::CalibrationError;
use crate::calibrate::validate::{
    FrameValues, PositionErrors, pose_errors, registered_frames, seen_by,
};
use crate::dataset::DataSet;
use crate::io::Arm;

/// One frame's registration and the arm's 3-D errors in it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameEvaluation {
    /// The frame's name.
    pub name: String,
    /// Registered as the arm file states it (`true`), or in closed form on
    /// the positions evaluated (`false`: optimistic).
    pub from_arm_file: bool,
    /// Its rotation vector, deg.
    pub rotation_deg: [f64; 3],
    /// Its translation, mm.
    pub translation_mm: [f64; 3],
    /// The 3-D errors `|R p + t − y|` of its rows, mm.
    pub errors: PositionErrors,
}

/// The 3-D errors of an arm at the reference positions of a file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PositionEvaluation {
    /// The positions file.
    pub positions_file: String,
    /// Over every row, mm.
    pub errors: PositionErrors,
    /// Per frame, in the file's order.
    pub frames: Vec<FrameEvaluation>,
}

impl PositionEvaluation {
    /// The errors of `arm` (through the corrections its file states) at
    /// `data`'s reference positions, each frame registered as `stated`
    /// says (the arm file's frames), else in closed form on them.
    ///
    /// # Errors
    ///
    /// [`CalibrationError::Term`] for data without reference positions or
    /// a correction whose conditions the data lack; the kernel's.
    pub fn new(
        arm: &Arm,
        data: &DataSet,
        stated: &[FrameValues],
    ) -> Result<PositionEvaluation, CalibrationError> {
        let seen = seen_by(&arm.params, &arm.physics, data)?;
        let Some(p) = seen.positions() else {
            return Err(CalibrationError::Term {
                term: "positions".into(),
                message: "no reference positions to evaluate".into(),
            });
        };
        let mut closed = registered_frames(&arm.params, &seen)?;
        // The frames alone (a mount of orientations after them: not here).
        closed.truncate(p.rows().frames().len());
        let frames: Vec<(FrameValues, bool)> = (closed.into_iter())
            .map(|(name, x)| match stated.iter().find(|(n, _)| *n == name) {
                Some(s) => (s.clone(), true),
                None => ((name, x), false),
            })
            .collect();
        let values: Vec<FrameValues> = frames.iter().map(|(f, _)| f.clone()).collect();
        let (_, d) = pose_errors(&arm.params, p, &values)?;
        let rows = p.rows();
        let per_frame = frames
            .into_iter()
            .enumerate()
            .map(|(k, ((name, x), from_arm_file))| {
                let mine: Vec<f64> = (0..d.len())
                    .filter(|&i| rows.frame(i) == k)
                    .map(|i| d[i])
                    .collect();
                FrameEvaluation {
                    name,
                    from_arm_file,
                    rotation_deg: [x[0], x[1], x[2]].map(f64::to_degrees),
                    translation_mm: [x[3], x[4], x[5]],
                    errors: PositionErrors::of(&mine),
                }
            })
            .collect();
        Ok(PositionEvaluation {
            positions_file: p.file().to_string(),
            errors: PositionErrors::of(&d),
            frames: per_frame,
        })
    }

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
        t += "3-D error |R p + t - y| (mm)\n";
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
            row(&f.name, &f.errors);
        }
        if self.frames.len() > 1 {
            row("all", &self.errors);
        }
        t
    }
}
