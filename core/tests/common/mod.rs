//! Data shared by the core's integration tests.

use aacmm_core::calibrate::{FixSpec, LmOptions, Method, ModelOptions, SolverSettings};
use aacmm_core::domain::ReferenceLength;
use aacmm_core::session::Problem;
use aacmm_core::{Arm, DataSet};

/// `points` points of 3 touches each, spread over ±1.5 rad in every joint,
/// the first 100 joined in pairs by 50 lengths: with a few hundred points
/// the normal equations and the metrics split across threads.
pub fn many_points(points: usize) -> DataSet {
    let mut labels = Vec::new();
    let mut q = Vec::new();
    for p in 0..points {
        for t in 0..3 {
            labels.push(format!("P{p}"));
            let row: Vec<f64> = (0..6)
                .map(|j| ((p * 7 + t * 13 + j * 3) as f64 * 0.37).sin() * 1.5)
                .collect();
            q.push(row);
        }
    }
    let lengths: Vec<ReferenceLength> = (0..50)
        .map(|i| ReferenceLength {
            a: format!("P{}", 2 * i),
            b: format!("P{}", 2 * i + 1),
            distance: 100.0 + i as f64,
            uncertainty: None,
            line: 0,
        })
        .collect();
    DataSet::from_touches(&labels, &q, &lengths).unwrap()
}

/// `calibration.json` of an 8-iteration LM session of `arm` on `data` on
/// `threads` threads (the paper's usual fixed set), with `tune` applied to
/// the model and the settings: what the "same bytes on any thread count"
/// tests compare.
pub fn lm_report_on_threads(
    arm: &Arm,
    data: &DataSet,
    threads: usize,
    tune: impl Fn(&mut ModelOptions, &mut SolverSettings),
) -> String {
    let mut model = ModelOptions {
        fix: FixSpec::parse("theta1,d1,theta6,alpha6,Bx,By", 6).unwrap(),
        ..ModelOptions::default()
    };
    let mut settings = SolverSettings {
        method: Method::Lm,
        lm: LmOptions::default().max_iterations(8),
        threads,
        ..SolverSettings::default()
    };
    tune(&mut model, &mut settings);
    Problem::new(arm.clone(), data.clone(), model)
        .unwrap()
        .run(&settings)
        .unwrap()
        .to_json()
}
