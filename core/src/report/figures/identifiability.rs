//! Figure 4: identifiability. Left: the singular values of the scaled
//! Jacobian on a log scale with the rank threshold. Right: the correlation
//! matrix of the free parameters as a heat map.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{frame, header_height, short};
use crate::calibrate::Calibration;
use crate::identify::Identification;
use crate::report::svg::{
    Area, Axis, BLUE, Class, DrawResult, GREY, INK, Key, Marker, PURPLE, Shape, WIDTH, chart,
    dashed_across, font, font_at, group, message, render,
};
use crate::report::{Figure, IDENTIFIABILITY_SVG, ReportError};

/// The figure's title.
pub(crate) const TITLE: &str = "Identifiability: singular values of the scaled Jacobian, and correlations of the free parameters";

/// Height of the panels, px.
const PANEL: u32 = 470;

/// Negative correlation (ColorBrewer RdBu end).
const NEG: RGBColor = RGBColor(0x21, 0x66, 0xAC);
/// Positive correlation.
const POS: RGBColor = RGBColor(0xB2, 0x18, 0x2B);

/// The colour of `rho` on the diverging scale white (0) to red (+1) and
/// blue (−1).
pub(crate) fn rho_color(rho: f64) -> RGBColor {
    let t = if rho.is_finite() {
        rho.abs().min(1.0)
    } else {
        0.0
    };
    let end = if rho < 0.0 { NEG } else { POS };
    let mix = |w: u8, e: u8| (f64::from(w) + (f64::from(e) - f64::from(w)) * t).round() as u8;
    RGBColor(mix(255, end.0), mix(255, end.1), mix(255, end.2))
}

/// Draws figure 4.
pub(crate) fn figure(cal: &Calibration) -> Result<Figure, ReportError> {
    let id = cal.identification.as_ref();
    let mut entries = Vec::new();
    if let Some(id) = id {
        entries.push((
            Key::Marker(Marker::new(Shape::Dot, GREY)),
            format!("all {} columns", id.singular_values.len()),
        ));
        entries.push((
            Key::Marker(Marker::new(Shape::Dot, BLUE)),
            "after the structural rules (analysed)".to_string(),
        ));
        entries.push((
            Key::Line(PURPLE, 2, true),
            format!("rank threshold {} (rank {})", short(id.threshold), id.rank),
        ));
    }
    let height = header_height(&entries) + PANEL;
    let svg = render(IDENTIFIABILITY_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let (left, right) = area.split_horizontally(WIDTH / 2 - 20);
        match id {
            Some(id) => singular_panel(&left, id)?,
            None => message(
                &left,
                "Singular values",
                &[
                    "The fixed set was given (--fix NAMES):",
                    "no identifiability analysis ran.",
                    "`aacmm identify` gives it.",
                ],
            )?,
        }
        heat_map(&right, cal)
    })?;
    Ok(Figure {
        file: IDENTIFIABILITY_SVG,
        title: TITLE.to_string(),
        svg,
    })
}

/// Singular values, descending, against their index; zeros drawn at the
/// axis floor.
fn singular_panel(area: &Area, id: &Identification) -> DrawResult {
    let all = &id.singular_values;
    let analysed = &id.analysed_singular_values;
    let positive = all
        .iter()
        .chain(analysed)
        .chain(std::iter::once(&id.threshold))
        .filter(|v| **v > 0.0 && v.is_finite());
    let (lo, hi) = positive.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(*v), b.max(*v))
    });
    let n = all.len().max(analysed.len()).max(1);
    let labels: Vec<String> = (1..=n).map(|i| i.to_string()).collect();
    let x = Axis::categories(&labels, 14, "index (descending)");
    let y = Axis::log(
        lo,
        hi,
        "singular value of the weighted, scaled Jacobian, log scale",
    );
    let mut chart = chart(
        area,
        &format!(
            "rank {} of {} (condition number {})",
            id.rank,
            analysed.len(),
            short(id.condition_number)
        ),
        &x,
        &y,
        64,
    )?;
    group(area, Class::Guide, "rank threshold", 1, || {
        let t = y.at(id.threshold);
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x.range.start, y.range.start), (x.range.end, t)],
            PURPLE.mix(0.08).filled(),
        )))?;
        dashed_across(&mut chart, &x, t, PURPLE, 2)
    })?;
    for (name, values, color, dx) in [
        ("all columns", all, GREY, -0.12),
        ("analysed", analysed, BLUE, 0.12),
    ] {
        group(area, Class::Series, name, values.len(), || {
            chart.draw_series(values.iter().enumerate().map(|(i, s)| {
                let shape = if *s > 0.0 {
                    Shape::Dot
                } else {
                    Shape::Triangle
                };
                Marker::new(shape, color).at((i as f64 + dx, y.at(*s)))
            }))?;
            Ok(())
        })?;
    }
    let (px, py) = chart.backend_coord(&(x.range.end, y.at(id.threshold)));
    let base = area.get_base_pixel();
    area.draw_text(
        "unidentifiable (▲ = exactly 0, drawn at the floor)",
        &font_at(11.5, HPos::Right, VPos::Top).color(&PURPLE),
        (px - base.0 - 6, py - base.1 + 4),
    )?;
    Ok(())
}

