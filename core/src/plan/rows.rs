//! The rows a pose adds to a calibration: its probe position's Jacobian
//! over the free geometry — and, for reference positions, over the
//! instrument's frame, which every fit estimates with the arm — each column
//! scaled to a unit mean square over the candidates, so that one weak
//! prior `ε I` means the same for a length and an angle.

use crate::kernel::{ArmKernel, KernelError, PreparedPoses};
use crate::params::DhParams;
use crate::residuals::Frame;

/// Row-major Jacobians of many poses: pose `i`, coordinate `k`, column `c`
/// at `[(3 i + k) p + c]`.
#[derive(Clone, Debug)]
pub(crate) struct Blocks {
    pub(crate) p: usize,
    pub(crate) j: Vec<f64>,
}

impl Blocks {
    pub(crate) fn len(&self) -> usize {
        self.j.len() / (3 * self.p).max(1)
    }

    /// Pose `i`'s 3 × p block.
    pub(crate) fn at(&self, i: usize) -> &[f64] {
        &self.j[3 * i * self.p..3 * (i + 1) * self.p]
    }
}

/// The unscaled Jacobians of `poses` over `free` (and the frame), and the
/// probe positions.
pub(crate) fn jacobians(
    params: &DhParams,
    poses: &PreparedPoses,
    free: &[usize],
    frame: bool,
) -> Result<(Blocks, Vec<[f64; 3]>), KernelError> {
    let kernel = ArmKernel::new(params)?;
    let p = free.len() + if frame { 6 } else { 0 };
    let mut j = vec![0.0; 3 * p * poses.len()];
    let mut positions = vec![[0.0; 3]; poses.len()];
    kernel.for_each_jacobian(poses, 0..poses.len(), |i, pos, jac| {
        positions[i] = *pos;
        let block = &mut j[3 * i * p..3 * (i + 1) * p];
        for k in 0..3 {
            let row = &mut block[k * p..(k + 1) * p];
            for (a, &c) in free.iter().enumerate() {
                row[a] = jac[c][k];
            }
            if frame {
                // The frame's columns at the identity: the information does
                // not depend on where the instrument stands.
                row[free.len()..].copy_from_slice(&Frame::jacobian(&[0.0; 6], *pos)[k]);
            }
        }
    })?;
    Ok((Blocks { p, j }, positions))
}

/// Each column's scale: one over its RMS over the blocks' rows (1 for a
/// column that moves nothing).
pub(crate) fn unit_scale(blocks: &Blocks) -> Vec<f64> {
    let p = blocks.p;
    let rows = (blocks.j.len() / p.max(1)).max(1);
    let mut ss = vec![0.0; p];
    for row in blocks.j.chunks_exact(p) {
        for (s, v) in ss.iter_mut().zip(row) {
            *s += v * v;
        }
    }
    ss.iter()
        .map(|&s| {
            let rms = (s / rows as f64).sqrt();
            if rms > 0.0 && rms.is_finite() {
                1.0 / rms
            } else {
                1.0
            }
        })
        .collect()
}

/// The blocks with every column multiplied by its scale.
pub(crate) fn scaled(mut blocks: Blocks, scale: &[f64]) -> Blocks {
    let p = blocks.p;
    for row in blocks.j.chunks_exact_mut(p) {
        for (v, s) in row.iter_mut().zip(scale) {
            *v *= s;
        }
    }
    blocks
}

/// `Σ_i J_iᵀ J_i / n` over the blocks (p × p, row-major): where the arm is
/// used, as the criterion weighs it.
pub(crate) fn mean_gram(blocks: &Blocks) -> Vec<f64> {
    let p = blocks.p;
    let mut w = vec![0.0; p * p];
    for row in blocks.j.chunks_exact(p) {
        for a in 0..p {
            let ra = row[a];
            if ra == 0.0 {
                continue;
            }
            for b in 0..p {
                w[a * p + b] += ra * row[b];
            }
        }
    }
    let n = blocks.len().max(1) as f64;
    w.iter_mut().for_each(|v| *v /= n);
    w
}
