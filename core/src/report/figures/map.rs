//! The uncertainty map: per sampled pose, the predicted radius that holds
//! the calibrated probe position's error with 95 % probability, against
//! the distance from the shoulder, coloured by the probe's height; the RMS
//! per band of that distance as a step line (the section's table).

use plotters::prelude::*;

use super::{frame, header_height, short};
use crate::plan::{MapPoint, Region, UncertaintyMap};
use crate::report::svg::{
    Axis, Class, INK, Key, Marker, Shape, WIDTH, chart, group, number, render,
};
use crate::report::{Figure, ReportError, UNCERTAINTY_MAP_SVG};

/// The figure's title.
pub(crate) const TITLE: &str =
    "Uncertainty map: predicted 95 % radius of the position error per sampled pose, by reach";

/// Bands of height the points are coloured by, lowest first: dark blue,
/// magenta, orange (a sequential scale, readable on white and in grey).
const HEIGHT_COLORS: [RGBColor; 3] = [
    RGBColor(0x0D, 0x08, 0x87),
    RGBColor(0xCC, 0x47, 0x78),
    RGBColor(0xF8, 0x95, 0x40),
];

/// Draws the figure of `map`.
pub(crate) fn figure(map: &UncertaintyMap) -> Result<Figure, ReportError> {
    let bands = height_bands(&map.points);
    let marker = |b: usize| Marker {
        size: 2,
        ..Marker::new(Shape::Dot, HEIGHT_COLORS[b])
    };
    let mut entries: Vec<(Key, String)> = (bands.iter().enumerate())
        .filter(|(_, b)| !b.points.is_empty())
        .map(|(i, b)| (Key::Marker(marker(i)), b.label()))
        .collect();
    entries.push((
        Key::Line(INK, 2, false),
        format!(
            "RMS per band of distance (all {} poses: RMS {} mm, max {} mm)",
            map.poses,
            short(map.rms_mm),
            short(map.max_mm)
        ),
    ));
    let (x_lo, x_hi) = reach_span(map);
    let top = (map.points.iter().map(|p| p.radius_mm))
        .fold(map.max_mm, f64::max)
        .max(1e-9);
    let height = header_height(&entries) + 420;
    let svg = render(UNCERTAINTY_MAP_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let x = Axis::linear(
            x_lo,
            x_hi,
            false,
            "distance of the probe from the shoulder (base axis at joint 1's height) [mm]",
        );
        let y = Axis::linear(0.0, top, true, "95 % radius of the position error [mm]");
        let mut c = chart(&area, "", &x, &y, 72)?;
        for (i, b) in bands.iter().enumerate() {
            if b.points.is_empty() {
                continue;
            }
            let m = marker(i);
            group(&area, Class::Series, &b.label(), b.points.len(), || {
                c.draw_series(
                    (b.points.iter()).map(|p| m.at((x.at(p.reach_mm), y.at(p.radius_mm)))),
                )?;
                Ok(())
            })?;
        }
        let steps = rms_steps(&map.regions);
        let drawn = steps.iter().map(Vec::len).sum::<usize>() / 2;
        group(&area, Class::Guide, "RMS per band", drawn, || {
            for s in steps {
                let path: Vec<(f64, f64)> = s.iter().map(|(r, v)| (x.at(*r), y.at(*v))).collect();
                c.draw_series(std::iter::once(PathElement::new(path, INK.stroke_width(2))))?;
            }
            Ok(())
        })
    })?;
    Ok(Figure {
        file: UNCERTAINTY_MAP_SVG,
        title: TITLE.to_string(),
        svg,
    })
}

/// The points of one band of height.
struct HeightBand<'a> {
    from_mm: f64,
    to_mm: f64,
    points: Vec<&'a MapPoint>,
}

impl HeightBand<'_> {
    fn label(&self) -> String {
        format!(
            "height above the shoulder {} to {} mm: {} poses",
            number(self.from_mm, 0),
            number(self.to_mm, 0),
            self.points.len()
        )
    }
}

