//! The 3-D errors section: the errors at the reference positions, and
//! the tool's orientation errors there.

use super::{Cell, table};
use crate::calibrate::validate::{Figures, PositionErrors};
use crate::report::{Arms, PoseErrors, ValidationRow};

/// The 3-D errors at the reference positions, as `calibration.json` has
/// them (per data set and arm), and per frame from `series` when a data
/// set has several frames.
pub(crate) fn positions(
    validation: &[ValidationRow],
    series: &[PoseErrors],
    arms: &Arms,
) -> String {
    let rows = error_rows(validation, series, arms, &POSITIONS);
    table(
        "3-D errors at the reference positions (mm)",
        &[
            "data, arm",
            "frame",
            "poses",
            "RMS [mm]",
            "95th percentile [mm]",
            "max [mm]",
            "mean [mm]",
        ],
        &rows,
    )
}

/// The orientation errors at the reference positions that give the tool's
/// orientation, as [`positions`] has the 3-D errors; empty when no data set
/// has orientations.
pub(crate) fn orientations(
    validation: &[ValidationRow],
    series: &[PoseErrors],
    arms: &Arms,
) -> String {
    let rows = error_rows(validation, series, arms, &ORIENTATIONS);
    if rows.is_empty() {
        return String::new();
    }
    table(
        "Tool orientation errors at the reference positions (deg): the angle of the turn \
         from where each arm puts the 6-D target to where the instrument saw it",
        &[
            "data, arm",
            "frame",
            "poses",
            "RMS [deg]",
            "95th percentile [deg]",
            "max [deg]",
            "mean [deg]",
        ],
        &rows,
    )
}

/// Which errors a table of errors at the reference positions shows.
struct ErrorKind {
    /// The figures' errors.
    figures: fn(&Figures) -> Option<PositionErrors>,
    /// The key in `calibration.json`'s figures.
    key: &'static str,
    /// Per pose of a series, its error (`None`: the pose has none).
    per_pose: fn(&PoseErrors, usize) -> Option<f64>,
}

const POSITIONS: ErrorKind = ErrorKind {
    figures: |f| f.positions,
    key: "positions",
    per_pose: |s, i| s.error_mm.get(i).copied(),
};

const ORIENTATIONS: ErrorKind = ErrorKind {
    figures: |f| f.orientations,
    key: "orientations",
    per_pose: |s, i| s.orientation_deg.get(i).copied().flatten(),
};

/// The rows of a table of errors at the reference positions: per data set
/// and arm, then per frame when the set has several.
fn error_rows(
    validation: &[ValidationRow],
    series: &[PoseErrors],
    arms: &Arms,
    kind: &ErrorKind,
) -> Vec<(String, Vec<Cell>)> {
    let mut out: Vec<(String, Vec<Cell>)> = Vec::new();
    for r in validation {
        let set = if r.name.starts_with("held out") {
            Some("held out")
        } else if r.name == "fitted" {
            Some("fitted")
        } else {
            None
        };
        for (after, f, key, arm) in [
            (false, &r.figures.before, "before", &arms.before),
            (true, &r.figures.after, "after", &arms.after),
        ] {
            let Some(p) = (kind.figures)(f) else { continue };
            let base = (r.json.as_ref()).map(|j| format!("{j}/{key}/{}", kind.key));
            let class = match (after, r.held_out) {
                (true, true) => "held after",
                (true, false) => "after",
                _ => "",
            };
            let name = format!("{}, {arm}", r.name);
            let frames = series.iter().find(|s| {
                s.after == after && set.is_some_and(|set| s.name.ends_with(&format!(", {set}")))
            });
            let several = frames.filter(|s| s.frame_names.len() > 1);
            out.push((
                class.to_string(),
                position_cells(
                    &name,
                    if several.is_some() { "all" } else { "" },
                    &p,
                    base.as_deref(),
                ),
            ));
            if let Some(s) = several {
                for (k, frame) in s.frame_names.iter().enumerate() {
                    let d: Vec<f64> = (0..s.frame.len())
                        .filter(|&i| s.frame[i] == k)
                        .filter_map(|i| (kind.per_pose)(s, i))
                        .collect();
                    let p = PositionErrors::of(&d);
                    out.push((class.to_string(), position_cells(&name, frame, &p, None)));
                }
            }
        }
    }
    out
}

