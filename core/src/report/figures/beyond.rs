//! The error each model beyond geometry explains: per pose, how far the
//! fitted correction moves the probe (the calibrated arm with it against
//! without it), against the reach.

use plotters::prelude::*;

use super::{frame, header_height, series_label};
use crate::report::svg::{
    Axis, BLUE, Class, GREEN, Key, Marker, PURPLE, Shape, VERMILLION, WIDTH, chart, group, render,
};
use crate::report::{BEYOND_SVG, Figure, PoseErrors, ReportError};

/// The figure's title.
pub(crate) const TITLE: &str =
    "Beyond geometry: how far each fitted model moves the probe, per pose, against reach";

const COLORS: [RGBColor; 4] = [BLUE, VERMILLION, GREEN, PURPLE];

/// Draws the figure of `series` (one per model, at least one).
pub(crate) fn figure(series: &[PoseErrors]) -> Result<Figure, ReportError> {
    let top = (series.iter().flat_map(|s| s.error_mm.iter().copied())).fold(1e-9, f64::max);
    let (r_lo, r_hi) = (series.iter().flat_map(|s| s.reach_mm.iter().copied()))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let marker = |i: usize| Marker {
        size: 2,
        ..Marker::new(Shape::Dot, COLORS[i % COLORS.len()])
    };
    let entries: Vec<(Key, String)> = (series.iter().enumerate())
        .map(|(i, s)| (Key::Marker(marker(i)), series_label(s)))
        .collect();
    let height = header_height(&entries) + 420;
    let svg = render(BEYOND_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let x = Axis::linear(
            r_lo.min(r_hi),
            r_hi.max(r_lo + 1.0),
            false,
            "reach: distance of the probe from the base axis [mm]",
        );
        let y = Axis::linear(0.0, top, true, "probe moved by the model [mm]");
        let mut c = chart(&area, "", &x, &y, 64)?;
        for (i, s) in series.iter().enumerate() {
            let m = marker(i);
            group(&area, Class::Series, &s.name, s.error_mm.len(), || {
                c.draw_series(
                    (s.reach_mm.iter().zip(&s.error_mm)).map(|(r, e)| m.at((x.at(*r), y.at(*e)))),
                )?;
                Ok(())
            })?;
        }
        Ok(())
    })?;
    Ok(Figure {
        file: BEYOND_SVG,
        title: TITLE.to_string(),
        svg,
    })
}