/// The correlation matrix as a heat map, with a colour bar.
fn heat_map(area: &Area, cal: &Calibration) -> DrawResult {
    let m = &cal.correlation_matrix;
    let names: Vec<String> = m.parameters.iter().map(|id| id.to_string()).collect();
    let p = names.len();
    let title = "correlation ρ of the free parameters";
    if p == 0 {
        return message(area, title, &["No free parameters."]);
    }
    let (map, bar) = area.split_horizontally(area.dim_in_pixel().0 - 70);
    let x = Axis::categories(&names, 40, "");
    let reversed: Vec<String> = names.iter().rev().cloned().collect();
    let y = Axis::categories(&reversed, 40, "");
    let mut chart = ChartBuilder::on(&map)
        .margin_top(6)
        .margin_right(4)
        .caption(title, font(15.0))
        .x_label_area_size(58)
        .y_label_area_size(58)
        .build_cartesian_2d(x.coord(), y.coord())?;
    let fx = |v: &f64| label_of(&names, *v);
    let fy = |v: &f64| label_of(&reversed, *v);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_label_style(
            font(11.0)
                .transform(FontTransform::Rotate90)
                .pos(Pos::new(HPos::Left, VPos::Center)),
        )
        .y_label_style(font(11.0))
        .axis_style(INK.stroke_width(1))
        .draw()?;
    group(area, Class::Series, "correlation cells", p * p, || {
        chart.draw_series(m.rho.iter().enumerate().flat_map(|(a, row)| {
            row.iter().enumerate().map(move |(b, r)| {
                let (cx, cy) = (b as f64, (p - 1 - a) as f64);
                Rectangle::new(
                    [(cx - 0.5, cy - 0.5), (cx + 0.5, cy + 0.5)],
                    rho_color(*r).filled(),
                )
            })
        }))?;
        Ok(())
    })?;
    // |ρ| > 0.9 off the diagonal, written in the cell.
    let strong: Vec<(usize, usize, f64)> = m
        .rho
        .iter()
        .enumerate()
        .flat_map(|(a, row)| {
            row.iter()
                .enumerate()
                .filter(move |(b, r)| *b != a && r.abs() > 0.9)
                .map(move |(b, r)| (a, b, *r))
        })
        .collect();
    group(area, Class::Guide, "|rho| > 0.9", strong.len(), || {
        let style = font_at(9.0, HPos::Center, VPos::Center).color(&WHITE);
        chart.draw_series(strong.iter().map(|(a, b, r)| {
            Text::new(
                format!("{r:.2}"),
                (*b as f64, (p - 1 - a) as f64),
                style.clone(),
            )
        }))?;
        Ok(())
    })?;
    colour_bar(&bar)
}

/// The label of category `v` among `names` (empty between categories).
fn label_of(names: &[String], v: f64) -> String {
    let i = v.round();
    if (v - i).abs() > 1e-6 || i < 0.0 {
        return String::new();
    }
    names.get(i as usize).cloned().unwrap_or_default()
}

/// A vertical colour bar from −1 (bottom) to +1 (top).
fn colour_bar(area: &Area) -> DrawResult {
    let (_, h) = area.dim_in_pixel();
    let (top, bottom) = (40i32, h as i32 - 64);
    let steps = 40;
    for k in 0..steps {
        let r0 = 1.0 - 2.0 * k as f64 / steps as f64;
        let y0 = top + (bottom - top) * k / steps;
        let y1 = top + (bottom - top) * (k + 1) / steps;
        area.draw(&Rectangle::new(
            [(10, y0), (26, y1)],
            rho_color(r0 - 1.0 / steps as f64).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(10, top), (26, bottom)],
        INK.stroke_width(1),
    ))?;
    for (v, label) in [
        (1.0, "+1"),
        (0.5, "0.5"),
        (0.0, "0"),
        (-0.5, "−0.5"),
        (-1.0, "−1"),
    ] {
        let y = top + ((1.0 - v) / 2.0 * (bottom - top) as f64).round() as i32;
        area.draw(&PathElement::new(
            vec![(26, y), (30, y)],
            INK.stroke_width(1),
        ))?;
        area.draw_text(label, &font_at(11.5, HPos::Left, VPos::Center), (32, y))?;
    }
    area.draw_text(
        "ρ",
        &font_at(13.0, HPos::Center, VPos::Bottom),
        (18, top - 6),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diverging_colours() {
        assert_eq!(rho_color(0.0), RGBColor(255, 255, 255));
        assert_eq!(rho_color(1.0), POS);
        assert_eq!(rho_color(-1.0), NEG);
        assert_eq!(rho_color(f64::NAN), RGBColor(255, 255, 255));
    }
}
