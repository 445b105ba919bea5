//! Figure 6: the solver's progress. Left: the LM cost `Σr²` per iteration
//! of the final fit, with the cost a fit with right weights ends at
//! (`m − p`, σ̂0 = 1). Right: for the annealing methods, the energy (the
//! paper's OA) against the temperature, and the share of moves accepted;
//! for `global`, the cost of every start's minimum.

use plotters::prelude::*;

use super::{frame, header_height};
use crate::calibrate::{AnnealTrace, Calibration, GlobalTrace, SolverSummary};
use crate::report::svg::{
    Area, Axis, BLUE, Class, DrawResult, GREEN, GREY, Key, Marker, PURPLE, Shape, VERMILLION,
    WIDTH, chart, dashed_across, group, message, render,
};
use crate::report::{Figure, ReportError, SOLVER_SVG};

/// The figure's title.
pub(crate) const TITLE: &str = "Solver progress";

/// Height of the panels, px.
const PANEL: u32 = 420;

/// Draws figure 6.
pub(crate) fn figure(cal: &Calibration) -> Result<Figure, ReportError> {
    let s = &cal.solver;
    let dof = cal.dof.degrees_of_freedom as f64;
    let mut entries = vec![
        (
            Key::Marker(Marker::new(Shape::Dot, BLUE)),
            "LM: cost Σr² after an accepted step (0: the start arm)".to_string(),
        ),
        (
            Key::Marker(Marker::new(Shape::Cross, PURPLE)),
            "LM: rejected step (damping raised)".to_string(),
        ),
        (
            Key::Line(GREEN, 2, true),
            format!("m − p = {} (σ̂0 = 1)", cal.dof.degrees_of_freedom),
        ),
    ];
    if s.anneal.is_some() {
        entries.push((
            Key::Line(GREY, 2, false),
            "annealing: energy after each chain".to_string(),
        ));
        entries.push((
            Key::Line(VERMILLION, 2, false),
            "annealing: best energy so far".to_string(),
        ));
    } else if s.global.is_some() {
        entries.push((
            Key::Marker(Marker::new(Shape::Dot, GREY)),
            "global: cost of each start's minimum".to_string(),
        ));
        entries.push((
            Key::Marker(Marker::new(Shape::Dot, VERMILLION)),
            "global: the lowest".to_string(),
        ));
        if s.global
            .as_ref()
            .is_some_and(|g| g.noise_floor_cost.is_some())
        {
            entries.push((
                Key::Line(PURPLE, 1, true),
                "global: the noise floor (a fit there stops the search)".to_string(),
            ));
        }
    }
    let height = header_height(&entries) + PANEL;
    let svg = render(SOLVER_SVG, TITLE, (WIDTH, height), |root| {
        let area = frame(root, TITLE, &entries)?;
        let right = s.anneal.is_some() || s.global.is_some();
        if right {
            let (left, right) = area.split_horizontally(WIDTH / 2);
            lm_panel(&left, s, dof)?;
            match (&s.anneal, &s.global) {
                (Some(a), _) => anneal_panel(&right, a),
                (None, Some(g)) => global_panel(&right, g, dof),
                (None, None) => Ok(()),
            }
        } else {
            lm_panel(&area, s, dof)
        }
    })?;
    Ok(Figure {
        file: SOLVER_SVG,
        title: TITLE.to_string(),
        svg,
    })
}

/// The final LM fit's cost per iteration.
fn lm_panel(area: &Area, s: &SolverSummary, dof: f64) -> DrawResult {
    let title = format!(
        "{}: final LM fit, {} iterations",
        s.method.name(),
        s.history.len()
    );
    if s.history.is_empty() {
        return message(
            area,
            &title,
            &["No LM iteration ran", &format!("({}).", s.stop.describe())],
        );
    }
    let mut accepted = vec![(0usize, s.initial_cost)];
    accepted.extend(
        s.history
            .iter()
            .filter(|h| h.accepted)
            .map(|h| (h.iteration, h.cost)),
    );
    let rejected: Vec<(usize, f64)> = s
        .history
        .iter()
        .filter(|h| !h.accepted)
        .map(|h| (h.iteration, h.cost))
        .collect();
    let costs = accepted
        .iter()
        .chain(&rejected)
        .map(|(_, c)| *c)
        .chain(std::iter::once(dof));
    let (lo, hi) = costs
        .filter(|c| *c > 0.0 && c.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
            (a.min(c), b.max(c))
        });
    let last = s.history.last().map_or(0, |h| h.iteration);
    let labels: Vec<String> = (0..=last).map(|i| i.to_string()).collect();
    let x = Axis::categories(&labels, 12, "LM iteration");
    let y = Axis::log(lo, hi, "cost Σr² (weighted, dimensionless), log scale");
    let mut chart = chart(area, &title, &x, &y, 64)?;
    group(area, Class::Guide, "m − p", 1, || {
        dashed_across(&mut chart, &x, y.at(dof), GREEN, 2)
    })?;
    group(area, Class::Series, "accepted", accepted.len(), || {
        chart.draw_series(std::iter::once(PathElement::new(
            accepted
                .iter()
                .map(|(i, c)| (*i as f64, y.at(*c)))
                .collect::<Vec<_>>(),
            BLUE.stroke_width(2),
        )))?;
        chart.draw_series(
            accepted
                .iter()
                .map(|(i, c)| Marker::new(Shape::Dot, BLUE).at((*i as f64, y.at(*c)))),
        )?;
        Ok(())
    })?;
    group(area, Class::Series, "rejected", rejected.len(), || {
        chart.draw_series(
            rejected
                .iter()
                .map(|(i, c)| Marker::new(Shape::Cross, PURPLE).at((*i as f64, y.at(*c)))),
        )?;
        Ok(())
    })
}

