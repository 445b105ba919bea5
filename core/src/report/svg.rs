//! Plotters plumbing the figures share: one SVG canvas per figure, axes whose
//! ticks are chosen here (linear, log10, categories), markers, legends, and
//! named groups around every series.
//!
//! Only plotters' SVG backend is used, without fonts: text is written as SVG
//! `<text>` for the viewer to set. Every coordinate plotters writes is an
//! integer pixel, so the same data give the same bytes.
//!
//! **Groups.** Each data series is wrapped in
//! `<g class="series" data-name="…" data-points="N">` (guides such as
//! thresholds and mean lines in `class="guide"`), with a `<title>` a browser
//! shows as a tooltip. Plotters cannot write a group, so [`group`] draws a
//! sentinel text that [`render`] replaces by the group's tags.

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::element::{DashedPathElement, Drawable, PointCollection};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters_backend::{BackendCoord, DrawingErrorKind};

use super::ReportError;
use super::html::escape;

/// The drawing area of a figure (pixel coordinates).
pub(crate) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
/// What plotters' drawing calls return.
pub(crate) type DrawResult<T = ()> = Result<T, DrawingAreaErrorKind<std::io::Error>>;
/// A chart with axes chosen by [`Axis`].
pub(crate) type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<Ticks, Ticks>>;

/// A linear f64 coordinate with the ticks an [`Axis`] chose (plotters'
/// own `WithKeyPoints` has no value formatter, so no mesh).
#[derive(Clone)]
pub(crate) struct Ticks {
    inner: RangedCoordf64,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Ranged for Ticks {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.inner.range()
    }
}

/// Marks a sentinel text (a character of Unicode's private use area).
const SENTINEL: char = '\u{E000}';
/// Separates the fields of a sentinel.
const SEP: char = '\u{E001}';

/// The shortest log axis, decades.
pub(crate) const MIN_LOG_SPAN: f64 = 0.7;

/// Width of every figure, px.
pub(crate) const WIDTH: u32 = 960;

/// Before calibration: grey.
pub(crate) const GREY: RGBColor = RGBColor(0x80, 0x80, 0x80);
/// Light grey (grid, bands).
pub(crate) const LIGHT: RGBColor = RGBColor(0xDD, 0xDD, 0xDD);
/// After calibration, fitted data (Okabe–Ito blue).
pub(crate) const BLUE: RGBColor = RGBColor(0x00, 0x72, 0xB2);
/// After calibration, held-out data (Okabe–Ito vermillion).
pub(crate) const VERMILLION: RGBColor = RGBColor(0xD5, 0x5E, 0x00);
/// Truth and thresholds (Okabe–Ito bluish green).
pub(crate) const GREEN: RGBColor = RGBColor(0x00, 0x9E, 0x73);
/// Warnings, limits (Okabe–Ito reddish purple).
pub(crate) const PURPLE: RGBColor = RGBColor(0xCC, 0x79, 0xA7);
/// Text and axes.
pub(crate) const INK: RGBColor = RGBColor(0x22, 0x22, 0x22);

/// A text style of `px` pixels (plotters writes `font-size` as its size / 1.24).
pub(crate) fn font(px: f64) -> TextStyle<'static> {
    ("sans-serif", px * 1.24).into_font().color(&INK)
}

/// [`font`], anchored.
pub(crate) fn font_at(px: f64, h: HPos, v: VPos) -> TextStyle<'static> {
    font(px).pos(Pos::new(h, v))
}

/// Renders one figure: `draw` paints on a white `width × height` canvas;
/// the sentinels become groups and the figure gets its `<title>`.
pub(crate) fn render(
    file: &'static str,
    title: &str,
    (width, height): (u32, u32),
    draw: impl FnOnce(&Area) -> DrawResult,
) -> Result<String, ReportError> {
    let mut raw = String::new();
    let drawn = {
        let root = SVGBackend::with_string(&mut raw, (width, height)).into_drawing_area();
        root.fill(&WHITE)
            .and_then(|()| draw(&root))
            .and_then(|()| root.present())
    };
    drawn.map_err(|e| ReportError::Draw {
        file,
        message: e.to_string(),
    })?;
    finish(&raw, title).ok_or(ReportError::Draw {
        file,
        message: "unbalanced series groups".to_string(),
    })
}

