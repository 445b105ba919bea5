//! Figure 3: the parameter corrections (calibrated − nominal) with ± 2σ
//! bars, lengths (mm) and angles (deg) in panels of their own; fixed
//! parameters as crosses at zero with the reason; the true errors when the
//! arm is simulated.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{frame, header_height};
use crate::calibrate::{Calibration, EstimateRecord};

use crate::params::{DhParams, ParamKind};
use crate::report::svg::{
    Area, Axis, BLUE, Chart, Class, DrawResult, GREEN, GREY, Key, Marker, Shape, WIDTH, chart,
    dashed_across, font, group, render,
};
use crate::report::{Figure, PARAMETERS_SVG, ReportError};

/// The figure's title.
pub(crate) const TITLE: &str =
    "Parameter corrections, calibrated − nominal, with ± 2σ (k = 2) bars";

/// Height of each panel, px.
const PANEL: u32 = 330;

/// The true error of every parameter (truth − nominal, user units),
/// by name.
pub(crate) fn true_errors(
    cal: &Calibration,
    truth: Option<&DhParams>,
) -> Vec<(String, Option<f64>)> {
    let joints = cal.params.joint_count();
    cal.params
        .param_ids()
        .zip(&cal.parameters)
        .map(|(id, p)| {
            let t = truth.filter(|t| t.joint_count() == joints).map(|t| {
                if id.kind == ParamKind::Theta {
                    crate::params::wrap(t.get(id) - p.nominal).to_degrees()
                } else {
                    id.to_user(t.get(id) - p.nominal)
                }
            });
            (id.to_string(), t)
        })
        .collect()
}

/// The short form of a reason to fix a parameter: the words before the
/// first colon (`base motion`, `redundant`, `scale`).
pub(crate) fn short_reason(reason: &str) -> String {
    let head = reason.split(':').next().unwrap_or(reason).trim();
    if head == "fixed by the user" {
        return "user's choice".to_string();
    }
    head.chars().take(18).collect()
}

/// Draws figure 3.
pub(crate) fn figure(cal: &Calibration, truth: Option<&DhParams>) -> Result<Figure, ReportError> {
    let truths = true_errors(cal, truth);
    let has_truth = truths.iter().any(|(_, t)| t.is_some());
    let mut entries = vec![
        (
            Key::Marker(Marker::new(Shape::Dot, BLUE)),
            "correction, free parameter; bar ± 2σ".to_string(),
        ),
        (
            Key::Marker(Marker::new(Shape::Cross, GREY)),
            "fixed at nominal, with the reason".to_string(),
        ),
    ];
    if has_truth {
        entries.push((
            Key::Marker(Marker::new(Shape::Ring, GREEN)),
            "true error of the simulated arm (truth − nominal)".to_string(),
        ));
    }
    let lengths: Vec<usize> = (0..cal.parameters.len())
        .filter(|&i| cal.parameters[i].id.kind.is_length())
        .collect();
    let angles: Vec<usize> = (0..cal.parameters.len())
        .filter(|&i| !cal.parameters[i].id.kind.is_length())
        .collect();
    let height = header_height(&entries) + 2 * PANEL;
    let svg = render(PARAMETERS_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let (top, bottom) = area.split_vertically(PANEL);
        panel(
            &top,
            cal,
            &truths,
            &lengths,
            "lengths a, d, B",
            "correction [mm]",
        )?;
        panel(
            &bottom,
            cal,
            &truths,
            &angles,
            "angles alpha (twist), theta (zero offset)",
            "correction [deg]",
        )
    })?;
    Ok(Figure {
        file: PARAMETERS_SVG,
        title: TITLE.to_string(),
        svg,
    })
}

