//! The tables beside the figures. A number that is also in the JSON
//! written beside the report carries `data-json` (its JSON Pointer) and
//! `data-value` (the number in full), so that the two can be checked
//! against each other.

use super::data::{Evaluated, Stage, deltas, median};
use super::html::escape;
use super::{Arms, PoseErrors, ValidationRow};
use crate::calibrate::validate::{Figures, PositionErrors};
use crate::calibrate::{Calibration, EstimateRecord, PriorReport};
use crate::plan::UncertaintyMap;

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

/// The uncertainty map's bands of distance from the shoulder (from, to,
/// poses, RMS and largest 95 % radius), then every pose together (with the
/// median); `json` is the map's pointer.
pub(crate) fn uncertainty_map(map: &UncertaintyMap, json: Option<&str>) -> String {
    let mut rows: Vec<(String, Vec<Cell>)> = (map.regions.iter().enumerate())
        .map(|(i, r)| {
            let at = |field: &str| format!("regions/{i}/{field}");
            let cells = vec![
                Cell::num(r.reach_from_mm, 0).at(json, &at("reach_from_mm"), r.reach_from_mm),
                Cell::num(r.reach_to_mm, 0).at(json, &at("reach_to_mm"), r.reach_to_mm),
                Cell::int(r.poses).at(json, &at("poses"), r.poses as f64),
                Cell::num(r.rms_mm, 4).at(json, &at("rms_mm"), r.rms_mm),
                Cell::none(),
                Cell::num(r.max_mm, 4).at(json, &at("max_mm"), r.max_mm),
            ];
            (String::new(), cells)
        })
        .collect();
    rows.push((
        "after".to_string(),
        vec![
            Cell::text("all poses"),
            Cell::text(""),
            Cell::int(map.poses).at(json, "poses", map.poses as f64),
            Cell::num(map.rms_mm, 4).at(json, "rms_mm", map.rms_mm),
            Cell::num(map.median_mm, 4).at(json, "median_mm", map.median_mm),
            Cell::num(map.max_mm, 4).at(json, "max_mm", map.max_mm),
        ],
    ));
    let head = [
        "from [mm]",
        "to [mm]",
        "poses",
        "RMS [mm]",
        "median [mm]",
        "max [mm]",
    ];
    let mut caption = format!(
        "{:.0} % radius per band of distance from the shoulder",
        100.0 * map.coverage
    );
    if let Some(name) = &map.frame {
        caption += &format!(", in frame `{name}`, its registration included");
    }
    table(&caption, &head, &rows)
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

/// The residual lengths per series.
pub(crate) fn residuals(evaluated: &[Evaluated], arms: &Arms) -> String {
    let rows: Vec<(String, Vec<Cell>)> = evaluated
        .iter()
        .map(|e| {
            let d = deltas(e);
            let rms = (d.iter().map(|v| v * v).sum::<f64>() / d.len().max(1) as f64).sqrt();
            let max = d.iter().copied().fold(0.0, f64::max);
            let touches = d.len();
            (
                row_class(e),
                vec![
                    Cell::text(&e.name(arms)),
                    Cell::int(touches),
                    Cell::num(median(d).unwrap_or(f64::NAN), 4),
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

/// The solver summary.
pub(crate) fn solver(cal: &Calibration, json: Option<&str>) -> String {
    let sb = json.map(|j| format!("{j}/solver"));
    let db = json.map(|j| format!("{j}/dof"));
    let mut rows = solver_rows(cal, sb.as_deref());
    rows.extend(dof_rows(cal, db.as_deref()));
    rows.extend(phase_rows(cal));
    rows.extend(anneal_rows(cal, sb.as_deref()));
    rows.extend(global_rows(cal));
    table("Solver", &["figure", "value"], &rows)
}

/// A row of the solver table: a figure's name and its value.
fn figure_row(name: &str, c: Cell) -> (String, Vec<Cell>) {
    (String::new(), vec![Cell::text(name), c])
}

/// How the solver stopped and what it evaluated (`sb`: the solver's JSON
/// Pointer).
fn solver_rows(cal: &Calibration, sb: Option<&str>) -> Vec<(String, Vec<Cell>)> {
    let s = &cal.solver;
    vec![
        figure_row("method", Cell::text(s.method.name())),
        figure_row("stopped", Cell::text(&s.stop.describe())),
        figure_row(
            "converged",
            Cell::text(if s.successful { "yes" } else { "no" }),
        ),
        figure_row(
            "iterations of the final LM",
            Cell::int(s.iterations).at(sb, "iterations", s.iterations as f64),
        ),
        figure_row(
            "cost evaluations (positions only)",
            Cell::int(s.cost_evaluations).at(sb, "cost_evaluations", s.cost_evaluations as f64),
        ),
        figure_row(
            "Jacobian evaluations",
            Cell::int(s.jacobian_evaluations).at(
                sb,
                "jacobian_evaluations",
                s.jacobian_evaluations as f64,
            ),
        ),
        figure_row(
            "cost Σr² of the start arm (final weights)",
            Cell::sci(s.initial_cost, 6).at(sb, "initial_cost", s.initial_cost),
        ),
        figure_row(
            "cost Σr² at the end",
            Cell::sci(s.final_cost, 6).at(sb, "final_cost", s.final_cost),
        ),
    ]
}

/// The residual rows, the unknowns and the σ behind the weights (`db`:
/// the dof's JSON Pointer).
fn dof_rows(cal: &Calibration, db: Option<&str>) -> Vec<(String, Vec<Cell>)> {
    let d = &cal.dof;
    let others: Vec<String> = (d.other_rows.iter())
        .map(|r| format!("{} {}", r.term, r.rows))
        .collect();
    // A row per kind of evidence present: the touch rows only with touches.
    let touches = d.touch_rows > 0 || d.length_rows > 0;
    let mut rows = if touches {
        vec![
            figure_row(
                "residual rows: touches (3 each) + lengths",
                Cell::text(&format!("{} + {}", d.touch_rows, d.length_rows)),
            ),
            figure_row(
                "unknowns: free parameters + centre coordinates",
                Cell::text(&format!("{} + {}", d.free_parameters, d.centre_coordinates)),
            ),
        ]
    } else {
        vec![
            figure_row("residual rows", Cell::text(&others.join(", "))),
            figure_row(
                "unknowns: free parameters (the frames' included)",
                Cell::int(d.free_parameters),
            ),
        ]
    };
    if touches && !others.is_empty() {
        rows.insert(
            1,
            figure_row("other residual rows", Cell::text(&others.join(", "))),
        );
    }
    rows.extend([
        figure_row(
            "degrees of freedom m − p",
            Cell::int(d.degrees_of_freedom).at(
                db,
                "degrees_of_freedom",
                d.degrees_of_freedom as f64,
            ),
        ),
        figure_row(
            "σ̂0 = sqrt(cost / (m − p))",
            Cell::num(d.sigma0, 4).at(db, "sigma0", d.sigma0),
        ),
        figure_row(
            &format!("{} σ behind the weights [mm]", evidence_noun(cal, touches)),
            Cell::num(d.touch_sigma_mm, 4).at(db, "touch_sigma_mm", d.touch_sigma_mm),
        ),
    ]);
    rows
}

/// The evaluations of each phase.
fn phase_rows(cal: &Calibration) -> Vec<(String, Vec<Cell>)> {
    cal.solver
        .phases
        .iter()
        .map(|p| {
            figure_row(
                &format!("phase {}", p.name),
                Cell::text(&format!(
                    "{} cost, {} Jacobian evaluations",
                    p.cost_evaluations, p.jacobian_evaluations
                )),
            )
        })
        .collect()
}

/// The annealing's settings and result, if it ran (`sb`: the solver's
/// JSON Pointer).
fn anneal_rows(cal: &Calibration, sb: Option<&str>) -> Vec<(String, Vec<Cell>)> {
    let Some(a) = &cal.solver.anneal else {
        return Vec::new();
    };
    let ab = sb.map(|b| format!("{b}/anneal"));
    let ab = ab.as_deref();
    let o = &a.options;
    vec![
        figure_row(
            "annealing settings",
            Cell::text(&format!(
                "T0 {} mm, cooling {}, chain {}, T_min {} mm, target {} mm",
                o.t0, o.cooling, o.chain, o.t_min, o.target
            )),
        ),
        figure_row(
            "annealing energy at the start [mm]",
            Cell::num(a.start_energy, 4).at(ab, "start_energy", a.start_energy),
        ),
        figure_row(
            "annealing best energy [mm]",
            Cell::num(a.best_energy, 4).at(ab, "best_energy", a.best_energy),
        ),
        figure_row(
            "annealing evaluations",
            Cell::int(a.evaluations).at(ab, "evaluations", a.evaluations as f64),
        ),
        figure_row("annealing stopped", Cell::text(a.stop.describe())),
    ]
}

/// The global search's starts and stop, if it ran.
fn global_rows(cal: &Calibration) -> Vec<(String, Vec<Cell>)> {
    let Some(g) = &cal.solver.global else {
        return Vec::new();
    };
    let mut rows = vec![
        figure_row(
            "global: starts, lowest reached",
            Cell::text(&format!("{}, {} times", g.minima.len(), g.best_hits)),
        ),
        figure_row("global stopped", Cell::text(g.stop.describe())),
    ];
    if !g.sign_changes.is_empty() {
        rows.push(figure_row(
            "signs put in the nominal convention",
            Cell::text(&g.sign_changes.join(", ")),
        ));
    }
    rows
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