/// The cells of one row of the 3-D errors.
fn position_cells(name: &str, frame: &str, p: &PositionErrors, base: Option<&str>) -> Vec<Cell> {
    vec![
        Cell::text(name),
        Cell::text(frame),
        Cell::int(p.count).at(base, "count", p.count as f64),
        Cell::num(p.rms, 4).at(base, "rms", p.rms),
        Cell::num(p.p95, 4).at(base, "p95", p.p95),
        Cell::num(p.max, 4).at(base, "max", p.max),
        Cell::num(p.mean, 4).at(base, "mean", p.mean),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::validate::BeforeAfter;
    use crate::report::tables::fixture::{self, arms, figures};

    /// A series of three poses in two frames (`laser`: the first, the
    /// other two in `station <2>`).
    fn series(after: bool, error_mm: Vec<f64>) -> PoseErrors {
        PoseErrors {
            name: format!("{}, fitted", if after { "calibrated" } else { "nominal" }),
            held_out: false,
            after,
            reach_mm: vec![0.0; 3],
            error_mm,
            frame: vec![0, 1, 1],
            frame_names: vec!["laser".into(), "station <2>".into()],
            orientation_deg: Vec::new(),
        }
    }

    #[test]
    fn a_row_per_set_and_arm_then_one_per_frame() {
        let ba = BeforeAfter {
            before: figures(0, 0.0, Some(&[3.0, 4.0, 5.0])),
            after: figures(0, 0.0, Some(&[0.1, 0.2, 0.3])),
        };
        let rows = [ValidationRow {
            name: "fitted".into(),
            held_out: false,
            figures: &ba,
            json: Some("/validation/fitted".into()),
        }];
        let s = [
            series(false, vec![3.0, 4.0, 5.0]),
            series(true, vec![0.1, 0.2, 0.3]),
        ];
        let t = positions(&rows, &s, &arms());
        // The header, then per arm: all frames, and each frame.
        assert_eq!(fixture::rows(&t), 7, "{t}");
        assert!(
            t.contains(
                "<tr><td>fitted, nominal</td><td>all</td><td class=\"n\" \
                 data-json=\"/validation/fitted/before/positions/count\" data-value=\"3.0\">3</td>"
            ),
            "{t}"
        );
        assert!(
            t.contains(
                "<tr class=\"after\"><td>fitted, calibrated</td><td>laser</td><td class=\"n\">1</td>\
                 <td class=\"n\">0.1000</td>"
            ),
            "{t}"
        );
        assert!(
            t.contains(
                "<tr class=\"after\"><td>fitted, calibrated</td><td>station &lt;2&gt;</td>\
                 <td class=\"n\">2</td>"
            ),
            "{t}"
        );
        // No set has orientations: no table.
        assert_eq!(orientations(&rows, &s, &arms()), "");

        // One frame: no per-frame rows, no `all`.
        let one: Vec<PoseErrors> = (s.iter().cloned())
            .map(|mut p| {
                p.frame = vec![0; 3];
                p.frame_names.truncate(1);
                p
            })
            .collect();
        let t = positions(&rows, &one, &arms());
        assert_eq!(fixture::rows(&t), 3, "{t}");
        assert!(t.contains("<td>fitted, nominal</td><td></td>"), "{t}");
    }

    #[test]
    fn orientations_point_at_their_own_figures() {
        let mut ba = BeforeAfter {
            before: figures(0, 0.0, Some(&[3.0])),
            after: figures(0, 0.0, Some(&[0.1])),
        };
        ba.before.orientations = Some(PositionErrors::of(&[1.0]));
        ba.after.orientations = Some(PositionErrors::of(&[0.5]));
        let rows = [ValidationRow {
            name: "held out (v.csv)".into(),
            held_out: true,
            figures: &ba,
            json: Some("/validation/held_out".into()),
        }];
        let t = orientations(&rows, &[], &arms());
        assert!(t.contains("<th>RMS [deg]</th>"), "{t}");
        assert_eq!(fixture::rows(&t), 3, "{t}");
        assert!(
            t.contains(
                "<tr class=\"held after\"><td>held out (v.csv), calibrated</td><td></td>\
                 <td class=\"n\" data-json=\"/validation/held_out/after/orientations/count\""
            ),
            "{t}"
        );
        assert!(
            t.contains(
                "data-json=\"/validation/held_out/after/orientations/rms\" \
                 data-value=\"0.5\">0.5000</td>"
            ),
            "{t}"
        );
    }
}
