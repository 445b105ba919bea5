//! A term written outside the library that reads the point it is
//! evaluated at — `At::x`, every column's value, and `At::arm`, the arm
//! those values make — as a user's own prior or regulariser does: a pin
//! of one link length to a value the user knows from elsewhere. The fit
//! moves that length to the pin, and to nothing else. (The fields it reads
//! are public API for such terms; this test stops a visibility sweep from
//! hiding them again.)

use aacmm_core::prelude::*;

#[path = "common/shipped.rs"]
mod shipped;
use shipped::{shipped, stated_noise};

/// `(x[column] − target) / σ`: one row.
#[derive(Clone, Debug)]
struct Pin {
    id: ParamId,
    column: usize,
    target: f64,
    sigma: f64,
}

impl Pin {
    /// The residual at `at`, read two ways that must agree: from the
    /// column's value and from the arm it makes.
    fn residual(&self, at: &At<'_>) -> f64 {
        let from_x = at.x[self.column];
        assert_eq!(from_x, at.arm.get(self.id), "the column and the arm");
        (from_x - self.target) / self.sigma
    }
}

impl Term for Pin {
    fn name(&self) -> &str {
        "pin"
    }

    fn rows(&self, free: &[usize]) -> usize {
        usize::from(free.contains(&self.column))
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let Some(a) = normal.free().iter().position(|&c| c == self.column) else {
            return Ok(0.0);
        };
        let mut j = vec![0.0; normal.free().len()];
        j[a] = 1.0 / self.sigma;
        let r = self.residual(at);
        normal.add_row(&j, r);
        Ok(r * r)
    }

    fn add_cost(
        &self,
        at: &At<'_>,
        free: &[usize],
        _shared: &mut Shared,
        _scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        if free.contains(&self.column) {
            *total += self.residual(at).powi(2);
        }
        Ok(())
    }
}

#[test]
fn a_term_of_another_crate_reads_the_columns_and_the_arm_it_is_evaluated_at() {
    let (arm, data) = shipped();
    let model = stated_noise();
    let settings = SolverSettings::default().with_method(Method::Lm);
    let plain = Problem::new(arm.clone(), data.clone(), model.clone())
        .unwrap()
        .run(&settings)
        .unwrap();
    let id: ParamId = "a2".parse().unwrap();
    let free = plain.calibration.estimate(id).unwrap();
    let sigma = free.sigma.expect("a2 is fitted");
    // Pinned 20 σ away from where the data put it, 100 times tighter
    // than the data know it.
    let target = free.calibrated + 20.0 * sigma;
    let pin = Pin {
        id,
        column: id.column(arm.params.joint_count()),
        target,
        sigma: sigma / 100.0,
    };
    let pinned = Problem::new(arm, data, model)
        .unwrap()
        .with_term(pin)
        .run(&settings)
        .unwrap();
    let a2 = pinned.calibration.estimate(id).unwrap();
    assert!(
        (a2.calibrated - target).abs() < sigma / 10.0,
        "a2 {} against the pin's {target} (σ {sigma})",
        a2.calibrated
    );
    assert!(
        (a2.calibrated - free.calibrated).abs() > 19.0 * sigma,
        "the pin moved a2 by {} only",
        a2.calibrated - free.calibrated
    );
}
