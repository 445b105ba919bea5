//! Weighted residuals of a calibration, and their normal equations.
//!
//! Unknowns are the free geometric parameters `x`; the socket centres `c_k`
//! are nuisance unknowns, eliminated (variable projection). Residual kinds, a
//! closed set ([`ResidualKind`]):
//!
//! - **touch** `i` of point `k`: `r_i = L_iᵀ (p(q_i; x) − c_k)` (3 rows),
//!   whitened by its covariance `Σ_i = σ_probe² I + σ_enc² J_q J_qᵀ`
//!   (`L_i L_iᵀ = A_i = Σ_i⁻¹`) — probe seating plus encoder noise carried
//!   through the joint Jacobian `J_q` at the arm the fit starts from (fixed
//!   during the fit, so the cost is one function). Encoder noise moves the
//!   probe mostly across the arm, so the 3 × 3 weight matters; without
//!   stated noise, `A_i = I/σ²`;
//! - **reference length** between points `a`, `b`:
//!   `r = w_L (|c_a − c_b| − L)` with `σ_L² = u_L² + uᵀ(C_a + C_b)u`, the
//!   stated uncertainty plus the variance of both centroids along the unit
//!   vector `u` between them (`C_k = (Σ_{i∈k} A_i)⁻¹`), or `w_L = 1/σ` from
//!   `--length-weight`.
//!
//! For fixed `x` the touch cost `Σ_i (p_i − c)ᵀA_i(p_i − c)` is least at the
//! weighted centroid `c_k = (Σ A_i)⁻¹ Σ A_i p_i`, so the centres are replaced
//! by centroids: the normal matrix stays `p × p` (`p` ≤ 31) whatever the
//! number of points, each touch costs only its own Jacobian, and the
//! reduced matrix is exactly the Schur complement one gets by carrying the
//! centres as parameters. Per point, with `J_i` the free columns of `∂p/∂x`
//! and `S = Σ A_i`, `G = Σ A_i J_i`:
//!
//! ```text
//! JᵀJ  += Σ J_iᵀA_iJ_i − Gᵀ S⁻¹ G
//! Jᵀr  += Σ J_iᵀA_i p_i − Gᵀ c_k
//! ```
//!
//! and a length adds `w_L² gᵀg`, `g = uᵀ (J̄_a − J̄_b)`, `J̄_k = S⁻¹G`. The lengths use the touch centroids (their
//! uncertainty folded into `σ_L`) rather than pulling the centres: a
//! reference length is one scalar against 3·n touch rows per point.
//! Degrees of freedom: `m − p` with `m = 3·touches + lengths` and
//! `p = free parameters + 3·points`.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::dataset::DataSet;
use crate::error::{OptionError, check_nonnegative, short};
use crate::kernel::{ArmKernel, KernelError, NoiseOf};

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

/// σ of a reference length whose file states none, mm.
pub const DEFAULT_LENGTH_SIGMA_MM: f64 = 0.001;

/// What is known of the measurement noise; `None` = not stated. The
/// default states no touch noise and [`DEFAULT_LENGTH_SIGMA_MM`] for
/// lengths without their own uncertainty.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
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

impl Default for Noise {
    fn default() -> Self {
        Noise {
            encoder_rad: None,
            probe_mm: None,
            length_default_mm: DEFAULT_LENGTH_SIGMA_MM,
            length_weight: None,
        }
    }
}

impl Noise {
    /// Whether any touch noise was stated.
    pub fn stated(&self) -> bool {
        self.encoder_rad.is_some() || self.probe_mm.is_some()
    }

    /// Checks the values: each finite and `≥ 0` (a length weight `> 0`),
    /// and stated touch noise not zero on both counts.
    ///
    /// ```
    /// use aacmm_core::residuals::Noise;
    /// assert!(Noise::default().check().is_ok());
    /// let zero = Noise { encoder_rad: Some(0.0), probe_mm: Some(0.0), ..Noise::default() };
    /// assert_eq!(zero.check().unwrap_err().field, "noise.probe_mm");
    /// let negative = Noise { probe_mm: Some(-0.01), ..Noise::default() };
    /// assert_eq!(negative.check().unwrap_err().field, "noise.probe_mm");
    /// ```
    pub fn check(&self) -> Result<(), OptionError> {
        for (field, v) in [
            ("noise.encoder_rad", self.encoder_rad),
            ("noise.probe_mm", self.probe_mm),
        ] {
            if let Some(v) = v {
                check_nonnegative(field, v, true)?;
            }
        }
        check_nonnegative("noise.length_default_mm", self.length_default_mm, true)?;
        if let Some(w) = self.length_weight {
            check_nonnegative("noise.length_weight", w, false)?;
        }
        let zero = |v: Option<f64>| v.unwrap_or(0.0) == 0.0;
        if self.stated() && zero(self.encoder_rad) && zero(self.probe_mm) {
            return Err(OptionError::new(
                "noise.probe_mm",
                0,
                "encoder and probe noise both 0: a touch needs some uncertainty",
            ));
        }
        Ok(())
    }
}

/// Refuses weights that are not finite numbers, naming the noise that made
/// them: a σ whose square overflows (the weight is 0/0), or one that
/// vanishes (the weight is 1/0). Positions are finite here, so the noise is
/// the only cause.
fn check_weights(
    touch: &[Sym3],
    length: &[f64],
    noise: &Noise,
    touch_sigma_mm: f64,
    data: &DataSet,
) -> Result<(), KernelError> {
    let overflow = "a σ this large overflows and one this small vanishes in double precision";
    let advice = format!(
        "{overflow}; state the instrument's noise (typically 0.001–0.1° per encoder and \
         0.001–0.1 mm for the probe)"
    );
    // A weight matrix must be finite with a positive diagonal (an
    // overflowing covariance can also invert to exact zeros).
    let bad = |a: &Sym3| !a.iter().all(|v| v.is_finite()) || !a[..3].iter().all(|&v| v > 0.0);
    if let Some(i) = touch.iter().position(bad) {
        let stated = match (noise.encoder_rad, noise.probe_mm) {
            (None, None) => format!("an assumed touch σ of {} mm", short(touch_sigma_mm)),
            (e, p) => [
                e.map(|e| {
                    format!(
                        "encoder noise σ = {}° ({} rad)",
                        short(e.to_degrees()),
                        short(e)
                    )
                }),
                p.map(|p| format!("probe noise σ = {} mm", short(p))),
            ]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(" and "),
        };
        return Err(KernelError::Noise {
            of: NoiseOf::Touches,
            message: format!(
                "the touch weights are not finite positive numbers with {stated} (first at \
                 {}); {advice}",
                data.source().touch(i)
            ),
        });
    }
    // A length weight given as 0 means "ignore the lengths"; one computed
    // as 0 means an uncertainty that overflowed.
    let given = noise.length_weight.is_some();
    if let Some(r) = length
        .iter()
        .position(|w| !(w.is_finite() && (*w > 0.0 || given)))
    {
        let sigma = match noise.length_weight {
            Some(w) => format!("a length weight of {} 1/mm", short(w)),
            None => format!(
                "a length uncertainty of {} mm",
                short(
                    data.references()[r]
                        .uncertainty
                        .unwrap_or(noise.length_default_mm)
                )
            ),
        };
        return Err(KernelError::Noise {
            of: NoiseOf::Lengths,
            message: format!(
                "the weight of the reference length at {} is not a finite positive number \
                 with {sigma}; {overflow}; give the uncertainty of the calibrated length \
                 (typically 0.0005–0.01 mm)",
                data.source().reference(r)
            ),
        });
    }
    Ok(())
}

