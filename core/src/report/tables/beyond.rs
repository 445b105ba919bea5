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
