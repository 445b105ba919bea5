//! The parameters section: a sentence on what was fitted, the tables of
//! lengths and angles, the strong correlations and the weak directions
//! held at nominal.

use super::{Cell, table};
use crate::calibrate::{Calibration, EstimateRecord, PriorReport};
use crate::report::html::escape;

/// A sentence on what was fixed and why.
pub(crate) fn parameters_intro(cal: &Calibration) -> String {
    let free = cal.parameters.iter().filter(|p| p.fixed.is_none()).count();
    format!(
        "{free} of {} parameters were fitted; {} were held at their nominal values (the reasons \
         are in the tables).",
        cal.parameters.len(),
        cal.parameters.len() - free
    )
}
/// The parameter tables: lengths (mm) and angles (deg).
pub(crate) fn parameters(
    cal: &Calibration,
    json: Option<&str>,
    truths: &[(String, Option<f64>)],
) -> String {
    let has_truth = truths.iter().any(|(_, t)| t.is_some());
    let mut out = String::new();
    for (unit, caption) in [
        ("mm", "Lengths a, d and the probe B"),
        ("deg", "Angles: twists alpha, zero offsets theta"),
    ] {
        let head = parameter_head(unit, has_truth, cal.prior.is_some());
        let rows: Vec<(String, Vec<Cell>)> = cal
            .parameters
            .iter()
            .map(|p| p.user())
            .enumerate()
            .filter(|(_, p)| p.unit == unit)
            .map(|(i, p)| {
                let truth = has_truth.then(|| truths.get(i).and_then(|t| t.1));
                (String::new(), parameter_row(cal, json, i, &p, truth))
            })
            .collect();
        let head: Vec<&str> = head.iter().map(String::as_str).collect();
        out += &table(caption, &head, &rows);
    }
    out += &correlations_note(cal);
    out += &held_note(cal);
    out
}

/// The weak directions held at nominal (none: nothing), with the σ the
/// data alone would give each and the remedy.
fn held_note(cal: &Calibration) -> String {
    if cal.held.is_empty() {
        return String::new();
    }
    let list: Vec<String> = cal.held.iter().map(|h| escape(&h.describe())).collect();
    format!(
        "<p class=\"note\">Held at nominal (<code>/calibration/held</code>): {} direction(s) of \
         the free parameters that the data determine more than {:.0} times worse than the best \
         one; fitted, they would follow noise and model error. State tolerances for their \
         parameters to fit them: {}.</p>\n",
        cal.held.len(),
        1.0 / crate::residuals::WEAK_RATIO,
        list.join("; ")
    )
}

/// The header of a parameter table in `unit`: the true-error columns when
/// a truth is known, the prior's when the fit had one.
fn parameter_head(unit: &str, has_truth: bool, has_prior: bool) -> Vec<String> {
    let mut head = vec![
        "parameter".to_string(),
        format!("nominal [{unit}]"),
        format!("calibrated [{unit}]"),
        format!("correction [{unit}]"),
        format!("σ [{unit}]"),
        format!("2σ [{unit}]"),
    ];
    if has_truth {
        head.push(format!("true error [{unit}]"));
        head.push("(correction − true)/σ".to_string());
    }
    if has_prior {
        head.push(format!("tolerance [{unit}]"));
        head.push("data share".to_string());
    }
    head.push("fixed because".to_string());
    head
}

/// The cells of parameter `i` (`p`, in user units), as [`parameter_head`]
/// heads them: `truth` is `Some` when the table has the true-error columns
/// (holding this parameter's true error, if known).
fn parameter_row(
    cal: &Calibration,
    json: Option<&str>,
    i: usize,
    p: &EstimateRecord,
    truth: Option<Option<f64>>,
) -> Vec<Cell> {
    let path = |k: &str| format!("parameters/{i}/{k}");
    let mut cells = vec![
        Cell::text(&p.name),
        Cell::num(p.nominal, 6).at(json, &path("nominal"), p.nominal),
        Cell::num(p.calibrated, 6).at(json, &path("calibrated"), p.calibrated),
        Cell::num(p.correction, 6).at(json, &path("correction"), p.correction),
    ];
    match p.sigma {
        Some(s) => {
            cells.push(Cell::num(s, 6).at(json, &path("sigma"), s));
            cells.push(Cell::num(2.0 * s, 6));
        }
        None => {
            cells.push(Cell::none());
            cells.push(Cell::none());
        }
    }
    if let Some(t) = truth {
        cells.push(t.map_or(Cell::none(), |t| Cell::num(t, 6)));
        let z = match (t, p.sigma) {
            (Some(t), Some(s)) if s > 0.0 => (p.correction - t) / s,
            _ => f64::NAN,
        };
        cells.push(Cell::num(z, 2));
    }
    if let Some(prior) = &cal.prior {
        cells.extend(prior_cells(prior, json, &p.name));
    }
    cells.push(Cell::markup(format!(
        "<span class=\"note\">{}</span>",
        escape(p.fixed.as_deref().unwrap_or(""))
    )));
    cells
}

