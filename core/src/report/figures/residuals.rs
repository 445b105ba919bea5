//! Figure 5: the per-touch residuals, `δ_i = |x_i − x̄|` (each touch against
//! its point's centroid — what the calibration minimises), as histograms on
//! log-spaced bins so that before and after share one axis.

use plotters::prelude::*;

use super::{frame, header_height, short};
use crate::report::data::{Evaluated, for_each_delta};
use crate::report::svg::{Axis, Class, Key, WIDTH, chart, dashed, group, render};
use crate::report::{Arms, Figure, RESIDUALS_SVG, ReportError};

/// The figure's title.
pub(crate) const TITLE: &str =
    "Residuals: histogram of the per-touch distances δ = |x_i − x̄| from the point's centroid";

/// Bins of the histogram.
pub(crate) const BINS: usize = 36;

/// Draws figure 5.
pub(crate) fn figure(evaluated: &[Evaluated], arms: &Arms) -> Result<Figure, ReportError> {
    // The δ are streamed (twice) rather than held: a list per series is
    // 8 MB per 10⁶ touches, at the command's peak of memory.
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for e in evaluated {
        for_each_delta(e, |v| {
            if v > 0.0 && v.is_finite() {
                (lo, hi) = (lo.min(v), hi.max(v));
            }
        });
    }
    let x = Axis::log(
        lo,
        hi,
        "δ = |x_i − x̄| [mm], log scale (bins of equal width in log δ)",
    );
    // Bin edges in log10 over the axis range; δ = 0 falls into the first bin.
    let (a, b) = (x.range.start, x.range.end);
    let width = (b - a) / BINS as f64;
    let counts: Vec<Vec<usize>> = evaluated
        .iter()
        .map(|e| {
            let mut c = vec![0usize; BINS];
            for_each_delta(e, |v| {
                let k = ((x.at(v) - a) / width).floor().max(0.0) as usize;
                c[k.min(BINS - 1)] += 1;
            });
            c
        })
        .collect();
    let top = counts.iter().flatten().copied().max().unwrap_or(1).max(1);
    let y = Axis::linear(0.0, top as f64, true, "touches per bin");
    let entries: Vec<(Key, String)> = evaluated
        .iter()
        .map(|e| {
            (
                Key::Line(e.color(), 2, e.held_out),
                format!(
                    "{}: {} touches, median δ {} mm",
                    e.name(arms),
                    e.xyz.len(),
                    short(e.median_delta().unwrap_or(f64::NAN))
                ),
            )
        })
        .collect();
    let height = header_height(&entries) + 400;
    let svg = render(RESIDUALS_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let mut chart = chart(&area, "", &x, &y, 64)?;
        for (e, c) in evaluated.iter().zip(&counts) {
            // A step outline: up and across each bin.
            let mut path = vec![(a, 0.0)];
            for (k, n) in c.iter().enumerate() {
                let (l, r) = (a + k as f64 * width, a + (k + 1) as f64 * width);
                path.push((l, *n as f64));
                path.push((r, *n as f64));
            }
            path.push((b, 0.0));
            let color = e.color();
            group(&area, Class::Series, &e.name(arms), BINS, || {
                if e.held_out {
                    dashed(&mut chart, path, color, 2)
                } else {
                    chart.draw_series(std::iter::once(PathElement::new(
                        path,
                        color.stroke_width(2),
                    )))?;
                    Ok(())
                }
            })?;
        }
        Ok(())
    })?;
    Ok(Figure {
        file: RESIDUALS_SVG,
        title: TITLE.to_string(),
        svg,
    })
}
