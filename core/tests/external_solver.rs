//! The `Solver` trait is open: a solver written outside the library
//! evaluates the task's objective (its cost, its normal equations over the
//! free columns, its local update) and returns its minimum; the library
//! assesses it as it does its own (weights at the solution, covariance,
//! verdict, validation).

use std::sync::Mutex;

#[path = "common/shipped.rs"]
mod shipped;
use shipped::{shipped, stated_noise};

use aacmm_core::calibrate::{
    CalibrationError, Context, Lm, Method, Outcome, Phase, Solver, SolverSettings, Stop, Task,
};
use aacmm_core::session::{Problem, run};
use nalgebra::{DMatrix, DVector};

/// Gauss–Newton with step halving: the least a solver needs of the
/// objective.
struct GaussNewton;

impl Solver for GaussNewton {
    fn method(&self) -> Method {
        Method::External
    }

    fn solve(
        &self,
        task: Task<'_, '_>,
        _ctx: &mut Context<'_>,
    ) -> Result<Outcome, CalibrationError> {
        let (objective, free) = (task.objective, task.free);
        let p = free.len();
        let mut x = task.x.to_vec();
        let mut scratch = Vec::new();
        let mut cost = objective.cost(&x, free, &mut scratch)?;
        let mut converged = false;
        for _ in 0..100 {
            let normal = objective.normal(&x, free)?;
            let n = DMatrix::from_fn(p, p, |a, b| normal.jtj_entry(a, b));
            let g = DVector::from_fn(p, |a, _| normal.gradient(a));
            let Some(step) = n.cholesky().map(|ch| -ch.solve(&g)) else {
                break;
            };
            let mut scale = 1.0;
            let accepted = loop {
                let delta: Vec<f64> = step.iter().map(|d| d * scale).collect();
                let trial = objective.plus(&x, free, &delta);
                let c = objective.cost(&trial, free, &mut scratch)?;
                if c <= cost {
                    break Some((trial, c));
                }
                scale /= 2.0;
                if scale < 1e-6 {
                    break None;
                }
            };
            let Some((trial, c)) = accepted else {
                converged = true;
                break;
            };
            let reduction = cost - c;
            (x, cost) = (trial, c);
            if reduction <= 1e-12 * cost {
                converged = true;
                break;
            }
        }
        Outcome::at(&task, x, Stop::External { converged })
    }
}

#[test]
fn a_solver_of_another_crate_calibrates_through_the_session() {
    let (arm, data) = shipped();
    let model = stated_noise();
    let problem = Problem::new(arm, data, model)
        .unwrap()
        .with_cross_validation(3)
        .unwrap();
    let settings = SolverSettings::default().with_method(Method::Lm);
    let ours = run(&problem, &settings, &GaussNewton, &mut Context::new()).unwrap();
    let lm = problem.run(&settings).unwrap();
    let c = &ours.calibration;
    assert_eq!(c.solver.method, Method::External);
    assert!(ours.is_usable(), "{:?}", ours.verdict);
    // The same minimum: every free parameter within a hundredth of its σ
    // of LM's (the library refits under the weights at the solution, so
    // both end on its LM polish or within tolerance of it).
    for (a, b) in c.parameters.iter().zip(&lm.calibration.parameters) {
        let Some(sigma) = b.sigma else { continue };
        assert!(
            (a.calibrated - b.calibrated).abs() < 0.01 * sigma,
            "{}: {} vs {} (σ {sigma})",
            a.id,
            a.calibrated,
            b.calibrated
        );
    }
    // The folds ran with the same solver.
    let folds = &ours.validation.cross_validation.as_ref().unwrap().folds;
    assert_eq!(folds.len(), 3);
    assert!(folds.iter().all(|f| f.successful));
    // It cannot be asked for by name: the library has no such solver.
    let named = problem.run(&settings.with_method(Method::External));
    match named {
        Err(CalibrationError::Option(e)) => assert_eq!(e.field(), "method"),
        other => panic!("an external method ran by name: {:?}", other.map(|_| ())),
    }
}

/// A solver that wraps the library's LM and reports on it, as a timing or
/// logging wrapper in another crate would: it reads the task's layout (its
/// columns' names), the inner outcome (its stop, iterations, per-iteration
/// history) and adds a phase of its own. Everything it touches is public
/// API a third-party solver needs; this test stops a visibility sweep from
/// hiding it again.
struct Wrapped {
    seen: Mutex<Vec<String>>,
}

impl Solver for Wrapped {
    fn method(&self) -> Method {
        Method::External
    }

    fn solve(
        &self,
        task: Task<'_, '_>,
        ctx: &mut Context<'_>,
    ) -> Result<Outcome, CalibrationError> {
        let layout = task.objective.layout();
        let names: Vec<String> = (0..layout.len())
            .filter_map(|c| layout.parameter(c))
            .map(|p| p.name)
            .collect();
        assert_eq!(names.len(), layout.len());
        assert_eq!(layout.arm(task.x).as_ref(), Some(layout.geometry()));
        let mut out = Lm.solve(task, ctx)?;
        assert!(matches!(out.stop, Stop::Lm(_)), "{:?}", out.stop);
        assert!(out.iterations > 0 && !out.history.is_empty());
        // The costs of the steps LM took only fall.
        let taken: Vec<f64> = (out.history.iter())
            .filter(|i| i.accepted)
            .map(|i| i.cost)
            .collect();
        assert!(taken.windows(2).all(|w| w[1] <= w[0]), "{taken:?}");
        assert_eq!(
            out.phases
                .iter()
                .map(|p| p.name.as_str())
                .collect::<Vec<_>>(),
            ["lm"]
        );
        assert!(out.phases[0].jacobian_evaluations > 0);
        out.phases.push(Phase::new("wrapper"));
        *self.seen.lock().unwrap() = names;
        Ok(out)
    }
}

#[test]
fn a_solver_of_another_crate_can_wrap_the_librarys_lm_and_read_its_work() {
    let (arm, data) = shipped();
    let model = stated_noise();
    let problem = Problem::new(arm, data, model).unwrap();
    let settings = SolverSettings::default().with_method(Method::Lm);
    let wrapped = Wrapped {
        seen: Mutex::new(Vec::new()),
    };
    let report = run(&problem, &settings, &wrapped, &mut Context::new()).unwrap();
    assert!(report.is_usable(), "{:?}", report.verdict);
    let seen = wrapped.seen.lock().unwrap();
    assert!(seen.iter().any(|n| n == "theta2"), "{seen:?}");
    let phases = &report.calibration.solver.phases;
    assert!(phases.iter().any(|p| p.name == "wrapper"), "{phases:?}");
}