/// The prior's cells of the parameter named `name`: its tolerance and the
/// data's share of the information (1 − posterior/prior variance), for the
/// free ones; two missing numbers for the others.
fn prior_cells(prior: &PriorReport, json: Option<&str>, name: &str) -> [Cell; 2] {
    match prior.parameters.iter().position(|e| e.name == name) {
        Some(k) => {
            let e = &prior.parameters[k];
            let at = |f: &str| format!("prior/parameters/{k}/{f}");
            [
                Cell::num(e.tolerance, 6).at(json, &at("tolerance"), e.tolerance),
                Cell::num(e.data_share, 3).at(json, &at("data_share"), e.data_share),
            ]
        }
        None => [Cell::none(), Cell::none()],
    }
}

/// The pairs of free parameters that correlate strongly, or that none do.
fn correlations_note(cal: &Calibration) -> String {
    if cal.correlations.is_empty() {
        "<p class=\"note\">No pair of free parameters correlates with |ρ| &gt; 0.9.</p>\n"
            .to_string()
    } else {
        let list: Vec<String> = cal
            .correlations
            .iter()
            .map(|c| format!("{}/{} {:+.3}", c.a, c.b, c.rho))
            .collect();
        format!(
            "<p class=\"note\">Correlations |ρ| &gt; 0.9: {}.</p>\n",
            escape(&list.join(", "))
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::Correlation;
    use crate::report::tables::fixture;

    #[test]
    fn a_row_per_parameter_in_its_units_table() {
        let cal = &fixture::case().cal;
        let t = parameters(cal, Some("/calibration"), &[]);
        assert_eq!(t.matches("<table>").count(), 2, "{t}");
        assert!(t.contains("<caption>Lengths a, d and the probe B</caption>"));
        assert!(t.contains("<caption>Angles: twists alpha, zero offsets theta</caption>"));
        assert_eq!(fixture::rows(&t), 2 + cal.parameters.len(), "{t}");
        // No truth, no prior: no columns of theirs.
        assert!(!t.contains("true error") && !t.contains("tolerance"), "{t}");
        let user: Vec<EstimateRecord> = cal.parameters.iter().map(|p| p.user()).collect();
        let (i, free) = (user.iter().enumerate())
            .find(|(_, p)| p.sigma.is_some())
            .unwrap();
        assert!(
            t.contains(&format!(
                "<tr><td>{}</td><td class=\"n\" data-json=\"/calibration/parameters/{i}/nominal\"",
                free.name
            )),
            "{t}"
        );
        assert!(
            t.contains(&format!(
                "data-json=\"/calibration/parameters/{i}/sigma\" data-value=\"{:?}\"",
                free.sigma.unwrap()
            )),
            "{t}"
        );
        let fixed = user.iter().find(|p| p.fixed.is_some()).unwrap();
        assert!(t.contains(&format!(
            "<span class=\"note\">{}</span>",
            escape(fixed.fixed.as_deref().unwrap())
        )));
        let n = user.len();
        let held = user.iter().filter(|p| p.fixed.is_some()).count();
        assert!(parameters_intro(cal).starts_with(&format!(
            "{} of {n} parameters were fitted; {held} were held",
            n - held
        )));
    }

    #[test]
    fn known_true_errors_add_their_columns() {
        let cal = &fixture::case().cal;
        // The truth is the correction itself: every free z is 0.
        let truths: Vec<(String, Option<f64>)> = (cal.parameters.iter())
            .map(|p| (String::new(), Some(p.user().correction)))
            .collect();
        let t = parameters(cal, None, &truths);
        assert!(
            t.contains("<th>true error [mm]</th><th>(correction − true)/σ</th>"),
            "{t}"
        );
        let free = cal.parameters.iter().filter(|p| p.sigma.is_some()).count();
        assert_eq!(t.matches("<td class=\"n\">0.00</td>").count(), free, "{t}");
        assert!(!t.contains("data-json"), "{t}");
    }

    #[test]
    fn the_header_has_truth_and_prior_columns_only_when_there_are_some() {
        assert_eq!(parameter_head("deg", false, false).len(), 7);
        let h = parameter_head("mm", true, true);
        assert_eq!(
            h[6..],
            [
                "true error [mm]",
                "(correction − true)/σ",
                "tolerance [mm]",
                "data share",
                "fixed because"
            ]
        );
    }

    #[test]
    fn strong_correlations_are_listed_and_none_is_said() {
        let mut cal = fixture::case().cal.clone();
        cal.correlations = vec![Correlation {
            a: "a1".into(),
            b: "d<2".into(),
            rho: -0.95,
        }];
        assert_eq!(
            correlations_note(&cal),
            "<p class=\"note\">Correlations |ρ| &gt; 0.9: a1/d&lt;2 -0.950.</p>\n"
        );
        cal.correlations.clear();
        assert!(correlations_note(&cal).contains("No pair of free parameters"));
        cal.held.clear();
        assert_eq!(held_note(&cal), "");
    }
}
