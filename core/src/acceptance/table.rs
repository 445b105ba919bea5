//! The acceptance tests as text: what `aacmm verify` prints.

use std::fmt::Write;

use super::{Acceptance, LDiaRadius, Use};

impl Acceptance {
    /// The tests' table, every placement, the `L_Dia` centres, the SPAT's
    /// cones, and the outcome in words.
    pub fn summary(&self) -> String {
        let mut t = String::new();
        self.write_tests(&mut t);
        self.write_placements(&mut t);
        self.write_l_dia(&mut t);
        self.write_spat(&mut t);
        t += &self.outcome();
        t
    }

    /// The outcome in one line: accepted, not accepted (and why), or
    /// nothing decided.
    pub(crate) fn outcome(&self) -> String {
        if !self.decided() {
            return "\nNo MPE stated (--mpe): the figures above are printed, nothing is decided \
                    (PASS, FAIL or INCONCLUSIVE needs an MPE).\n"
                .to_string();
        }
        let not = self.not_passed();
        let undecided: Vec<&str> = (self.tests.iter())
            .filter(|t| t.decision.is_none())
            .map(|t| t.figure.as_str())
            .collect();
        let mut t = if !not.is_empty() {
            format!("\nNOT ACCEPTED: {}.\n", not.join("; "))
        } else {
            "\nACCEPTED: every test with a stated MPE passes (ISO 14253-1: |value| ≤ MPE − U).\n"
                .to_string()
        };
        if !undecided.is_empty() {
            let mut names = undecided;
            names.dedup();
            let _ = writeln!(t, "Not decided (no MPE stated): {}.", names.join(", "));
        }
        t
    }

    fn write_tests(&self, t: &mut String) {
        let _ = writeln!(
            t,
            "Acceptance tests (ISO 10360-12 / ASME B89.4.22) on {}: sphere {} mm (u = {} mm, \
             k = 1), probe ball {} mm; U expanded (k = 2)",
            self.sphere_file, self.sphere_diameter, self.sphere_uncertainty, self.ball_diameter
        );
        // The `at` column as wide as its longest entry (a length's
        // `a–b (file:line)`).
        let w = (self.tests.iter())
            .map(|r| r.at.chars().count())
            .fold(8, usize::max);
        // The predicted column only when a prediction was made: the table
        // of a verification without one is what it always was.
        let predicted = self.prediction.is_some();
        let column = |p: Option<super::Predicted>| match (predicted, p) {
            (false, _) => String::new(),
            (true, None) => format!(" {:>19}", "-"),
            (true, Some(p)) => format!(" {:>19}", format!("{:.4} ± {:.4}", p.value, p.spread)),
        };
        let head = if predicted {
            format!(" {:>19}", "predicted (mm)")
        } else {
            String::new()
        };
        let _ = writeln!(
            t,
            "{:<22} {:<w$} {:>11} {:>10} {:>9}{head}  decision",
            "test", "at", "value (mm)", "MPE (mm)", "U (mm)"
        );
        for r in &self.tests {
            let mpe = r.mpe.map_or("-".to_string(), |m| format!("{m:.4}"));
            let decision = r.decision.map_or("not decided", |d| d.word());
            let _ = writeln!(
                t,
                "{:<22} {:<w$} {:>11.4} {:>10} {:>9.4}{}  {decision}",
                r.figure,
                r.at,
                r.value,
                mpe,
                r.u,
                column(r.predicted)
            );
        }
        for u in &self.untested {
            let _ = writeln!(
                t,
                "{:<22} {:<w$} an MPE is stated, no data tested it",
                u.key(),
                "-"
            );
        }
        self.write_agreement(t);
    }

    /// One note on the predictions: which measured values lie within two
    /// spreads of what the calibration predicts.
    fn write_agreement(&self, t: &mut String) {
        let Some(info) = &self.prediction else {
            return;
        };
        let judged: Vec<_> = (self.tests.iter())
            .filter_map(|r| r.predicted.map(|p| (r, p)))
            .collect();
        let beyond: Vec<String> = (judged.iter())
            .filter(|(_, p)| !p.agrees)
            .map(|(r, p)| {
                let off = (r.value - p.value).abs();
                if p.spread > 0.0 {
                    format!(
                        "{} at {} ({:.1} spreads off)",
                        r.figure,
                        r.at,
                        off / p.spread
                    )
                } else {
                    format!("{} at {} ({off:.4} mm off a spread of 0)", r.figure, r.at)
                }
            })
            .collect();
        let _ = writeln!(
            t,
            "Predicted from the calibration in {} ({} draws, seed {}; value ± spread, σ): {} of \
             {} measured values within 2 spreads{}",
            info.calibration,
            info.draws,
            info.seed,
            judged.len() - beyond.len(),
            judged.len(),
            if beyond.is_empty() {
                " — the arm performs as its calibration says.".to_string()
            } else {
                format!("; beyond: {}.", beyond.join("; "))
            }
        );
    }

    fn write_placements(&self, t: &mut String) {
        let _ = writeln!(
            t,
            "\nPlacements (a least-squares sphere through every point, radius free):\n{:<10} {:>6} \
             {:>6} {:<12} {:>21} {:>10} {:>9} {:>9}",
            "sphere", "line", "points", "used for", "diameter (mm) ± σ", "form", "P_Size", "P_Form"
        );
        for p in &self.placements {
            let used = match p.used_for {
                Use::Probing => "P_Size/Form",
                Use::Articulated => "L_Dia",
                Use::Length => "E_Uni",
            };
            let figure = |k: usize| {
                p.tests
                    .get(k)
                    .map_or("-".to_string(), |r| format!("{:.4}", r.value))
            };
            let _ = writeln!(
                t,
                "{:<10} {:>6} {:>6} {:<12} {:>12.4} ± {:<6.4} {:>10.4} {:>9} {:>9}",
                p.name,
                p.line,
                p.points,
                used,
                p.diameter,
                p.fit.diameter_sigma(),
                p.fit.form(),
                figure(0),
                figure(1)
            );
        }
    }

    fn write_l_dia(&self, t: &mut String) {
        if self.l_dia.is_empty() {
            return;
        }
        let how = match self.l_dia_radius {
            LDiaRadius::Held => "the calibrated diameter held",
            LDiaRadius::Free => "the radius fitted",
        };
        let _ = writeln!(t, "\nL_Dia: each articulation's centre with {how} (mm)");
        for p in &self.l_dia {
            for (g, c) in &p.centres {
                let _ = writeln!(
                    t,
                    "{:<10} articulation {g}: {:>11.4} {:>11.4} {:>11.4}",
                    p.name, c[0], c[1], c[2]
                );
            }
        }
    }

    fn write_spat(&self, t: &mut String) {
        if self.spat.is_empty() {
            return;
        }
        let _ = writeln!(
            t,
            "\nSPAT (ASME B89.4.22) per cone, mm:\n{:<10} {:>7} {:>9} {:>9} {:>9} {:>9} {:>9}",
            "cone", "touches", "delta_max", "2s", "hr X", "hr Y", "hr Z"
        );
        for c in &self.spat {
            let _ = writeln!(
                t,
                "{:<10} {:>7} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4}",
                c.label,
                c.touches,
                c.delta_max,
                c.two_s,
                c.half_range[0],
                c.half_range[1],
                c.half_range[2]
            );
        }
    }
}