/// Turns sentinels into groups and adds the title; `None` if a group is
/// left open or closed twice (a bug in a figure).
fn finish(raw: &str, title: &str) -> Option<String> {
    let lines: Vec<&str> = raw.lines().collect();
    let mut out = String::with_capacity(raw.len() + 256);
    let mut depth = 0usize;
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let sentinel = lines.get(i + 1).and_then(|s| s.strip_prefix(SENTINEL));
        if line.starts_with("<text")
            && lines.get(i + 2) == Some(&"</text>")
            && let Some(s) = sentinel
        {
            let fields: Vec<&str> = s.split(SEP).collect();
            match fields.as_slice() {
                ["begin", class, name, points] => {
                    out.push_str(&format!(
                        "<g class=\"{class}\" data-name=\"{name}\" data-points=\"{points}\">\n\
                         <title>{name}: {points} points</title>\n"
                    ));
                    depth += 1;
                }
                ["end"] => {
                    depth = depth.checked_sub(1)?;
                    out.push_str("</g>\n");
                }
                _ => return None,
            }
            i += 3;
            continue;
        }
        out.push_str(line);
        out.push('\n');
        if i == 0 {
            out.push_str(&format!("<title>{}</title>\n", escape(title)));
        }
        i += 1;
    }
    (depth == 0).then_some(out)
}

/// What a group holds: data (`series`) or a reference line or band (`guide`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Class {
    /// Data: one element per point.
    Series,
    /// A threshold, a mean line, a band.
    Guide,
}

/// Draws `body` inside a named group (see the module documentation).
pub(crate) fn group(
    area: &Area,
    class: Class,
    name: &str,
    points: usize,
    body: impl FnOnce() -> DrawResult,
) -> DrawResult {
    let class = match class {
        Class::Series => "series",
        Class::Guide => "guide",
    };
    let style = font(1.0);
    area.draw_text(
        &format!("{SENTINEL}begin{SEP}{class}{SEP}{name}{SEP}{points}"),
        &style,
        (0, 0),
    )?;
    body()?;
    area.draw_text(&format!("{SENTINEL}end"), &style, (0, 0))
}

/// Marker shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shape {
    /// Filled circle.
    Dot,
    /// Filled triangle.
    Triangle,
    /// Open circle.
    Ring,
    /// Diagonal cross.
    Cross,
    /// Filled square.
    Square,
}

/// A marker: shape, colour, size (radius in px).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Marker {
    /// The shape.
    pub(crate) shape: Shape,
    /// The colour.
    pub(crate) color: RGBColor,
    /// Radius, px.
    pub(crate) size: i32,
}

impl Marker {
    /// A marker of `shape` and `color`, 4 px.
    pub(crate) fn new(shape: Shape, color: RGBColor) -> Marker {
        Marker {
            shape,
            color,
            size: 4,
        }
    }

    /// The element at `at` (data coordinates of a chart, or pixels).
    pub(crate) fn at<C>(&self, at: C) -> Mark<C> {
        Mark { at, marker: *self }
    }
}

/// A [`Marker`] placed at a point: one SVG element (circle, polygon,
/// polyline or rect) per point.
pub(crate) struct Mark<C> {
    at: C,
    marker: Marker,
}

impl<'a, C: 'a> PointCollection<'a, C> for &'a Mark<C> {
    type Point = &'a C;
    type IntoIter = std::iter::Once<&'a C>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<C, DB: DrawingBackend> Drawable<DB> for Mark<C> {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = pos.next() else {
            return Ok(());
        };
        let s = self.marker.size;
        let c = self.marker.color;
        match self.marker.shape {
            Shape::Dot => backend.draw_circle((x, y), s as u32, &c.filled(), true),
            Shape::Ring => backend.draw_circle((x, y), (s + 2) as u32, &c.stroke_width(2), false),
            Shape::Triangle => {
                let r = f64::from(s + 1) * 1.25;
                let corner = |deg: f64| {
                    let a = deg.to_radians();
                    (
                        x + (a.cos() * r).round() as i32,
                        y + (a.sin() * r).round() as i32,
                    )
                };
                backend.fill_polygon([corner(-90.0), corner(30.0), corner(150.0)], &c.filled())
            }
            Shape::Cross => backend.draw_path(
                [
                    (x - s, y - s),
                    (x + s, y + s),
                    (x, y),
                    (x + s, y - s),
                    (x - s, y + s),
                ],
                &c.stroke_width(2),
            ),
            Shape::Square => backend.draw_rect((x - s, y - s), (x + s, y + s), &c.filled(), true),
        }
    }
}

