//! The section on the models beyond geometry: one table of correction
//! columns per model.

use super::{Cell, table};
use crate::calibrate::Calibration;

/// The correction columns beyond geometry, one table per model: start,
/// calibrated, σ, and why a column was held; empty without any.
pub(crate) fn beyond(cal: &Calibration, json: Option<&str>) -> String {
    let models = [
        ("compliance", "Joint compliance under gravity"),
        ("harmonic", "Encoder harmonics a·sin(kq) + b·cos(kq)"),
        (
            "backlash",
            "Backlash: half-play b on the flank the gravity torque presses, q + b·sgn τ",
        ),
        ("thermal", "Thermal expansion of the lengths (from 20 °C)"),
        ("drift", "Drift of the base against the instrument"),
    ];
    let mut out = String::new();
    for (prefix, caption) in models {
        let rows: Vec<(String, Vec<Cell>)> = (cal.auxiliary.iter().enumerate())
            .filter(|(_, a)| a.name.starts_with(prefix))
            .map(|(i, a)| {
                let cells = vec![
                    Cell::text(&a.name),
                    Cell::text(&a.unit),
                    Cell::num(a.start, 6),
                    Cell::num(a.calibrated, 6).at(
                        json,
                        &format!("auxiliary/{i}/calibrated"),
                        a.calibrated,
                    ),
                    a.sigma.map_or_else(Cell::none, |s| {
                        Cell::num(s, 6).at(json, &format!("auxiliary/{i}/sigma"), s)
                    }),
                    Cell::text(a.fixed.as_deref().unwrap_or("")),
                ];
                (String::new(), cells)
            })
            .collect();
        if !rows.is_empty() {
            let head = ["column", "unit", "start", "calibrated", "σ", "held because"];
            out += &table(caption, &head, &rows);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::AuxiliaryEstimate;
    use crate::report::tables::fixture;

    fn column(name: &str, sigma: Option<f64>, fixed: Option<&str>) -> AuxiliaryEstimate {
        AuxiliaryEstimate {
            name: name.into(),
            unit: "deg".into(),
            start: 0.0,
            calibrated: 0.5,
            sigma,
            sigma_of: None,
            fixed: fixed.map(Into::into),
        }
    }

    #[test]
    fn a_table_per_model_with_columns_and_nothing_without() {
        let mut cal = fixture::case().cal.clone();
        cal.auxiliary.clear();
        assert_eq!(beyond(&cal, Some("/calibration")), "");
        cal.auxiliary = vec![
            column("frame_x", Some(0.1), None),
            column("harmonic_3_sin", None, Some("not seen <here>")),
            column("compliance_2", Some(0.01), None),
        ];
        let t = beyond(&cal, Some("/calibration"));
        assert_eq!(t.matches("<table>").count(), 2, "{t}");
        // In the models' order, not the columns'.
        assert!(
            t.find("Joint compliance under gravity").unwrap()
                < t.find("Encoder harmonics").unwrap(),
            "{t}"
        );
        assert!(
            t.contains("data-json=\"/calibration/auxiliary/2/calibrated\""),
            "{t}"
        );
        assert!(
            t.contains("data-json=\"/calibration/auxiliary/2/sigma\""),
            "{t}"
        );
        assert!(!t.contains("auxiliary/1/sigma"), "{t}");
        assert!(
            t.contains("<td class=\"n\">-</td><td>not seen &lt;here&gt;</td></tr>"),
            "{t}"
        );
        assert!(!t.contains("frame_x"), "{t}");
    }
}
