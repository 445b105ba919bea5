//! The identifiability section: the rank, threshold and condition, and
//! what the data cannot see.

use super::{Cell, table};
use crate::calibrate::Calibration;

/// The identifiability analysis in numbers.
pub(crate) fn identification(cal: &Calibration, json: Option<&str>) -> String {
    let Some(id) = &cal.identification else {
        return "<p class=\"note\">The fixed set was given by the user: no identifiability \
                analysis ran (aacmm identify gives it). Every free direction was checked to be \
                seen by the data.</p>\n"
            .to_string();
    };
    let base = json.map(|j| format!("{j}/identification"));
    let base = base.as_deref();
    let rows = vec![
        (
            String::new(),
            vec![
                Cell::text("rank (identifiable combinations)"),
                Cell::int(id.rank).at(base, "rank", id.rank as f64),
            ],
        ),
        (
            String::new(),
            vec![
                Cell::text("rank threshold (scaled)"),
                Cell::sci(id.threshold, 3).at(base, "threshold", id.threshold),
            ],
        ),
        (
            String::new(),
            vec![
                Cell::text("condition number of the identifiable part"),
                Cell::num(id.condition_number, 1).at(base, "condition_number", id.condition_number),
            ],
        ),
        (
            String::new(),
            vec![
                Cell::text("reach R dividing angle columns [mm]"),
                Cell::num(id.reach_mm, 1).at(base, "reach_mm", id.reach_mm),
            ],
        ),
    ];
    let mut out = table("Identifiability", &["figure", "value"], &rows);
    let rules: Vec<(String, Vec<Cell>)> = id
        .rules
        .iter()
        .map(|r| {
            (
                String::new(),
                vec![Cell::text(&r.name), Cell::text(&r.explanation)],
            )
        })
        .chain(id.null_relations.iter().map(|r| {
            (
                String::new(),
                vec![
                    Cell::text(&format!("redundant (s = {:.1e})", r.singular_value)),
                    Cell::text(&r.text),
                ],
            )
        }))
        .collect();
    if !rules.is_empty() {
        out += &table(
            "What the data cannot see",
            &["rule or direction", "explanation"],
            &rules,
        );
    }
    out
}