/// A symmetric 3 × 3 matrix: `[xx, yy, zz, xy, xz, yz]`.
pub(crate) type Sym3 = [f64; 6];

/// `A·v` for a symmetric `A`.
#[inline(always)]
fn sym_mul(a: &Sym3, v: &[f64; 3]) -> [f64; 3] {
    [
        a[0] * v[0] + a[3] * v[1] + a[4] * v[2],
        a[3] * v[0] + a[1] * v[1] + a[5] * v[2],
        a[4] * v[0] + a[5] * v[1] + a[2] * v[2],
    ]
}

/// The inverse of a symmetric positive-definite 3 × 3 matrix (adjugate).
fn sym_inv(a: &Sym3) -> Sym3 {
    let [xx, yy, zz, xy, xz, yz] = *a;
    let c = [
        yy * zz - yz * yz,
        xx * zz - xz * xz,
        xx * yy - xy * xy,
        xz * yz - xy * zz,
        xy * yz - xz * yy,
        xy * xz - xx * yz,
    ];
    let det = xx * c[0] + xy * c[3] + xz * c[4];
    c.map(|v| v / det)
}

/// The centroid covariance `(Σ A_i)⁻¹` of a point from its touches'
/// weights, summed in touch order.
fn centroid_cov(touch: &[Sym3]) -> Sym3 {
    let mut sum = [0.0; 6];
    for a in touch {
        for (s, v) in sum.iter_mut().zip(a) {
            *s += v;
        }
    }
    sym_inv(&sum)
}

/// Per reference length, `1/σ_L`: the stated weight, or the length's own
/// uncertainty combined with its two centroids' covariances along it.
fn length_weights(
    kernel: &ArmKernel,
    data: &DataSet,
    noise: &Noise,
    centroid_cov: &[Sym3],
) -> Result<Vec<f64>, KernelError> {
    data.references()
        .iter()
        .map(|r| match noise.length_weight {
            Some(w) => Ok(w),
            None => {
                let (ca, cb) = (
                    kernel.position(data.reading(data.points()[r.a].touches.start))?,
                    kernel.position(data.reading(data.points()[r.b].touches.start))?,
                );
                let d: [f64; 3] = std::array::from_fn(|k| ca[k] - cb[k]);
                let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
                    .sqrt()
                    .max(f64::MIN_POSITIVE);
                let u = d.map(|v| v / n);
                let along = |c: &Sym3| {
                    let cu = sym_mul(c, &u);
                    u[0] * cu[0] + u[1] * cu[1] + u[2] * cu[2]
                };
                let ul = r.uncertainty.unwrap_or(noise.length_default_mm);
                Ok(1.0 / (ul * ul + along(&centroid_cov[r.a]) + along(&centroid_cov[r.b])).sqrt())
            }
        })
        .collect()
}

/// One touch's weight at an arm: `A_i = (p²I + e² J_q J_qᵀ)⁻¹` with stated
/// noise, `I/σ²` without.
struct TouchWeight<'a> {
    kernel: &'a ArmKernel,
    data: &'a DataSet,
    stated: bool,
    e2: f64,
    p2: f64,
    unit: f64,
}

impl<'a> TouchWeight<'a> {
    fn new(kernel: &'a ArmKernel, data: &'a DataSet, noise: &Noise, touch_sigma_mm: f64) -> Self {
        TouchWeight {
            kernel,
            data,
            stated: noise.stated(),
            e2: noise.encoder_rad.unwrap_or(0.0).powi(2),
            p2: noise.probe_mm.unwrap_or(0.0).powi(2),
            unit: 1.0 / (touch_sigma_mm * touch_sigma_mm),
        }
    }

    /// The weights of touches `range`, in order, to `f(i, A_i)`; the joint
    /// Jacobians a batch of lanes at a time.
    fn each(
        &self,
        mut range: Range<usize>,
        mut f: impl FnMut(usize, Sym3) -> Result<(), KernelError>,
    ) -> Result<(), KernelError> {
        if !self.stated {
            let w = self.unit;
            return range.try_for_each(|i| f(i, [w, w, w, 0.0, 0.0, 0.0]));
        }
        let (e2, p2) = (self.e2, self.p2);
        let mut result = Ok(());
        self.kernel
            .for_each_joint_jacobian(self.data.poses(), range, |i, jq| {
                if result.is_ok() {
                    result = f(i, touch_weight(jq, e2, p2));
                }
            })?;
        result
    }
}

/// `(p²I + e² J_q J_qᵀ)⁻¹` of one touch's joint Jacobian.
#[inline(always)]
fn touch_weight(jq: &[[f64; 3]], e2: f64, p2: f64) -> Sym3 {
    let s = |a: usize, b: usize| jq.iter().map(|c| c[a] * c[b]).sum::<f64>() * e2;
    let cov = [
        p2 + s(0, 0),
        p2 + s(1, 1),
        p2 + s(2, 2),
        s(0, 1),
        s(0, 2),
        s(1, 2),
    ];
    sym_inv(&cov)
}

