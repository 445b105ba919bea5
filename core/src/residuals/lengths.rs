//! Reference lengths: the distance between two point centres against a
//! calibrated length, one row each, `r = w_L (|c_a − c_b| − L)`. The
//! centres are the touch term's ([`super::Shared::centres`]), so this term
//! comes after it.

use super::sym3::{Sym3, sym_mul};
use super::{At, Centres, Noise, Normal, Sees, Shared, Term, TermError};
use crate::dataset::DataSet;
use crate::error::short;
use crate::kernel::{ArmKernel, KernelError, NoiseOf};

/// The reference lengths of a data set, weighed by `1/σ_L`: the stated
/// weight, or each length's own uncertainty combined with its two centres'
/// covariances along it.
#[derive(Clone)]
pub(crate) struct LengthTerm<'d> {
    data: &'d DataSet,
    noise: Noise,
    /// Per reference length, `1/σ_L` (1/mm); empty until weighed.
    weights: Vec<f64>,
}

impl std::fmt::Debug for LengthTerm<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LengthTerm")
            .field("lengths", &self.data.references().len())
            .field("noise", &self.noise)
            .field("weighed", &!self.weights.is_empty())
            .finish()
    }
}

impl<'d> LengthTerm<'d> {
    /// The reference lengths of `data` under `noise` (its length part), not
    /// weighed yet.
    pub(crate) fn new(data: &'d DataSet, noise: Noise) -> LengthTerm<'d> {
        LengthTerm {
            data,
            noise,
            weights: Vec::new(),
        }
    }

    /// Per reference length, its weight `1/σ_L`, 1/mm.
    #[cfg(test)]
    pub(crate) fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Per reference length, `1/σ_L` at `kernel` with the centres'
    /// covariances `covs`.
    fn weights_at(&self, kernel: &ArmKernel, covs: &[Sym3]) -> Result<Vec<f64>, KernelError> {
        let (data, noise) = (self.data, &self.noise);
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
                    Ok(1.0 / (ul * ul + along(&covs[r.a]) + along(&covs[r.b])).sqrt())
                }
            })
            .collect()
    }

    /// Refuses a weight that is not a finite positive number: a length
    /// weight given as 0 means "ignore the lengths"; one computed as 0 means
    /// an uncertainty that overflowed.
    fn check(&self, weights: &[f64]) -> Result<(), KernelError> {
        let noise = &self.noise;
        let given = noise.length_weight.is_some();
        let Some(r) = weights
            .iter()
            .position(|w| !(w.is_finite() && (*w > 0.0 || given)))
        else {
            return Ok(());
        };
        let sigma = match noise.length_weight {
            Some(w) => format!("a length weight of {} 1/mm", short(w)),
            None => format!(
                "a length uncertainty of {} mm",
                short(
                    self.data.references()[r]
                        .uncertainty
                        .unwrap_or(noise.length_default_mm)
                )
            ),
        };
        Err(KernelError::Noise {
            of: NoiseOf::Lengths,
            message: format!(
                "the weight of the reference length at {} is not a finite positive number with \
                 {sigma}; a σ this large overflows and one this small vanishes in double \
                 precision; give the uncertainty of the calibrated length (typically \
                 0.0005–0.01 mm)",
                self.data.source().reference(r)
            ),
        })
    }
}

/// The touch term's centroids (and their Jacobians), which the lengths
/// measure between: refused when no touch term has left them.
fn centres(shared: &Shared) -> Result<&Centres, TermError> {
    shared.centres.as_ref().ok_or_else(|| {
        TermError::invalid(
            "lengths",
            "evaluated before the touches they measure between",
        )
    })
}

/// The touch term's centre covariances, which the lengths' weights need.
fn covariances(shared: &Shared) -> Option<&[Sym3]> {
    shared.centre_covariances.as_deref()
}

impl Term for LengthTerm<'_> {
    fn name(&self) -> &str {
        "lengths"
    }

    fn role(&self) -> super::Role {
        super::Role::Lengths
    }

    fn rows(&self, _free: &[usize]) -> usize {
        self.data.references().len()
    }

    fn sees(&self) -> Sees {
        Sees {
            base_rotation: false,
            base_slide: false,
            scale: true,
        }
    }

    fn needs_centre_jacobians(&self) -> bool {
        true
    }

    fn weigh(
        &mut self,
        at: &At<'_>,
        shared: &mut Shared,
        _unit_sigma: f64,
    ) -> Result<(), TermError> {
        let covs = covariances(shared).ok_or_else(|| {
            TermError::invalid("lengths", "weighed before the touches they measure between")
        })?;
        let weights = self.weights_at(at.kernel, covs)?;
        self.check(&weights)?;
        self.weights = weights;
        Ok(())
    }

    /// `|a − b|/|b|` of each length's weight; infinite where the new weight
    /// would be refused.
    fn weight_change(
        &self,
        at: &At<'_>,
        shared: &mut Shared,
        _unit_sigma: f64,
    ) -> Result<f64, TermError> {
        let Some(covs) = covariances(shared) else {
            return Ok(f64::INFINITY);
        };
        if self.weights.len() != self.data.references().len() {
            return Ok(f64::INFINITY);
        }
        let weights = self.weights_at(at.kernel, covs)?;
        if self.check(&weights).is_err() {
            return Ok(f64::INFINITY);
        }
        Ok(weights
            .iter()
            .zip(&self.weights)
            .map(|(a, b)| (a - b).abs() / b.abs())
            .fold(0.0, f64::max))
    }

    /// `w_L² gᵀg` and `w_L g r`, `g = uᵀ(J̄_a − J̄_b)`.
    fn accumulate(
        &self,
        _at: &At<'_>,
        shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let centres = centres(shared)?;
        let p = normal.free.len();
        let mut cost = 0.0;
        // One `g` for every length, and rows of `JᵀJ` walked as slices:
        // indexed entry by entry, each addition was bounds-checked and the
        // loop stayed scalar.
        let mut g = vec![0.0; p];
        for (r, &w) in self.data.references().iter().zip(&self.weights) {
            let (ca, cb) = (centres.points[r.a], centres.points[r.b]);
            let d: [f64; 3] = std::array::from_fn(|k| ca[k] - cb[k]);
            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let res = w * (len - r.distance);
            cost += res * res;
            if p == 0 {
                // No free column: the cost alone (and no centre Jacobians
                // to read: a cost pass leaves none).
                continue;
            }
            let u = d.map(|v| v / len);
            let (ja, jb) = (&centres.jacobians[r.a][..p], &centres.jacobians[r.b][..p]);
            for ((gc, ja), jb) in g.iter_mut().zip(ja).zip(jb) {
                *gc = w * (0..3).map(|k| u[k] * (ja[k] - jb[k])).sum::<f64>();
            }
            for (a, (jtr, &ga)) in normal.jtr.iter_mut().zip(&g).enumerate() {
                *jtr += ga * res;
                for (o, &gb) in normal.jtj[a * p..(a + 1) * p].iter_mut().zip(&g) {
                    *o += ga * gb;
                }
            }
        }
        Ok(cost)
    }

    fn add_cost(
        &self,
        _at: &At<'_>,
        _free: &[usize],
        shared: &mut Shared,
        _scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        let centres = centres(shared)?;
        for (r, &w) in self.data.references().iter().zip(&self.weights) {
            let d = crate::geometry::distance(&centres.points[r.a], &centres.points[r.b]);
            let res = w * (d - r.distance);
            *total += res * res;
        }
        Ok(())
    }
}
