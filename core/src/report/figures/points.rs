//! Figure 1: the paper's single-point error `e` per point (its Fig. 6),
//! before and after, fitted and held-out points side by side.

use plotters::style::text_anchor::{HPos, VPos};

use super::{frame, header_height, short};
use crate::dataset::DataSet;
use crate::report::data::{Evaluated, sets};
use crate::report::svg::{
    Area, Axis, Chart, Class, DrawResult, GREY, Key, Marker, WIDTH, chart, dashed, font_at, group,
    render,
};
use crate::report::{Arms, Figure, ReportError, SINGLE_POINT_SVG};

/// Point labels shown on the axis at most (every k-th beyond).
const MAX_LABELS: usize = 30;

/// The figure's title.
pub(crate) const TITLE: &str = "Single-point error e per point (paper Fig. 6): mean distance of the touches from their centroid";

/// Draws figure 1.
pub(crate) fn figure(evaluated: &[Evaluated], arms: &Arms) -> Result<Figure, ReportError> {
    let sets = sets(evaluated);
    let (offsets, labels) = columns(&sets);
    let offset = |set: usize| offsets[sets.iter().position(|s| s.0 == set).unwrap_or(0)];
    let (x, y) = axes(evaluated, &labels);
    let entries = legend_entries(evaluated, arms);
    let height = header_height(&entries) + 420;
    // Smaller markers when many points share the width.
    let size = match labels.len() {
        0..=60 => 4,
        61..=200 => 3,
        _ => 2,
    };
    let svg = render(SINGLE_POINT_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let mut chart = chart(&area, "", &x, &y, 64)?;
        set_blocks(&area, &mut chart, &sets, &offsets, &y)?;
        for e in evaluated {
            point_series(&area, &mut chart, e, arms, offset(e.set), size, &y)?;
        }
        Ok(())
    })?;
    Ok(Figure {
        file: SINGLE_POINT_SVG,
        title: TITLE.to_string(),
        svg,
    })
}

/// The x axis's columns: every set's points side by side, as the column
/// of each set's first point and the labels of all of them.
fn columns(sets: &[(usize, &str, &DataSet, bool)]) -> (Vec<usize>, Vec<String>) {
    let mut offsets = Vec::new();
    let mut labels = Vec::new();
    for (_, _, data, _) in sets {
        offsets.push(labels.len());
        labels.extend(data.points().iter().map(|p| p.label.clone()));
    }
    (offsets, labels)
}

/// The axes: the points by `labels`, and `e` on a log scale over the
/// positive values of every evaluated arm.
fn axes(evaluated: &[Evaluated], labels: &[String]) -> (Axis, Axis) {
    let values = evaluated
        .iter()
        .flat_map(|e| e.ev.points.iter().map(|p| p.e));
    let (lo, hi) = values
        .filter(|v| *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    // As many labels as fit side by side (about 7 px a character).
    let widest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(1);
    let fit = (760 / (widest * 7 + 12)).clamp(2, MAX_LABELS);
    let x = Axis::categories(labels, fit, "point (socket)");
    let y = Axis::log(lo, hi, "e [mm], log scale");
    (x, y)
}

/// The legend: every evaluated arm's marker and mean `e`.
fn legend_entries(evaluated: &[Evaluated], arms: &Arms) -> Vec<(Key, String)> {
    evaluated
        .iter()
        .map(|e| {
            (
                Key::Marker(e.marker()),
                format!(
                    "{}: mean {} mm",
                    e.name(arms),
                    short(e.ev.single_point_e.mean)
                ),
            )
        })
        .collect()
}

/// Blocks of points: a divider before every set but the first, and the
/// data set's name over it.
fn set_blocks(
    area: &Area,
    chart: &mut Chart,
    sets: &[(usize, &str, &DataSet, bool)],
    offsets: &[usize],
    y: &Axis,
) -> DrawResult {
    for (k, (_, name, data, _)) in sets.iter().enumerate() {
        let start = offsets[k] as f64 - 0.5;
        if k > 0 {
            dashed(
                chart,
                vec![(start, y.range.start), (start, y.range.end)],
                GREY,
                1,
            )?;
        }
        let centre = start + data.points().len() as f64 / 2.0;
        let (px, py) = chart.backend_coord(&(centre, y.range.end));
        area.draw_text(
            &format!("{name} ({} points)", data.points().len()),
            &font_at(12.5, HPos::Center, VPos::Top),
            (
                px - area.get_base_pixel().0,
                py - area.get_base_pixel().1 + 4,
            ),
        )?;
    }
    Ok(())
}

/// One evaluated arm's points from column `o`: its mean as a dashed guide,
/// then a marker of `size` per point.
fn point_series(
    area: &Area,
    chart: &mut Chart,
    e: &Evaluated,
    arms: &Arms,
    o: usize,
    size: i32,
    y: &Axis,
) -> DrawResult {
    let o = o as f64;
    let n = e.ev.points.len();
    let mean = e.ev.single_point_e.mean;
    group(
        area,
        Class::Guide,
        &format!("{} mean", e.name(arms)),
        1,
        || {
            dashed(
                chart,
                vec![(o - 0.4, y.at(mean)), (o + n as f64 - 0.6, y.at(mean))],
                e.color(),
                1,
            )
        },
    )?;
    let marker = Marker { size, ..e.marker() };
    group(area, Class::Series, &e.name(arms), n, || {
        chart.draw_series(
            e.ev.points
                .iter()
                .enumerate()
                .map(|(i, p)| marker.at((o + i as f64, y.at(p.e)))),
        )?;
        Ok(())
    })
}
