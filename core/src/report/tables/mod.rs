//! The tables beside the figures. A number that is also in the JSON
//! written beside the report carries `data-json` (its JSON Pointer) and
//! `data-value` (the number in full), so that the two can be checked
//! against each other.
//!
//! One file per section of the report; this one holds the cell and the
//! table they are all made of.

mod beyond;
#[cfg(test)]
mod fixture;
mod identification;
mod lengths;
mod map;
mod parameters;
mod positions;
mod solver;
mod summary;
mod touches;

pub(crate) use beyond::beyond;
pub(crate) use identification::identification;
pub(crate) use lengths::{lengths, references};
pub(crate) use map::uncertainty_map;
pub(crate) use parameters::{parameters, parameters_intro};
pub(crate) use positions::{orientations, positions};
pub(crate) use solver::solver;
pub(crate) use summary::{glance, verdict};
pub(crate) use touches::{points, points_summary, residuals, validation};

use super::data::{Evaluated, Stage};
use super::html::escape;
use crate::calibrate::Calibration;

/// One cell.
struct Cell {
    text: String,
    /// JSON Pointer and full value, when the number is in the JSON.
    json: Option<(String, String)>,
    numeric: bool,
}

impl Cell {
    /// A missing number.
    fn none() -> Cell {
        Cell {
            text: "-".to_string(),
            json: None,
            numeric: true,
        }
    }

    /// A text cell.
    fn text(s: &str) -> Cell {
        Cell {
            text: escape(s),
            json: None,
            numeric: false,
        }
    }

    /// Markup as is (already escaped).
    fn markup(s: String) -> Cell {
        Cell {
            text: s,
            json: None,
            numeric: false,
        }
    }

    /// A number with `decimals` decimals; `-` when not finite.
    fn num(v: f64, decimals: usize) -> Cell {
        Cell {
            text: if v.is_finite() {
                super::svg::number(v, decimals)
            } else {
                "-".to_string()
            },
            json: None,
            numeric: true,
        }
    }

    /// A number in scientific notation with `digits` after the point.
    fn sci(v: f64, digits: usize) -> Cell {
        Cell {
            text: if v.is_finite() {
                format!("{v:.digits$e}")
            } else {
                "-".to_string()
            },
            json: None,
            numeric: true,
        }
    }

    /// An integer.
    fn int(v: usize) -> Cell {
        Cell {
            text: v.to_string(),
            json: None,
            numeric: true,
        }
    }

    /// Marks the cell as `pointer` in the JSON (`base` + `path`), holding
    /// `value`; nothing when there is no JSON.
    fn at(mut self, base: Option<&str>, path: &str, value: f64) -> Cell {
        if let Some(b) = base {
            self.json = Some((format!("{b}/{path}"), format!("{value:?}")));
        }
        self
    }

    fn html(&self) -> String {
        let class = if self.numeric { " class=\"n\"" } else { "" };
        match &self.json {
            Some((p, v)) => format!(
                "<td{class} data-json=\"{}\" data-value=\"{}\">{}</td>",
                escape(p),
                escape(v),
                self.text
            ),
            None => format!("<td{class}>{}</td>", self.text),
        }
    }
}

/// A table: caption, header, rows (with a row class).
fn table(caption: &str, head: &[&str], rows: &[(String, Vec<Cell>)]) -> String {
    let mut t = format!("<table>\n<caption>{}</caption>\n<tr>", escape(caption));
    for h in head {
        t += &format!("<th>{}</th>", escape(h));
    }
    t += "</tr>\n";
    for (class, cells) in rows {
        if class.is_empty() {
            t += "<tr>";
        } else {
            t += &format!("<tr class=\"{class}\">");
        }
        for c in cells {
            t += &c.html();
        }
        t += "</tr>\n";
    }
    t += "</table>\n";
    t
}

/// The row class of a series: `after`, `held after`, or none.
fn row_class(e: &Evaluated) -> String {
    match (e.stage, e.held_out) {
        (Stage::Before, _) => String::new(),
        (Stage::After, false) => "after".to_string(),
        (Stage::After, true) => "held after".to_string(),
    }
}

/// What the σ behind the weights is of: a `touch` (with touches), a
/// `sphere point` (points on spheres without reference positions), else a
/// `position`.
fn evidence_noun(cal: &Calibration, touches: bool) -> &'static str {
    let d = &cal.dof;
    match (
        touches,
        d.rows_of("spheres") > 0 && d.rows_of("positions") == 0,
    ) {
        (true, _) => "touch",
        (false, true) => "sphere point",
        (false, false) => "position",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cell_escapes_its_text_and_carries_its_json_pointer() {
        assert_eq!(Cell::text("a<b & c").html(), "<td>a&lt;b &amp; c</td>");
        assert_eq!(Cell::markup("<b>x</b>".into()).html(), "<td><b>x</b></td>");
        assert_eq!(Cell::none().html(), "<td class=\"n\">-</td>");
        assert_eq!(
            Cell::num(1.23456, 2).at(Some("/c"), "x", 1.23456).html(),
            "<td class=\"n\" data-json=\"/c/x\" data-value=\"1.23456\">1.23</td>"
        );
        // Without a JSON beside the report, no pointer.
        assert_eq!(
            Cell::int(7).at(None, "x", 7.0).html(),
            "<td class=\"n\">7</td>"
        );
        assert_eq!(Cell::num(f64::NAN, 2).text, "-");
        assert_eq!(Cell::sci(f64::INFINITY, 2).text, "-");
        assert_eq!(Cell::sci(1234.5, 2).text, "1.23e3");
    }

    #[test]
    fn a_table_escapes_caption_and_header_and_classes_its_rows() {
        let rows = vec![
            (String::new(), vec![Cell::text("a"), Cell::int(1)]),
            ("after".to_string(), vec![Cell::text("b"), Cell::int(2)]),
        ];
        assert_eq!(
            table("x < y", &["name", "n [\"]"], &rows),
            "<table>\n<caption>x &lt; y</caption>\n<tr><th>name</th><th>n [&quot;]</th></tr>\n\
             <tr><td>a</td><td class=\"n\">1</td></tr>\n\
             <tr class=\"after\"><td>b</td><td class=\"n\">2</td></tr>\n</table>\n"
        );
    }

    #[test]
    fn the_evidence_is_named_by_what_the_fit_had() {
        let mut cal = fixture::case().cal.clone();
        assert_eq!(evidence_noun(&cal, true), "touch");
        assert_eq!(evidence_noun(&cal, false), "position");
        cal.dof.other_rows.push(crate::calibrate::TermRows {
            term: "spheres".into(),
            rows: 12,
            eliminated: 0,
        });
        assert_eq!(evidence_noun(&cal, false), "sphere point");
    }

    #[test]
    fn a_series_row_is_classed_by_its_arm_and_data() {
        let mut e = fixture::evaluated();
        assert_eq!(row_class(&e[0]), "");
        assert_eq!(row_class(&e[1]), "after");
        e[1].held_out = true;
        assert_eq!(row_class(&e[1]), "held after");
    }
}
