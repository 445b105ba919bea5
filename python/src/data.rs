//! `aacmm.DataSet`: touches grouped by point, with reference lengths, and
//! reference positions an instrument saw — from files or from arrays.

use std::path::PathBuf;

use aacmm_core::dataset::DataSet as CoreDataSet;
use aacmm_core::domain::ReferenceLength;
use aacmm_core::io::{
    AngleUnit, JointColumns, read_lengths, read_poses, read_positions, source_name,
};
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arm::{points_array, shaped, warn_all};
use crate::error::{Error, Result, detached};
use crate::positions::{ARRAYS, PositionArgs};
use crate::readings::Readings;

/// Touches grouped by point (in order of first appearance), the encoder
/// readings prepared for the kernel, reference lengths between points, and
/// reference positions an instrument saw (each frame's registration fitted
/// with the arm). Immutable.
#[pyclass(frozen, module = "aacmm")]
pub struct DataSet {
    pub(crate) data: CoreDataSet,
    /// The poses file as named, or `<arrays>`; for positions alone, their
    /// file (as the command line's report names it).
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

impl DataSet {
    /// No touch, no position, of `arm`'s joints: the data set of a
    /// calibration on points on spheres alone, named by their source
    /// `name` (as the command line's report names the sphere file).
    pub(crate) fn without_touches(arm: &crate::arm::Arm, name: String) -> DataSet {
        DataSet {
            data: CoreDataSet::without_touches(arm.joints(), arm.prismatic()),
            poses_file: name,
            lengths_file: None,
            warnings: Vec::new(),
            unit: AngleUnit::Deg,
        }
    }
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
    #[pyo3(signature = (labels, q, lengths = None, angle_unit = "rad", joint_types = None))]
    fn new(
        py: Python<'_>,
        labels: &Bound<'_, PyAny>,
        q: &Bound<'_, PyAny>,
        lengths: Option<&Bound<'_, PyAny>>,
        angle_unit: &str,
        joint_types: Option<&str>,
    ) -> PyResult<DataSet> {
        let unit = crate::angle_unit(angle_unit)?;
        let labels: Vec<String> = labels
            .try_iter()?
            .map(|l| Ok(l?.str()?.to_string()))
            .collect::<PyResult<_>>()?;
        let joints = columns(q)?;
        let shape = crate::readings::joint_types(joint_types, joints)?;
        let prismatic = shape.map_or(0, |s| s.prismatic_mask());
        let readings = Readings::new(q, "q", joints, unit)?.with_prismatic(prismatic);
        let count = crate::error::elements(&[readings.rows(), joints], "q")?;
        let mut flat = crate::error::buffer(count, "q")?;
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
        let data = match shape {
            Some(shape) => data.for_shape(shape).map_err(Error::from)?,
            None => data,
        };
        // Rows counted once (a repeated row of a point) are said, as a
        // file's would be.
        let warnings: Vec<String> = data
            .repeat_warnings()
            .iter()
            .map(ToString::to_string)
            .collect();
        warn_all(py, &warnings)?;
        Ok(DataSet {
            data,
            poses_file: "<arrays>".to_string(),
            lengths_file: has_lengths.then(|| "<arrays>".to_string()),
            warnings,
            unit,
        })
    }

