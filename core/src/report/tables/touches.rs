//! The tables on the touches: the validation figures per data set (the
//! single-point section), every point of one evaluation and their summary,
//! and the residual lengths per series.

use super::{Cell, row_class, table};
use crate::calibrate::validate::Figures;
use crate::report::data::{Evaluated, for_each_delta};
use crate::report::{Arms, ValidationRow};

/// The validation table, as `calibration.json` has it.
pub(crate) fn validation(rows: &[ValidationRow], arms: &Arms) -> String {
    let mut out: Vec<(String, Vec<Cell>)> = Vec::new();
    for r in rows {
        let held = r.held_out;
        for (stage, f, key, arm) in [
            ("before", &r.figures.before, "before", &arms.before),
            ("after", &r.figures.after, "after", &arms.after),
        ] {
            let base = r.json.as_ref().map(|j| format!("{j}/{key}"));
            let class = match (stage, held) {
                ("after", true) => "held after",
                ("after", false) => "after",
                _ => "",
            };
            out.push((
                class.to_string(),
                figure_cells(&format!("{}, {arm}", r.name), f, base.as_deref()),
            ));
        }
    }
    table(
        "Validation: the figures before and after (mm)",
        &[
            "data, arm",
            "points",
            "e mean [mm]",
            "e max [mm]",
            "2s mean [mm]",
            "δ_max [mm]",
            "lengths",
            "length RMS [mm]",
            "length max |error| [mm]",
        ],
        &out,
    ) + "<p class=\"note\">e: the paper's single-point error; 2s and δ_max: the ASME B89.4.22 \
         single-point articulation test; length: error against the reference lengths."
        + if rows.iter().any(|r| r.name.starts_with("fold")) {
            " Folds: k-fold cross-validation over points, each fold's points scored by an arm \
             fitted without them."
        } else {
            ""
        }
        + "</p>\n"
}

/// The cells of one [`Figures`] row.
fn figure_cells(name: &str, f: &Figures, base: Option<&str>) -> Vec<Cell> {
    let opt = |v: Option<f64>, key: &str| match v {
        Some(v) => Cell::num(v, 4).at(base, key, v),
        None => Cell::none(),
    };
    vec![
        Cell::text(name),
        Cell::int(f.points).at(base, "points", f.points as f64),
        Cell::num(f.e_mean, 4).at(base, "e_mean", f.e_mean),
        Cell::num(f.e_max, 4).at(base, "e_max", f.e_max),
        Cell::num(f.two_s_mean, 4).at(base, "two_s_mean", f.two_s_mean),
        Cell::num(f.delta_max, 4).at(base, "delta_max", f.delta_max),
        Cell::int(f.lengths).at(base, "lengths", f.lengths as f64),
        opt(f.length_rms, "length_rms"),
        opt(f.length_max, "length_max"),
    ]
}
/// The residual lengths per series.
pub(crate) fn residuals(evaluated: &[Evaluated], arms: &Arms) -> String {
    let rows: Vec<(String, Vec<Cell>)> = evaluated
        .iter()
        .map(|e| {
            // Summed in touch order from −0.0, as a float sum folds.
            let (mut squares, mut max, mut touches) = (-0.0, 0.0, 0usize);
            for_each_delta(e, |v| {
                squares += v * v;
                max = f64::max(max, v);
                touches += 1;
            });
            let rms = (squares / touches.max(1) as f64).sqrt();
            (
                row_class(e),
                vec![
                    Cell::text(&e.name(arms)),
                    Cell::int(touches),
                    Cell::num(e.median_delta().unwrap_or(f64::NAN), 4),
                    Cell::num(rms, 4),
                    Cell::num(max, 4),
                ],
            )
        })
        .collect();
    table(
        "Per-touch distance δ from the point's centroid",
        &[
            "arm, data",
            "touches",
            "median δ [mm]",
            "RMS δ [mm]",
            "max δ [mm]",
        ],
        &rows,
    )
}
/// The summary across points of one evaluation.
pub(crate) fn points_summary(e: &Evaluated, json: Option<&str>) -> String {
    let ev = &e.ev;
    let mut rows = Vec::new();
    for (name, key, s) in [
        (
            "e (paper Fig. 6)",
            "single_point_e",
            Some(ev.single_point_e),
        ),
        (
            "δ_max",
            "single_point_delta_max",
            Some(ev.single_point_delta_max),
        ),
        ("2s", "single_point_two_s", Some(ev.single_point_two_s)),
        (
            "|d|_error (eq. 19, abs.)",
            "pair_length_abs_summary",
            ev.pair_length_abs_summary,
        ),
        (
            "d_error (eq. 19 as printed)",
            "pair_length_summary",
            ev.pair_length_summary,
        ),
    ] {
        let Some(s) = s else { continue };
        let path = |k: &str| format!("{key}/{k}");
        rows.push((
            String::new(),
            vec![
                Cell::text(name),
                Cell::int(s.count).at(json, &path("count"), s.count as f64),
                Cell::num(s.min, 4).at(json, &path("min"), s.min),
                Cell::num(s.mean, 4).at(json, &path("mean"), s.mean),
                Cell::num(s.max, 4).at(json, &path("max"), s.max),
                Cell::num(s.std, 4).at(json, &path("std"), s.std),
            ],
        ));
    }
    table(
        "Across points and pairs (std = population)",
        &crate::metrics::table::SUMMARY_HEADER,
        &rows,
    )
}