/// What a legend entry shows.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Key {
    /// A marker.
    Marker(Marker),
    /// A line of this colour and width; dashed or not.
    Line(RGBColor, u32, bool),
}

/// Draws a legend in `area`, entries left to right, wrapping; returns the
/// height used.
pub(crate) fn legend(area: &Area, entries: &[(Key, String)], px: f64) -> DrawResult<i32> {
    let (width, _) = area.dim_in_pixel();
    let row = (px * 1.6).round() as i32;
    let (mut x, mut y) = (8i32, row / 2);
    for (key, label) in entries {
        let w = 28 + (label.chars().count() as f64 * px * 0.56).round() as i32 + 18;
        if x > 8 && x + w > width as i32 {
            x = 8;
            y += row;
        }
        match key {
            Key::Marker(m) => area.draw(&m.at((x + 10, y)))?,
            Key::Line(c, wdt, dashed) => {
                if *dashed {
                    for k in 0..3 {
                        let x0 = x + k * 8;
                        area.draw(&PathElement::new(
                            vec![(x0, y), (x0 + 5, y)],
                            c.stroke_width(*wdt),
                        ))?;
                    }
                } else {
                    area.draw(&PathElement::new(
                        vec![(x, y), (x + 20, y)],
                        c.stroke_width(*wdt),
                    ))?;
                }
            }
        }
        area.draw_text(label, &font_at(px, HPos::Left, VPos::Center), (x + 28, y))?;
        x += w;
    }
    Ok(y + row / 2)
}

/// How many legend rows `entries` take in `width` px (the same layout as
/// [`legend`]), for sizing the strip before drawing it.
pub(crate) fn legend_rows(width: u32, entries: &[(Key, String)], px: f64) -> i32 {
    let mut rows = 1;
    let mut x = 8i32;
    for (_, label) in entries {
        let w = 28 + (label.chars().count() as f64 * px * 0.56).round() as i32 + 18;
        if x > 8 && x + w > width as i32 {
            x = 8;
            rows += 1;
        }
        x += w;
    }
    rows
}

/// The height of a legend strip of `entries` in `width` px.
pub(crate) fn legend_height(width: u32, entries: &[(Key, String)], px: f64) -> u32 {
    (legend_rows(width, entries, px) as f64 * (px * 1.6).round()) as u32 + 4
}

/// An axis: its range and ticks in axis coordinates (log10 of the value for
/// a log axis, the index for categories), the tick labels, the description.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Axis {
    /// Description with unit, e.g. `e [mm]`.
    pub(crate) desc: String,
    /// Range in axis coordinates.
    pub(crate) range: Range<f64>,
    /// Labelled ticks (axis coordinates) and their labels.
    pub(crate) ticks: Vec<(f64, String)>,
    /// Unlabelled grid lines.
    pub(crate) minor: Vec<f64>,
    /// Whether values are mapped through log10.
    pub(crate) log: bool,
    /// Whether the axis runs from high to low values (coordinates negated).
    pub(crate) flip: bool,
}

