//! Weighted residuals of a calibration, and their normal equations.
//!
//! Unknowns are the free geometric parameters `x`; the socket centres `c_k`
//! are nuisance unknowns, eliminated (variable projection). Residual kinds, a
//! closed set ([`ResidualKind`]):
//!
//! - **touch** `i` of point `k`: `r_i = w_i (p(q_i; x) − c_k)` (3 rows), with
//!   `w_i = 1/σ_i` and `σ_i² = σ_probe² + σ_enc² ‖∂p/∂q‖²_F / 3` — probe
//!   seating plus encoder noise carried through the joint Jacobian at the
//!   arm the fit starts from (fixed during the fit, so the cost is one
//!   function);
//! - **reference length** between points `a`, `b`:
//!   `r = w_L (|c_a − c_b| − L)` with `σ_L² = u_L² + 1/W_a + 1/W_b`, the
//!   stated uncertainty plus the variance of both centroids along the line
//!   (`W_k = Σ_{i∈k} w_i²`), or `w_L = 1/σ` from `--length-weight`.
//!
//! For fixed `x` the touch cost `Σ_i w_i² |p_i − c_k|²` is least at the
//! weighted centroid `c_k = Σ w_i² p_i / W_k`, so the centres are replaced
//! by centroids: the normal matrix stays `p × p` (`p` ≤ 31) whatever the
//! number of points, each touch costs only its own Jacobian, and the
//! reduced matrix is exactly the Schur complement one gets by carrying the
//! centres as parameters. Per point, with `J_i` the free columns of `∂p/∂x`:
//!
//! ```text
//! JᵀJ  += Σ w_i² J_iᵀJ_i − (Σ w_i² J_i)ᵀ(Σ w_i² J_i) / W_k
//! Jᵀr  += Σ w_i² J_iᵀ p_i − (Σ w_i² J_i)ᵀ c_k
//! ```
//!
//! and a length adds `w_L² gᵀg`, `g = u_abᵀ (J̄_a − J̄_b)`,
//! `J̄_k = Σ w_i² J_i / W_k`. The lengths use the touch centroids (their
//! uncertainty folded into `σ_L`) rather than pulling the centres: a
//! reference length is one scalar against 3·n touch rows per point.
//! Degrees of freedom: `m − p` with `m = 3·touches + lengths` and
//! `p = free parameters + 3·points`.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::dataset::DataSet;
use crate::kernel::{ArmKernel, KernelError};

/// The residual kinds of a calibration: a closed set, matched exhaustively
/// wherever residuals are counted or reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResidualKind {
    /// A touch against its point's centroid (3 rows).
    Touch,
    /// A distance between two centroids against a reference length (1 row).
    Length,
}

/// What is known of the measurement noise; `None` = not stated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Noise {
    /// σ of each encoder reading, rad.
    pub encoder_rad: Option<f64>,
    /// σ of the probe seating per axis, mm.
    pub probe_mm: Option<f64>,
    /// σ of a reference length when its file states none, mm.
    pub length_default_mm: f64,
    /// Overrides every length's weight (1/mm).
    pub length_weight: Option<f64>,
}

impl Noise {
    /// Whether any touch noise was stated.
    pub fn stated(&self) -> bool {
        self.encoder_rad.is_some() || self.probe_mm.is_some()
    }
}

/// Weights of every residual: `1/σ` (1/mm).
#[derive(Clone, Debug, PartialEq)]
pub struct Weights {
    /// Per touch (data-set order).
    pub touch: Vec<f64>,
    /// Per reference length.
    pub length: Vec<f64>,
}

