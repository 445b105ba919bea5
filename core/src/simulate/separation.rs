//! The touches of one socket, indexed for the separation test.
//!
//! A new touch is refused when some earlier touch of its socket lies
//! within `min_sep` of it in every joint (the largest joint difference,
//! [`separation_scaled`], below `min_sep`). Scanning every earlier touch
//! made a socket of `P` touches cost `O(P²)`: at 1 000 touches a socket it
//! was two thirds of `simulate`'s time. Here the poses are also filed in a
//! grid over up to three revolute joints, on the circle, with cells wider
//! than `min_sep`: a pose within `min_sep` of the new one in every joint is
//! within one cell of it in each indexed joint, so only the 3 × 3 × 3
//! neighbouring cells are scanned — with the same test as before, so the
//! same touches are refused and the output is the same bytes.

use std::f64::consts::TAU;

use super::touches::separation_scaled;

/// Indexed joints at most (27 neighbouring cells).
const INDEXED: usize = 3;
/// Cells per turn at most (32³ list heads, 128 KiB, a socket): a small
/// `min_sep` would otherwise make the grid large and mostly empty. Wider
/// cells than needed only scan more poses; the answer is the same.
const MAX_CELLS: usize = 32;
/// The end of a cell's list.
const NONE: u32 = u32::MAX;

/// Accepted poses of one socket, with the grid over them.
pub(crate) struct Accepted<'a> {
    scales: &'a [f64],
    min_sep: f64,
    /// The indexed joints (revolute ones, `scales[j] == 0`).
    joints: Vec<usize>,
    /// Cells per turn; 0 when the grid is not used (too few cells for the
    /// one-cell neighbourhood to be exact, or no revolute joint).
    cells: usize,
    poses: Vec<Vec<f64>>,
    /// Per cell (flat index) its latest pose, and per pose the one filed
    /// in its cell before it: a linked list per cell, two arrays in all.
    head: Vec<u32>,
    next: Vec<u32>,
}

impl<'a> Accepted<'a> {
    /// No poses yet; `scales` as for [`separation_scaled`], `min_sep` rad.
    pub(crate) fn new(scales: &'a [f64], min_sep: f64, capacity: usize) -> Self {
        let joints: Vec<usize> = (0..scales.len())
            .filter(|&j| scales[j] == 0.0)
            .take(INDEXED)
            .collect();
        // One cell fewer than fit, so that a cell is wider than `min_sep`
        // by a margin no rounding of `rem_euclid` comes near; at least 4
        // cells, so that a cell's neighbours on the circle are distinct.
        let fit = if min_sep > 0.0 {
            (TAU / min_sep).floor()
        } else {
            0.0
        };
        let cells = if fit >= 5.0 && !joints.is_empty() {
            (fit as usize - 1).min(MAX_CELLS)
        } else {
            0
        };
        let head = vec![NONE; cells.pow(joints.len() as u32)];
        Self {
            scales,
            min_sep,
            joints,
            cells,
            poses: Vec::with_capacity(capacity),
            head,
            next: Vec::with_capacity(capacity),
        }
    }

    /// How many poses were accepted.
    pub(crate) fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether some accepted pose lies within `min_sep` of `q` in every
    /// joint.
    pub(crate) fn too_close(&self, q: &[f64]) -> bool {
        let near = |i: &usize| separation_scaled(&self.poses[*i], q, self.scales) < self.min_sep;
        if self.cells == 0 {
            return (0..self.poses.len()).any(|i| near(&i));
        }
        let centre = self.cell(q);
        let n = self.cells;
        (0..3usize.pow(self.joints.len() as u32)).any(|mut k| {
            let mut flat = 0;
            for &c in centre.iter().take(self.joints.len()).rev() {
                // -1, 0, +1 around the centre's cell, on the circle.
                flat = flat * n + (c + n + k % 3 - 1) % n;
                k /= 3;
            }
            let mut i = self.head[flat];
            while i != NONE {
                if near(&(i as usize)) {
                    return true;
                }
                i = self.next[i as usize];
            }
            false
        })
    }

    /// Files `q` among the accepted poses.
    pub(crate) fn push(&mut self, q: Vec<f64>) {
        if self.cells > 0 {
            let flat = (self.cell(&q).iter().take(self.joints.len()).rev())
                .fold(0, |f, &c| f * self.cells + c);
            // A socket has far fewer than 2³² touches (they are poses a
            // user asked for); `as` cannot wrap below that.
            self.next.push(self.head[flat]);
            self.head[flat] = self.poses.len() as u32;
        }
        self.poses.push(q);
    }

    /// The cell of `q`: per indexed joint its angle's place on the circle
    /// (unused slots 0).
    fn cell(&self, q: &[f64]) -> [usize; INDEXED] {
        let width = TAU / self.cells as f64;
        let mut key = [0; INDEXED];
        for (slot, &j) in key.iter_mut().zip(&self.joints) {
            // `rem_euclid` may round up to TAU itself: the last cell, which
            // is the first's neighbour anyway.
            *slot = ((q[j].rem_euclid(TAU) / width) as usize).min(self.cells - 1);
        }
        key
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    use super::*;

    /// The grid's answer is the scan's, on poses crowded around the cells'
    /// edges and the ±π seam, for several separations and a slide.
    #[test]
    fn the_grid_refuses_what_the_scan_refuses() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for (min_deg, scales) in [
            (20.0, vec![0.0; 6]),
            (60.0, vec![0.0; 7]),
            (45.0, vec![0.0, 0.0]),
            (2.0, vec![0.0; 6]),
            (20.0, vec![TAU / 800.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ] {
            let min_sep = f64::to_radians(min_deg);
            let mut acc = Accepted::new(&scales, min_sep, 0);
            assert!(acc.cells > 0, "{min_deg}°: the grid is used");
            let (mut refused, mut kept) = (0, 0);
            for _ in 0..1500 {
                let q: Vec<f64> = (0..scales.len())
                    .map(|j| {
                        if scales[j] > 0.0 {
                            rng.random_range(0.0..800.0)
                        } else {
                            // Whole multiples of the separation, nudged: on
                            // or beside the cells' edges and the seam, in
                            // several turns.
                            let k = rng.random_range(-3..3) as f64;
                            let turn = TAU * rng.random_range(-2..=2) as f64;
                            let seam = if rng.random_bool(0.5) { PI } else { 0.0 };
                            turn + seam + k * min_sep * 0.5 + rng.random_range(-1e-9..1e-9)
                        }
                    })
                    .collect();
                let scan = (acc.poses.iter()).any(|a| separation_scaled(a, &q, &scales) < min_sep);
                assert_eq!(acc.too_close(&q), scan, "{min_deg}°, pose {q:?}");
                if scan {
                    refused += 1;
                } else {
                    kept += 1;
                    acc.push(q);
                }
            }
            assert!(
                refused > 100 && kept > 20,
                "{min_deg}°: {refused} refused, {kept} kept"
            );
        }
    }

    /// Too few cells for an exact one-cell neighbourhood: the plain scan.
    #[test]
    fn a_wide_separation_scans_every_pose() {
        let scales = vec![0.0; 6];
        let acc = Accepted::new(&scales, f64::to_radians(80.0), 0);
        assert_eq!(acc.cells, 0);
        let slides = vec![1.0; 3];
        assert_eq!(Accepted::new(&slides, 0.3, 0).cells, 0);
    }
}
