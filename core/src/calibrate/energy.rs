//! The paper's objective as an annealing energy (method.md §3, §5):
//! `E = mean over points of (e + 3σ)` (eq. 9–12) plus, when the data has
//! reference lengths, the RMS of their errors — both mm, so a length that is
//! off by 1 mm weighs like a point whose touches scatter by 1 mm.
//!
//! Evaluated millions of times by the annealer, so it runs the position
//! kernel into buffers made once and allocates nothing per call.

use crate::dataset::DataSet;
use crate::geometry::distance;
use crate::kernel::{ArmKernel, KernelError};
use crate::params::DhParams;

/// Buffers for [`Energy::of`]: one position per touch, one centroid per point.
#[derive(Clone, Debug)]
pub struct Energy {
    xyz: Vec<[f64; 3]>,
    centroids: Vec<[f64; 3]>,
    /// Energy evaluations so far.
    pub(crate) evaluations: usize,
}

impl Energy {
    /// Buffers sized for `data`.
    pub fn new(data: &DataSet) -> Energy {
        Energy {
            xyz: vec![[0.0; 3]; data.len()],
            centroids: vec![[0.0; 3]; data.points().len()],
            evaluations: 0,
        }
    }

    /// The energy of `params` on `data`, mm; `+∞` when not finite.
    ///
    /// ```
    /// use aacmm_core::{calibrate::energy::Energy, domain::Arm, params::DhParams, simulate::*};
    /// let nominal = Arm::without_limits("n", DhParams::paper_nominal());
    /// let campaign = simulate(&nominal, &CampaignSettings::new(1, ErrorModel::Paper, 4, 6)).unwrap();
    /// let data = campaign.data_set().unwrap();
    /// let mut energy = Energy::new(&data);
    /// // The true arm makes the noise-free touches agree exactly.
    /// assert!(energy.of(&campaign.true_arm.params, &data).unwrap() < 1e-6);
    /// assert!(energy.of(&nominal.params, &data).unwrap() > 0.5);
    /// ```
    pub fn of(&mut self, params: &DhParams, data: &DataSet) -> Result<f64, KernelError> {
        let kernel = ArmKernel::new(params)?;
        Ok(self.of_kernel(&kernel, data))
    }

    /// [`Energy::of`] for a prepared kernel.
    pub fn of_kernel(&mut self, kernel: &ArmKernel, data: &DataSet) -> f64 {
        self.evaluations += 1;
        if kernel
            .positions(data.poses(), 0..data.len(), &mut self.xyz)
            .is_err()
        {
            return f64::INFINITY;
        }
        let mut oa = 0.0;
        for (point, c) in data.points().iter().zip(&mut self.centroids) {
            let touches = &self.xyz[point.touches.clone()];
            let n = touches.len() as f64;
            let origin = touches[0];
            let mut sum = [0.0; 3];
            for t in touches {
                for k in 0..3 {
                    sum[k] += t[k] - origin[k];
                }
            }
            *c = std::array::from_fn(|k| origin[k] + sum[k] / n);
            // e and σ (population form) in one pass: mean δ and mean δ².
            let (mut s1, mut s2) = (0.0, 0.0);
            for t in touches {
                let d = distance(t, c);
                s1 += d;
                s2 += d * d;
            }
            let e = s1 / n;
            let var = (s2 / n - e * e).max(0.0);
            oa += e + 3.0 * var.sqrt();
        }
        let mut total = oa / data.points().len().max(1) as f64;
        let refs = data.references();
        if !refs.is_empty() {
            let ss: f64 = refs
                .iter()
                .map(|r| {
                    let err = distance(&self.centroids[r.a], &self.centroids[r.b]) - r.distance;
                    err * err
                })
                .sum();
            total += (ss / refs.len() as f64).sqrt();
        }
        if total.is_finite() {
            total
        } else {
            f64::INFINITY
        }
    }
}
