//! `aacmm.DataSet`: touches grouped by point, with reference lengths — from
//! files or from arrays.

use std::path::PathBuf;

use aacmm_core::dataset::DataSet as CoreDataSet;
use aacmm_core::io::{AngleUnit, ReferenceLength, read_lengths, read_poses, source_name};
use numpy::PyArrayDyn;
use pyo3::prelude::*;

use crate::arm::{shaped, warn_all};
use crate::error::{Error, Result, detached};
use crate::readings::Readings;

/// Touches grouped by point (in order of first appearance), the encoder
/// readings prepared for the kernel, and reference lengths between points.
/// Immutable.
#[pyclass(frozen, module = "aacmm")]
pub struct DataSet {
    pub(crate) data: CoreDataSet,
    /// The poses file as named, or `<arrays>`.
    pub(crate) poses_file: String,
    /// The lengths file as named, `<arrays>`, or `None` without lengths.
    pub(crate) lengths_file: Option<String>,
    pub(crate) warnings: Vec<String>,
    /// The unit the readings were given in (messages show them so).
    pub(crate) unit: AngleUnit,
}

/// One reference length handed in from Python:
/// `(point_a, point_b, distance_mm[, uncertainty_mm])`.
type LengthTuple = (String, String, f64, Option<f64>);

/// The data set of touches given as arrays (`q`: `joints` readings per
/// touch, rad, row-major): the library's [`CoreDataSet::from_touches`], whose
/// messages name `<arrays>`, the 1-based touch or length and the field.
fn touches_data_set(
    labels: &[String],
    joints: usize,
    q: &[f64],
    lengths: &[LengthTuple],
) -> Result<CoreDataSet> {
    let rows: Vec<&[f64]> = q.chunks_exact(joints.max(1)).collect();
    let refs: Vec<ReferenceLength> = lengths
        .iter()
        .enumerate()
        .map(|(i, (a, b, distance, uncertainty))| ReferenceLength {
            a: a.clone(),
            b: b.clone(),
            distance: *distance,
            uncertainty: *uncertainty,
            line: i + 1,
        })
        .collect();
    Ok(CoreDataSet::from_touches(labels, &rows, &refs)?)
}

/// A length as a Python tuple, or a clear error.
fn length_tuple(item: &Bound<'_, PyAny>, i: usize) -> PyResult<LengthTuple> {
    let bad = || {
        Error::value(format!(
            "lengths[{i}]: expected (point_a, point_b, distance_mm) or (point_a, point_b, \
             distance_mm, uncertainty_mm)"
        ))
    };
    let parts: Vec<Bound<'_, PyAny>> = item
        .try_iter()
        .map_err(|_| bad())?
        .collect::<PyResult<_>>()?;
    if !(3..=4).contains(&parts.len()) {
        return Err(bad().into());
    }
    let number = |v: &Bound<'_, PyAny>| -> PyResult<f64> { v.extract().map_err(|_| bad().into()) };
    let uncertainty = match parts.get(3) {
        Some(u) if !u.is_none() => Some(number(u)?),
        _ => None,
    };
    Ok((
        parts[0].str()?.to_string(),
        parts[1].str()?.to_string(),
        number(&parts[2])?,
        uncertainty,
    ))
}

#[pymethods]
impl DataSet {
    /// A data set from touches given as arrays: `labels` (one per touch; any
    /// values, taken as `str`), `q` an array-like `n × joints` of readings in
    /// `angle_unit`, and `lengths` an optional list of `(point_a, point_b,
    /// distance_mm[, uncertainty_mm])`. Checked as the file readers check
    /// files (`aacmm.InputError` naming `<arrays>`, the 1-based touch or
    /// length, and the field).
    #[new]
    #[pyo3(signature = (labels, q, lengths = None, angle_unit = "rad"))]
    fn new(
        py: Python<'_>,
        labels: &Bound<'_, PyAny>,
        q: &Bound<'_, PyAny>,
        lengths: Option<&Bound<'_, PyAny>>,
        angle_unit: &str,
    ) -> PyResult<DataSet> {
        let unit = crate::angle_unit(angle_unit)?;
        let labels: Vec<String> = labels
            .try_iter()?
            .map(|l| Ok(l?.str()?.to_string()))
            .collect::<PyResult<_>>()?;
        let joints = columns(q)?;
        let readings = Readings::new(q, "q", joints, unit)?;
        let mut flat = Vec::with_capacity(readings.rows() * joints);
        readings.for_chunks(py, |_, chunk| {
            flat.extend_from_slice(chunk);
            Ok(())
        })?;
        let lengths: Vec<LengthTuple> = match lengths {
            None => Vec::new(),
            Some(l) => l
                .try_iter()?
                .enumerate()
                .map(|(i, item)| length_tuple(&item?, i))
                .collect::<PyResult<_>>()?,
        };
        let has_lengths = !lengths.is_empty();
        let data = detached(py, || touches_data_set(&labels, joints, &flat, &lengths))?;
        Ok(DataSet {
            data,
            poses_file: "<arrays>".to_string(),
            lengths_file: has_lengths.then(|| "<arrays>".to_string()),
            warnings: Vec::new(),
            unit,
        })
    }

