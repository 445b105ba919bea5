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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::{Relation, Rule};
    use crate::report::tables::fixture;

    #[test]
    fn the_figures_then_what_the_data_cannot_see_or_the_users_choice() {
        let mut cal = fixture::case().cal.clone();
        let id = cal.identification.as_mut().expect("an automatic fixed set");
        id.rules = vec![Rule {
            name: "base <z>".into(),
            explanation: "θ1 & d1".into(),
        }];
        id.null_relations = vec![Relation {
            singular_value: 1e-9,
            terms: Vec::new(),
            text: "∂p/∂Bx = +1.0000 ∂p/∂a6".into(),
        }];
        let rank = id.rank;
        let t = identification(&cal, Some("/calibration"));
        assert!(
            t.contains(&format!(
                "<tr><td>rank (identifiable combinations)</td><td class=\"n\" \
                 data-json=\"/calibration/identification/rank\" data-value=\"{:?}\">{rank}</td>",
                rank as f64
            )),
            "{t}"
        );
        assert!(
            t.contains("<caption>What the data cannot see</caption>"),
            "{t}"
        );
        assert!(t.contains("<tr><td>base &lt;z&gt;</td><td>θ1 &amp; d1</td></tr>"));
        assert!(t.contains("<tr><td>redundant (s = 1.0e-9)</td><td>∂p/∂Bx = +1.0000 ∂p/∂a6</td>"));
        let id = cal.identification.as_mut().unwrap();
        id.rules.clear();
        id.null_relations.clear();
        let t = identification(&cal, None);
        assert_eq!(t.matches("<table>").count(), 1, "{t}");
        assert_eq!(fixture::rows(&t), 5, "{t}");
        cal.identification = None;
        assert!(
            identification(&cal, None)
                .starts_with("<p class=\"note\">The fixed set was given by the user")
        );
    }
}
