//! The summary section: a few sentences on the result, and the headline
//! figures per data set and arm.

use super::{Cell, evidence_noun, row_class, table};
use crate::calibrate::Calibration;
use crate::report::data::{Evaluated, Stage};
use crate::report::html::escape;
use crate::report::{Arms, ValidationRow};

/// A few sentences on the result.
pub(crate) fn verdict(
    cal: &Calibration,
    evaluated: &[Evaluated],
    arms: &Arms,
    validation: &[ValidationRow],
) -> String {
    let s = &cal.solver;
    let d = &cal.dof;
    let mut p = String::from("<p>");
    if s.successful {
        p += &format!(
            "<span class=\"good\">The solver converged</span> ({}: {}).",
            escape(s.method.name()),
            escape(&s.stop.describe())
        );
    } else {
        p += &format!(
            "<span class=\"bad\">The solver did not converge</span> ({}: {}): treat the \
             result with suspicion.",
            escape(s.method.name()),
            escape(&s.stop.describe())
        );
    }
    let touches = !evaluated.is_empty();
    p += &format!(
        " σ̂0 = {:.4} with {} degrees of freedom ({}); {} σ {:.4} mm {}.",
        d.sigma0,
        d.degrees_of_freedom,
        if (0.5..=2.0).contains(&d.sigma0) {
            "about 1: the residuals are as large as the stated noise"
        } else if d.sigma0 > 2.0 {
            "well above 1: the residuals exceed the stated noise — noise understated, outliers or a model error"
        } else {
            "well below 1: the stated noise is larger than the residuals"
        },
        evidence_noun(cal, touches),
        d.touch_sigma_mm,
        if d.touch_sigma_estimated {
            "(estimated from the fit)"
        } else {
            "(from the stated noise)"
        }
    );
    for e in evaluated.iter().filter(|e| e.stage == Stage::After) {
        let before = evaluated
            .iter()
            .find(|b| b.set == e.set && b.stage == Stage::Before);
        if let Some(b) = before {
            p += &format!(
                " On the {} points, e falls from {:.4} mm ({}) to {:.4} mm ({})",
                escape(&e.set_name),
                b.ev.single_point_e.mean,
                escape(&arms.before),
                e.ev.single_point_e.mean,
                escape(&arms.after)
            );
            if let (Some(rb), Some(ra)) = (b.ev.reference_summary, e.ev.reference_summary) {
                p += &format!(
                    " and the RMS error of its {} reference lengths from {:.4} mm to {:.4} mm",
                    e.ev.reference.len(),
                    rb.rms,
                    ra.rms
                );
            }
            p += ".";
        }
    }
    p += &positions_sentence(validation);
    // Cross-validation folds are held-out data too (section 1's table).
    if !evaluated.iter().any(|e| e.held_out) && !validation.iter().any(|r| r.held_out) {
        p += match evidence_noun(cal, touches) {
            "touch" => {
                " No held-out data were given (--validate): the figures after calibration are \
                 on the data the fit used."
            }
            "position" => {
                " No held-out data were given (--validate-positions): the figures after \
                 calibration are on the data the fit used."
            }
            _ => {
                " No held-out data were given: the figures after calibration are on the data \
                  the fit used."
            }
        };
    }
    p += "</p>\n";
    p
}
/// Per data set with reference positions (not the folds: their table has
/// them), how the RMS 3-D error changes.
fn positions_sentence(validation: &[ValidationRow]) -> String {
    let mut p = String::new();
    for r in validation.iter().filter(|r| !r.name.starts_with("fold")) {
        if let (Some(b), Some(a)) = (r.figures.before.positions, r.figures.after.positions) {
            p += &format!(
                " At the {} reference positions ({}), the RMS 3-D error falls from {:.4} mm \
                 (nominal) to {:.4} mm (calibrated), the 95th percentile from {:.4} to {:.4} mm.",
                a.count,
                escape(&r.name),
                b.rms,
                a.rms,
                b.p95,
                a.p95
            );
        }
        if let (Some(b), Some(a)) = (r.figures.before.orientations, r.figures.after.orientations) {
            p += &format!(
                " Of the {} tool orientations seen there, the RMS orientation error falls from \
                 {:.4}° (nominal) to {:.4}° (calibrated).",
                a.count, b.rms, a.rms
            );
        }
    }
    p
}
/// The headline figures per data set and arm.
pub(crate) fn glance(evaluated: &[Evaluated], arms: &Arms) -> String {
    let rows: Vec<(String, Vec<Cell>)> = evaluated
        .iter()
        .map(|e| {
            let ev = &e.ev;
            let pair = ev.pair_length_abs_summary.map_or(f64::NAN, |s| s.mean);
            let (rms, max) = ev
                .reference_summary
                .map_or((f64::NAN, f64::NAN), |r| (r.rms, r.max_abs));
            (
                row_class(e),
                vec![
                    Cell::text(&e.name(arms)),
                    Cell::int(ev.points.len()),
                    Cell::num(ev.single_point_e.mean, 4),
                    Cell::num(ev.single_point_e.std, 4),
                    Cell::num(pair, 4),
                    Cell::num(rms, 4),
                    Cell::num(max, 4),
                ],
            )
        })
        .collect();
    table(
        "At a glance (paper: e mean 1.873 → 0.127 mm, length error mean 1.038 → 0.092 mm)",
        &[
            "arm, data",
            "points",
            "e mean [mm]",
            "e std [mm]",
            "|d|_error mean [mm]",
            "reference RMS [mm]",
            "reference max |error| [mm]",
        ],
        &rows,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::validate::BeforeAfter;
    use crate::report::tables::fixture::{self, arms, evaluated, figures};

    #[test]
    fn the_verdict_says_how_the_fit_went_and_what_its_figures_are_on() {
        let c = fixture::case();
        let ev = evaluated();
        let p = verdict(&c.cal, &ev, &arms(), &[]);
        assert!(
            p.starts_with("<p><span class=\"good\">The solver converged</span> (lm: "),
            "{p}"
        );
        assert!(p.contains(" touch σ "), "{p}");
        assert!(p.contains(" On the fitted points, e falls from "), "{p}");
        assert!(
            p.contains("the RMS error of its 2 reference lengths from"),
            "{p}"
        );
        assert!(
            p.contains(" No held-out data were given (--validate): "),
            "{p}"
        );
        assert!(p.ends_with(".</p>\n"), "{p}");

        let mut cal = c.cal.clone();
        cal.solver.successful = false;
        let mut held = ev.clone();
        held[1].held_out = true;
        let p = verdict(&cal, &held, &arms(), &[]);
        assert!(p.contains("<span class=\"bad\">The solver did not converge</span>"));
        assert!(!p.contains("No held-out data"), "{p}");

        // Without touches the σ is a position's, and nothing falls.
        let p = verdict(&c.cal, &[], &arms(), &[]);
        assert!(p.contains(" position σ "), "{p}");
        assert!(p.contains("(--validate-positions)"), "{p}");
        assert!(!p.contains("e falls"), "{p}");
    }

    #[test]
    fn the_positions_sentence_skips_folds_and_sets_without_positions() {
        let ba = BeforeAfter {
            before: figures(0, 0.0, Some(&[3.0, 4.0])),
            after: figures(0, 0.0, Some(&[0.3, 0.4])),
        };
        let row = |name: &str, figures| ValidationRow {
            name: name.into(),
            held_out: true,
            figures,
            json: None,
        };
        let s = positions_sentence(&[row("held <1>", &ba), row("fold 1 (2 points)", &ba)]);
        assert_eq!(s.matches(" At the 2 reference positions").count(), 1, "{s}");
        assert!(
            s.contains(
                "(held &lt;1&gt;), the RMS 3-D error falls from 3.5355 mm (nominal) to 0.3536 mm \
                 (calibrated), the 95th percentile from 4.0000 to 0.4000 mm."
            ),
            "{s}"
        );
        assert!(!s.contains("orientation"), "{s}");
        let none = BeforeAfter {
            before: figures(1, 0.1, None),
            after: figures(1, 0.1, None),
        };
        assert_eq!(positions_sentence(&[row("fitted", &none)]), "");
    }

    #[test]
    fn glance_has_a_row_per_series_the_calibrated_one_classed() {
        let ev = evaluated();
        let t = glance(&ev, &arms());
        let points = ev[0].ev.points.len();
        assert_eq!(fixture::rows(&t), 3, "{t}");
        assert!(
            t.contains(&format!(
                "<tr><td>nominal, fitted</td><td class=\"n\">{points}</td>"
            )),
            "{t}"
        );
        assert!(
            t.contains(&format!(
                "<tr class=\"after\"><td>calibrated, fitted</td><td class=\"n\">{points}</td>"
            )),
            "{t}"
        );
        assert_eq!(fixture::rows(&glance(&[], &arms())), 1);
    }
}