    /// Reads a poses file (CSV `point,q1,...,qn`, angles in `angle_unit`,
    /// degrees by default as on the command line) and, optionally, a
    /// reference-lengths file (CSV `point_a,point_b,distance[,uncertainty]`,
    /// mm). `joints` (if given) is the number of angle columns required.
    /// Errors name file, line and field (`aacmm.InputError`; `OSError` when
    /// a file cannot be read); warnings go to `warnings` and `UserWarning`.
    #[staticmethod]
    #[pyo3(signature = (poses, lengths = None, angle_unit = "deg", joints = None))]
    fn from_files(
        py: Python<'_>,
        poses: PathBuf,
        lengths: Option<PathBuf>,
        angle_unit: &str,
        joints: Option<usize>,
    ) -> PyResult<DataSet> {
        let unit = crate::angle_unit(angle_unit)?;
        let set = detached(py, || {
            let (read, warnings) = read_poses(&poses, unit, joints)?;
            let poses_file = source_name(&poses);
            let mut data = CoreDataSet::from_poses(&read, &poses_file)?;
            let lengths_file = lengths.as_deref().map(source_name);
            if let (Some(path), Some(name)) = (&lengths, &lengths_file) {
                data = data.with_lengths(&read_lengths(path)?, name)?;
            }
            Ok(DataSet {
                data,
                poses_file,
                lengths_file,
                warnings: warnings.iter().map(ToString::to_string).collect(),
                unit,
            })
        })?;
        warn_all(py, &set.warnings)?;
        Ok(set)
    }

    /// Number of touches.
    fn __len__(&self) -> usize {
        self.data.len()
    }

    /// Number of joints (angle columns).
    #[getter]
    fn joints(&self) -> usize {
        self.data.joints()
    }

    /// The points' labels, in the data set's order (first appearance).
    #[getter]
    fn points(&self) -> Vec<String> {
        self.data.points().iter().map(|p| p.label.clone()).collect()
    }

    /// Per touch, in the data set's order (grouped by point), its point's
    /// label.
    #[getter]
    fn labels(&self) -> Vec<String> {
        let mut out = Vec::with_capacity(self.data.len());
        for p in self.data.points() {
            out.extend(p.touches.clone().map(|_| p.label.clone()));
        }
        out
    }

    /// The readings, rad, `n × joints`, in the data set's order (grouped by
    /// point, as `labels`).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let j = self.data.joints();
        let mut v = Vec::with_capacity(self.data.len() * j);
        for i in 0..self.data.len() {
            v.extend_from_slice(self.data.reading(i));
        }
        shaped(py, v, &[self.data.len(), j])
    }

    /// The reference lengths: `(point_a, point_b, distance_mm,
    /// uncertainty_mm or None)`.
    #[getter]
    fn lengths(&self) -> Vec<LengthTuple> {
        let points = self.data.points();
        self.data
            .references()
            .iter()
            .map(|r| {
                (
                    points[r.a].label.clone(),
                    points[r.b].label.clone(),
                    r.distance,
                    r.uncertainty,
                )
            })
            .collect()
    }

    /// The poses file as named (`<arrays>` for arrays).
    #[getter]
    fn poses_file(&self) -> &str {
        &self.poses_file
    }

    /// The lengths file as named (`<arrays>`, or `None` without lengths).
    #[getter]
    fn lengths_file(&self) -> Option<&str> {
        self.lengths_file.as_deref()
    }

    /// The readers' warnings.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Where touch `i` (in the data set's order) came from: `file:line`.
    fn source_of(&self, i: usize) -> PyResult<String> {
        if i >= self.data.len() {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                "touch {i} of {}",
                self.data.len()
            )));
        }
        Ok(self.data.source().touch(i).to_string())
    }

    fn __repr__(&self) -> String {
        format!(
            "DataSet({} touches of {} points, {} joints, {} reference lengths, from {:?})",
            self.data.len(),
            self.data.points().len(),
            self.data.joints(),
            self.data.references().len(),
            self.poses_file
        )
    }
}

/// The number of columns of a 2-D array-like `q` (through `numpy.asarray`),
/// for data sets that have no arm to tell the joint count.
fn columns(q: &Bound<'_, PyAny>) -> PyResult<usize> {
    let np = q.py().import("numpy")?;
    let shape: Vec<usize> = np.call_method1("shape", (q,))?.extract()?;
    match shape[..] {
        [_, j] => Ok(j),
        _ => Err(Error::value(format!(
            "q: shape {shape:?}; expected (n, joints), one row of readings per touch"
        ))
        .into()),
    }
}