impl Axis {
    /// A linear axis covering `lo..=hi` with a margin; `zero` keeps 0 in
    /// range. Degenerate or non-finite input gives a small range around it.
    pub(crate) fn linear(lo: f64, hi: f64, zero: bool, desc: &str) -> Axis {
        let (lo, hi) = finite_span(lo, hi);
        // Far beyond any length in mm, and the margins stay finite.
        let (mut lo, mut hi) = (lo.clamp(-1e300, 1e300), hi.clamp(-1e300, 1e300));
        if zero {
            lo = lo.min(0.0);
            hi = hi.max(0.0);
        }
        if hi - lo <= f64::EPSILON * hi.abs().max(lo.abs()).max(1e-300) {
            let pad = (hi.abs() * 0.1).max(1e-3);
            lo -= pad;
            hi += pad;
        }
        let margin = (hi - lo) * 0.06;
        let (lo, hi) = (
            if zero && lo == 0.0 { 0.0 } else { lo - margin },
            if zero && hi == 0.0 { 0.0 } else { hi + margin },
        );
        let step = nice_step((hi - lo) / 6.0);
        let decimals = decimals_of(step);
        let (first, last) = ((lo / step).ceil(), (hi / step).floor());
        let ticks = if last - first <= 20.0 && decimals < 12 {
            (first as i64..=last as i64)
                .map(|k| {
                    let v = k as f64 * step;
                    (v, number(v, decimals))
                })
                .collect()
        } else {
            // Spans beyond round numbers (huge or overflowing values).
            vec![(lo, format!("{lo:.3e}")), (hi, format!("{hi:.3e}"))]
        };
        Axis {
            desc: desc.to_string(),
            range: lo..hi,
            ticks,
            minor: Vec::new(),
            log: false,
            flip: false,
        }
    }

    /// A log10 axis covering the positive `lo..=hi` (non-positive or
    /// non-finite bounds are replaced by the other bound); at least
    /// [`MIN_LOG_SPAN`] decades. Labels are plain decimals when every one
    /// is between 0.001 and 10000, else all `me±k`.
    pub(crate) fn log(lo: f64, hi: f64, desc: &str) -> Axis {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        let (lo, hi) = match (ok(lo), ok(hi)) {
            (true, true) => (lo.min(hi), hi.max(lo)),
            (true, false) => (lo, lo),
            (false, true) => (hi, hi),
            (false, false) => (1.0, 1.0),
        };
        let (mut a, mut b) = (lo.log10(), hi.log10());
        let pad = ((b - a) * 0.06).max(0.12);
        a -= pad;
        b += pad;
        if b - a < MIN_LOG_SPAN {
            let mid = (a + b) / 2.0;
            a = mid - MIN_LOG_SPAN / 2.0;
            b = mid + MIN_LOG_SPAN / 2.0;
        }
        let mut ticks = Vec::new();
        let mut minor = Vec::new();
        let dense = b - a <= 3.5;
        let very_dense = b - a <= 1.6;
        let sparse_every = ((b - a) / 8.0).ceil().max(1.0) as i64;
        for k in (a.floor() as i64)..=(b.ceil() as i64) {
            for m in 1..10 {
                let c = k as f64 + (m as f64).log10();
                if c < a || c > b {
                    continue;
                }
                let labelled = if m == 1 {
                    k.rem_euclid(sparse_every) == 0
                } else {
                    (dense && (m == 2 || m == 5)) || (very_dense && m == 3)
                };
                if labelled {
                    ticks.push((c, (m, k)));
                } else if b - a <= 8.0 {
                    minor.push(c);
                }
            }
        }
        let plain = ticks.iter().all(|(_, (_, k))| (-3..=3).contains(k));
        let ticks = ticks
            .into_iter()
            .map(|(c, (m, k))| (c, log_label(m, k, plain)))
            .collect();
        Axis {
            desc: desc.to_string(),
            range: a..b,
            ticks,
            minor,
            log: true,
            flip: false,
        }
    }

    /// Categories at 0, 1, …, labelled (every k-th when there are more than
    /// `max_labels`).
    pub(crate) fn categories(labels: &[String], max_labels: usize, desc: &str) -> Axis {
        let n = labels.len().max(1);
        let every = n.div_ceil(max_labels.max(1)).max(1);
        Axis {
            desc: desc.to_string(),
            range: -0.6..(n as f64 - 0.4),
            ticks: labels
                .iter()
                .enumerate()
                .filter(|(i, _)| i % every == 0)
                .map(|(i, l)| (i as f64, l.clone()))
                .collect(),
            minor: Vec::new(),
            log: false,
            flip: false,
        }
    }

    /// The same axis running from high to low values.
    pub(crate) fn reversed(mut self) -> Axis {
        self.range = -self.range.end..-self.range.start;
        for t in &mut self.ticks {
            t.0 = -t.0;
        }
        self.ticks.reverse();
        for m in &mut self.minor {
            *m = -*m;
        }
        self.flip = !self.flip;
        self
    }