/// The points split into [`HEIGHT_COLORS`]'s bands of equal height; one
/// band when every point has the same height.
fn height_bands(points: &[MapPoint]) -> Vec<HeightBand<'_>> {
    let (lo, hi) = (points.iter().map(|p| p.height_mm))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
            (a.min(h), b.max(h))
        });
    let n = HEIGHT_COLORS.len();
    let width = (hi - lo) / n as f64;
    let bands = if width.is_finite() && width > 0.0 {
        n
    } else {
        1
    };
    (0..bands)
        .map(|b| HeightBand {
            from_mm: lo + b as f64 * width.max(0.0),
            to_mm: if b + 1 == bands {
                hi
            } else {
                lo + (b + 1) as f64 * width
            },
            points: (points.iter())
                .filter(|p| bands == 1 || band_of(p.height_mm, lo, width, bands) == b)
                .collect(),
        })
        .collect()
}

/// The band of height `h` (the top edge belongs to the last band).
fn band_of(h: f64, lo: f64, width: f64, bands: usize) -> usize {
    (((h - lo) / width).floor().max(0.0) as usize).min(bands - 1)
}

/// The x span: the bands of reach, else the points.
fn reach_span(map: &UncertaintyMap) -> (f64, f64) {
    let reaches = (map.regions.iter())
        .flat_map(|r| [r.reach_from_mm, r.reach_to_mm])
        .chain(map.points.iter().map(|p| p.reach_mm));
    reaches.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    })
}

/// The RMS per band as steps (reach, RMS): one path per run of bands with
/// poses, so that an empty band (RMS 0 by convention) draws no drop to 0.
fn rms_steps(regions: &[Region]) -> Vec<Vec<(f64, f64)>> {
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut run: Vec<(f64, f64)> = Vec::new();
    for r in regions {
        if r.poses == 0 {
            if !run.is_empty() {
                runs.push(std::mem::take(&mut run));
            }
            continue;
        }
        run.push((r.reach_from_mm, r.rms_mm));
        run.push((r.reach_to_mm, r.rms_mm));
    }
    if !run.is_empty() {
        runs.push(run);
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region(from: f64, poses: usize, rms: f64) -> Region {
        Region {
            reach_from_mm: from,
            reach_to_mm: from + 100.0,
            poses,
            rms_mm: rms,
            max_mm: rms * 1.5,
        }
    }

    #[test]
    fn an_empty_band_breaks_the_step_line() {
        let steps = rms_steps(&[
            region(0.0, 3, 0.02),
            region(100.0, 0, 0.0),
            region(200.0, 5, 0.03),
            region(300.0, 1, 0.04),
        ]);
        assert_eq!(
            steps,
            [
                vec![(0.0, 0.02), (100.0, 0.02)],
                vec![(200.0, 0.03), (300.0, 0.03), (300.0, 0.04), (400.0, 0.04)]
            ]
        );
    }

    #[test]
    fn every_point_is_in_one_height_band() {
        let at = |h: f64| MapPoint {
            reach_mm: 1.0,
            height_mm: h,
            radius_mm: 0.01,
        };
        let points: Vec<MapPoint> = [-300.0, -150.0, 0.0, 99.0, 300.0].map(at).to_vec();
        let bands = height_bands(&points);
        let counts: Vec<usize> = bands.iter().map(|b| b.points.len()).collect();
        assert_eq!(counts, [2, 2, 1]);
        assert_eq!((bands[0].from_mm, bands[2].to_mm), (-300.0, 300.0));
        // One height: one band; no points: one empty band.
        assert_eq!(height_bands(&[at(5.0), at(5.0)]).len(), 1);
        assert_eq!(height_bands(&[at(5.0), at(5.0)])[0].points.len(), 2);
        assert!(height_bands(&[])[0].points.is_empty());
    }
}
