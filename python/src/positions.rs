//! Reference positions handed in from Python as arrays (the arguments of
//! `DataSet.from_positions` and `DataSet.with_positions`): checked as the
//! library's reader checks a positions file, each refusal a `ValueError`
//! naming the argument and the row (0-based, as numpy indexes it).

use aacmm_core::domain::{DEFAULT_FRAME, Positions};
use aacmm_core::io::AngleUnit;
use numpy::{AllowTypeChange, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyString;

use crate::error::{Error, Result};
use crate::readings::Readings;

/// The name arrays go by in messages and reports (a row's "line" is its
/// 1-based index).
pub(crate) const ARRAYS: &str = "<arrays>";

/// The positions given as arrays, checked row by row (not yet frame by
/// frame: [`PositionArrays::check_frames`], which needs no GIL).
pub(crate) struct PositionArrays {
    pub(crate) rows: Positions,
    /// The argument a frame's refusal names: `frames` when given, else
    /// `xyz` (every row in one frame).
    frames_arg: &'static str,
}

/// The arguments as Python gave them.
pub(crate) struct PositionArgs<'a, 'py> {
    pub(crate) q: &'a Bound<'py, PyAny>,
    pub(crate) xyz: &'a Bound<'py, PyAny>,
    pub(crate) frames: Option<&'a Bound<'py, PyAny>>,
    pub(crate) uncertainty: Option<&'a Bound<'py, PyAny>>,
    pub(crate) labels: Option<&'a Bound<'py, PyAny>>,
    /// Per row the tool seen (an arm's `[[tool]]`; empty: its `[probe]`),
    /// or one name for every row.
    pub(crate) tools: Option<&'a Bound<'py, PyAny>>,
    pub(crate) unit: AngleUnit,
    /// Which columns of `q` are slides (bit j: joint j+1): read in mm,
    /// whatever `unit` says.
    pub(crate) prismatic: u16,
}

impl PositionArgs<'_, '_> {
    /// The rows, for `joints` joints if given (those of the touches they
    /// join), else as many as `q` has columns.
    pub(crate) fn read(&self, py: Python<'_>, joints: Option<usize>) -> PyResult<PositionArrays> {
        let shape = shape_of(self.q, "q")?;
        let j = match shape[..] {
            [_, j] if j > 0 && joints.is_none_or(|want| want == j) => j,
            _ => {
                let want = joints.map_or("joints".to_string(), |j| j.to_string());
                let whose =
                    joints.map_or(String::new(), |j| format!(" for the data set's {j} joints"));
                return Err(Error::value(format!(
                    "q: shape {shape:?}; expected (n, {want}){whose}, one row of readings \
                     per position"
                ))
                .into());
            }
        };
        let readings = Readings::new(self.q, "q", j, self.unit)?.with_prismatic(self.prismatic);
        let n = readings.rows();
        if n == 0 {
            return Err(Error::value("q: no rows: no positions").into());
        }
        let mut q = crate::error::buffer(crate::error::elements(&[n, j], "q")?, "q")?;
        readings.for_chunks(py, |_, chunk| {
            q.extend_from_slice(chunk);
            Ok(())
        })?;
        if let Some(k) = q.iter().position(|v| !v.is_finite()) {
            return Err(Error::value(format!(
                "q[{}, {}] = {}: readings must be finite numbers",
                k / j,
                k % j,
                q[k]
            ))
            .into());
        }
        let xyz = positions_mm(self.xyz, n)?;
        let uncertainty = match self.uncertainty {
            None => vec![None; n],
            Some(u) => uncertainties(u, n)?,
        };
        let frames = match self.frames {
            None => vec![DEFAULT_FRAME.to_string(); n],
            Some(f) => names(f, "frames", "frame", n, true)?,
        };
        let labels = match self.labels {
            None => (1..=n).map(|i| format!("P{i}")).collect(),
            Some(l) => names(l, "labels", "label", n, false)?,
        };
        let tools = match self.tools {
            None => Vec::new(),
            Some(t) => tool_names(t, "tools", n)?,
        };
        let mut rows = Positions::new(j);
        for i in 0..n {
            let reading = &q[i * j..(i + 1) * j];
            rows.push(
                &labels[i],
                &frames[i],
                reading,
                xyz[i],
                uncertainty[i],
                i + 1,
            );
            if let Some(tool) = tools.get(i) {
                rows.set_tool(tool.trim());
            }
        }
        Ok(PositionArrays {
            rows,
            frames_arg: if self.frames.is_some() {
                "frames"
            } else {
                "xyz"
            },
        })
    }
}

impl PositionArrays {
    /// Refuses a frame whose rows cannot determine its registration (six
    /// unknowns): fewer than [`MIN_FRAME_POSITIONS`] distinct positions, or
    /// all of them on one line — the checks of the library's reader.
    pub(crate) fn check_frames(&self) -> Result<()> {
        match self.rows.unregistrable_frame() {
            Some((row, why)) => Err(Error::value(format!(
                "{}: {why} (the frame's first row is {row})",
                self.frames_arg
            ))),
            None => Ok(()),
        }
    }
}

/// The shape of the array-like argument `arg` (through `numpy.shape`).
fn shape_of(a: &Bound<'_, PyAny>, arg: &str) -> PyResult<Vec<usize>> {
    let np = a.py().import("numpy")?;
    let shape = np.call_method1("shape", (a,)).map_err(|e| {
        Error::value(format!(
            "{arg}: expected an array of numbers, one row per position ({e})"
        ))
    })?;
    shape.extract()
}

/// `xyz`: `n × 3` finite numbers, mm.
fn positions_mm(xyz: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<[f64; 3]>> {
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = xyz.extract().map_err(|e| {
        Error::value(format!(
            "xyz: expected an array of numbers, n × 3 (x, y, z in mm, one row per row of q) ({e})"
        ))
    })?;
    let shape = array.shape().to_vec();
    if shape[..] != [n, 3] {
        return Err(Error::value(format!(
            "xyz: shape {shape:?}; expected ({n}, 3): x, y, z (mm) for each of the {n} rows of q"
        ))
        .into());
    }
    // Logical (row-major) order whatever the memory layout.
    let flat: Vec<f64> = array.as_array().iter().copied().collect();
    if let Some(k) = flat.iter().position(|v| !v.is_finite()) {
        return Err(Error::value(format!(
            "xyz[{}, {}] ({}) = {}: positions must be finite numbers (mm)",
            k / 3,
            k % 3,
            ["x", "y", "z"][k % 3],
            flat[k]
        ))
        .into());
    }
    Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// `uncertainty`: one number for every row or one per row, mm, each
/// positive or NaN (not stated).
fn uncertainties(u: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<Option<f64>>> {
    let array: PyArrayLikeDyn<'_, f64, AllowTypeChange> = u.extract().map_err(|e| {
        Error::value(format!(
            "uncertainty: expected a number or an array of n numbers (mm; NaN: not stated) ({e})"
        ))
    })?;
    let shape = array.shape().to_vec();
    let per_row = match shape[..] {
        [] => false,
        [m] if m == n => true,
        _ => {
            return Err(Error::value(format!(
                "uncertainty: shape {shape:?}; expected ({n},), one per row of q (NaN: not \
                 stated), or one number for every row"
            ))
            .into());
        }
    };
    // Copied once its shape is known: a huge array of the wrong shape is
    // refused, not copied.
    let values: Vec<f64> = array.as_array().iter().copied().collect();
    let checked = |k: usize, v: f64| -> Result<Option<f64>> {
        match v {
            v if v.is_nan() => Ok(None),
            v if v.is_finite() && v > 0.0 => Ok(Some(v)),
            v => {
                let at = if per_row {
                    format!("[{k}]")
                } else {
                    String::new()
                };
                Err(Error::value(format!(
                    "uncertainty{at} = {}: must be positive (a standard uncertainty per \
                     coordinate, mm), or NaN for not stated",
                    aacmm_core::error::short(v)
                )))
            }
        }
    };
    if per_row {
        Ok(values
            .iter()
            .enumerate()
            .map(|(k, &v)| checked(k, v))
            .collect::<Result<_>>()?)
    } else {
        Ok(vec![checked(0, values[0])?; n])
    }
}

/// Per row of `n` its tool's name (`arg` names the argument in errors): one `str` for every row, or a sequence
/// of `n` (an empty name: the arm's `[probe]`). Whether the arm has such a
/// tool is checked when the data meet it (`calibrate`), by row.
pub(crate) fn tool_names(given: &Bound<'_, PyAny>, arg: &str, n: usize) -> PyResult<Vec<String>> {
    if let Ok(s) = given.cast::<PyString>() {
        return Ok(vec![s.to_string(); n]);
    }
    let names: Vec<String> = given
        .try_iter()
        .map_err(|_| {
            Error::value(format!(
                "{arg}: expected a str or a sequence of {n} tool names, one per row of q"
            ))
        })?
        .map(|v| Ok(v?.str()?.to_string()))
        .collect::<PyResult<_>>()?;
    if names.len() != n {
        return Err(Error::value(format!("{arg}: {} names for {n} rows of q", names.len())).into());
    }
    Ok(names)
}

/// `n` names of rows (any values, taken as `str`), none empty; with
/// `broadcast`, one `str` names every row.
fn names(
    given: &Bound<'_, PyAny>,
    arg: &str,
    what: &str,
    n: usize,
    broadcast: bool,
) -> PyResult<Vec<String>> {
    if let Ok(s) = given.cast::<PyString>() {
        if broadcast {
            let name = s.to_string();
            if name.trim().is_empty() {
                return Err(Error::value(format!("{arg}: empty {what} name")).into());
            }
            return Ok(vec![name; n]);
        }
        return Err(Error::value(format!(
            "{arg}: a str; expected a sequence of {n} {what}s, one per row of q"
        ))
        .into());
    }
    let names: Vec<String> = given
        .try_iter()
        .map_err(|_| {
            Error::value(format!(
                "{arg}: expected a sequence of {n} {what}s, one per row of q"
            ))
        })?
        .map(|v| Ok(v?.str()?.to_string()))
        .collect::<PyResult<_>>()?;
    if names.len() != n {
        return Err(
            Error::value(format!("{arg}: {} {what}s for {n} rows of q", names.len())).into(),
        );
    }
    if let Some(k) = names.iter().position(|s| s.trim().is_empty()) {
        return Err(Error::value(format!("{arg}[{k}]: empty {what} name")).into());
    }
    Ok(names)
}
