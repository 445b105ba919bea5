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
//!
//! Then outliers: on paper-error campaigns (10 sockets × 10 touches, 3
//! lengths, the same noise, seeds 1–10), one touch displaced 2 mm, and 5 %
//! of the touches displaced 1 mm (by turning one joint of the true arm's
//! reading): whether every displaced touch is named, and the held-out ratio
//! — repeatability `e` on fresh sockets of the same true arm over the true
//! arm's own — of plain least squares and of `--robust huber` / `cauchy`.

use aacmm_core::calibrate::validate::figures;
use aacmm_core::calibrate::{Loss, Method, ModelOptions, Robust, SolverSettings};
use aacmm_core::domain::Arm;
use aacmm_core::geometry::rigid_distance;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::{DhParams, ParamId, ParamKind, wrap};
use aacmm_core::residuals::Noise;
use aacmm_core::session::Problem;
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};
use aacmm_core::{DataSet, geometry::distance};
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
        let options = ModelOptions {
            noise,
            ..ModelOptions::default()
        };
        let settings = SolverSettings::default()
            .with_method(Method::Global)
            .with_seed(1);
        let report = Problem::new(Arm::clone(&nominal), data, options)?.run(&settings)?;
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
                    report
                        .verdict
                        .words(aacmm_core::session::Spelling::Cli)
                        .reasons
                        .join("; ")
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
    outliers(&nominal, noise)
}

/// Moves touch `i` (readings `q`, rad) so that the true arm puts the probe
/// `mm` further off, by turning the joint with the longest lever among the
/// first three.
fn displace(q: &mut [Vec<f64>], i: usize, mm: f64, truth: &DhParams) -> Result<()> {
    let k = ArmKernel::new(truth)?;
    let q0 = q[i].clone();
    let p0 = k.position(&q0)?;
    let moved = |j: usize, d: f64| -> Result<f64> {
        let mut r = q0.clone();
        r[j] += d;
        Ok(distance(&k.position(&r)?, &p0))
    };
    let (mut j, mut lever) = (0, 0.0);
    for c in 0..3 {
        let l = moved(c, 1e-6)?;
        if l > lever {
            (j, lever) = (c, l);
        }
    }
    let mut d = mm * 1e-6 / lever;
    for _ in 0..3 {
        d *= mm / moved(j, d)?;
    }
    q[i][j] += d;
    Ok(())
}

/// The outlier cases: touches named, held-out ratio plain / huber / cauchy.
fn outliers(nominal: &Arm, noise: Noise) -> Result<()> {
    let cases: [(&str, &[usize], f64); 2] = [
        ("one touch moved 2 mm", &[16], 2.0),
        ("5 of 100 touches moved 1 mm", &[3, 23, 47, 68, 91], 1.0),
    ];
    let settings = |seed: u64| {
        let mut s = CampaignSettings::new(seed, ErrorModel::Paper, 10, 10);
        s.encoder_noise_deg = 0.005;
        s.probe_noise_mm = 0.01;
        s.reference_lengths = 3;
        s
    };
    let fits = [None, Some(Loss::Huber), Some(Loss::Cauchy)];
    println!(
        "\nOutliers (paper errors, 10 × 10, 3 lengths, seeds 1-10): held-out e / true \
         arm's, mean [max] over seeds; touches named (plain LS) / displaced; usable fits"
    );
    for (name, moved, mm) in cases {
        let (mut ratio, mut worst) = ([0.0; 3], [0.0f64; 3]);
        let (mut named, mut total, mut usable) = (0, 0, [0; 3]);
        let seeds = 1..=10u64;
        for seed in seeds.clone() {
            let campaign = simulate(nominal, &settings(seed))?;
            let labels: Vec<String> = campaign.poses.labels().map(str::to_string).collect();
            let mut q: Vec<Vec<f64>> = campaign.poses.rows().map(<[f64]>::to_vec).collect();
            for &i in moved {
                displace(&mut q, i, mm, &campaign.true_arm.params)?;
            }
            let data = DataSet::from_touches(&labels, &q, &campaign.lengths)?;
            let fresh = simulate(nominal, &settings(10_000 + seed))?.data_set()?;
            let truth = figures(&campaign.true_arm.params, &fresh)?.e_mean;
            for (f, loss) in fits.iter().enumerate() {
                let options = ModelOptions {
                    noise,
                    robust: loss.map(Robust::new),
                    ..ModelOptions::default()
                };
                let report = Problem::new(Arm::clone(nominal), data.clone(), options)?
                    .run(&SolverSettings::default())?;
                let r = figures(&report.calibration.params, &fresh)?.e_mean / truth;
                ratio[f] += r / 10.0;
                worst[f] = worst[f].max(r);
                usable[f] += usize::from(report.is_usable());
                if loss.is_none() {
                    let at: Vec<&str> = report
                        .calibration
                        .checks
                        .outliers
                        .iter()
                        .map(|o| o.at.as_str())
                        .collect();
                    total += moved.len();
                    named += moved
                        .iter()
                        .filter(|&&i| at.contains(&format!("<arrays>:{}", i + 1).as_str()))
                        .count();
                }
            }
        }
        println!(
            "  {name:<28} named {named}/{total}; plain {:.3} [{:.3}] usable {}/10; \
             huber {:.3} [{:.3}] usable {}/10; cauchy {:.3} [{:.3}] usable {}/10",
            ratio[0],
            worst[0],
            usable[0],
            ratio[1],
            worst[1],
            usable[1],
            ratio[2],
            worst[2],
            usable[2]
        );
    }
    Ok(())
}
