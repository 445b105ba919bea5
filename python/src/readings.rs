//! Encoder readings handed in from Python: any array-like of numbers,
//! `n × joints` (or one pose of `joints`), read in chunks.
//!
//! A chunk is copied out of the caller's array while the GIL is held, so no
//! Python thread can change it under us; the work on it (unit conversion,
//! sin/cos, the kernel) runs without the GIL. Chunks are small enough to stay
//! in cache, so the copy costs little next to the sin/cos it feeds.

use std::ops::Range;

use aacmm_core::io::AngleUnit;
use aacmm_core::kernel::PreparedPoses;
use aacmm_core::params::ChainShape;
use numpy::ndarray::{Ix2, s};
use numpy::{AllowTypeChange, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::error::{Error, Result, detached};

/// Poses per chunk: 16 Ki poses of 6 readings are 768 KiB.
const CHUNK: usize = 16 * 1024;

/// Readings from Python, checked for shape.
pub(crate) struct Readings<'py> {
    array: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    joints: usize,
    rows: usize,
    single: bool,
    unit: AngleUnit,
    /// The prismatic joints (bit `j` for joint `j`): their readings are mm
    /// whatever `unit` says.
    prismatic: u16,
}

impl<'py> Readings<'py> {
    /// The readings `q` (named `name` in messages) of a `joints`-joint arm,
    /// in `unit`.
    pub(crate) fn new(
        q: &Bound<'py, PyAny>,
        name: &str,
        joints: usize,
        unit: AngleUnit,
    ) -> PyResult<Readings<'py>> {
        let array: PyArrayLikeDyn<'py, f64, AllowTypeChange> = q.extract().map_err(|e| {
            Error::value(format!(
                "{name}: expected an array of numbers, n × {joints} (one row per pose) \
                 ({e})"
            ))
        })?;
        let shape = array.shape().to_vec();
        let (rows, single) = match shape[..] {
            [j] if j == joints => (1, true),
            [n, j] if j == joints => (n, false),
            _ => {
                return Err(Error::value(format!(
                    "{name}: shape {shape:?}; expected (n, {joints}) for the arm's {joints} \
                     joints, or ({joints},) for one pose"
                ))
                .into());
            }
        };
        Ok(Readings {
            array,
            joints,
            rows,
            single,
            unit,
            prismatic: 0,
        })
    }

    /// These readings as those of a chain whose joints of the bits
    /// `prismatic` slide: their columns are mm, not converted from `unit`.
    pub(crate) fn with_prismatic(mut self, prismatic: u16) -> Readings<'py> {
        self.prismatic = prismatic;
        self
    }

    /// Number of poses.
    pub(crate) fn rows(&self) -> usize {
        self.rows
    }

    /// The shape of a result with `per_pose` per pose: `(n, *per_pose)`,
    /// or `per_pose` for one pose given as a 1-D array.
    pub(crate) fn shape(&self, per_pose: &[usize]) -> Vec<usize> {
        let pose_axis = (!self.single).then_some(self.rows);
        pose_axis
            .into_iter()
            .chain(per_pose.iter().copied())
            .collect()
    }

    /// Appends the readings of `rows` to `buf`, row-major, as given.
    fn copy(&self, rows: Range<usize>, buf: &mut Vec<f64>) {
        let j = self.joints;
        // `as_slice` also accepts Fortran order: only C order is row-major.
        if self.array.is_c_contiguous()
            && let Ok(all) = self.array.as_slice()
        {
            buf.extend_from_slice(&all[rows.start * j..rows.end * j]);
            return;
        }
        let view = self.array.as_array();
        match view.view().into_dimensionality::<Ix2>() {
            Ok(m) => buf.extend(m.slice(s![rows, ..]).iter()),
            Err(_) => buf.extend(view.iter()),
        }
    }

    /// Calls `f(rows, q)` for consecutive chunks of poses, `q` the chunk's
    /// readings in rad (row-major), without the GIL.
    pub(crate) fn for_chunks(
        &self,
        py: Python<'_>,
        mut f: impl FnMut(Range<usize>, &[f64]) -> Result<()> + Send,
    ) -> PyResult<()> {
        let mut buf = Vec::with_capacity(CHUNK.min(self.rows) * self.joints);
        let (unit, prismatic, joints) = (self.unit, self.prismatic, self.joints.max(1));
        let slides = |j: usize| j < 16 && prismatic & (1 << j) != 0;
        let mut start = 0;
        while start < self.rows {
            let rows = start..(start + CHUNK).min(self.rows);
            buf.clear();
            self.copy(rows.clone(), &mut buf);
            let chunk = &mut buf;
            detached(py, || {
                if unit != AngleUnit::Rad {
                    for (i, x) in chunk.iter_mut().enumerate() {
                        if !slides(i % joints) {
                            *x = unit.to_internal(*x);
                        }
                    }
                }
                f(rows.clone(), chunk)
            })?;
            start = rows.end;
        }
        Ok(())
    }
}

/// Readings `q` (row-major, one row per pose, in rad; mm for a prismatic
/// joint) prepared for the kernel of a chain of `shape` (the C API's
/// `prepare`).
pub(crate) fn prepare(shape: ChainShape, q: &[f64]) -> Result<PreparedPoses> {
    Ok(match shape.joints() {
        6 => PreparedPoses::for_shape(shape, q.as_chunks::<6>().0)?,
        7 => PreparedPoses::for_shape(shape, q.as_chunks::<7>().0)?,
        joints => PreparedPoses::for_shape(shape, &q.chunks_exact(joints).collect::<Vec<_>>())?,
    })
}

/// The chain shape a `joint_types` argument names (`"PRRRRRR"`: one letter
/// per joint, R revolute, P prismatic), checked against `joints`; `None`
/// when not given.
pub(crate) fn joint_types(text: Option<&str>, joints: usize) -> Result<Option<ChainShape>> {
    let Some(text) = text else {
        return Ok(None);
    };
    let shape: ChainShape = text
        .parse()
        .map_err(|e| Error::value(format!("joint_types: {e}")))?;
    if shape.joints() != joints {
        return Err(Error::value(format!(
            "joint_types: {text} names {} joints, the readings have {joints}",
            shape.joints()
        )));
    }
    Ok(Some(shape))
}