/// `‖a − b‖/‖b‖` in the Frobenius norm (off-diagonal entries count twice).
/// A touch weight that [`check_weights`] would refuse counts as an infinite
/// change.
fn touch_change(a: &Sym3, b: &Sym3) -> f64 {
    if !a.iter().all(|v| v.is_finite()) || !a[..3].iter().all(|&v| v > 0.0) {
        return f64::INFINITY;
    }
    let norm = |a: &Sym3| {
        (a[..3].iter().map(|v| v * v).sum::<f64>()
            + 2.0 * a[3..].iter().map(|v| v * v).sum::<f64>())
        .sqrt()
    };
    let d: Sym3 = std::array::from_fn(|k| a[k] - b[k]);
    norm(&d) / norm(b)
}

/// `|a − b|/|b|` for a length weight.
fn length_change(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Weights of every residual.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Weights {
    /// Per touch (data-set order), the inverse covariance `A_i = Σ_i⁻¹` of its
    /// position, 1/mm².
    pub touch: Vec<Sym3>,
    /// Per reference length, `1/σ_L` (1/mm).
    pub length: Vec<f64>,
    /// The stated tolerances of the geometry, if any
    /// ([`crate::calibrate::prior`]): added by the fits, not here.
    pub prior: Option<crate::calibrate::prior::PriorTerm>,
}

impl Weights {
    /// Weights from `noise` at the arm `kernel` (the fit's start). Without
    /// stated touch noise every touch has `A = I/touch_sigma_mm²`.
    pub fn new(
        kernel: &ArmKernel,
        data: &DataSet,
        noise: &Noise,
        touch_sigma_mm: f64,
    ) -> Result<Weights, KernelError> {
        Weights::new_threads(kernel, data, noise, touch_sigma_mm, 1)
    }

    /// [`Weights::new`] with the touches' weights (a joint Jacobian each) on
    /// up to `threads` threads, in chunks of fixed size: each touch's weight
    /// is its own, so the result is the same bits whatever `threads`.
    pub fn new_threads(
        kernel: &ArmKernel,
        data: &DataSet,
        noise: &Noise,
        touch_sigma_mm: f64,
        threads: usize,
    ) -> Result<Weights, KernelError> {
        let touch = if noise.stated() {
            let mut touch = vec![[0.0; 6]; data.len()];
            let parts = touch
                .chunks_mut(TOUCHES_PER_CHUNK)
                .enumerate()
                .collect::<Vec<_>>();
            let parts: Vec<std::sync::Mutex<(usize, &mut [Sym3])>> =
                parts.into_iter().map(std::sync::Mutex::new).collect();
            let results = parallel_map(&parts, threads, |part| {
                let mut part = part
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
                let (k, out) = &mut *part;
                let start = *k * TOUCHES_PER_CHUNK;
                TouchWeight::new(kernel, data, noise, touch_sigma_mm).each(
                    start..start + out.len(),
                    |i, w| {
                        out[i - start] = w;
                        Ok(())
                    },
                )
            });
            drop(parts);
            results.into_iter().collect::<Result<(), KernelError>>()?;
            touch
        } else {
            let w = 1.0 / (touch_sigma_mm * touch_sigma_mm);
            vec![[w, w, w, 0.0, 0.0, 0.0]; data.len()]
        };
        let centroid_cov: Vec<Sym3> = data
            .points()
            .iter()
            .map(|p| centroid_cov(&touch[p.touches.clone()]))
            .collect();
        let length = length_weights(kernel, data, noise, &centroid_cov)?;
        check_weights(&touch, &length, noise, touch_sigma_mm, data)?;
        Ok(Weights {
            touch,
            length,
            prior: None,
        })
    }

    /// The largest relative change from `other` to `self` of any touch's
    /// weight matrix (Frobenius norm) or any length's weight; infinite when
    /// the shapes differ.
    #[cfg(test)]
    pub fn relative_change(&self, other: &Weights) -> f64 {
        if self.touch.len() != other.touch.len() || self.length.len() != other.length.len() {
            return f64::INFINITY;
        }
        let touch = self
            .touch
            .iter()
            .zip(&other.touch)
            .map(|(a, b)| touch_change(a, b));
        let length = self
            .length
            .iter()
            .zip(&other.length)
            .map(|(a, b)| length_change(*a, *b));
        touch.chain(length).fold(0.0, f64::max)
    }

    /// What `Weights::new_threads(kernel, data, noise, touch_sigma_mm,
    /// threads)?.relative_change(self)` would be, without holding a second
    /// set of weights (at 10⁶ touches, 48 MB): the new touch weights are made
    /// a chunk of whole points at a time and compared at once. Infinite
    /// where the new weights would be refused, so that the caller builds
    /// them and reports why.
    pub fn relative_change_to(
        &self,
        kernel: &ArmKernel,
        data: &DataSet,
        noise: &Noise,
        touch_sigma_mm: f64,
        threads: usize,
    ) -> Result<f64, KernelError> {
        if self.touch.len() != data.len() || self.length.len() != data.references().len() {
            return Ok(f64::INFINITY);
        }
        // Chunks of whole points, so that each chunk's centroid covariances
        // are its own.
        let mut chunks = Vec::new();
        let mut first = 0;
        for (k, p) in data.points().iter().enumerate() {
            if p.touches.end - data.points()[first].touches.start >= TOUCHES_PER_CHUNK
                || k + 1 == data.points().len()
            {
                chunks.push(first..k + 1);
                first = k + 1;
            }
        }
        let results = parallel_map(&chunks, threads, |points| {
            let all = &data.points()[points.clone()];
            let mut change = 0.0_f64;
            let mut covs = Vec::with_capacity(points.len());
            let mut buffer = Vec::new();
            let mut point = all.iter().map(|p| p.touches.end).peekable();
            let touches = all[0].touches.start..all[all.len() - 1].touches.end;
            TouchWeight::new(kernel, data, noise, touch_sigma_mm).each(touches, |i, a| {
                change = change.max(touch_change(&a, &self.touch[i]));
                buffer.push(a);
                if point.next_if_eq(&(i + 1)).is_some() {
                    covs.push(centroid_cov(&buffer));
                    buffer.clear();
                }
                Ok(())
            })?;
            Ok::<_, KernelError>((change, covs))
        });
        let mut change = 0.0_f64;
        let mut covs = Vec::with_capacity(data.points().len());
        for r in results {
            let (c, v) = r?;
            change = change.max(c);
            covs.extend(v);
        }
        let length = length_weights(kernel, data, noise, &covs)?;
        if check_weights(&[], &length, noise, touch_sigma_mm, data).is_err() {
            return Ok(f64::INFINITY);
        }
        Ok(length
            .iter()
            .zip(&self.length)
            .map(|(a, b)| length_change(*a, *b))
            .fold(change, f64::max))
    }

    /// These weights with touch `i`'s matrix `A_i` multiplied by
    /// `scale[i]` (a robust fit's weight in (0, 1]); the lengths' weights
    /// unchanged.
    pub fn scaled_touches(&self, scale: &[f64]) -> Weights {
        Weights {
            touch: self
                .touch
                .iter()
                .zip(scale)
                .map(|(a, &w)| a.map(|v| v * w))
                .collect(),
            length: self.length.clone(),
            prior: self.prior.clone(),
        }
    }

    /// A typical touch σ, mm: the median over touches of `sqrt(trace(Σ_i)/3)`.
    pub fn typical_touch_sigma(&self) -> f64 {
        let mut s: Vec<f64> = self
            .touch
            .iter()
            .map(|a| (sym_inv(a)[..3].iter().sum::<f64>() / 3.0).sqrt())
            .collect();
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied().unwrap_or(f64::NAN)
    }
}

/// The reduced normal equations at one parameter set: `JᵀJ` and `Jᵀr` over
/// the free columns, the cost `Σ r²`, and its parts.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Normal {
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
    /// `Σ r²` of the prior's pseudo-observations (0 without a prior).
    pub prior_cost: f64,
    /// Weighted centroid of every point, mm.
    pub centroids: Vec<[f64; 3]>,
}

