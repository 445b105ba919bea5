//! Writes the `calibrate-lm` bench's campaign (benches/calibrate.rs: the paper's arm
//! and errors, seed 7, 3 reference lengths, 0.005° encoder and 0.01 mm probe
//! noise, the fixed set of method.md §8.1) as plain text for the Ceres
//! comparison program (benches/compare/), then calibrates it with aacmm
//! (`lm`, one thread) and writes the result and the time of a fit.
//!
//! `cargo run --release --example ceres_export -- SOCKETS TOUCHES DIR [REPEATS]`
//!
//! Files in DIR (all angles in radians, lengths in mm, `{:e}` round trips):
//! - `problem.txt`: `joints n`, `touches m`, `points k`, `lengths l`,
//!   `encoder_rad σ`, `probe_mm σ`, `length_default_mm σ`, then
//!   `nominal` with the 4n+3 parameters in `DhParams::to_vec` order
//!   (a, d, α, θ per joint, then Bx By Bz) and `fixed` with their 0/1 flags;
//! - `touches.txt`: one touch a line, `point q1 … qn`;
//! - `lengths.txt`: one reference a line, `a b L u` (u: the stated
//!   uncertainty, or −1 for the default);
//! - `aacmm.txt`: `params` (calibrated, same order), `cost` (final weighted
//!   cost), `ms` (the fastest of REPEATS fits, default 5) and `iterations`.

use std::fmt::Write as _;
use std::time::Instant;

use aacmm_core::calibrate::{FixSpec, Method, ModelOptions, SolverSettings, calibrate};
use aacmm_core::domain::Arm;
use aacmm_core::params::DhParams;
use aacmm_core::residuals::Noise;
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};

const UNOBSERVABLE: &str = "theta1,d1,theta6,alpha6,Bx,By";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: ceres_export SOCKETS TOUCHES DIR [REPEATS]".into());
    }
    let sockets: usize = args[0].parse()?;
    let touches: usize = args[1].parse()?;
    let dir = std::path::PathBuf::from(&args[2]);
    let repeats: usize = args.get(3).map(|r| r.parse()).transpose()?.unwrap_or(5);
    std::fs::create_dir_all(&dir)?;

    let nominal = Arm::without_limits("paper-table-1", DhParams::paper_nominal());
    let mut s = CampaignSettings::new(7, ErrorModel::Paper, sockets, touches);
    s.reference_lengths = 3;
    s.encoder_noise_deg = 0.005;
    s.probe_noise_mm = 0.01;
    let data = simulate(&nominal, &s)?.data_set()?;
    let fix = FixSpec::parse(UNOBSERVABLE, 6)?;
    let options = ModelOptions {
        fix: fix.clone(),
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        },
        ..ModelOptions::default()
    };
    let settings = SolverSettings {
        method: Method::Lm,
        threads: 1,
        ..SolverSettings::default()
    };

    let start = &nominal.params;
    let n = start.joint_count();
    let fixed = match &fix {
        FixSpec::Columns(c) => c.clone(),
        FixSpec::Auto => Vec::new(),
    };
    let mut p = String::new();
    writeln!(p, "joints {n}")?;
    writeln!(p, "touches {}", data.len())?;
    writeln!(p, "points {}", data.points().len())?;
    writeln!(p, "lengths {}", data.references().len())?;
    writeln!(
        p,
        "encoder_rad {:e}",
        options.noise.encoder_rad.unwrap_or(0.0)
    )?;
    writeln!(p, "probe_mm {:e}", options.noise.probe_mm.unwrap_or(0.0))?;
    writeln!(p, "length_default_mm {:e}", options.noise.length_default_mm)?;
    let v = start.to_vec();
    writeln!(p, "nominal {}", join(v.iter().map(|x| format!("{x:e}"))))?;
    writeln!(
        p,
        "fixed {}",
        join((0..v.len()).map(|c| u8::from(fixed.contains(&c)).to_string()))
    )?;
    std::fs::write(dir.join("problem.txt"), p)?;

    let mut point_of = vec![0usize; data.len()];
    for (k, point) in data.points().iter().enumerate() {
        for i in point.touches.clone() {
            point_of[i] = k;
        }
    }
    let mut t = String::with_capacity(data.len() * 140);
    for (i, &k) in point_of.iter().enumerate() {
        writeln!(
            t,
            "{k} {}",
            join(data.reading(i).iter().map(|x| format!("{x:e}")))
        )?;
    }
    std::fs::write(dir.join("touches.txt"), t)?;
    let mut l = String::new();
    for r in data.references() {
        writeln!(
            l,
            "{} {} {:e} {:e}",
            r.a,
            r.b,
            r.distance,
            r.uncertainty.unwrap_or(-1.0)
        )?;
    }
    std::fs::write(dir.join("lengths.txt"), l)?;

    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..repeats.max(1) {
        let t0 = Instant::now();
        let c = calibrate(start, &data, &options, &settings)?;
        best = best.min(t0.elapsed().as_secs_f64() * 1e3);
        result = Some(c);
    }
    let c = result.ok_or("no fit")?;
    let mut a = String::new();
    writeln!(
        a,
        "params {}",
        join(c.params.to_vec().iter().map(|x| format!("{x:e}")))
    )?;
    writeln!(a, "cost {:e}", c.solver.final_cost)?;
    writeln!(a, "ms {best:.4}")?;
    writeln!(a, "iterations {}", c.solver.iterations)?;
    std::fs::write(dir.join("aacmm.txt"), a)?;
    println!(
        "{}: {} touches, {} points, {} lengths; aacmm lm {best:.3} ms (fastest of {repeats}), cost {:.6e}",
        dir.display(),
        data.len(),
        data.points().len(),
        data.references().len(),
        c.solver.final_cost
    );
    Ok(())
}

fn join(items: impl Iterator<Item = String>) -> String {
    items.collect::<Vec<_>>().join(" ")
}