    /// A value in axis coordinates (log10 on a log axis; clamped to the
    /// range's floor for values a log axis cannot show).
    pub(crate) fn at(&self, v: f64) -> f64 {
        let c = if self.log {
            if v > 0.0 && v.is_finite() {
                v.log10()
            } else if self.flip {
                -self.range.end
            } else {
                self.range.start
            }
        } else {
            v
        };
        if self.flip { -c } else { c }
    }

    /// The label of tick `c` (axis coordinates); empty between ticks.
    fn label(&self, c: f64) -> String {
        let tol = (self.range.end - self.range.start).abs() * 1e-9;
        self.ticks
            .iter()
            .find(|(t, _)| (t - c).abs() <= tol)
            .map(|(_, l)| l.clone())
            .unwrap_or_default()
    }

    /// The plotters coordinate with these ticks.
    pub(crate) fn coord(&self) -> Ticks {
        let bold: Vec<f64> = self.ticks.iter().map(|(t, _)| *t).collect();
        let mut light = self.minor.clone();
        light.extend(&bold);
        Ticks {
            inner: self.range.clone().into(),
            bold,
            light,
        }
    }
}

/// Finite bounds of a span (0..1 when nothing is finite).
fn finite_span(lo: f64, hi: f64) -> (f64, f64) {
    match (lo.is_finite(), hi.is_finite()) {
        (true, true) => (lo.min(hi), hi.max(lo)),
        (true, false) => (lo, lo),
        (false, true) => (hi, hi),
        (false, false) => (0.0, 1.0),
    }
}

/// 1, 2, 2.5 or 5 times a power of ten, at least `raw`.
fn nice_step(raw: f64) -> f64 {
    let raw = if raw.is_finite() && raw > 0.0 {
        raw
    } else {
        1.0
    };
    let mag = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw * (1.0 - 1e-12))
        .unwrap_or(10.0 * mag)
}

/// Decimals that show multiples of `step` exactly.
fn decimals_of(step: f64) -> usize {
    (0..12)
        .find(|&d| {
            let scaled = step * 10f64.powi(d as i32);
            (scaled - scaled.round()).abs() < 1e-6 * scaled.max(1.0)
        })
        .unwrap_or(12)
}

