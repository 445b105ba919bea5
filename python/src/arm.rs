//! `aacmm.Arm`: an arm's geometry and its generated kernel — positions,
//! parameter Jacobians, joint Jacobians of numpy batches.

use std::path::PathBuf;

use aacmm_core::domain::Arm as CoreArm;
use aacmm_core::io::{AngleUnit, LengthUnit, Rejected, arm_to_toml, read_arm_with, source_name};
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::{DhParams, ParamId, param_count, supported_joints_text, supports_joints};
use numpy::ndarray::{Array1, ArrayD};
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArrayDyn, PyArrayLike1, PyArrayMethods};
use pyo3::prelude::*;

use crate::error::{Error, Kind, Result, detached};
use crate::readings::{Readings, prepare};

/// An arm: its D-H geometry (mm, rad) prepared for the generated kernel of
/// its joint count (1 to 12). Immutable; safe to share between threads.
#[pyclass(frozen, module = "aacmm")]
pub struct Arm {
    pub(crate) arm: CoreArm,
    pub(crate) kernel: ArmKernel,
    /// Where the arm came from: the file as named, or `<parameters>`.
    pub(crate) source: String,
    pub(crate) warnings: Vec<String>,
}

impl Arm {
    pub(crate) fn new(arm: CoreArm, source: String, warnings: Vec<String>) -> Result<Arm> {
        let kernel = ArmKernel::new(&arm.params).map_err(|e| Error::from(e).prefixed(&source))?;
        Ok(Arm {
            arm,
            kernel,
            source,
            warnings,
        })
    }

    pub(crate) fn joints(&self) -> usize {
        self.kernel.joints()
    }

    /// The prismatic joints, bit `j` for joint `j`.
    pub(crate) fn prismatic(&self) -> u16 {
        self.kernel.shape().prismatic_mask()
    }
}

/// Issues each of `warnings` as a Python `UserWarning`.
pub(crate) fn warn_all(py: Python<'_>, warnings: &[String]) -> PyResult<()> {
    let module = py.import("warnings")?;
    for w in warnings {
        module.call_method1(
            "warn",
            (
                w.as_str(),
                py.get_type::<pyo3::exceptions::PyUserWarning>(),
                2,
            ),
        )?;
    }
    Ok(())
}

/// The names of the `4·joints + 3` parameters in the toolkit's order:
/// `a1..an, d1..dn, alpha1..alphan, theta1..thetan, Bx, By, Bz`; a joint
/// count without a kernel is `aacmm.UnsupportedError` (0 would divide by
/// zero, a huge count overflow `4·joints + 3`).
#[pyfunction]
pub fn param_names(joints: usize) -> PyResult<Vec<String>> {
    supported(joints)?;
    Ok(ParamId::all(joints).map(|p| p.to_string()).collect())
}

/// `joints` is a count the toolkit has a kernel for, or
/// `aacmm.UnsupportedError` saying which it has.
fn supported(joints: usize) -> Result<(), Error> {
    if supports_joints(joints) {
        return Ok(());
    }
    Err(Error::new(
        Kind::Unsupported,
        format!(
            "joints = {joints}: the toolkit computes {}",
            supported_joints_text()
        ),
    ))
}

#[pymethods]
impl Arm {
    /// Reads an arm file (TOML: 1 to 12 `[[joint]]` entries, in the units the
    /// file declares). Errors name the file, line and field
    /// (`aacmm.InputError`; `OSError` when it cannot be read). Legal but
    /// suspicious content is kept in `warnings` and issued as `UserWarning`.
    /// A file whose `[verdict]` says NOT usable (a refused calibration's
    /// `calibrated.toml`) is refused (`aacmm.InputError` naming the
    /// reasons) unless `accept_rejected=True`: it is then read with a
    /// warning. A path `-` is a file of that name (not standard input, as
    /// on the command line).
    #[staticmethod]
    #[pyo3(signature = (path, accept_rejected = false))]
    fn from_file(py: Python<'_>, path: PathBuf, accept_rejected: bool) -> PyResult<Arm> {
        let path = crate::file_path(path);
        let rejected = if accept_rejected {
            Rejected::Warn
        } else {
            Rejected::Refuse
        };
        let arm = detached(py, || {
            let (arm, warnings) = read_arm_with(&path, rejected)?;
            let warnings = warnings.iter().map(ToString::to_string).collect();
            Arm::new(arm, source_name(&path), warnings)
        })?;
        warn_all(py, &arm.warnings)?;
        Ok(arm)
    }

