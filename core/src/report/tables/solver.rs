//! The solver section: how it stopped, the degrees of freedom, and each
//! phase's, the annealing's and the global search's figures.

use super::{Cell, evidence_noun, table};
use crate::calibrate::Calibration;

/// The solver summary.
pub(crate) fn solver(cal: &Calibration, json: Option<&str>) -> String {
    let sb = json.map(|j| format!("{j}/solver"));
    let db = json.map(|j| format!("{j}/dof"));
    let mut rows = solver_rows(cal, sb.as_deref());
    rows.extend(dof_rows(cal, db.as_deref()));
    rows.extend(phase_rows(cal));
    rows.extend(anneal_rows(cal, sb.as_deref()));
    rows.extend(global_rows(cal));
    table("Solver", &["figure", "value"], &rows)
}

/// A row of the solver table: a figure's name and its value.
fn figure_row(name: &str, c: Cell) -> (String, Vec<Cell>) {
    (String::new(), vec![Cell::text(name), c])
}

/// How the solver stopped and what it evaluated (`sb`: the solver's JSON
/// Pointer).
fn solver_rows(cal: &Calibration, sb: Option<&str>) -> Vec<(String, Vec<Cell>)> {
    let s = &cal.solver;
    vec![
        figure_row("method", Cell::text(s.method.name())),
        figure_row("stopped", Cell::text(&s.stop.describe())),
        figure_row(
            "converged",
            Cell::text(if s.successful { "yes" } else { "no" }),
        ),
        figure_row(
            "iterations of the final LM",
            Cell::int(s.iterations).at(sb, "iterations", s.iterations as f64),
        ),
        figure_row(
            "cost evaluations (positions only)",
            Cell::int(s.cost_evaluations).at(sb, "cost_evaluations", s.cost_evaluations as f64),
        ),
        figure_row(
            "Jacobian evaluations",
            Cell::int(s.jacobian_evaluations).at(
                sb,
                "jacobian_evaluations",
                s.jacobian_evaluations as f64,
            ),
        ),
        figure_row(
            "cost Σr² of the start arm (final weights)",
            Cell::sci(s.initial_cost, 6).at(sb, "initial_cost", s.initial_cost),
        ),
        figure_row(
            "cost Σr² at the end",
            Cell::sci(s.final_cost, 6).at(sb, "final_cost", s.final_cost),
        ),
    ]
}

/// The residual rows, the unknowns and the σ behind the weights (`db`:
/// the dof's JSON Pointer).
fn dof_rows(cal: &Calibration, db: Option<&str>) -> Vec<(String, Vec<Cell>)> {
    let d = &cal.dof;
    let others: Vec<String> = (d.other_rows.iter())
        .map(|r| format!("{} {}", r.term, r.rows))
        .collect();
    // A row per kind of evidence present: the touch rows only with touches.
    let touches = d.touch_rows > 0 || d.length_rows > 0;
    let mut rows = if touches {
        vec![
            figure_row(
                "residual rows: touches (3 each) + lengths",
                Cell::text(&format!("{} + {}", d.touch_rows, d.length_rows)),
            ),
            figure_row(
                "unknowns: free parameters + centre coordinates",
                Cell::text(&format!("{} + {}", d.free_parameters, d.centre_coordinates)),
            ),
        ]
    } else {
        vec![
            figure_row("residual rows", Cell::text(&others.join(", "))),
            figure_row(
                "unknowns: free parameters (the frames' included)",
                Cell::int(d.free_parameters),
            ),
        ]
    };
    if touches && !others.is_empty() {
        rows.insert(
            1,
            figure_row("other residual rows", Cell::text(&others.join(", "))),
        );
    }
    rows.extend([
        figure_row(
            "degrees of freedom m − p",
            Cell::int(d.degrees_of_freedom).at(
                db,
                "degrees_of_freedom",
                d.degrees_of_freedom as f64,
            ),
        ),
        figure_row(
            "σ̂0 = sqrt(cost / (m − p))",
            Cell::num(d.sigma0, 4).at(db, "sigma0", d.sigma0),
        ),
        figure_row(
            &format!("{} σ behind the weights [mm]", evidence_noun(cal, touches)),
            Cell::num(d.touch_sigma_mm, 4).at(db, "touch_sigma_mm", d.touch_sigma_mm),
        ),
    ]);
    rows
}