impl Normal {
    /// The whole cost `Σ r²` (a χ² when the weights are right).
    pub fn cost(&self) -> f64 {
        self.touch_cost + self.length_cost + self.prior_cost
    }

    /// The normal equations over `cols`, a subset of these columns: every
    /// term (touch, centroid elimination, length) is bilinear in the
    /// columns, so the reduced system of a subset is the principal
    /// submatrix. `None` when a column is not among these.
    pub fn restrict(&self, cols: &[usize]) -> Option<Normal> {
        let at: Vec<usize> = cols
            .iter()
            .map(|c| self.free.iter().position(|f| f == c))
            .collect::<Option<_>>()?;
        let p = self.free.len();
        Some(Normal {
            free: cols.to_vec(),
            jtj: at
                .iter()
                .flat_map(|&a| at.iter().map(move |&b| self.jtj[a * p + b]))
                .collect(),
            jtr: at.iter().map(|&a| self.jtr[a]).collect(),
            touch_cost: self.touch_cost,
            length_cost: self.length_cost,
            prior_cost: self.prior_cost,
            centroids: self.centroids.clone(),
        })
    }
}

/// Per-point sums: `G = Σ A J` (3 × p), `Σ Jᵀ A p̃`, `Σ A p̃`, `Σ p̃ᵀA p̃`,
/// `S = Σ A`, with `p̃` the position relative to the point's first touch (no
/// cancellation of metre-sized coordinates).
struct PointSums {
    g: Vec<[f64; 3]>,
    jap: Vec<f64>,
    ap: [f64; 3],
    pap: f64,
    s: Sym3,
    started: bool,
    origin: [f64; 3],
    /// Row stride of the padded `JᵀAJ` and of the scratch: `p` rounded up to
    /// a whole number of [`LANES`].
    stride: usize,
    /// Scratch, up to [`BLOCK`] touches of one point: the free columns of
    /// `J` and of `A·J`, one padded row per touch and coordinate, so the
    /// `JᵀAJ` update runs over whole lanes of contiguous memory.
    j: [Vec<f64>; 3],
    aj: [Vec<f64>; 3],
    /// Touches held in the scratch, not yet in `JᵀAJ`.
    pending: usize,
    /// Scratch: the point's `J̄ = S⁻¹ G`.
    mean: Vec<[f64; 3]>,
}

/// Touches whose `JᵀAJ` terms are added in one sweep over the matrix: each
/// entry is loaded and stored once per block, the terms still added one
/// touch at a time in touch order (the same bits as touch by touch).
const BLOCK: usize = 8;

/// Entries of a `JᵀAJ` row updated together (one AVX2 register of f64).
const LANES: usize = 4;

/// What one chunk of points contributes.
struct Partial {
    jtj: Vec<f64>,
    jtr: Vec<f64>,
    cost: f64,
    /// Per point of the chunk: centroid, and `J̄` (3 × p) if lengths need it.
    centroids: Vec<[f64; 3]>,
    mean_j: Vec<Vec<[f64; 3]>>,
}

/// Touches per work item of [`Weights::new_threads`] (about 0.1 ms of work:
/// enough to pay for handing it out).
const TOUCHES_PER_CHUNK: usize = 1024;

/// Points per work item: fixed, so the sums are added in the same order
/// whatever the number of threads (same bytes on any machine).
const POINTS_PER_CHUNK: usize = 64;

/// How many chunks of work the normal equations of `points` points split
/// into: chunks of a fixed number of points, run on several threads from 4
/// chunks up (below that, on the calling thread whatever the thread count).
/// What a test of thread-independence asks, to know that the work really
/// splits.
///
/// ```
/// use aacmm_core::residuals::point_chunks;
/// assert_eq!(point_chunks(64), 1);
/// assert_eq!(point_chunks(65), 2);
/// assert!(point_chunks(300) >= 4, "300 points: on several threads");
/// ```
pub fn point_chunks(points: usize) -> usize {
    points.div_ceil(POINTS_PER_CHUNK)
}