/// Every point of one evaluation.
pub(crate) fn points(e: &Evaluated, json: Option<&str>) -> String {
    let rows: Vec<(String, Vec<Cell>)> =
        e.ev.points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let path = |k: &str| format!("points/{i}/{k}");
                (
                    String::new(),
                    vec![
                        Cell::text(&p.label),
                        Cell::int(p.touches).at(json, &path("touches"), p.touches as f64),
                        Cell::num(p.e, 4).at(json, &path("e"), p.e),
                        Cell::num(p.sigma, 4).at(json, &path("sigma"), p.sigma),
                        Cell::num(p.oa, 4).at(json, &path("oa"), p.oa),
                        Cell::num(p.delta_max, 4).at(json, &path("delta_max"), p.delta_max),
                        Cell::num(p.two_s, 4).at(json, &path("two_s"), p.two_s),
                    ],
                )
            })
            .collect();
    table(
        "Per point: paper eq. 9–12 and the ASME B89.4.22 single-point test",
        &[
            "point",
            "touches",
            "e [mm]",
            "σ [mm]",
            "e + 3σ [mm]",
            "δ_max [mm]",
            "2s [mm]",
        ],
        &rows,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::validate::BeforeAfter;
    use crate::report::html::escape;
    use crate::report::tables::fixture::{self, arms, evaluated, figures};

    #[test]
    fn validation_has_both_arms_per_set_and_notes_folds() {
        let ba = BeforeAfter {
            before: figures(4, 1.5, None),
            after: figures(4, 0.1, None),
        };
        let row = |name: &str, held_out| ValidationRow {
            name: name.into(),
            held_out,
            figures: &ba,
            json: Some(format!("/validation/{name}")),
        };
        let t = validation(&[row("fitted", false)], &arms());
        assert_eq!(fixture::rows(&t), 3, "{t}");
        assert!(
            t.contains(
                "<tr><td>fitted, nominal</td><td class=\"n\" \
                 data-json=\"/validation/fitted/before/points\" data-value=\"4.0\">4</td>\
                 <td class=\"n\" data-json=\"/validation/fitted/before/e_mean\" \
                 data-value=\"1.5\">1.5000</td>"
            ),
            "{t}"
        );
        // Without lengths, their figures are missing numbers.
        assert!(
            t.contains(">0</td><td class=\"n\">-</td><td class=\"n\">-</td></tr>"),
            "{t}"
        );
        assert!(!t.contains("Folds:"), "{t}");
        let t = validation(&[row("fitted", false), row("fold 1", true)], &arms());
        assert!(t.contains("<tr class=\"held after\"><td>fold 1, calibrated</td>"));
        assert!(
            t.contains(" Folds: k-fold cross-validation over points"),
            "{t}"
        );
    }

    #[test]
    fn points_have_a_row_each_and_their_summary_the_pairs_when_there_are_some() {
        let ev = evaluated();
        let e = &ev[1];
        let t = points(e, Some("/evaluation"));
        assert_eq!(fixture::rows(&t), 1 + e.ev.points.len(), "{t}");
        let p = &e.ev.points[0];
        assert!(
            t.contains(&format!(
                "<tr><td>{}</td><td class=\"n\" data-json=\"/evaluation/points/0/touches\" \
                 data-value=\"{:?}\">{}</td>",
                escape(&p.label),
                p.touches as f64,
                p.touches
            )),
            "{t}"
        );
        let s = points_summary(e, None);
        assert_eq!(fixture::rows(&s), 6, "{s}");
        assert!(s.contains("<td>|d|_error (eq. 19, abs.)</td>"), "{s}");
        assert!(!s.contains("data-json"), "{s}");
        let mut lone = e.clone();
        lone.ev.pair_length_abs_summary = None;
        lone.ev.pair_length_summary = None;
        let s = points_summary(&lone, Some("/evaluation"));
        assert_eq!(fixture::rows(&s), 4, "{s}");
        assert!(!s.contains("eq. 19"), "{s}");
        assert!(
            s.contains("data-json=\"/evaluation/single_point_e/mean\""),
            "{s}"
        );
    }

    #[test]
    fn residuals_count_every_touch_of_each_series() {
        let ev = evaluated();
        let n = fixture::case().data.len();
        let t = residuals(&ev, &arms());
        assert_eq!(fixture::rows(&t), 3, "{t}");
        assert!(
            t.contains(&format!(
                "<tr><td>nominal, fitted</td><td class=\"n\">{n}</td>"
            )),
            "{t}"
        );
        assert!(
            t.contains(&format!(
                "<tr class=\"after\"><td>calibrated, fitted</td><td class=\"n\">{n}</td>"
            )),
            "{t}"
        );
        assert_eq!(fixture::rows(&residuals(&[], &arms())), 1);
    }
}
