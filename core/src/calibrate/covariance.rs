//! The covariances a prediction needs from a calibration: of the free
//! geometry, with a fitted frame's registration, or at a fitted tool point.

use super::{Calibration, Estimate};
use crate::params::{ParamId, ParamKind};

impl Calibration {
    /// The free geometry's columns (of the `4n + 3`) and their covariance
    /// (mm, rad): the parameters' σ with the correlation matrix. `None`
    /// without a free parameter, or with one whose σ is not finite.
    pub fn geometry_covariance(&self) -> Option<(Vec<usize>, nalgebra::DMatrix<f64>)> {
        let (free, columns) = self.free_geometry()?;
        Some((free, self.covariance_of(&columns)?))
    }

    /// The free geometry's columns, the registration of the fitted frame
    /// `name` (`[rx, ry, rz, tx, ty, tz]`, rad, mm) and the joint
    /// covariance of the two (mm, rad; `(q + 6)²`, the frame's six columns
    /// last, its rotation's of a small rotation about the frame's axes):
    /// what a prediction in that instrument's frame
    /// ([`crate::plan::position_covariances`]) needs, the frame's
    /// registration error and its correlation with the arm's counted in.
    /// `None` without such a frame, or as [`Calibration::geometry_covariance`].
    pub fn frame_covariance(
        &self,
        name: &str,
    ) -> Option<(Vec<usize>, [f64; 6], nalgebra::DMatrix<f64>)> {
        let (free, mut columns) = self.free_geometry()?;
        let (_, cols) = (self.frame_columns().into_iter()).find(|(n, _)| *n == name)?;
        for (k, c) in cols.iter().enumerate() {
            let sigma = if k < 3 {
                c.sigma.map(f64::to_radians)
            } else {
                c.sigma
            };
            columns.push((c.name.clone(), sigma));
        }
        let x = self.frames().into_iter().find(|(n, _)| n == name)?.1;
        Some((free, x, self.covariance_of(&columns)?))
    }

    /// What a prediction at the tool point `name` (a `[[tool]]` whose
    /// offset was fitted, block `tool.NAME`) needs: the free geometry's
    /// columns but the probe's (the tool replaces the probe), then the
    /// probe's three — the kernel's derivative over the probe's offset,
    /// which at the tool's offset is the derivative over the tool's —; the
    /// tool's fitted offset (mm, the last joint's frame); and the joint
    /// covariance of those geometry columns and the tool's `x, y, z` (mm
    /// and rad), their correlation counted in. `None` when the tool's
    /// offset was not fitted or a σ is not finite, or without free
    /// geometry.
    pub fn tool_covariance(
        &self,
        name: &str,
    ) -> Option<(Vec<usize>, [f64; 3], nalgebra::DMatrix<f64>)> {
        let n = self.params.joint_count();
        let (free, named) = self.free_geometry()?;
        // The probe's columns: the tool's offset takes their place.
        let probe: [usize; 3] = std::array::from_fn(|k| {
            let id = ParamId {
                kind: ParamKind::Probe,
                index: k,
            };
            id.column(n)
        });
        let (mut columns, mut sigmas): (Vec<usize>, NamedSigmas) = (free.iter().zip(named))
            .filter(|(c, _)| !probe.contains(c))
            .map(|(c, s)| (*c, s))
            .unzip();
        let prefix = crate::domain::TOOL_BLOCK_PREFIX;
        let mut x = [0.0; 3];
        for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
            let full = format!("{prefix}{name}.{axis}");
            let c = self.auxiliary.iter().find(|c| c.name == full)?;
            x[k] = c.calibrated;
            sigmas.push((full, Some(c.sigma?)));
            columns.push(probe[k]);
        }
        Some((columns, x, self.covariance_of(&sigmas)?))
    }

    /// The free geometry parameters' columns (of the `4n + 3`), and each
    /// one's name and σ. `None` without one.
    fn free_geometry(&self) -> Option<(Vec<usize>, NamedSigmas)> {
        let n = self.params.joint_count();
        let free: Vec<&Estimate> = (self.parameters.iter())
            .filter(|e| e.fixed.is_none())
            .collect();
        if free.is_empty() {
            return None;
        }
        let columns = free.iter().map(|e| (e.id.to_string(), e.sigma)).collect();
        Some((free.iter().map(|e| e.id.column(n)).collect(), columns))
    }

    /// The covariance of the named free columns: their σ with the
    /// correlation matrix. `None` when one is not in the matrix or its σ is
    /// not finite.
    fn covariance_of(&self, columns: &[(String, Option<f64>)]) -> Option<nalgebra::DMatrix<f64>> {
        let names = &self.correlation_matrix.parameters;
        let at: Vec<usize> = (columns.iter())
            .map(|(name, _)| names.iter().position(|m| m == name))
            .collect::<Option<_>>()?;
        let sigma: Vec<f64> = columns.iter().map(|c| c.1).collect::<Option<_>>()?;
        if sigma.iter().any(|s| !s.is_finite()) {
            return None;
        }
        let rho = &self.correlation_matrix.rho;
        let q = columns.len();
        Some(nalgebra::DMatrix::from_fn(q, q, |a, b| {
            let r = if a == b { 1.0 } else { rho[at[a]][at[b]] };
            sigma[a] * sigma[b] * r
        }))
    }
}

/// Columns by name, each with its σ (`None`: not determined).
type NamedSigmas = Vec<(String, Option<f64>)>;