    /// An arm from its `4·joints + 3` parameters in the toolkit's order
    /// (see `param_names`), lengths in mm and angles in rad. Each link is
    /// `Rz(theta + q)·Tz(d)·Tx(a)·Rx(alpha)`; `B` is the probe centre in the
    /// last link's frame. No joint limits. `joint_types` (default all
    /// revolute) names each joint's kind, one letter per joint from the
    /// base: `R` revolute, `P` prismatic (`"PRRRRRR"`: a robot on a track),
    /// whose reading (mm) adds to `d` instead of `theta`.
    #[staticmethod]
    #[pyo3(signature = (joints, params, name = "arm", joint_types = None))]
    fn from_params(
        joints: usize,
        params: PyArrayLike1<'_, f64, AllowTypeChange>,
        name: &str,
        joint_types: Option<&str>,
    ) -> PyResult<Arm> {
        supported(joints)?;
        // Checked before the copy: a huge array is refused, not copied.
        let expected = param_count(joints);
        let given = params.as_array().len();
        if given != expected {
            return Err(Error::value(format!(
                "params: {given} values, expected {expected} (4 · joints + 3)"
            ))
            .into());
        }
        let values = params.as_array().to_vec();
        if let Some((id, v)) = ParamId::all(joints)
            .zip(&values)
            .find(|(_, v)| !v.is_finite())
        {
            return Err(Error::value(format!(
                "params[{}] ({id}) = {v}: parameters must be finite numbers",
                id.column(joints)
            ))
            .into());
        }
        let mut dh = DhParams::from_slice(&values)
            .ok_or_else(|| Error::value("params: not a parameter vector"))?;
        if let Some(shape) = crate::readings::joint_types(joint_types, joints)? {
            for (j, joint) in dh.joints.iter_mut().enumerate() {
                joint.kind = shape.kind(j);
            }
        }
        Ok(Arm::new(
            CoreArm::without_limits(name, dh),
            "<parameters>".to_string(),
            Vec::new(),
        )?)
    }

    /// The arm's name (from its file, or given to `from_params`).
    #[getter]
    fn name(&self) -> &str {
        &self.arm.name
    }

    /// Number of joints (1 to 12).
    #[getter(joints)]
    fn joints_py(&self) -> usize {
        self.joints()
    }

    /// Each joint's kind, one letter per joint from the base: `R`
    /// revolute, `P` prismatic (whose readings are mm, whatever the angle
    /// unit), e.g. `"PRRRRRR"`.
    #[getter]
    fn joint_types(&self) -> String {
        self.kernel.shape().to_string()
    }