    /// Reads a poses file (CSV `point,q1,...,qn`, angles in `angle_unit`,
    /// degrees by default as on the command line), optionally a
    /// reference-lengths file (CSV `point_a,point_b,distance[,uncertainty]`,
    /// mm) and a reference-positions file (CSV
    /// `point,q1,...,qn,x,y,z[,frame][,uncertainty]`, mm in the
    /// instrument's frame: `--positions`), or the positions file alone
    /// (`poses=None`). `joints` (if given) is the number of angle columns
    /// required; `joint_types` (`"PRRRRRR"`, one letter per joint: R
    /// revolute, P prismatic) says which columns are lengths (mm, whatever
    /// `angle_unit` says) and implies `joints`. Errors name file, line and field (`aacmm.InputError`;
    /// `OSError` when a file cannot be read); warnings go to `warnings` and
    /// `UserWarning`. A path `-` is a file of that name (not standard input,
    /// as on the command line).
    #[staticmethod]
    #[pyo3(signature = (poses = None, lengths = None, angle_unit = "deg", joints = None, positions = None, joint_types = None))]
    fn from_files(
        py: Python<'_>,
        poses: Option<PathBuf>,
        lengths: Option<PathBuf>,
        angle_unit: &str,
        joints: Option<usize>,
        positions: Option<PathBuf>,
        joint_types: Option<&str>,
    ) -> PyResult<DataSet> {
        let unit = crate::angle_unit(angle_unit)?;
        let joints: JointColumns = match joint_types {
            Some(text) => {
                let count = joints.unwrap_or(text.chars().count());
                match crate::readings::joint_types(Some(text), count)? {
                    Some(shape) => shape.into(),
                    None => joints.into(),
                }
            }
            None => joints.into(),
        };
        let (poses, lengths, positions) = (
            poses.map(crate::file_path),
            lengths.map(crate::file_path),
            positions.map(crate::file_path),
        );
        let Some(poses) = poses else {
            return match (positions, lengths) {
                (None, _) => Err(Error::value("give poses, positions or both").into()),
                (Some(_), Some(_)) => Err(Error::value(
                    "lengths: reference lengths join touched points: give poses too",
                )
                .into()),
                (Some(path), None) => detached(py, || {
                    let name = source_name(&path);
                    let rows = read_positions(&path, unit, joints.clone())?;
                    Ok(DataSet {
                        data: CoreDataSet::from_positions(rows, &name)?,
                        poses_file: name,
                        lengths_file: None,
                        warnings: Vec::new(),
                        unit,
                    })
                }),
            };
        };
        let set = detached(py, || {
            let (read, warnings) = read_poses(&poses, unit, joints.clone())?;
            let poses_file = source_name(&poses);
            let mut data = CoreDataSet::from_poses(&read, &poses_file)?;
            let mut warnings = warnings;
            warnings.extend_from_slice(data.repeat_warnings());
            let lengths_file = lengths.as_deref().map(source_name);
            if let (Some(path), Some(name)) = (&lengths, &lengths_file) {
                data = data.with_lengths(&read_lengths(path)?, name)?;
            }
            if let Some(path) = &positions {
                let rows = read_positions(path, unit, joints.clone())?;
                data = data.with_positions(rows, &source_name(path))?;
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

    /// A data set of reference positions alone, from arrays: `q` an
    /// array-like `n × joints` of readings in `angle_unit`; `xyz` `n × 3`,
    /// where the instrument saw the probe, mm in its own frame; `frames`
    /// per row the frame (station, placement) it was seen from, each with
    /// its own unknown registration (a `str` for every row; default every
    /// row in `"instrument"`); `uncertainty` the standard uncertainty per
    /// coordinate, mm, one number or one per row (NaN: not stated, the
    /// noise model applies); `labels` per row its point (default `P1`,
    /// `P2`, …; rows with one label in one frame are one physical point);
    /// `tools` per row the tool point seen — a `[[tool]]` of the arm file
    /// (its offset fitted with the arm), `""` the arm's `[probe]` — or one
    /// `str` for every row (default: every row the probe). Checked as the library's reader checks a positions file: a
    /// `ValueError` naming the argument and row (0-based) for a wrong
    /// shape, a value that is not finite, an uncertainty not positive, an
    /// empty name, and a frame with fewer than 3 distinct positions or all
    /// of them on one line. Reports name the rows `<arrays>:i+1`.
    #[staticmethod]
    #[pyo3(signature = (q, xyz, frames = None, uncertainty = None, labels = None, angle_unit = "rad", joint_types = None, tools = None))]
    #[allow(clippy::too_many_arguments)]
    fn from_positions(
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        xyz: &Bound<'_, PyAny>,
        frames: Option<&Bound<'_, PyAny>>,
        uncertainty: Option<&Bound<'_, PyAny>>,
        labels: Option<&Bound<'_, PyAny>>,
        angle_unit: &str,
        joint_types: Option<&str>,
        tools: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<DataSet> {
        let unit = crate::angle_unit(angle_unit)?;
        // Only with types given: `read` names a wrong shape of `q` itself.
        let shape = match joint_types {
            Some(_) => crate::readings::joint_types(joint_types, columns(q)?)?,
            None => None,
        };
        let args = PositionArgs {
            q,
            xyz,
            frames,
            uncertainty,
            labels,
            tools,
            unit,
            prismatic: shape.map_or(0, |s| s.prismatic_mask()),
        };
        let read = args.read(py, None)?;
        let data = detached(py, || {
            read.check_frames()?;
            let data = CoreDataSet::from_positions(read.rows, ARRAYS)?;
            Ok(match shape {
                Some(shape) => data.for_shape(shape)?,
                None => data,
            })
        })?;
        Ok(DataSet {
            data,
            poses_file: ARRAYS.to_string(),
            lengths_file: None,
            warnings: Vec::new(),
            unit,
        })
    }

    /// These touches (and lengths) with reference positions given as arrays,
    /// fitted together: the arguments and checks of `from_positions`, `q`
    /// with the data set's joint count. A new data set; a data set that
    /// already has positions is refused (give them all at once).
    #[pyo3(signature = (q, xyz, frames = None, uncertainty = None, labels = None, angle_unit = "rad", tools = None))]
    #[allow(clippy::too_many_arguments)]
    fn with_positions(
        &self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
        xyz: &Bound<'_, PyAny>,
        frames: Option<&Bound<'_, PyAny>>,
        uncertainty: Option<&Bound<'_, PyAny>>,
        labels: Option<&Bound<'_, PyAny>>,
        angle_unit: &str,
        tools: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<DataSet> {
        let unit = crate::angle_unit(angle_unit)?;
        if let Some(p) = self.data.positions() {
            return Err(Error::value(format!(
                "this data set already has {} reference positions (from {}): give them all in \
                 one data set",
                p.len(),
                p.file()
            ))
            .into());
        }
        let args = PositionArgs {
            q,
            xyz,
            frames,
            uncertainty,
            labels,
            tools,
            unit,
            // The readings of the data set's own chain: its slides in mm.
            prismatic: self.data.shape().map_or(0, |s| s.prismatic_mask()),
        };
        let read = args.read(py, Some(self.data.joints()))?;
        let data = detached(py, || {
            read.check_frames()?;
            Ok(self.data.clone().with_positions(read.rows, ARRAYS)?)
        })?;
        Ok(DataSet {
            data,
            poses_file: self.poses_file.clone(),
            lengths_file: self.lengths_file.clone(),
            warnings: self.warnings.clone(),
            unit: self.unit,
        })
    }

    /// Number of touches (0 for reference positions alone).
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

    /// The positions file as named (`<arrays>`, or `None` without
    /// reference positions).
    #[getter]
    fn positions_file(&self) -> Option<&str> {
        self.data.positions().map(|p| p.file())
    }

    /// The reference positions (`None` without): a dict of `labels` and
    /// `frames` (per row, `str`), `q` (readings, rad, `n × joints`), `xyz`
    /// (mm, `n × 3`) and `uncertainty` (mm, `n`, NaN where not stated), in
    /// the rows' order — the arguments of `from_positions` (angles in rad).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(p) = self.data.positions() else {
            return Ok(None);
        };
        let rows = p.rows();
        let n = rows.len();
        let d = PyDict::new(py);
        let labels: Vec<&str> = (0..n).map(|i| rows.label(i)).collect();
        let frames: Vec<&str> = (0..n)
            .map(|i| rows.frames()[rows.frame(i)].as_str())
            .collect();
        let xyz: Vec<[f64; 3]> = (0..n).map(|i| rows.position(i)).collect();
        let u: Vec<f64> = (0..n)
            .map(|i| rows.uncertainty(i).unwrap_or(f64::NAN))
            .collect();
        d.set_item("labels", labels)?;
        d.set_item("frames", frames)?;
        d.set_item(
            "q",
            shaped(py, rows.readings().to_vec(), &[n, rows.joints()])?,
        )?;
        d.set_item("xyz", points_array(py, &xyz)?)?;
        d.set_item("uncertainty", shaped(py, u, &[n])?)?;
        Ok(Some(d))
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
        let positions = self.data.positions().map_or(String::new(), |p| {
            let frames = p.rows().frames().len();
            format!(
                ", {} reference positions in {frames} frame{}",
                p.len(),
                if frames == 1 { "" } else { "s" }
            )
        });
        format!(
            "DataSet({} touches of {} points, {} joints, {} reference lengths{positions}, from \
             {:?})",
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