/// One panel: the parameters `which` (indices into `cal.parameters`).
fn panel(
    area: &Area,
    cal: &Calibration,
    truths: &[(String, Option<f64>)],
    which: &[usize],
    title: &str,
    y_desc: &str,
) -> DrawResult {
    let params: Vec<EstimateRecord> = which.iter().map(|&i| cal.parameters[i].user()).collect();
    let names: Vec<String> = params.iter().map(|p| p.name.clone()).collect();
    let (lo, hi) = value_range(&params, truths, which);
    // Room above for the reasons of fixed parameters.
    let span = (hi - lo).max(1e-6);
    let x = Axis::categories(&names, 40, "parameter");
    let y = Axis::linear(lo - 0.12 * span, hi + 0.25 * span, true, y_desc);
    let mut chart = chart(area, title, &x, &y, 72)?;
    group(area, Class::Guide, "zero", 1, || {
        dashed_across(&mut chart, &x, 0.0, GREY, 1)
    })?;
    let free: Vec<(usize, &EstimateRecord)> = params
        .iter()
        .enumerate()
        .filter(|(_, p)| p.fixed.is_none())
        .collect();
    let fixed: Vec<(usize, &EstimateRecord)> = params
        .iter()
        .enumerate()
        .filter(|(_, p)| p.fixed.is_some())
        .collect();
    group(area, Class::Series, "free corrections", free.len(), || {
        free_corrections(&mut chart, &free)
    })?;
    group(area, Class::Series, "fixed parameters", fixed.len(), || {
        fixed_parameters(&mut chart, &fixed, truths, which)
    })?;
    let known: Vec<(usize, f64)> = which
        .iter()
        .enumerate()
        .filter_map(|(k, &i)| truths[i].1.map(|t| (k, t)))
        .collect();
    if !known.is_empty() {
        group(area, Class::Series, "true errors", known.len(), || {
            chart.draw_series(
                known
                    .iter()
                    .map(|(k, t)| Marker::new(Shape::Ring, GREEN).at((*k as f64, *t))),
            )?;
            Ok(())
        })?;
    }
    Ok(())
}

/// The half-length of a parameter's error bar, 2σ, where σ is finite.
fn bar(p: &EstimateRecord) -> Option<f64> {
    p.sigma.filter(|s| s.is_finite()).map(|s| 2.0 * s)
}

/// The range the panel of `params` (the parameters `which`) must show:
/// zero, every correction with its bar, every known true error.
fn value_range(
    params: &[EstimateRecord],
    truths: &[(String, Option<f64>)],
    which: &[usize],
) -> (f64, f64) {
    let mut lo = 0.0f64;
    let mut hi = 0.0f64;
    for (k, p) in params.iter().enumerate() {
        let b = bar(p).unwrap_or(0.0);
        for v in [p.correction - b, p.correction + b]
            .into_iter()
            .chain(truths[which[k]].1)
        {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    (lo, hi)
}

/// The free parameters (with their column): a dot at the correction and
/// its ± 2σ bar.
fn free_corrections(chart: &mut Chart, free: &[(usize, &EstimateRecord)]) -> DrawResult {
    for (i, p) in free {
        let xi = *i as f64;
        if let Some(b) = bar(p) {
            let style = BLUE.stroke_width(2);
            let (c0, c1) = (p.correction - b, p.correction + b);
            chart.draw_series([
                PathElement::new(vec![(xi, c0), (xi, c1)], style),
                PathElement::new(vec![(xi - 0.18, c0), (xi + 0.18, c0)], style),
                PathElement::new(vec![(xi - 0.18, c1), (xi + 0.18, c1)], style),
            ])?;
        }
        chart.draw_series(std::iter::once(
            Marker::new(Shape::Dot, BLUE).at((xi, p.correction)),
        ))?;
    }
    Ok(())
}

/// The fixed parameters (with their column): a cross at the correction
/// and the short reason they were fixed.
fn fixed_parameters(
    chart: &mut Chart,
    fixed: &[(usize, &EstimateRecord)],
    truths: &[(String, Option<f64>)],
    which: &[usize],
) -> DrawResult {
    // The reason runs away from the true error, so that they do not
    // overlap: up from the cross, or down when the truth lies above.
    let up = font(11.5)
        .color(&GREY)
        .transform(FontTransform::Rotate270)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let down = font(11.5)
        .color(&GREY)
        .transform(FontTransform::Rotate90)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (i, p) in fixed {
        let xi = *i as f64;
        chart.draw_series(std::iter::once(
            Marker::new(Shape::Cross, GREY).at((xi, p.correction)),
        ))?;
        let reason = short_reason(p.fixed.as_deref().unwrap_or(""));
        let truth_above = truths[which[*i]].1.is_some_and(|t| t > p.correction);
        let (offset, style) = if truth_above {
            ((0, 10), down.clone())
        } else {
            ((0, -10), up.clone())
        };
        chart.draw_series(std::iter::once(
            EmptyElement::at((xi, p.correction)) + Text::new(reason, offset, style),
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::short_reason;

    #[test]
    fn reasons_are_shortened_to_their_head() {
        assert_eq!(
            short_reason("base motion: never identifiable"),
            "base motion"
        );
        assert_eq!(short_reason("redundant: ∂p/∂alpha6 = …"), "redundant");
        assert_eq!(short_reason("fixed by the user"), "user's choice");
    }
}