/// Energy and acceptance against temperature, temperature falling to the
/// right.
fn anneal_panel(area: &Area, a: &AnnealTrace) -> DrawResult {
    let title = format!(
        "annealing: {} temperatures, {} evaluations",
        a.temperatures.len(),
        a.evaluations
    );
    if a.temperatures.is_empty() {
        return message(area, "annealing", &["No temperature completed."]);
    }
    let (energy_area, accept_area) = area.split_vertically(area.dim_in_pixel().1 * 64 / 100);
    let (t0, t1) = a
        .temperatures
        .iter()
        .map(|t| t.temperature)
        .filter(|t| *t > 0.0 && t.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
            (lo.min(t), hi.max(t))
        });
    let x = Axis::log(t0, t1, "temperature T [mm] (falling →), log scale").reversed();
    let (e0, e1) = a
        .temperatures
        .iter()
        .flat_map(|t| [t.energy, t.best])
        .chain([a.start_energy])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| {
            (lo.min(e), hi.max(e))
        });
    let y = Axis::linear(e0, e1, false, "energy OA = e + 3σ [mm]");
    let mut chart = chart(&energy_area, &title, &x, &y, 64)?;
    let line = |f: fn(&crate::calibrate::AnnealStep) -> f64| -> Vec<(f64, f64)> {
        a.temperatures
            .iter()
            .map(|t| (x.at(t.temperature), f(t)))
            .collect()
    };
    let n = a.temperatures.len();
    group(area, Class::Series, "energy", n, || {
        let pts = line(|t| t.energy);
        chart.draw_series(std::iter::once(PathElement::new(
            pts.clone(),
            GREY.stroke_width(2),
        )))?;
        chart.draw_series(pts.iter().map(|p| {
            Marker {
                size: 2,
                ..Marker::new(Shape::Dot, GREY)
            }
            .at(*p)
        }))?;
        Ok(())
    })?;
    group(area, Class::Series, "best energy", n, || {
        chart.draw_series(std::iter::once(PathElement::new(
            line(|t| t.best),
            VERMILLION.stroke_width(2),
        )))?;
        Ok(())
    })?;
    let top = a
        .temperatures
        .iter()
        .map(|t| 100.0 * t.acceptance)
        .fold(1.0, f64::max);
    let accept = Axis::linear(0.0, top, true, "moves accepted [%]");
    let mut lower = chart_only(&accept_area, &x, &accept)?;
    group(area, Class::Series, "acceptance", n, || {
        lower.draw_series(a.temperatures.iter().map(|t| {
            let (xc, v) = (x.at(t.temperature), 100.0 * t.acceptance);
            PathElement::new(vec![(xc, 0.0), (xc, v)], GREY.stroke_width(4))
        }))?;
        Ok(())
    })
}

/// A chart without a title, for a panel under another.
fn chart_only<'a, 'b>(
    area: &'a Area<'b>,
    x: &Axis,
    y: &Axis,
) -> DrawResult<crate::report::svg::Chart<'a, 'b>> {
    chart(area, "", x, y, 64)
}

/// The cost of every start's minimum (`global`).
fn global_panel(area: &Area, g: &GlobalTrace, dof: f64) -> DrawResult {
    let plural =
        |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    let title = format!(
        "global: {}, the lowest reached {}",
        plural(g.minima.len(), "start", "starts"),
        plural(g.best_hits, "time", "times")
    );
    if g.minima.is_empty() {
        return message(area, "global", &["No start finished."]);
    }
    let best = g.minima.iter().copied().fold(f64::INFINITY, f64::min);
    let (lo, hi) = g
        .minima
        .iter()
        .copied()
        .chain([dof])
        .chain(g.noise_floor_cost)
        .filter(|c| *c > 0.0 && c.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
            (a.min(c), b.max(c))
        });
    let labels: Vec<String> = (1..=g.minima.len()).map(|i| i.to_string()).collect();
    let x = Axis::categories(&labels, 16, "start (1 = from the start arm)");
    let y = Axis::log(
        lo,
        hi,
        "cost Σr² at the start's minimum (dimensionless), log scale",
    );
    let mut chart = chart(area, &title, &x, &y, 64)?;
    if let Some(floor) = g.noise_floor_cost {
        group(area, Class::Guide, "noise floor", 1, || {
            dashed_across(&mut chart, &x, y.at(floor), PURPLE, 1)
        })?;
    }
    group(area, Class::Series, "minima", g.minima.len(), || {
        chart.draw_series(g.minima.iter().enumerate().map(|(i, c)| {
            let color = if *c == best { VERMILLION } else { GREY };
            Marker::new(Shape::Dot, color).at((i as f64, y.at(*c)))
        }))?;
        Ok(())
    })
}
