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

/// The rows of points probed on spheres, one per candidate in its block's
/// first row (the other two zero): the probe's move along its sphere's
/// normal `nᵀ J` over `free`, then per sphere its centre's columns (`−nᵀ`)
/// and, unless the diameter is stated, its radius's (`−1`). The spheres'
/// own unknowns are columns of the design that nothing but the weak prior
/// knows, so that a sphere's first points — which fix the sphere, not the
/// arm — gain the arm nothing, as the fit's elimination of them gives.
/// Each sphere's centre and normals are those of the algebraic sphere
/// through its candidates' nominal probe positions. `group` is each
/// candidate's sphere of `names`; returns the blocks and the positions.
pub(crate) fn sphere_rows(
    params: &DhParams,
    poses: &PreparedPoses,
    free: &[usize],
    group: &[usize],
    names: &[String],
    stated: bool,
) -> Result<(Blocks, Vec<[f64; 3]>), super::PlanError> {
    let (raw, positions) = jacobians(params, poses, free, false)?;
    let (g, per) = (free.len(), sphere_columns(stated));
    let p = g + per * names.len();
    // Each sphere's points, in one pass over the candidates.
    let mut points: Vec<Vec<[f64; 3]>> = vec![Vec::new(); names.len()];
    for (pos, &s) in positions.iter().zip(group) {
        points[s].push(*pos);
    }
    let mut centres = Vec::with_capacity(names.len());
    for (name, points) in names.iter().zip(&points) {
        let (c, _) = crate::residuals::spheres::algebraic_sphere(points).ok_or_else(|| {
            super::PlanError::Invalid(format!(
                "sphere `{name}`: its {} candidates fix no sphere (fewer than 4, or on one \
                 circle)",
                points.len()
            ))
        })?;
        centres.push(c);
    }
    let mut j = vec![0.0; 3 * p * positions.len()];
    for (i, pos) in positions.iter().enumerate() {
        let s = group[i];
        let d = crate::geometry::distance(pos, &centres[s]);
        let n: [f64; 3] =
            std::array::from_fn(|k| (pos[k] - centres[s][k]) / d.max(f64::MIN_POSITIVE));
        let row = &mut j[3 * i * p..3 * i * p + p];
        let jac = raw.at(i);
        for (a, v) in row[..g].iter_mut().enumerate() {
            *v = (0..3).map(|k| n[k] * jac[k * g + a]).sum();
        }
        let own = &mut row[g + per * s..g + per * (s + 1)];
        own[..3].copy_from_slice(&n.map(|v| -v));
        if !stated {
            own[3] = -1.0;
        }
    }
    Ok((Blocks { p, j }, positions))
}

/// The columns a sphere adds to the design: its centre's three, and its
/// radius unless the diameter is stated.
pub(crate) fn sphere_columns(stated: bool) -> usize {
    if stated { 3 } else { 4 }
}

/// `blocks` (`g` columns) widened to `p`, the new columns zero: the
/// workspace's rows, on which the spheres' own unknowns do not act.
pub(crate) fn widened(blocks: Blocks, p: usize) -> Blocks {
    if blocks.p == p {
        return blocks;
    }
    let g = blocks.p;
    let mut j = vec![0.0; blocks.j.len() / g.max(1) * p];
    for (out, row) in j.chunks_exact_mut(p).zip(blocks.j.chunks_exact(g)) {
        out[..g].copy_from_slice(row);
    }
    Blocks { p, j }
}