impl Weights {
    /// Weights from `noise` at the arm `kernel` (the fit's start). Without
    /// stated touch noise every touch has weight `1/touch_sigma_mm`.
    ///
    /// ```
    /// use aacmm_core::{kernel::ArmKernel, params::DhParams, residuals::*};
    /// # use aacmm_core::{dataset::DataSet, io::{AngleUnit, parse_poses}};
    /// # let (poses, _) = parse_poses("point,q1,q2,q3,q4,q5,q6\nA,0,0,0,0,0,0\nA,1,0,0,0,0,0\nA,2,0,0,0,0,0\n", "p.csv", AngleUnit::Deg, Some(6)).unwrap();
    /// # let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    /// let k = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
    /// let noise = Noise { probe_mm: Some(0.01), ..Noise::default() };
    /// let w = Weights::new(&k, &data, &noise, 1.0).unwrap();
    /// assert!((w.touch[0] - 100.0).abs() < 1e-9); // 1 / 0.01 mm
    /// ```
    pub fn new(
        kernel: &ArmKernel,
        data: &DataSet,
        noise: &Noise,
        touch_sigma_mm: f64,
    ) -> Result<Weights, KernelError> {
        let touch = if noise.stated() {
            let enc = noise.encoder_rad.unwrap_or(0.0);
            let probe = noise.probe_mm.unwrap_or(0.0);
            let mut jq = vec![[0.0; 3]; data.joints()];
            (0..data.len())
                .map(|i| {
                    kernel.joint_jacobian(data.reading(i), &mut jq)?;
                    let frob: f64 = jq.iter().flatten().map(|v| v * v).sum();
                    Ok(1.0 / (probe * probe + enc * enc * frob / 3.0).sqrt())
                })
                .collect::<Result<Vec<f64>, KernelError>>()?
        } else {
            vec![1.0 / touch_sigma_mm; data.len()]
        };
        let big_w = |k: usize| {
            data.points()[k]
                .touches
                .clone()
                .map(|i| touch[i] * touch[i])
                .sum::<f64>()
        };
        let length = data
            .references()
            .iter()
            .map(|r| match noise.length_weight {
                Some(w) => w,
                None => {
                    let u = r.uncertainty.unwrap_or(noise.length_default_mm);
                    1.0 / (u * u + 1.0 / big_w(r.a) + 1.0 / big_w(r.b)).sqrt()
                }
            })
            .collect();
        Ok(Weights { touch, length })
    }
}

/// The reduced normal equations at one parameter set: `JᵀJ` and `Jᵀr` over
/// the free columns, the cost `Σ r²`, and its parts.
#[derive(Clone, Debug, PartialEq)]
pub struct Normal {
    /// Free columns, in order (indices into the full parameter vector).
    pub free: Vec<usize>,
    /// `JᵀJ`, row-major `p × p`.
    pub jtj: Vec<f64>,
    /// `Jᵀr`.
    pub jtr: Vec<f64>,
    /// `Σ r²` of the touch residuals.
    pub touch_cost: f64,
    /// `Σ r²` of the length residuals.
    pub length_cost: f64,
    /// Weighted centroid of every point, mm.
    pub centroids: Vec<[f64; 3]>,
}

impl Normal {
    /// The whole cost `Σ r²` (a χ² when the weights are right).
    pub fn cost(&self) -> f64 {
        self.touch_cost + self.length_cost
    }
}

/// Per-point sums: `Σ w² J` (3 × p), `Σ w² Jᵀ p̃`, `Σ w² p̃`, `W`, with `p̃`
/// the position relative to the point's first touch (no cancellation of
/// metre-sized coordinates).
struct PointSums {
    sj: Vec<[f64; 3]>,
    sjp: Vec<f64>,
    sp: [f64; 3],
    spp: f64,
    w: f64,
    origin: [f64; 3],
}

/// What one chunk of points contributes.
struct Partial {
    jtj: Vec<f64>,
    jtr: Vec<f64>,
    cost: f64,
    /// Per point of the chunk: centroid, and `J̄` (3 × p) if lengths need it.
    centroids: Vec<[f64; 3]>,
    mean_j: Vec<Vec<[f64; 3]>>,
}

/// Points per work item: fixed, so the sums are added in the same order
/// whatever the number of threads (same bytes on any machine).
const POINTS_PER_CHUNK: usize = 64;