/// The normal equations of the weighted residuals at `kernel`, over the
/// columns `free`. Chunks of points run on up to `threads` threads; the
/// result does not depend on `threads`.
pub(crate) fn normal_equations(
    kernel: &ArmKernel,
    data: &DataSet,
    weights: &Weights,
    free: &[usize],
    threads: usize,
) -> Result<Normal, KernelError> {
    let np = data.points().len();
    // Counted by `point_chunks`, so that what it tells the tests holds here.
    let chunks: Vec<Range<usize>> = (0..point_chunks(np))
        .map(|c| c * POINTS_PER_CHUNK..((c + 1) * POINTS_PER_CHUNK).min(np))
        .collect();
    let need_mean = !data.references().is_empty();
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
        prior_cost: 0.0,
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
        let stride = p.div_ceil(LANES) * LANES;
        PointSums {
            g: vec![[0.0; 3]; p],
            jap: vec![0.0; p],
            ap: [0.0; 3],
            pap: 0.0,
            s: [0.0; 6],
            started: false,
            origin: [0.0; 3],
            stride,
            j: std::array::from_fn(|_| vec![0.0; BLOCK * stride]),
            aj: std::array::from_fn(|_| vec![0.0; BLOCK * stride]),
            pending: 0,
            mean: vec![[0.0; 3]; p],
        }
    }

    /// Ready for the next point, keeping the buffers.
    fn reset(&mut self) {
        self.g.fill([0.0; 3]);
        self.jap.fill(0.0);
        self.ap = [0.0; 3];
        self.pap = 0.0;
        self.s = [0.0; 6];
        self.started = false;
    }

    /// Adds one touch: position, weight, free Jacobian columns. `jtj` is
    /// `p` rows of [`PointSums::stride`] (lower triangle meaningful).
    #[inline(always)]
    fn add(&mut self, pos: &[f64; 3], a: &Sym3, jac: &[[f64; 3]], free: &[usize], jtj: &mut [f64]) {
        if !self.started {
            self.origin = *pos;
            self.started = true;
        }
        let d: [f64; 3] = std::array::from_fn(|k| pos[k] - self.origin[k]);
        let ad = sym_mul(a, &d);
        for (s, v) in self.ap.iter_mut().zip(&ad) {
            *s += v;
        }
        self.pap += d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
        for (s, v) in self.s.iter_mut().zip(a) {
            *s += v;
        }
        let at = self.pending * self.stride;
        let end = at + free.len();
        let [jx, jy, jz] = &mut self.j;
        let [ax, ay, az] = &mut self.aj;
        let (jx, jy, jz) = (&mut jx[at..end], &mut jy[at..end], &mut jz[at..end]);
        let (ax, ay, az) = (&mut ax[at..end], &mut ay[at..end], &mut az[at..end]);
        for (i, &ci) in free.iter().enumerate() {
            let j = jac[ci];
            let wa = sym_mul(a, &j);
            let g = &mut self.g[i];
            g[0] += wa[0];
            g[1] += wa[1];
            g[2] += wa[2];
            self.jap[i] += wa[0] * d[0] + wa[1] * d[1] + wa[2] * d[2];
            (jx[i], jy[i], jz[i]) = (j[0], j[1], j[2]);
            (ax[i], ay[i], az[i]) = (wa[0], wa[1], wa[2]);
        }
        self.pending += 1;
        if self.pending == BLOCK {
            self.flush(jtj);
        }
    }

    /// The held touches' terms into the lower triangle of `jtj`: row `i`
    /// gets `(AJ)_iᵀ J_b` for `b ≤ i`, a lane at a time (the entries past
    /// the diagonal in a row's last lane are upper-triangle scratch).
    #[inline(always)]
    fn flush(&mut self, jtj: &mut [f64]) {
        let (n, w) = (self.pending, self.stride);
        if n == 0 {
            return;
        }
        let p = self.jap.len();
        for i in 0..p {
            let row = &mut jtj[i * w..i * w + w];
            // Up to four lanes at once: independent sums, so the additions'
            // latency overlaps (one lane's sum is a chain over the touches).
            let mut c = 0;
            while c <= i {
                c += match (i - c) / LANES + 1 {
                    1 => self.lanes::<1>(row, i, c, n),
                    2 => self.lanes::<2>(row, i, c, n),
                    3 => self.lanes::<3>(row, i, c, n),
                    _ => self.lanes::<4>(row, i, c, n),
                };
            }
        }
        self.pending = 0;
    }

    /// `K` lanes of `row` (row `i` of `JᵀAJ`) from column `c`, the `n` held
    /// touches added in touch order; returns the columns done.
    #[inline(always)]
    fn lanes<const K: usize>(&self, row: &mut [f64], i: usize, c: usize, n: usize) -> usize {
        let (w, m) = (self.stride, K * LANES);
        let [jx, jy, jz] = &self.j;
        let [ax, ay, az] = &self.aj;
        let out = &mut row[c..c + m];
        let mut r: [[f64; LANES]; K] =
            std::array::from_fn(|k| std::array::from_fn(|l| out[k * LANES + l]));
        for t in 0..n {
            let o = t * w;
            let (x, y, z) = (ax[o + i], ay[o + i], az[o + i]);
            let (bx, by, bz) = (
                &jx[o + c..o + c + m],
                &jy[o + c..o + c + m],
                &jz[o + c..o + c + m],
            );
            for (k, rk) in r.iter_mut().enumerate() {
                for (l, v) in rk.iter_mut().enumerate() {
                    let b = k * LANES + l;
                    *v += x * bx[b] + y * by[b] + z * bz[b];
                }
            }
        }
        for (o, rk) in out.chunks_exact_mut(LANES).zip(&r) {
            o.copy_from_slice(rk);
        }
        m
    }

    /// Closes the point: its Schur term into the lower triangle of `jtj`
    /// (rows of [`PointSums::stride`]), its gradient and cost; resets for
    /// the next point.
    #[inline(always)]
    fn finish(&mut self, part: &mut Partial, jtj: &mut [f64], need_mean: bool) {
        self.flush(jtj);
        let (p, w) = (self.jap.len(), self.stride);
        let cinv = sym_inv(&self.s);
        let c = sym_mul(&cinv, &self.ap);
        // Σ p̃ᵀAp̃ − cᵀ S c, with S c = Σ A p̃
        part.cost += self.pap - (c[0] * self.ap[0] + c[1] * self.ap[1] + c[2] * self.ap[2]);
        for (m, g) in self.mean.iter_mut().zip(&self.g) {
            *m = sym_mul(&cinv, g);
        }
        for i in 0..p {
            let gi = self.g[i];
            part.jtr[i] += self.jap[i] - (gi[0] * c[0] + gi[1] * c[1] + gi[2] * c[2]);
            for (b, mb) in self.mean.iter().enumerate().take(i + 1) {
                jtj[i * w + b] -= gi[0] * mb[0] + gi[1] * mb[1] + gi[2] * mb[2];
            }
        }
        part.centroids
            .push(std::array::from_fn(|k| c[k] + self.origin[k]));
        if need_mean {
            part.mean_j.push(self.mean.clone());
        }
        self.reset();
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
    // The lower triangle, in padded rows (see [`PointSums::flush`]).
    let w = sums.stride;
    let mut jtj = vec![0.0; p * w];
    let mut point = points.start;
    let mut finite = true;
    // Inlined into the kernel's loop, so the accumulation is compiled with
    // the same target features (AVX2 where the CPU has it).
    kernel.for_each_jacobian(
        data.poses(),
        touches,
        #[inline(always)]
        |i, pos, jac| {
            if i == all[point].touches.end {
                sums.finish(&mut part, &mut jtj, need_mean);
                point += 1;
            }
            finite &= pos.iter().all(|v| v.is_finite());
            sums.add(pos, &weights.touch[i], jac, free, &mut jtj);
        },
    )?;
    sums.finish(&mut part, &mut jtj, need_mean);
    for a in 0..p {
        for b in 0..=a {
            part.jtj[a * p + b] = jtj[a * w + b];
            part.jtj[b * p + a] = jtj[a * w + b];
        }
    }
    if !finite {
        part.cost = f64::INFINITY;
    }
    Ok(part)
}