/// `v` with `decimals` decimals, never `-0`.
pub(crate) fn number(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// The label of `m·10^k` on a log axis: a plain decimal (`0.05`, `2000`)
/// or `me±k` (`5e-6`, `2e5`).
fn log_label(m: u32, k: i64, plain: bool) -> String {
    if plain {
        let v = format!("{m}e{k}").parse::<f64>().unwrap_or(0.0);
        format!("{v}")
    } else {
        format!("{m}e{k}")
    }
}

/// Builds a chart in `area` with `title` and the axes' ticks, grid and
/// descriptions.
pub(crate) fn chart<'a, 'b>(
    area: &'a Area<'b>,
    title: &str,
    x: &Axis,
    y: &Axis,
    y_label_width: u32,
) -> DrawResult<Chart<'a, 'b>> {
    let mut builder = ChartBuilder::on(area);
    builder
        .margin_top(6)
        .margin_right(18)
        .margin_left(6)
        .x_label_area_size(48)
        .y_label_area_size(y_label_width);
    if !title.is_empty() {
        builder.caption(title, font(15.0));
    }
    let mut chart = builder.build_cartesian_2d(x.coord(), y.coord())?;
    let fx = |v: &f64| x.label(*v);
    let fy = |v: &f64| y.label(*v);
    chart
        .configure_mesh()
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_desc(x.desc.as_str())
        .y_desc(y.desc.as_str())
        .label_style(font(12.5))
        .axis_desc_style(font(14.0))
        .bold_line_style(LIGHT.stroke_width(1))
        .light_line_style(RGBColor(0xF0, 0xF0, 0xF0).stroke_width(1))
        .axis_style(INK.stroke_width(1))
        .draw()?;
    Ok(chart)
}

/// A dashed line through `points` (data coordinates).
pub(crate) fn dashed(
    chart: &mut Chart,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    width: u32,
) -> DrawResult {
    chart.draw_series(std::iter::once(DashedPathElement::new(
        points,
        6,
        4,
        color.stroke_width(width),
    )))?;
    Ok(())
}

/// A dashed horizontal line across the whole x axis at `y` (plot
/// coordinates): zero lines, thresholds, floors.
pub(crate) fn dashed_across(
    chart: &mut Chart,
    x: &Axis,
    y: f64,
    color: RGBColor,
    width: u32,
) -> DrawResult {
    dashed(
        chart,
        vec![(x.range.start, y), (x.range.end, y)],
        color,
        width,
    )
}

/// A message centred in `area`, for a panel with nothing to draw.
pub(crate) fn message(area: &Area, title: &str, lines: &[&str]) -> DrawResult {
    let (w, h) = area.dim_in_pixel();
    let (w, h) = (w as i32, h as i32);
    area.draw(&Rectangle::new(
        [(10, 30), (w - 10, h - 10)],
        LIGHT.stroke_width(1),
    ))?;
    area.draw_text(title, &font_at(15.0, HPos::Center, VPos::Top), (w / 2, 8))?;
    for (i, line) in lines.iter().enumerate() {
        area.draw_text(
            line,
            &font_at(14.0, HPos::Center, VPos::Center),
            (w / 2, h / 2 - 10 * lines.len() as i32 + 22 * i as i32),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_ticks_are_round_numbers_inside_the_range() {
        let a = Axis::linear(0.03, 0.97, false, "x [mm]");
        assert!(a.range.start < 0.03 && a.range.end > 0.97);
        let labels: Vec<&str> = a.ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        let z = Axis::linear(2.0, 3.0, true, "x");
        assert_eq!(z.range.start, 0.0);
    }

    #[test]
    fn degenerate_and_non_finite_ranges_still_give_an_axis() {
        for (lo, hi) in [
            (1.0, 1.0),
            (0.0, 0.0),
            (f64::NAN, 2.0),
            (f64::NAN, f64::INFINITY),
        ] {
            let a = Axis::linear(lo, hi, false, "x");
            assert!(a.range.end > a.range.start, "{lo} {hi}");
            assert!(
                a.range.start.is_finite() && a.range.end.is_finite(),
                "{lo} {hi}"
            );
            assert!(!a.ticks.is_empty(), "{lo} {hi}");
            let l = Axis::log(lo, hi, "x");
            assert!(
                l.range.end - l.range.start >= MIN_LOG_SPAN - 1e-12,
                "{lo} {hi}"
            );
            assert!(l.ticks.len() >= 2, "{lo} {hi}");
            assert!(!l.ticks.is_empty(), "{lo} {hi}");
        }
    }

    #[test]
    fn log_ticks_read_as_plain_decimals() {
        let a = Axis::log(0.04, 6.0, "e [mm]");
        let labels: Vec<&str> = a.ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0.05", "0.1", "0.2", "0.5", "1", "2", "5"]);
        assert_eq!(a.at(0.1), -1.0);
        let wide = Axis::log(1e-8, 1e3, "s");
        // Only decades on a wide axis.
        assert!(wide.ticks.iter().all(|(_, l)| {
            let v: f64 = l.parse().unwrap();
            (v.log10() - v.log10().round()).abs() < 1e-9
        }));
        assert!(
            wide.ticks.iter().any(|(_, l)| l == "1e-6"),
            "{:?}",
            wide.ticks
        );
    }

    #[test]
    fn no_negative_zero() {
        assert_eq!(number(-0.00001, 2), "0.00");
        assert_eq!(number(-0.5, 1), "-0.5");
    }

    #[test]
    fn sentinels_become_groups() {
        let svg = render("t.svg", "A & B", (100, 50), |area| {
            group(area, Class::Series, "after, fitted", 1, || {
                area.draw(&Circle::new((5, 5), 2, BLUE.filled()))
            })
        })
        .unwrap();
        assert!(svg.contains("<title>A &amp; B</title>"), "{svg}");
        assert!(
            svg.contains("<g class=\"series\" data-name=\"after, fitted\" data-points=\"1\">"),
            "{svg}"
        );
        assert!(!svg.contains(SENTINEL), "{svg}");
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let g = doc
            .descendants()
            .find(|n| n.has_tag_name("g"))
            .expect("group");
        assert_eq!(g.children().filter(|c| c.has_tag_name("circle")).count(), 1);
    }
}
