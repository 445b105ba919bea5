//! Can a calibration be trusted? On newly assembled arms (zero offsets
//! anywhere in ±180°), the seeds where the cost's mirror-image twin used to
//! win (issue 15: 16, 114, 134, 188, 235, 255, 277, 323) and 100 more: how
//! many calibrations are usable (exit 0), how far each is from the true arm
//! after the best *proper* rigid motion (a mirror image is hundreds of mm
//! off), whether a reflection would fit better (a mirror twin), and whether
//! the sign convention was restored.
//!
//! ```sh
//! cargo run --release --example trust [-- EXTRA_SEEDS]
//! ```
//!
//! Campaign: `aacmm simulate --errors assembled --sockets 10 --poses 10
//! --encoder-noise 0.005 --probe-noise 0.01 --reference-lengths 3 --seed S`;
//! calibration: `aacmm calibrate` with the same noise, `--seed 1`.

use aacmm_core::calibrate::{CalibrateOptions, Method};
use aacmm_core::geometry::rigid_distance;
use aacmm_core::io::Arm;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::{DhParams, ParamId, ParamKind, wrap};
use aacmm_core::residuals::Noise;
use aacmm_core::session::Problem;
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};
use anyhow::Result;

const MIRROR_SEEDS: [u64; 8] = [16, 114, 134, 188, 235, 255, 277, 323];

/// Lengths `a` and twists of every joint but the last whose sign differs
/// from the nominal's (the last link's may turn about the last axis when
/// its zero offset is held).
fn sign_flips(cal: &DhParams, nominal: &DhParams) -> usize {
    let last = nominal.joint_count() - 1;
    ParamId::all(nominal.joint_count())
        .filter(|id| matches!(id.kind, ParamKind::A | ParamKind::Alpha) && id.index < last)
        .filter(|&id| {
            let (n, c) = (nominal.get(id), cal.get(id));
            n.abs() > 1e-9 && (n.signum() != c.signum() && wrap(c - n).abs() > 1.0)
        })
        .count()
}

fn main() -> Result<()> {
    let extra: u64 = std::env::args().nth(1).map_or(Ok(100), |s| s.parse())?;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (nominal, _) = aacmm_core::read_arm(&root.join("examples/paper-table-1.toml"))?;
    let seeds: Vec<u64> = MIRROR_SEEDS.into_iter().chain(1000..1000 + extra).collect();
    let noise = Noise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        ..Noise::default()
    };
    let (mut usable, mut mirrored, mut far, mut flips, mut worst) = (0, 0, 0, 0, 0.0f64);
    println!(
        "{:>6} {:>7} {:>12} {:>12} {:>6}  verdict",
        "seed", "exit", "proper mm", "mirror mm", "flips"
    );
    for &seed in &seeds {
        let mut s = CampaignSettings::new(seed, ErrorModel::random(1.0, true), 10, 10);
        s.encoder_noise_deg = 0.005;
        s.probe_noise_mm = 0.01;
        s.reference_lengths = 3;
        let campaign = simulate(&nominal, &s)?;
        let data = campaign.data_set()?;
        let options = CalibrateOptions {
            method: Method::Global,
            noise,
            seed: 1,
            ..CalibrateOptions::default()
        };
        let report = Problem::new(Arm::clone(&nominal), data, options)?.run()?;
        let cal = &report.calibration.params;
        let rows: Vec<&[f64]> = campaign.poses.rows().collect();
        let xyz = |p: &DhParams| ArmKernel::new(p)?.positions_of(&rows);
        let (c, t) = (xyz(cal)?, xyz(&campaign.true_arm.params)?);
        let proper = rigid_distance(&c, &t, false);
        let mirror = rigid_distance(&c, &t, true);
        let f = sign_flips(cal, &nominal.params);
        let ok = report.is_usable();
        usable += usize::from(ok);
        if ok {
            mirrored += usize::from(mirror < proper);
            far += usize::from(proper > 1.0);
            flips += usize::from(f > 0);
            worst = worst.max(proper);
        }
        if !ok || MIRROR_SEEDS.contains(&seed) || proper > 1.0 || f > 0 {
            println!(
                "{seed:>6} {:>7} {proper:>12.4} {mirror:>12.4} {f:>6}  {}",
                if ok { 0 } else { 1 },
                if ok {
                    "usable".to_string()
                } else {
                    report.verdict.reasons.join("; ")
                }
            );
        }
    }
    println!(
        "\n{} assembled campaigns: {usable} usable (exit 0); among those {mirrored} mirror images, \
         {far} more than 1 mm from the true arm after the best proper rigid motion (worst \
         {worst:.4} mm), {flips} with a sign convention not restored",
        seeds.len()
    );
    Ok(())
}