/// The name of the worker threads the library starts: a host that silences
/// the panic messages of library code (the C API does) recognises them by it.
pub const WORKER_THREAD_NAME: &str = "aacmm-worker";

/// `f` over `items` on `threads` scoped threads, results in item order; on
/// the calling thread when one thread (or one item) is all there is.
///
/// A panic in `f` reaches the caller with its own payload (not the scope's
/// "a scoped thread panicked"), so the caller's `catch_unwind` sees what
/// went wrong. A worker the system refuses to start is replaced by the
/// calling thread.
pub(crate) fn parallel_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
    use std::sync::{Mutex, PoisonError};
    if threads <= 1 || items.len() <= 1 {
        return items.iter().map(f).collect();
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let done = Mutex::new(Vec::new());
    let panicked = Mutex::new(None);
    let work = || {
        let run = catch_unwind(AssertUnwindSafe(|| {
            let mut mine = Vec::new();
            loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if i >= items.len() {
                    break;
                }
                mine.push((i, f(&items[i])));
            }
            mine
        }));
        // Neither lock is held while `f` runs, so a poisoned one holds
        // complete data.
        match run {
            Ok(mine) => done
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .extend(mine),
            Err(payload) => {
                panicked
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .get_or_insert(payload);
            }
        }
    };
    std::thread::scope(|s| {
        let mut all_started = true;
        for _ in 0..threads.min(items.len()) {
            let started = std::thread::Builder::new()
                .name(WORKER_THREAD_NAME.into())
                .spawn_scoped(s, work);
            all_started &= started.is_ok();
        }
        if !all_started {
            work();
        }
    });
    if let Some(payload) = panicked
        .into_inner()
        .unwrap_or_else(PoisonError::into_inner)
    {
        resume_unwind(payload);
    }
    let mut slots: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
    for (i, r) in done.into_inner().unwrap_or_else(PoisonError::into_inner) {
        slots[i] = Some(r);
    }
    // Every index below `items.len()` was taken by exactly one loop, which
    // either finished it (its result is in `done`) or panicked (resumed
    // above); a refused worker's share is run by the caller.
    slots
        .into_iter()
        .map(|r| r.expect("every item ran"))
        .collect()
}

/// The cost `Σ r²` alone (positions only, no Jacobian): what a trial step
/// or an annealing move needs. `xyz` is a buffer of one position per touch.
pub(crate) fn cost(
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
        let (mut ap, mut pap, mut sum) = ([0.0; 3], 0.0, [0.0; 6]);
        for i in point.touches.clone() {
            let a = &weights.touch[i];
            let d: [f64; 3] = std::array::from_fn(|k| xyz[i][k] - origin[k]);
            let ad = sym_mul(a, &d);
            for (s, v) in ap.iter_mut().zip(&ad) {
                *s += v;
            }
            pap += d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
            for (s, v) in sum.iter_mut().zip(a) {
                *s += v;
            }
        }
        let c = sym_mul(&sym_inv(&sum), &ap);
        total += pap - (c[0] * ap[0] + c[1] * ap[1] + c[2] * ap[2]);
        centroids.push(std::array::from_fn(|k| c[k] + origin[k]));
    }
    for (r, &w) in data.references().iter().zip(&weights.length) {
        let res = w * (crate::geometry::distance(&centroids[r.a], &centroids[r.b]) - r.distance);
        total += res * res;
    }
    Ok(if total.is_finite() {
        total
    } else {
        f64::INFINITY
    })
}

/// The weighted cost `Σ r²` of the arm `params` on `data`, with every
/// residual weighed from `noise` at the arm `weighed_at` (so that two arms
/// compare under the same weights). Without stated touch noise a touch
/// weighs as a 1 mm σ.
///
/// ```
/// use aacmm_core::{DhParams, residuals::{Noise, weighted_cost}, simulate::*, Arm};
/// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
/// let c = simulate(&nominal, &CampaignSettings::new(2, ErrorModel::Paper, 4, 6)).unwrap();
/// let data = c.data_set().unwrap();
/// let noise = Noise { probe_mm: Some(0.01), ..Noise::default() };
/// let truth = &c.true_arm.params;
/// let at_truth = weighted_cost(truth, truth, &data, &noise).unwrap();
/// let at_nominal = weighted_cost(&nominal.params, truth, &data, &noise).unwrap();
/// assert!(at_truth < at_nominal);
/// ```
///
/// # Errors
///
/// The kernel's, for an arm it cannot evaluate.
pub fn weighted_cost(
    params: &crate::params::DhParams,
    weighed_at: &crate::params::DhParams,
    data: &DataSet,
    noise: &Noise,
) -> Result<f64, KernelError> {
    let weights = Weights::new(&ArmKernel::new(weighed_at)?, data, noise, 1.0)?;
    let mut xyz = vec![[0.0; 3]; data.len()];
    cost(&ArmKernel::new(params)?, data, &weights, &mut xyz)
}