/// The evaluations of each phase.
fn phase_rows(cal: &Calibration) -> Vec<(String, Vec<Cell>)> {
    cal.solver
        .phases
        .iter()
        .map(|p| {
            figure_row(
                &format!("phase {}", p.name),
                Cell::text(&format!(
                    "{} cost, {} Jacobian evaluations",
                    p.cost_evaluations, p.jacobian_evaluations
                )),
            )
        })
        .collect()
}

/// The annealing's settings and result, if it ran (`sb`: the solver's
/// JSON Pointer).
fn anneal_rows(cal: &Calibration, sb: Option<&str>) -> Vec<(String, Vec<Cell>)> {
    let Some(a) = &cal.solver.anneal else {
        return Vec::new();
    };
    let ab = sb.map(|b| format!("{b}/anneal"));
    let ab = ab.as_deref();
    let o = &a.options;
    vec![
        figure_row(
            "annealing settings",
            Cell::text(&format!(
                "T0 {} mm, cooling {}, chain {}, T_min {} mm, target {} mm",
                o.t0, o.cooling, o.chain, o.t_min, o.target
            )),
        ),
        figure_row(
            "annealing energy at the start [mm]",
            Cell::num(a.start_energy, 4).at(ab, "start_energy", a.start_energy),
        ),
        figure_row(
            "annealing best energy [mm]",
            Cell::num(a.best_energy, 4).at(ab, "best_energy", a.best_energy),
        ),
        figure_row(
            "annealing evaluations",
            Cell::int(a.evaluations).at(ab, "evaluations", a.evaluations as f64),
        ),
        figure_row("annealing stopped", Cell::text(a.stop.describe())),
    ]
}

/// The global search's starts and stop, if it ran.
fn global_rows(cal: &Calibration) -> Vec<(String, Vec<Cell>)> {
    let Some(g) = &cal.solver.global else {
        return Vec::new();
    };
    let mut rows = vec![
        figure_row(
            "global: starts, lowest reached",
            Cell::text(&format!("{}, {} times", g.minima.len(), g.best_hits)),
        ),
        figure_row("global stopped", Cell::text(g.stop.describe())),
    ];
    if !g.sign_changes.is_empty() {
        rows.push(figure_row(
            "signs put in the nominal convention",
            Cell::text(&g.sign_changes.join(", ")),
        ));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::TermRows;
    use crate::report::tables::fixture;

    #[test]
    fn how_the_solver_stopped_and_the_touch_rows() {
        let cal = &fixture::case().cal;
        let t = solver(cal, Some("/calibration"));
        assert!(t.contains("<tr><td>method</td><td>lm</td></tr>"), "{t}");
        assert!(
            t.contains(&format!(
                "<tr><td>iterations of the final LM</td><td class=\"n\" \
                 data-json=\"/calibration/solver/iterations\" data-value=\"{:?}\">{}</td>",
                cal.solver.iterations as f64, cal.solver.iterations
            )),
            "{t}"
        );
        let d = &cal.dof;
        assert!(
            t.contains(&format!(
                "<tr><td>residual rows: touches (3 each) + lengths</td><td>{} + {}</td></tr>",
                d.touch_rows, d.length_rows
            )),
            "{t}"
        );
        assert!(t.contains("data-json=\"/calibration/dof/sigma0\""), "{t}");
        assert!(
            t.contains("<tr><td>touch σ behind the weights [mm]</td>"),
            "{t}"
        );
        // LM alone: neither annealing nor a global search.
        assert!(!t.contains("annealing") && !t.contains("global"), "{t}");
        let others = usize::from(!d.other_rows.is_empty());
        let phases = cal.solver.phases.len();
        assert_eq!(fixture::rows(&t), 1 + 8 + 5 + others + phases, "{t}");
    }

    #[test]
    fn without_touches_the_rows_are_the_terms() {
        let mut cal = fixture::case().cal.clone();
        cal.dof.touch_rows = 0;
        cal.dof.length_rows = 0;
        cal.dof.other_rows = vec![
            TermRows {
                term: "positions".into(),
                rows: 30,
                eliminated: 6,
            },
            TermRows {
                term: "orientations".into(),
                rows: 9,
                eliminated: 0,
            },
        ];
        let t = solver(&cal, None);
        assert!(
            t.contains("<tr><td>residual rows</td><td>positions 30, orientations 9</td></tr>"),
            "{t}"
        );
        assert!(
            t.contains("<td>unknowns: free parameters (the frames&#39; included)</td>"),
            "{t}"
        );
        assert!(
            t.contains("<td>position σ behind the weights [mm]</td>"),
            "{t}"
        );
        assert!(!t.contains("touches (3 each)"), "{t}");
        assert!(!t.contains("data-json"), "{t}");
    }
}