    /// Where the arm came from: its file as named, `<parameters>`,
    /// `<calibration>` or `<simulation>`.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// The warnings read with the arm file (empty otherwise).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The `4·joints + 3` parameters (mm, rad) in the order of
    /// `param_names`, as a new float64 array.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        Array1::from(self.arm.params.to_vec()).into_pyarray(py)
    }

    /// The parameters' names, in order.
    #[getter(param_names)]
    fn names(&self) -> Vec<String> {
        ParamId::all(self.joints()).map(|p| p.to_string()).collect()
    }

    /// Per joint, `(min, max)` in rad, or `None` for a joint without limits.
    #[getter]
    fn limits(&self) -> Vec<Option<(f64, f64)>> {
        self.arm
            .limits
            .iter()
            .map(|l| l.map(|[a, b]| (a, b)))
            .collect()
    }

    /// Probe positions (mm) of poses `q`: an array-like `n × joints` of
    /// encoder readings in `angle_unit` (`"rad"` or `"deg"`) → `n × 3`
    /// (x, y, z). A 1-D `q` of one pose gives a 1-D result. Bit-identical to
    /// the Rust API's `ArmKernel::positions`. Non-finite readings give
    /// non-finite positions. Runs without the GIL.
    #[pyo3(signature = (q, angle_unit = "rad"))]
    fn positions<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        angle_unit: &str,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let unit = crate::angle_unit(angle_unit)?;
        let r = Readings::new(q, "q", self.joints(), unit)?.with_prismatic(self.prismatic());
        let out = zeros(py, &r.shape(&[3]), "positions")?;
        {
            let mut out = out.readwrite();
            let xyz = out.as_slice_mut().map_err(internal)?.as_chunks_mut::<3>().0;
            r.for_chunks(py, |rows, q| {
                let poses = prepare(self.kernel.shape(), q)?;
                self.kernel
                    .positions(&poses, 0..rows.len(), &mut xyz[rows])?;
                Ok(())
            })?;
        }
        Ok(out)
    }

    /// Probe positions and parameter Jacobians of poses `q` (as in
    /// `positions`): returns `(p, jac)`, `p` of shape `(n, 3)` and `jac` of
    /// shape `(n, 3, 4·joints + 3)` with `jac[i, k, c] = ∂p_k/∂param_c` (mm/mm
    /// for lengths, mm/rad for angles). A 1-D `q` drops the pose axis. The
    /// positions are those of the Jacobian kernel (they may differ from
    /// `positions` in the last bit). Runs without the GIL.
    #[pyo3(signature = (q, angle_unit = "rad"))]
    fn jacobians<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        angle_unit: &str,
    ) -> PyResult<PositionsAndJacobians<'py>> {
        let unit = crate::angle_unit(angle_unit)?;
        let r = Readings::new(q, "q", self.joints(), unit)?.with_prismatic(self.prismatic());
        let params = param_count(self.joints());
        let per_pose = 3 * params;
        let (p_out, jac_out) = (
            zeros(py, &r.shape(&[3]), "positions")?,
            zeros(py, &r.shape(&[3, params]), "jacobians")?,
        );
        {
            let (mut p_rw, mut jac_rw) = (p_out.readwrite(), jac_out.readwrite());
            let p = p_rw.as_slice_mut().map_err(internal)?;
            let jac = jac_rw.as_slice_mut().map_err(internal)?;
            r.for_chunks(py, |rows, q| {
                let poses = prepare(self.kernel.shape(), q)?;
                let p = &mut p[3 * rows.start..3 * rows.end];
                let jac = &mut jac[per_pose * rows.start..per_pose * rows.end];
                self.kernel
                    .for_each_jacobian(&poses, 0..rows.len(), |i, pos, cols| {
                        p[3 * i..3 * i + 3].copy_from_slice(pos);
                        let block = &mut jac[per_pose * i..per_pose * (i + 1)];
                        for (c, col) in cols.iter().enumerate() {
                            for (k, &v) in col.iter().enumerate() {
                                block[k * params + c] = v;
                            }
                        }
                    })?;
                Ok(())
            })?;
        }
        Ok((p_out, jac_out))
    }

    /// Probe positions and joint Jacobians `∂p/∂q` of poses `q` (as in
    /// `positions`): returns `(p, jac)`, `p` of shape `(n, 3)` and `jac` of
    /// shape `(n, 3, joints)`, mm/rad, `jac[i, k, j] = ∂p_k/∂q_j` — what
    /// inverse kinematics and encoder-noise propagation need. A 1-D `q`
    /// drops the pose axis. Runs without the GIL.
    #[pyo3(signature = (q, angle_unit = "rad"))]
    fn joint_jacobian<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        angle_unit: &str,
    ) -> PyResult<PositionsAndJacobians<'py>> {
        let unit = crate::angle_unit(angle_unit)?;
        let joints = self.joints();
        let r = Readings::new(q, "q", joints, unit)?.with_prismatic(self.prismatic());
        let (p_out, jac_out) = (
            zeros(py, &r.shape(&[3]), "positions")?,
            zeros(py, &r.shape(&[3, joints]), "joint_jacobian")?,
        );
        {
            let (mut p_rw, mut jac_rw) = (p_out.readwrite(), jac_out.readwrite());
            let p = p_rw.as_slice_mut().map_err(internal)?;
            let jac = jac_rw.as_slice_mut().map_err(internal)?;
            r.for_chunks(py, |rows, q| {
                let mut cols = vec![[0.0; 3]; joints];
                for (i, reading) in rows.zip(q.chunks_exact(joints)) {
                    let pos = self.kernel.joint_jacobian(reading, &mut cols)?;
                    p[3 * i..3 * i + 3].copy_from_slice(&pos);
                    let block = &mut jac[3 * joints * i..3 * joints * (i + 1)];
                    for (j, col) in cols.iter().enumerate() {
                        for (k, &v) in col.iter().enumerate() {
                            block[k * joints + j] = v;
                        }
                    }
                }
                Ok(())
            })?;
        }
        Ok((p_out, jac_out))
    }

    /// The arm in the arm-file schema (TOML), in `length_unit` (`"mm"`,
    /// `"m"`, …) and `angle_unit` (`"deg"`, `"rad"`): what `aacmm calibrate`
    /// writes as `calibrated.toml` with the defaults.
    #[pyo3(signature = (length_unit = "mm", angle_unit = "deg"))]
    fn to_toml(&self, length_unit: &str, angle_unit: &str) -> PyResult<String> {
        let lengths: LengthUnit = length_unit
            .parse()
            .map_err(|e: aacmm_core::io::UnknownUnit| Error::value(format!("length_unit: {e}")))?;
        let angles: AngleUnit = crate::angle_unit(angle_unit)?;
        Ok(arm_to_toml(&self.arm, lengths, angles))
    }

    /// The parameters as a dict `name → value` (mm, rad).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        // The arm's own names: a Hayati joint's d-slot is `hbeta…` (rad).
        let pairs: Vec<(String, f64)> = (self.arm.params.param_ids())
            .map(|id| (id.to_string(), self.arm.params.get(id)))
            .collect();
        let dict = pyo3::types::PyDict::new(py);
        for (k, v) in pairs {
            dict.set_item(k, v)?;
        }
        Ok(dict.into_any())
    }

    fn __repr__(&self) -> String {
        format!(
            "Arm(name={:?}, joints={}, source={:?})",
            self.arm.name,
            self.joints(),
            self.source
        )
    }
}

