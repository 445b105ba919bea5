//! What `evaluate --spheres` prints of a [`SphereEvaluation`].

use crate::session::spheres::SphereEvaluation;

impl SphereEvaluation {
    /// What `evaluate --spheres` prints.
    pub fn summary(&self) -> String {
        let mut t = format!(
            "Points on spheres ({}): each sphere's centre{} fitted on its points with the arm \
             held fixed\n{:<10} {:>6} {:>14} {:>12} {:>10}\n",
            self.file,
            match self.stated_diameter {
                Some(d) => format!(" (its diameter stated, {d} mm)"),
                None => " and diameter".to_string(),
            },
            "sphere",
            "points",
            "diameter (mm)",
            "RMS radial",
            "form"
        );
        for (name, n, d, e) in &self.spheres {
            t += &format!(
                "{name:<10} {n:>6} {d:>14.4} {:>12.4} {:>10.4}\n",
                e.rms, e.form
            );
        }
        let e = &self.errors;
        t += &format!(
            "every point: |radial error| mean {:.4}, RMS {:.4}, p95 {:.4}, max {:.4} mm ({} \
             points)\n",
            e.mean, e.rms, e.p95, e.max, e.count
        );
        t
    }
}
