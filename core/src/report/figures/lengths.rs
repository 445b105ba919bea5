//! Figure 2: length errors (the paper's Fig. 7). Top: eq. 19 with absolute
//! values, `|d|_error`, per pair of points against the distance of their
//! centroids. Bottom: errors against the reference lengths (ISO 10360-12
//! `E_Uni`), the only figure that tests scale — one panel per arm, since
//! before and after differ by orders of magnitude.

use super::{frame, header_height, short};
use crate::report::data::{Evaluated, Pairs, Stage};
use crate::report::svg::{
    Area, Axis, Class, GREY, Key, Marker, Shape, WIDTH, chart, dashed_across, group, message,
    render,
};
use crate::report::{Arms, Figure, LENGTHS_SVG, ReportError};

/// The figure's title.
pub(crate) const TITLE: &str =
    "Length errors (paper Fig. 7): eq. 19 per pair of points, and against reference lengths";

/// Height of each row of panels, px.
const ROW: u32 = 380;

/// Draws figure 2.
pub(crate) fn figure(evaluated: &[Evaluated], arms: &Arms) -> Result<Figure, ReportError> {
    let series: Vec<(usize, Pairs)> = evaluated
        .iter()
        .enumerate()
        .filter(|(_, e)| e.ev.points.len() > 1)
        .map(|(i, e)| (i, e.pairs.clone()))
        .collect();
    let mut entries: Vec<(Key, String)> = Vec::new();
    for (i, p) in &series {
        let e = &evaluated[*i];
        let mean = e.ev.pair_length_abs_summary.map_or(f64::NAN, |s| s.mean);
        let mut label = format!("{}: mean |d| {} mm", e.name(arms), short(mean));
        match (e.ev.pair_sample, p) {
            (Some(s), Pairs::Binned { .. }) => {
                label += &format!(" ({}; mean per distance bin)", s.describe());
            }
            (Some(s), Pairs::Each(_)) => label += &format!(" ({})", s.describe()),
            (None, Pairs::Binned { count, .. }) => {
                label += &format!(" ({count} pairs, mean per distance bin)");
            }
            (None, Pairs::Each(_)) => {}
        }
        entries.push((Key::Marker(e.marker()), label));
    }
    for e in evaluated.iter().filter(|e| !e.ev.reference.is_empty()) {
        if let Some(r) = e.ev.reference_summary {
            entries.push((
                Key::Marker(reference_marker(e)),
                format!(
                    "{}: reference RMS {} mm, max |error| {} mm",
                    e.name(arms),
                    short(r.rms),
                    short(r.max_abs)
                ),
            ));
        }
    }
    let height = header_height(&entries) + 2 * ROW;
    let svg = render(LENGTHS_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let (top, bottom) = area.split_vertically(ROW);
        pair_panel(&top, evaluated, &series, arms)?;
        let stages: Vec<Stage> = [Stage::Before, Stage::After]
            .into_iter()
            .filter(|s| evaluated.iter().any(|e| e.stage == *s))
            .collect();
        let panels = bottom.split_evenly((1, stages.len().max(1)));
        for (panel, stage) in panels.iter().zip(&stages) {
            let arm = match stage {
                Stage::Before => &arms.before,
                Stage::After => &arms.after,
            };
            let mine: Vec<&Evaluated> = evaluated.iter().filter(|e| e.stage == *stage).collect();
            reference_panel(panel, &mine, arms, arm)?;
        }
        Ok(())
    })?;
    Ok(Figure {
        file: LENGTHS_SVG,
        title: TITLE.to_string(),
        svg,
    })
}

/// Eq. 19 `|d|_error` against the centroid distance, every series on one
/// log axis.
fn pair_panel(
    area: &Area,
    evaluated: &[Evaluated],
    series: &[(usize, Pairs)],
    arms: &Arms,
) -> DrawResultOf {
    let title = "eq. 19 with absolute values: |d|_error = (1/n) Σ_k | |x_ik − x_jk| − |x̄_i − x̄_j| | per pair";
    if series.is_empty() {
        return message(area, title, &["A single point has no pairs."]);
    }
    let xy = |p: &Pairs| -> Vec<(f64, f64)> {
        match p {
            Pairs::Each(v) => v.clone(),
            Pairs::Binned { bins, .. } => bins.iter().map(|b| (b.0, b.1)).collect(),
        }
    };
    let all: Vec<(f64, f64)> = series.iter().flat_map(|(_, p)| xy(p)).collect();
    let bound = |f: fn(&(f64, f64)) -> f64, pos: bool| {
        all.iter()
            .map(f)
            .filter(|v| v.is_finite() && (!pos || *v > 0.0))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            })
    };
    let (x0, x1) = bound(|p| p.0, false);
    let (y0, y1) = bound(|p| p.1, true);
    let x = Axis::linear(
        x0,
        x1,
        false,
        "distance between the centroids |x̄_i − x̄_j| [mm]",
    );
    let y = Axis::log(y0, y1, "|d|_error [mm], log scale");
    let mut chart = chart(area, title, &x, &y, 64)?;
    for (i, p) in series {
        let e = &evaluated[*i];
        let points = xy(p);
        let marker = Marker {
            size: 3,
            ..e.marker()
        };
        group(area, Class::Series, &e.name(arms), points.len(), || {
            chart.draw_series(points.iter().map(|(d, v)| marker.at((*d, y.at(*v)))))?;
            Ok(())
        })?;
    }
    Ok(())
}

/// Reference errors of one arm against the reference length.
fn reference_panel(area: &Area, mine: &[&Evaluated], arms: &Arms, arm: &str) -> DrawResultOf {
    let title = format!("{arm}: error against the reference lengths, measured − reference");
    let with: Vec<&&Evaluated> = mine.iter().filter(|e| !e.ev.reference.is_empty()).collect();
    if with.is_empty() {
        return message(
            area,
            &title,
            &[
                "No reference lengths were given:",
                "scale is untested (eq. 19 cannot see it).",
            ],
        );
    }
    let refs = || with.iter().flat_map(|e| e.ev.reference.iter());
    let (x0, x1) = refs().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
        (a.min(r.reference), b.max(r.reference))
    });
    let (y0, y1) = refs().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
        (a.min(r.error), b.max(r.error))
    });
    let x = Axis::linear(x0, x1, false, "reference length L [mm]");
    let y = Axis::linear(y0, y1, true, "error |x̄_a − x̄_b| − L [mm]");
    let mut chart = chart(area, &title, &x, &y, 72)?;
    group(area, Class::Guide, "zero error", 1, || {
        dashed_across(&mut chart, &x, 0.0, GREY, 1)
    })?;
    for e in with {
        let marker = reference_marker(e);
        let n = e.ev.reference.len();
        group(
            area,
            Class::Series,
            &format!("{} reference errors", e.name(arms)),
            n,
            || {
                chart.draw_series(
                    e.ev.reference
                        .iter()
                        .map(|r| marker.at((r.reference, r.error))),
                )?;
                Ok(())
            },
        )?;
    }
    Ok(())
}

/// Squares for reference lengths (diamond-like next to the pairs' dots).
fn reference_marker(e: &Evaluated) -> Marker {
    Marker {
        size: 5,
        ..Marker::new(
            if e.held_out {
                Shape::Triangle
            } else {
                Shape::Square
            },
            e.color(),
        )
    }
}

/// What a panel returns.
type DrawResultOf = crate::report::svg::DrawResult;