/// The normal equations of the weighted residuals at `kernel`, over the
/// columns `free`. Chunks of points run on up to `threads` threads; the
/// result does not depend on `threads`.
pub fn normal_equations(
    kernel: &ArmKernel,
    data: &DataSet,
    weights: &Weights,
    free: &[usize],
    threads: usize,
) -> Result<Normal, KernelError> {
    let np = data.points().len();
    let chunks: Vec<Range<usize>> = (0..np)
        .step_by(POINTS_PER_CHUNK)
        .map(|s| s..(s + POINTS_PER_CHUNK).min(np))
        .collect();
    let need_mean = data.references().len() > 0;
    let run = |c: &Range<usize>| chunk(kernel, data, weights, free, c.clone(), need_mean);
    let partials: Vec<Result<Partial, KernelError>> = if threads <= 1 || chunks.len() < 4 {
        chunks.iter().map(run).collect()
    } else {
        parallel_map(&chunks, threads, run)
    };
    let p = free.len();
    let mut out = Normal {
        free: free.to_vec(),
        jtj: vec![0.0; p * p],
        jtr: vec![0.0; p],
        touch_cost: 0.0,
        length_cost: 0.0,
        centroids: Vec::with_capacity(np),
    };
    let mut mean_j: Vec<Vec<[f64; 3]>> = Vec::with_capacity(if need_mean { np } else { 0 });
    for part in partials {
        let part = part?;
        for (o, v) in out.jtj.iter_mut().zip(&part.jtj) {
            *o += v;
        }
        for (o, v) in out.jtr.iter_mut().zip(&part.jtr) {
            *o += v;
        }
        out.touch_cost += part.cost;
        out.centroids.extend(part.centroids);
        mean_j.extend(part.mean_j);
    }
    for (r, &w) in data.references().iter().zip(&weights.length) {
        let (ca, cb) = (out.centroids[r.a], out.centroids[r.b]);
        let d: [f64; 3] = std::array::from_fn(|k| ca[k] - cb[k]);
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let res = w * (len - r.distance);
        out.length_cost += res * res;
        let u = d.map(|v| v / len);
        let g: Vec<f64> = (0..p)
            .map(|c| {
                let (ja, jb) = (mean_j[r.a][c], mean_j[r.b][c]);
                w * (0..3).map(|k| u[k] * (ja[k] - jb[k])).sum::<f64>()
            })
            .collect();
        for a in 0..p {
            out.jtr[a] += g[a] * res;
            for b in 0..p {
                out.jtj[a * p + b] += g[a] * g[b];
            }
        }
    }
    Ok(out)
}

impl PointSums {
    fn new(p: usize) -> PointSums {
        PointSums {
            sj: vec![[0.0; 3]; p],
            sjp: vec![0.0; p],
            sp: [0.0; 3],
            spp: 0.0,
            w: 0.0,
            origin: [0.0; 3],
        }
    }

    /// Adds one touch: position, weight², free Jacobian columns.
    #[inline]
    fn add(&mut self, pos: &[f64; 3], w2: f64, jac: &[[f64; 3]], free: &[usize], jtj: &mut [f64]) {
        if self.w == 0.0 {
            self.origin = *pos;
        }
        let p = free.len();
        let d: [f64; 3] = std::array::from_fn(|k| pos[k] - self.origin[k]);
        for (s, v) in self.sp.iter_mut().zip(&d) {
            *s += w2 * v;
        }
        self.spp += w2 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        self.w += w2;
        for (a, &ca) in free.iter().enumerate() {
            let wa = jac[ca].map(|v| v * w2);
            let s = &mut self.sj[a];
            s[0] += wa[0];
            s[1] += wa[1];
            s[2] += wa[2];
            self.sjp[a] += wa[0] * d[0] + wa[1] * d[1] + wa[2] * d[2];
            let row = &mut jtj[a * p..a * p + a + 1];
            for (r, &cb) in row.iter_mut().zip(&free[..=a]) {
                let jb = jac[cb];
                *r += wa[0] * jb[0] + wa[1] * jb[1] + wa[2] * jb[2];
            }
        }
    }

