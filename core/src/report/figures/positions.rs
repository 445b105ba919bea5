//! The 3-D errors at reference positions (a laser tracker's, an
//! artefact's): `|R p + t − y|` per pose before and after, against the
//! reach (the probe's distance from the base axis), and their
//! distribution.

use plotters::prelude::*;

use super::{frame, header_height, series_label};
use crate::report::svg::{
    Axis, BLUE, Class, GREY, Key, Marker, Shape, VERMILLION, WIDTH, chart, group, render,
};
use crate::report::{Figure, POSITIONS_SVG, PoseErrors, ReportError};

/// The figure's title.
pub(crate) const TITLE: &str =
    "Reference positions: 3-D error |R p + t − y| per pose against reach, and its distribution";

/// Bins of the histogram.
const BINS: usize = 30;

/// Grey before; blue (fitted) or vermillion (held out) after.
fn color(s: &PoseErrors) -> RGBColor {
    match (s.after, s.held_out) {
        (false, _) => GREY,
        (true, false) => BLUE,
        (true, true) => VERMILLION,
    }
}

fn marker(s: &PoseErrors) -> Marker {
    let shape = if s.held_out {
        Shape::Triangle
    } else {
        Shape::Dot
    };
    Marker {
        size: 2,
        ..Marker::new(shape, color(s))
    }
}

/// Draws the figure of `series` (at least one).
pub(crate) fn figure(series: &[PoseErrors]) -> Result<Figure, ReportError> {
    let all = || series.iter().flat_map(|s| s.error_mm.iter().copied());
    let top = all().fold(0.0, f64::max).max(1e-9);
    let (r_lo, r_hi) = (series.iter().flat_map(|s| s.reach_mm.iter().copied()))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let entries: Vec<(Key, String)> = series
        .iter()
        .map(|s| (Key::Marker(marker(s)), series_label(s)))
        .collect();
    let height = header_height(&entries) + 420;
    let svg = render(POSITIONS_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let (left, right) = area.split_horizontally(WIDTH * 3 / 5);
        let x = Axis::linear(
            r_lo.min(r_hi),
            r_hi.max(r_lo + 1.0),
            false,
            "reach: distance of the probe from the base axis [mm]",
        );
        let y = Axis::linear(0.0, top, true, "3-D error [mm]");
        let mut c = chart(&left, "", &x, &y, 64)?;
        for s in series {
            let m = marker(s);
            group(&left, Class::Series, &s.name, s.error_mm.len(), || {
                c.draw_series(
                    (s.reach_mm.iter().zip(&s.error_mm)).map(|(r, e)| m.at((x.at(*r), y.at(*e)))),
                )?;
                Ok(())
            })?;
        }
        let width = top / BINS as f64;
        let counts: Vec<Vec<usize>> = series
            .iter()
            .map(|s| {
                let mut c = vec![0usize; BINS];
                for e in &s.error_mm {
                    c[((e / width) as usize).min(BINS - 1)] += 1;
                }
                c
            })
            .collect();
        let most = counts.iter().flatten().copied().max().unwrap_or(1).max(1);
        let hx = Axis::linear(0.0, top, true, "3-D error [mm]");
        let hy = Axis::linear(0.0, most as f64, true, "poses per bin");
        let mut h = chart(&right, "", &hx, &hy, 56)?;
        for (s, c) in series.iter().zip(&counts) {
            let mut path = vec![(0.0, 0.0)];
            for (k, n) in c.iter().enumerate() {
                path.push((k as f64 * width, *n as f64));
                path.push(((k + 1) as f64 * width, *n as f64));
            }
            path.push((top, 0.0));
            let path: Vec<(f64, f64)> = path
                .into_iter()
                .map(|(a, b)| (hx.at(a), hy.at(b)))
                .collect();
            group(&right, Class::Series, &s.name, BINS, || {
                h.draw_series(std::iter::once(PathElement::new(
                    path,
                    color(s).stroke_width(2),
                )))?;
                Ok(())
            })?;
        }
        Ok(())
    })?;
    Ok(Figure {
        file: POSITIONS_SVG,
        title: TITLE.to_string(),
        svg,
    })
}