/// Per touch (data-set order), its standardised squared residual
/// `rᵀ A r / (1 − h)`: `r` the touch's offset from its point's weighted
/// centroid, `A` its weight, `h = tr(A (Σ A)⁻¹)/3` its leverage on that
/// centroid. About `χ²₃` for a touch that fits the noise model.
pub(crate) fn standardised_residuals(
    kernel: &ArmKernel,
    data: &DataSet,
    weights: &Weights,
) -> Result<Vec<f64>, KernelError> {
    // Positions one point at a time: memory stays the output's.
    let most = data.points().iter().map(|p| p.touches.len()).max();
    let mut xyz = vec![[0.0; 3]; most.unwrap_or(0)];
    let mut out = vec![0.0; data.len()];
    for point in data.points() {
        let first = point.touches.start;
        let xyz = &mut xyz[..point.touches.len()];
        kernel.positions(data.poses(), point.touches.clone(), xyz)?;
        let (mut sum_a, mut sum_ap) = ([0.0; 6], [0.0; 3]);
        for i in point.touches.clone() {
            let a = &weights.touch[i];
            let ap = sym_mul(a, &xyz[i - first]);
            for k in 0..6 {
                sum_a[k] += a[k];
            }
            for k in 0..3 {
                sum_ap[k] += ap[k];
            }
        }
        let inv = sym_inv(&sum_a);
        let c = sym_mul(&inv, &sum_ap);
        for i in point.touches.clone() {
            let a = &weights.touch[i];
            let r: [f64; 3] = std::array::from_fn(|k| xyz[i - first][k] - c[k]);
            let ar = sym_mul(a, &r);
            let q = r[0] * ar[0] + r[1] * ar[1] + r[2] * ar[2];
            // tr(A·inv) for symmetric A and inv.
            let tr = a[0] * inv[0]
                + a[1] * inv[1]
                + a[2] * inv[2]
                + 2.0 * (a[3] * inv[3] + a[4] * inv[4] + a[5] * inv[5]);
            let h = (tr / 3.0).clamp(0.0, 0.999);
            out[i] = q / (1.0 - h);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{AngleUnit, parse_lengths, parse_poses};
    use crate::params::DhParams;

    #[test]
    fn relative_change_is_the_largest_relative_difference() {
        let a = Weights {
            touch: vec![[4.0, 4.0, 4.0, 0.0, 0.0, 0.0]],
            length: vec![2.0],
            prior: None,
        };
        let b = Weights {
            touch: vec![[4.0, 4.0, 4.0, 0.0, 0.0, 0.0]],
            length: vec![2.2],
            prior: None,
        };
        assert!((b.relative_change(&a) - 0.1).abs() < 1e-12);
        assert_eq!(a.relative_change(&a), 0.0);
    }

    /// A simulated campaign (paper errors, `sockets` × `touches`, `lengths`
    /// reference lengths, 0.005° and 0.01 mm noise) with the nominal arm's
    /// kernel and its weights from that noise.
    fn simulated_at_nominal(
        seed: u64,
        sockets: usize,
        touches: usize,
        lengths: usize,
    ) -> (DataSet, ArmKernel, Weights) {
        use crate::simulate::{CampaignSettings, ErrorModel, simulate};
        let nominal = crate::io::Arm::without_limits("n", DhParams::paper_nominal());
        let mut settings = CampaignSettings::new(seed, ErrorModel::Paper, sockets, touches);
        settings.reference_lengths = lengths;
        settings.encoder_noise_deg = 0.005;
        settings.probe_noise_mm = 0.01;
        let data = simulate(&nominal, &settings).unwrap().data_set().unwrap();
        let kernel = ArmKernel::new(&nominal.params).unwrap();
        let noise = Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        };
        let weights = Weights::new(&kernel, &data, &noise, 1.0).unwrap();
        (data, kernel, weights)
    }

    /// The free columns' normal equations are the full system's principal
    /// submatrix, to the bit (what the first LM step reuses).
    #[test]
    fn the_free_columns_system_is_the_restriction_of_the_full_one() {
        let (data, kernel, weights) = simulated_at_nominal(9, 10, 10, 3);
        let all: Vec<usize> = (0..27).collect();
        let full = normal_equations(&kernel, &data, &weights, &all, 1).unwrap();
        let free: Vec<usize> = vec![1, 0, 7, 12, 19, 26];
        let direct = normal_equations(&kernel, &data, &weights, &free, 1).unwrap();
        // Same products summed in the same order: equal to the bit.
        assert_eq!(full.restrict(&free).unwrap(), direct);
        assert!(full.restrict(&[27]).is_none());
        assert!(direct.restrict(&[2]).is_none());
    }

    /// The blocked, lane-wise accumulation adds every product in the order
    /// of the plain loops it replaced (touch by touch, `b ≤ i`, then the
    /// point's Schur term): the same bits, with points of more touches than
    /// a block and an odd number of free columns.
    #[test]
    fn blocked_normal_equations_are_the_plain_loops_bits() {
        // No lengths: the touches' sums alone.
        let (data, kernel, weights) = simulated_at_nominal(5, 7, 2 * BLOCK + 3, 0);
        for free in [
            (0..27).collect::<Vec<usize>>(),
            vec![2, 3, 5, 8, 13, 21, 26],
        ] {
            let p = free.len();
            let (mut jtj, mut jtr, mut cost) = (vec![0.0; p * p], vec![0.0; p], 0.0);
            let mut rows = Vec::new();
            kernel
                .for_each_jacobian(data.poses(), 0..data.len(), |_, pos, jac| {
                    rows.push((*pos, jac.to_vec()))
                })
                .unwrap();
            for point in data.points() {
                let origin = rows[point.touches.start].0;
                let (mut g, mut jap) = (vec![[0.0; 3]; p], vec![0.0; p]);
                let (mut ap, mut pap, mut sa) = ([0.0; 3], 0.0, [0.0; 6]);
                for t in point.touches.clone() {
                    let (pos, jac) = &rows[t];
                    let a = &weights.touch[t];
                    let d: [f64; 3] = std::array::from_fn(|k| pos[k] - origin[k]);
                    let ad = sym_mul(a, &d);
                    (0..3).for_each(|k| ap[k] += ad[k]);
                    pap += d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
                    (0..6).for_each(|k| sa[k] += a[k]);
                    let wa: Vec<[f64; 3]> = free.iter().map(|&c| sym_mul(a, &jac[c])).collect();
                    for i in 0..p {
                        (0..3).for_each(|k| g[i][k] += wa[i][k]);
                        jap[i] += wa[i][0] * d[0] + wa[i][1] * d[1] + wa[i][2] * d[2];
                        for b in 0..=i {
                            let j = jac[free[b]];
                            jtj[i * p + b] += wa[i][0] * j[0] + wa[i][1] * j[1] + wa[i][2] * j[2];
                        }
                    }
                }
                let cinv = sym_inv(&sa);
                let c = sym_mul(&cinv, &ap);
                cost += pap - (c[0] * ap[0] + c[1] * ap[1] + c[2] * ap[2]);
                let mean: Vec<[f64; 3]> = g.iter().map(|gi| sym_mul(&cinv, gi)).collect();
                for i in 0..p {
                    let gi = g[i];
                    jtr[i] += jap[i] - (gi[0] * c[0] + gi[1] * c[1] + gi[2] * c[2]);
                    for b in 0..=i {
                        let mb = mean[b];
                        jtj[i * p + b] -= gi[0] * mb[0] + gi[1] * mb[1] + gi[2] * mb[2];
                    }
                }
            }
            for a in 0..p {
                for b in 0..a {
                    jtj[b * p + a] = jtj[a * p + b];
                }
            }
            // One chunk of points (under POINTS_PER_CHUNK): no partial sums.
            assert!(data.points().len() <= POINTS_PER_CHUNK);
            let n = normal_equations(&kernel, &data, &weights, &free, 1).unwrap();
            assert_eq!(n.jtj, jtj);
            assert_eq!(n.jtr, jtr);
            assert_eq!(n.touch_cost, cost);
        }
    }

    /// `n` points of 3 touches each, spread in joint space, with 20
    /// reference lengths between them.
    fn points_of_three_touches(n: usize) -> DataSet {
        let mut text = String::from("point,q1,q2,q3,q4,q5,q6\n");
        for p in 0..n {
            for k in 0..3 {
                let q: Vec<String> = (0..6)
                    .map(|j| {
                        let base = ((p * 7 + j * 13) as f64 * 0.37).sin() * 120.0;
                        format!("{}", base + (k * 20 + j) as f64 * 0.5)
                    })
                    .collect();
                text.push_str(&format!("P{p},{}\n", q.join(",")));
            }
        }
        let (poses, _) = parse_poses(&text, "p.csv", AngleUnit::Deg, Some(6)).unwrap();
        let mut lengths = String::from("point_a,point_b,distance\n");
        for i in 0..20 {
            lengths.push_str(&format!("P{i},P{},{}\n", n - 1 - i, 500 + i));
        }
        DataSet::from_poses(&poses, "p.csv")
            .unwrap()
            .with_lengths(&parse_lengths(&lengths, "l.csv").unwrap(), "l.csv")
            .unwrap()
    }

    /// The weights' change to another arm, streamed a chunk of points at a
    /// time, is the change built-then-compared, to the bit, on any thread
    /// count; with and without stated noise.
    #[test]
    fn the_streamed_change_of_weights_is_the_built_one() {
        let data = points_of_three_touches(1000);
        assert!(data.len() > 2 * TOUCHES_PER_CHUNK);
        let here = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
        let mut moved = DhParams::paper_nominal();
        moved.joints[1].d += 3.0;
        moved.joints[2].theta += 0.02;
        let there = ArmKernel::new(&moved).unwrap();
        let stated = Noise {
            encoder_rad: Some(1e-4),
            probe_mm: Some(0.01),
            length_default_mm: 0.001,
            length_weight: None,
        };
        let unstated = Noise {
            encoder_rad: None,
            probe_mm: None,
            ..stated
        };
        for (noise, sigma) in [(&stated, 1.0), (&unstated, 0.7)] {
            let old = Weights::new(&here, &data, noise, 1.0).unwrap();
            let built = Weights::new(&there, &data, noise, sigma)
                .unwrap()
                .relative_change(&old);
            assert!(built > 0.0 && built.is_finite());
            for threads in [1, 2, 4] {
                let streamed = old
                    .relative_change_to(&there, &data, noise, sigma, threads)
                    .unwrap();
                assert_eq!(streamed.to_bits(), built.to_bits(), "{threads} threads");
            }
            let same = old.relative_change_to(&here, &data, noise, 1.0, 2).unwrap();
            assert_eq!(same, 0.0);
        }
        let mut short = Weights::new(&here, &data, &stated, 1.0).unwrap();
        short.touch.pop();
        let change = short.relative_change_to(&here, &data, &stated, 1.0, 1);
        assert_eq!(change.unwrap(), f64::INFINITY);
    }

    /// 1000 points of 3 touches with stated noise and reference lengths:
    /// 16 chunks of points, so 2 and 4 threads really split the work (one
    /// thread below 4 chunks). The normal equations, their cost and the
    /// centroids are the same bits on 1, 2 and 4 threads.
    #[test]
    fn normal_equations_are_the_same_bits_on_any_thread_count() {
        let n = 1000;
        let data = points_of_three_touches(n);
        assert_eq!(data.points().len(), n);
        assert!(n > 4 * POINTS_PER_CHUNK, "enough chunks to run in parallel");
        let kernel = ArmKernel::new(&DhParams::paper_nominal()).unwrap();
        let noise = Noise {
            encoder_rad: Some(1e-4),
            probe_mm: Some(0.01),
            length_default_mm: 0.001,
            length_weight: None,
        };
        let weights = Weights::new(&kernel, &data, &noise, 1.0).unwrap();
        assert!(data.len() > 2 * TOUCHES_PER_CHUNK, "weights in chunks too");
        for threads in [2, 4] {
            let w = Weights::new_threads(&kernel, &data, &noise, 1.0, threads).unwrap();
            assert_eq!(w, weights, "{threads} threads");
        }
        let free: Vec<usize> = (0..27).collect();
        let bits = |threads: usize| {
            let ne = normal_equations(&kernel, &data, &weights, &free, threads).unwrap();
            let mut v: Vec<u64> = ne.jtj.iter().chain(&ne.jtr).map(|x| x.to_bits()).collect();
            v.extend([ne.touch_cost, ne.length_cost, ne.cost()].map(f64::to_bits));
            v.extend(ne.centroids.iter().flatten().map(|x| x.to_bits()));
            assert!(ne.length_cost > 0.0 && ne.touch_cost > 0.0);
            v
        };
        let one = bits(1);
        assert_eq!(bits(2), one);
        assert_eq!(bits(4), one);
    }
}