/// Positions and Jacobians, as numpy arrays.
type PositionsAndJacobians<'py> = (Bound<'py, PyArrayDyn<f64>>, Bound<'py, PyArrayDyn<f64>>);

/// A new numpy array of zeros of `shape` (numpy's `zeros`: pages are
/// given as they are written), its size checked first: a `MemoryError`
/// naming `what` when it cannot be had, before any work.
pub(crate) fn zeros<'py>(
    py: Python<'py>,
    shape: &[usize],
    what: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    crate::error::elements(shape, what)?;
    let array = py
        .import("numpy")?
        .call_method1("zeros", (shape.to_vec(),))
        .map_err(|e| {
            if e.is_instance_of::<pyo3::exceptions::PyMemoryError>(py) {
                Error::new(
                    Kind::Memory,
                    format!("{what}: an array of shape {shape:?} cannot be allocated ({e})"),
                )
                .into()
            } else {
                e
            }
        })?;
    Ok(array.cast_into::<PyArrayDyn<f64>>()?)
}

/// A numpy array that is not the contiguous one just made: a bug.
fn internal(e: impl std::fmt::Display) -> PyErr {
    Error::new(Kind::Internal, format!("internal: output array: {e}")).into()
}

/// An owned buffer as a numpy array of `shape` (no copy).
pub(crate) fn shaped<'py>(
    py: Python<'py>,
    v: Vec<f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let array = ArrayD::from_shape_vec(shape.to_vec(), v)
        .map_err(|e| Error::new(Kind::Internal, format!("internal: array shape: {e}")))?;
    Ok(array.into_pyarray(py))
}

/// Points as an `n × 3` numpy array.
pub(crate) fn points_array<'py>(
    py: Python<'py>,
    xyz: &[[f64; 3]],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    shaped(py, xyz.as_flattened().to_vec(), &[xyz.len(), 3])
}
