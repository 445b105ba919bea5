//! The lengths section: eq. 19 over the pairs of points, and every
//! reference length.

use super::{Cell, row_class, table};
use crate::report::Arms;
use crate::report::data::Evaluated;
use crate::report::html::escape;

/// Eq. 19 over the pairs, both forms.
pub(crate) fn lengths(evaluated: &[Evaluated], arms: &Arms) -> String {
    let rows: Vec<(String, Vec<Cell>)> = evaluated
        .iter()
        .filter_map(|e| {
            let abs = e.ev.pair_length_abs_summary?;
            let signed = e.ev.pair_length_summary?;
            Some((
                row_class(e),
                vec![
                    Cell::text(&e.name(arms)),
                    Cell::int(abs.count),
                    Cell::num(abs.min, 4),
                    Cell::num(abs.mean, 4),
                    Cell::num(abs.max, 4),
                    Cell::num(abs.std, 4),
                    Cell::num(signed.mean, 4),
                ],
            ))
        })
        .collect();
    if rows.is_empty() {
        return "<p class=\"note\">No pairs of points: eq. 19 needs two points.</p>\n".to_string();
    }
    let sampled: Vec<String> = (evaluated.iter())
        .filter_map(|e| {
            let s = e.ev.pair_sample?;
            Some(format!("{}: {}", escape(&e.name(arms)), s.describe()))
        })
        .collect();
    let (caption, sample_note) = match sampled.is_empty() {
        true => ("Eq. 19 over all pairs of points", String::new()),
        false => (
            "Eq. 19 over a sample of the pairs of points",
            format!(
                "<p class=\"note\">Pairs sampled, each with the same probability (all of them \
                 would cost more than {} touch distances): the mean and std estimate the \
                 all-pairs figures, min and max are the sample's. {}.</p>\n",
                crate::metrics::PAIR_TOUCH_BUDGET,
                sampled.join("; ")
            ),
        ),
    };
    table(
        &format!("{caption} (paper Fig. 7: 1.038 → 0.092 mm mean)"),
        &[
            "arm, data",
            "pairs",
            "|d|_error min [mm]",
            "mean [mm]",
            "max [mm]",
            "std [mm]",
            "d_error as printed, mean [mm]",
        ],
        &rows,
    ) + "<p class=\"note\">|d|_error: eq. 19 with absolute values, our reading of the paper's \
         figures; d_error: eq. 19 as printed, of second order in the scatter. Std: population \
         (divides by the count).</p>\n"
        + &sample_note
}

/// Every reference length, before and after.
pub(crate) fn references(evaluated: &[Evaluated], arms: &Arms, json: Option<&str>) -> String {
    let mut rows: Vec<(String, Vec<Cell>)> = Vec::new();
    for e in evaluated {
        let base = json;
        for (i, r) in e.ev.reference.iter().enumerate() {
            let path = |k: &str| format!("reference/{i}/{k}");
            rows.push((
                row_class(e),
                vec![
                    Cell::text(&e.name(arms)),
                    Cell::text(&r.a),
                    Cell::text(&r.b),
                    Cell::num(r.reference, 4).at(base, &path("reference"), r.reference),
                    Cell::num(r.measured, 4).at(base, &path("measured"), r.measured),
                    Cell::num(r.error, 4).at(base, &path("error"), r.error),
                ],
            ));
        }
    }
    if rows.is_empty() {
        return "<p class=\"note\">No reference lengths: nothing here tests the arm's scale \
                (method.md §8.2).</p>\n"
            .to_string();
    }
    table(
        "Reference lengths: error = measured − reference (ISO 10360-12 E_Uni)",
        &[
            "arm, data",
            "point a",
            "point b",
            "reference L [mm]",
            "measured [mm]",
            "error [mm]",
        ],
        &rows,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tables::fixture::{self, arms, evaluated};

    #[test]
    fn eq_19_over_all_pairs_or_a_note_without_pairs() {
        let ev = evaluated();
        let t = lengths(&ev, &arms());
        assert!(
            t.contains("<caption>Eq. 19 over all pairs of points (paper Fig. 7: "),
            "{t}"
        );
        let n = ev[1].ev.points.len();
        assert_eq!(fixture::rows(&t), 3, "{t}");
        assert!(
            t.contains(&format!(
                "<tr class=\"after\"><td>calibrated, fitted</td><td class=\"n\">{}</td>",
                n * (n - 1) / 2
            )),
            "{t}"
        );
        assert!(!t.contains("Pairs sampled"), "{t}");
        let mut none = ev.clone();
        for e in &mut none {
            e.ev.pair_length_abs_summary = None;
        }
        assert_eq!(
            lengths(&none, &arms()),
            "<p class=\"note\">No pairs of points: eq. 19 needs two points.</p>\n"
        );
    }

    #[test]
    fn a_row_per_reference_length_and_arm_or_a_note_without_any() {
        let ev = evaluated();
        let t = references(&ev, &arms(), Some("/evaluation"));
        let n = ev[1].ev.reference.len();
        assert_eq!(n, 2);
        assert_eq!(fixture::rows(&t), 1 + 2 * n, "{t}");
        let r = &ev[1].ev.reference[1];
        assert!(
            t.contains(&format!(
                "<tr class=\"after\"><td>calibrated, fitted</td><td>{}</td><td>{}</td>",
                escape(&r.a),
                escape(&r.b)
            )),
            "{t}"
        );
        assert!(
            t.contains(&format!(
                "data-json=\"/evaluation/reference/1/error\" data-value=\"{:?}\"",
                r.error
            )),
            "{t}"
        );
        assert!(!references(&ev, &arms(), None).contains("data-json"));
        let mut none = ev.clone();
        for e in &mut none {
            e.ev.reference.clear();
        }
        assert!(
            references(&none, &arms(), None).starts_with("<p class=\"note\">No reference lengths")
        );
    }
}