    /// Closes the point: its Schur term into the lower triangle of `jtj`,
    /// its gradient and cost; resets for the next point.
    fn finish(&mut self, part: &mut Partial, need_mean: bool) {
        let p = self.sjp.len();
        let w = self.w;
        let c: [f64; 3] = std::array::from_fn(|k| self.sp[k] / w);
        // Σ w²|p̃ − c̃|² = Σ w²|p̃|² − W|c̃|²
        part.cost += self.spp - w * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        for a in 0..p {
            let sa = self.sj[a];
            part.jtr[a] += self.sjp[a] - (sa[0] * c[0] + sa[1] * c[1] + sa[2] * c[2]);
            for b in 0..=a {
                let sb = self.sj[b];
                part.jtj[a * p + b] -= (sa[0] * sb[0] + sa[1] * sb[1] + sa[2] * sb[2]) / w;
            }
        }
        part.centroids
            .push(std::array::from_fn(|k| c[k] + self.origin[k]));
        if need_mean {
            part.mean_j
                .push(self.sj.iter().map(|s| s.map(|v| v / w)).collect());
        }
        *self = PointSums::new(p);
    }
}

fn chunk(
    kernel: &ArmKernel,
    data: &DataSet,
    weights: &Weights,
    free: &[usize],
    points: Range<usize>,
    need_mean: bool,
) -> Result<Partial, KernelError> {
    let p = free.len();
    let mut part = Partial {
        jtj: vec![0.0; p * p],
        jtr: vec![0.0; p],
        cost: 0.0,
        centroids: Vec::with_capacity(points.len()),
        mean_j: Vec::new(),
    };
    let all = data.points();
    let touches = all[points.start].touches.start..all[points.end - 1].touches.end;
    let mut sums = PointSums::new(p);
    let mut point = points.start;
    let mut finite = true;
    kernel.for_each_jacobian(data.poses(), touches, |i, pos, jac| {
        if i == all[point].touches.end {
            sums.finish(&mut part, need_mean);
            point += 1;
        }
        finite &= pos.iter().all(|v| v.is_finite());
        let w = weights.touch[i];
        sums.add(pos, w * w, jac, free, &mut part.jtj);
    })?;
    sums.finish(&mut part, need_mean);
    for a in 0..p {
        for b in 0..a {
            part.jtj[b * p + a] = part.jtj[a * p + b];
        }
    }
    if !finite {
        part.cost = f64::INFINITY;
    }
    Ok(part)
}

/// `f` over `items` on `threads` scoped threads, results in item order.
pub(crate) fn parallel_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut slots: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
    let done = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads.min(items.len()) {
            s.spawn(|| {
                let mut mine = Vec::new();
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    if i >= items.len() {
                        break;
                    }
                    mine.push((i, f(&items[i])));
                }
                done.lock().expect("no worker panics").extend(mine);
            });
        }
    });
    for (i, r) in done.into_inner().expect("no worker panics") {
        slots[i] = Some(r);
    }
    slots
        .into_iter()
        .map(|r| r.expect("every item ran"))
        .collect()
}

/// The cost `Σ r²` alone (positions only, no Jacobian): what a trial step
/// or an annealing move needs. `xyz` is a buffer of one position per touch.
pub fn cost(
    kernel: &ArmKernel,
    data: &DataSet,
    weights: &Weights,
    xyz: &mut [[f64; 3]],
) -> Result<f64, KernelError> {
    kernel.positions(data.poses(), 0..data.len(), xyz)?;
    let mut total = 0.0;
    let mut centroids = Vec::with_capacity(data.points().len());
    for point in data.points() {
        let origin = xyz[point.touches.start];
        let (mut sp, mut spp, mut w) = ([0.0; 3], 0.0, 0.0);
        for i in point.touches.clone() {
            let w2 = weights.touch[i] * weights.touch[i];
            let d: [f64; 3] = std::array::from_fn(|k| xyz[i][k] - origin[k]);
            for k in 0..3 {
                sp[k] += w2 * d[k];
            }
            spp += w2 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            w += w2;
        }
        let c: [f64; 3] = std::array::from_fn(|k| sp[k] / w);
        total += spp - w * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        centroids.push(std::array::from_fn(|k| c[k] + origin[k]));
    }
    for (r, &w) in data.references().iter().zip(&weights.length) {
        let res = w * (crate::geometry::distance(&centroids[r.a], &centroids[r.b]) - r.distance);
        total += res * res;
    }
    Ok(if total.is_finite() { total } else { f64::INFINITY })
}
