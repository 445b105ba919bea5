//! What is printed of points on spheres: `evaluate --spheres`' table of a
//! [`SphereEvaluation`], and the calibration summary's lines of its spheres
//! and its held-out ones.

use crate::session::spheres::{HeldOutSpheres, SphereEvaluation, SphereReport};

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

impl SphereReport {
    /// The summary's lines: the spheres, their centres and diameters, and
    /// the radial residuals before and after.
    pub(crate) fn summary(&self) -> String {
        let mut t = format!(
            "\nSpheres ({}): diameter {}; probe ball {} mm\n",
            self.file,
            match self.stated_diameter {
                Some(d) => format!("{d} mm (stated)"),
                None => "fitted per sphere".to_string(),
            },
            self.ball_diameter
        );
        t += &format!(
            "{:<10} {:>6} {:>32} {:>18} {:>21} {:>21}\n",
            "sphere",
            "points",
            "centre (mm) ± sigma",
            "diameter (mm)",
            "RMS radial before/after",
            "form before/after"
        );
        for s in &self.spheres {
            let sig = s
                .centre_sigma
                .map_or(0.0, |v| v.iter().fold(0.0, |a: f64, b| a.max(*b)));
            let d = match s.diameter_sigma {
                Some(ds) => format!("{:.4} ± {:.4}", s.diameter, ds),
                None => format!("{:.4}", s.diameter),
            };
            t += &format!(
                "{:<10} {:>6} {:>24} ± {:.4} {:>18} {:>10.4} / {:<8.4} {:>10.4} / {:<8.4}\n",
                s.name,
                s.points,
                format!("{:.3}, {:.3}, {:.3}", s.centre[0], s.centre[1], s.centre[2]),
                sig,
                d,
                s.before.rms,
                s.after.rms,
                s.before.form,
                s.after.form
            );
        }
        if !self.probes.is_empty() {
            t += &format!(
                "{:<12} {:>38} {:>28} {:>10} {}\n",
                "probe", "offset x, y, z (mm)", "sigma x, y, z (mm)", "ball (mm)", "spheres"
            );
        }
        for p in &self.probes {
            let (o, s) = super::tools::offset_cells(p.offset, p.sigma);
            t += &format!(
                "{:<12} {:>38} {:>28} {:>10} {}\n",
                p.name,
                o,
                s,
                p.ball_diameter,
                p.spheres.join(", ")
            );
        }
        t
    }
}

impl HeldOutSpheres {
    /// The summary's lines: per sphere its refitted diameter and radial
    /// residuals before and after, and every point's.
    pub(crate) fn summary(&self) -> String {
        let mut t = format!(
            "\nHeld-out points on spheres ({}): each sphere's centre{} refitted on its own points \
             with the arm held fixed\n",
            self.file,
            match self.stated_diameter {
                Some(d) => format!(" (its diameter stated, {d} mm)"),
                None => " and diameter".to_string(),
            }
        );
        t += &format!(
            "{:<10} {:>6} {:>23} {:>21} {:>21}\n",
            "sphere",
            "points",
            "diameter before/after",
            "RMS radial before/after",
            "form before/after"
        );
        for s in &self.spheres {
            t += &format!(
                "{:<10} {:>6} {:>11.4} / {:<9.4} {:>10.4} / {:<8.4} {:>10.4} / {:<8.4}\n",
                s.name,
                s.points,
                s.diameter_before,
                s.diameter_after,
                s.before.rms,
                s.after.rms,
                s.before.form,
                s.after.form
            );
        }
        t += &format!(
            "every point: |radial error| mean {:.4} / {:.4}, RMS {:.4} / {:.4}, p95 {:.4} / {:.4}, \
             max {:.4} / {:.4} mm (before / after)\n",
            self.before.mean,
            self.after.mean,
            self.before.rms,
            self.after.rms,
            self.before.p95,
            self.after.p95,
            self.before.max,
            self.after.max
        );
        t
    }
}
