//! `aacmm verify`'s computation: the acceptance tests of 10 sphere
//! placements of 25 points (P_Size, P_Form) and 20 ball-bar positions
//! (E_Uni, two spheres of 25 points each), the probe centres given — the
//! issue's bound is 10 ms (the whole command 50 ms).

use aacmm_core::acceptance::{LDiaRadius, Settings, SpherePoints, parse_mpe, verify};
use aacmm_core::io::Arm;
use aacmm_core::kernel::ArmKernel;
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
}

criterion_group!(benches, bench);
criterion_main!(benches);
