//! Several markers on one body ([`crate::io::tools`]): each pose of a
//! tracker campaign seen at every marker (or a subset), each with its own
//! true offset — what `simulate --positions N --tools K` records.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::SimError;
use super::positions::PositionCampaign;
use super::truth::normal;
use crate::domain::{Arm, Positions, Tool};
use crate::kernel::ArmKernel;
use crate::residuals::{Frame, Noise};

/// `count` markers named `m1`, `m2`, … on a body on the flange: spread
/// 40–90 mm about the last joint's axis, 60–160 mm along it, in random
/// directions (seeded by `seed`).
pub fn random_tools(count: usize, seed: u64) -> Vec<Tool> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|k| {
            let angle = std::f64::consts::TAU * (k as f64 + rng.random_range(0.0..0.5))
                / count.max(1) as f64;
            let r = rng.random_range(40.0..90.0);
            Tool {
                name: format!("m{}", k + 1),
                offset: [
                    r * angle.cos(),
                    r * angle.sin(),
                    rng.random_range(60.0..160.0),
                ],
                ball_diameter_mm: None,
            }
        })
        .collect()
}

/// `tools` with each offset moved by `N(0, sigma_mm²)` per coordinate: the
/// true markers of a nominal body (seeded by `seed`).
pub fn perturbed_tools(tools: &[Tool], sigma_mm: f64, seed: u64) -> Vec<Tool> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (tools.iter())
        .map(|t| Tool {
            name: t.name.clone(),
            offset: t.offset.map(|v| v + sigma_mm * normal(&mut rng)),
            ball_diameter_mm: t.ball_diameter_mm,
        })
        .collect()
}

/// The poses of `campaign` seen at `truth`'s markers instead of its probe:
/// per row, one row per marker (each kept with probability `seen`, at
/// least one per pose), labelled `P1.m1`, in the row's frame, with the
/// noise of `noise` (`σ = A + B·distance`, seeded by `seed`). The
/// readings, frames and orientations (the body's, the same at each of its
/// markers) are the campaign's.
///
/// # Errors
///
/// An arm without `[[tool]]`, `seen` outside (0, 1], a noise not stated;
/// the kernel's.
pub fn seen_at_markers(
    truth: &Arm,
    campaign: &PositionCampaign,
    noise: &Noise,
    seen: f64,
    seed: u64,
) -> Result<Positions, SimError> {
    let a = noise.position_mm.unwrap_or(-1.0);
    let b = noise.position_mm_per_m.unwrap_or(0.0);
    if truth.tools.is_empty() || !(seen > 0.0 && seen <= 1.0) || !(a >= 0.0 && b >= 0.0) {
        return Err(SimError::setting(
            "tools",
            "an arm with [[tool]] markers, a share seen in (0, 1] and a position noise A ≥ 0",
        ));
    }
    let model = |e: crate::kernel::KernelError| SimError::Model(e.to_string());
    let kernels = (truth.tools.iter())
        .map(|t| {
            let mut params = truth.params.clone();
            params.probe = t.offset;
            ArmKernel::new(&params)
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(model)?;
    let rows = &campaign.positions;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Positions::new(rows.joints()).with_shape(kernels[0].shape());
    for i in 0..rows.len() {
        let frame = &campaign.frames[rows.frame(i)];
        let keep: Vec<bool> = (0..kernels.len()).map(|_| rng.random_bool(seen)).collect();
        let first = rng.random_range(0..kernels.len());
        for (k, kernel) in kernels.iter().enumerate() {
            if !(keep[k] || (k == first && !keep.contains(&true))) {
                continue;
            }
            let y = Frame::apply(&frame.1, kernel.position(rows.reading(i)).map_err(model)?);
            let distance = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt() / 1000.0;
            let sigma = a + b * distance;
            let noisy = y.map(|v| v + sigma * normal(&mut rng));
            let label = format!("{}.{}", rows.label(i), truth.tools[k].name);
            out.push(&label, &frame.0, rows.reading(i), noisy, None, 0);
            out.set_tool(&truth.tools[k].name);
            // The body's orientation, whichever marker is seen.
            out.set_orientation(rows.orientation(i));
        }
    }
    Ok(out)
}
