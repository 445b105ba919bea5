//! `aacmm verify`'s computation: the acceptance tests of 10 sphere
//! placements of 25 points (P_Size, P_Form) and 20 ball-bar positions
//! (E_Uni, two spheres of 25 points each), the probe centres given — the
//! issue's bound is 10 ms (the whole command 50 ms). And the same tests
//! predicted from a calibration (`verify --calibration`): 200 draws through
//! a covariance of 20 free parameters and the readings' noise, on one
//! thread and on every core.

use aacmm_core::acceptance::{
    Calibrated, Draws, LDiaRadius, Measured, ReadingNoise, Settings, SpherePoints, parse_mpe,
    predict, verify,
};
use aacmm_core::domain::Arm;
use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::params::DhParams;
use aacmm_core::simulate::{AcceptanceSettings, SphereSettings, simulate_spheres, with_acceptance};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let arm = Arm {
        ball_diameter_mm: Some(6.0),
        ..Arm::without_limits("paper", DhParams::paper_nominal())
    };
    let settings = SphereSettings {
        placements: 10,
        diameter_mm: 25.4,
        ball_diameter_mm: 6.0,
        encoder_rad: 0.0005f64.to_radians(),
        probe_mm: 0.003,
        seed: 41,
    };
    let base = simulate_spheres(&arm, &settings.for_campaign()).expect("placements");
    let more = AcceptanceSettings {
        articulated: 0,
        bar_positions: 20,
        bar_length_mm: 500.0,
    };
    let campaign = with_acceptance(&arm, base, &settings, &more).expect("a ball bar");
    let kernel = ArmKernel::new(&arm.params).expect("a kernel");
    let rows = &campaign.spheres;
    let xyz: Vec<[f64; 3]> = (0..rows.len())
        .map(|i| kernel.position(rows.reading(i)).expect("a position"))
        .collect();
    let s = Settings {
        sphere_diameter: 25.4,
        sphere_uncertainty: 0.0005,
        ball_diameter: 6.0,
        l_dia_radius: LDiaRadius::Held,
        mpe: parse_mpe("P_Size=0.01,P_Form=0.03,E_Uni=0.016+L/60000").expect("a spec"),
    };
    c.bench_function("verify/10x25+20bars", |b| {
        b.iter(|| {
            let points = SpherePoints {
                rows,
                file: "spheres.csv",
                centres: &xyz,
            };
            black_box(
                verify(&s, points, Some((&campaign.lengths, "bar.csv")), None).expect("tests"),
            )
        })
    });
    let readings: Vec<&[f64]> = (0..rows.len()).map(|i| rows.reading(i)).collect();
    let poses = PreparedPoses::new(6, &readings).expect("poses");
    let points = SpherePoints {
        rows,
        file: "spheres.csv",
        centres: &xyz,
    };
    let measured = Measured {
        points,
        poses: &poses,
        lengths: Some((&campaign.lengths, "bar.csv")),
    };
    let measured_tests = verify(&s, points, measured.lengths, None).expect("the measured tests");
    // 20 free parameters (a, d, α of joints 2–6 and θ of 2–6), σ 0.01 mm
    // and 0.002° apart from correlations.
    let free: Vec<usize> = (1..6).chain(7..12).chain(13..18).chain(19..24).collect();
    let covariance = nalgebra::DMatrix::from_fn(free.len(), free.len(), |i, j| {
        let s = |k: usize| {
            if free[k] < 12 {
                0.01
            } else {
                0.002f64.to_radians()
            }
        };
        let rho = if i == j {
            1.0
        } else {
            0.3 / (1.0 + (i as f64 - j as f64).abs())
        };
        rho * s(i) * s(j)
    });
    let cal = Calibrated {
        params: &arm.params,
        free: &free,
        covariance: &covariance,
        noise: ReadingNoise {
            encoder_rad: 0.0005f64.to_radians(),
            probe_mm: 0.003,
            stated: true,
        },
    };
    for threads in [1, aacmm_core::calibrate::available_threads()] {
        let name = format!("predict/10x25+20bars/200 draws/{threads} threads");
        c.bench_function(&name, |b| {
            b.iter(|| {
                let mut a = measured_tests.clone();
                let draws = Draws {
                    count: 200,
                    seed: 1,
                    threads,
                };
                predict(&mut a, &s, measured, cal, draws, "cal").expect("a prediction");
                black_box(a)
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
