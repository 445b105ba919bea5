//! Points probed on reference spheres handed in from Python: the
//! `spheres=` and `validate_spheres=` arguments of `aacmm.calibrate` — a
//! sphere-surface file's path (`--spheres`), or `(labels, q[, tools])` arrays —
//! given to the library's request, which checks them as it does the
//! command line's.

use std::path::PathBuf;

use aacmm_core::domain::{Spheres, Tool, ToolNames};
use aacmm_core::io::AngleUnit;
use aacmm_core::session::Request;
use pyo3::prelude::*;

use crate::arm::Arm;
use crate::error::Error;
use crate::readings::Readings;

/// The name arrays go by in messages and the report.
const ARRAYS: &str = "<arrays>";

/// One `spheres=` argument as given.
pub(crate) enum SphereArg {
    /// A sphere-surface file, its readings in the given unit.
    File(PathBuf, AngleUnit),
    /// Rows from arrays (readings in rad; mm for a slide).
    Rows(Box<Spheres>),
}

impl SphereArg {
    /// `arg` (named `name` in messages) for `arm`: a path (`str` or
    /// `os.PathLike`, readings in `unit`), or a pair `(labels, q)` — per
    /// point its sphere's label and its readings, `n × joints`, in rad (mm
    /// for a slide), each point named `<arrays>:ROW` (1-based) — or a
    /// triple `(labels, q, tools)`, `tools` per point its probe (an arm's
    /// `[[tool]]`, `""` its `[probe]`) or one `str` for every point.
    pub(crate) fn of(
        py: Python<'_>,
        arg: &Bound<'_, PyAny>,
        name: &str,
        arm: &Arm,
        unit: AngleUnit,
    ) -> PyResult<SphereArg> {
        if let Ok(path) = arg.extract::<PathBuf>() {
            return Ok(SphereArg::File(crate::file_path(path), unit));
        }
        let refused = || {
            Error::value(format!(
                "{name}: a sphere-surface file's path, or a pair (labels, q) of arrays, or a \
                 triple (labels, q, tools)"
            ))
        };
        let (labels, q, tools): (Bound<'_, PyAny>, Bound<'_, PyAny>, Option<Bound<'_, PyAny>>) =
            match arg.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>() {
                Ok((l, q)) => (l, q, None),
                Err(_) => {
                    let (l, q, t) = arg.extract().map_err(|_| refused())?;
                    (l, q, Some(t))
                }
            };
        let labels: Vec<String> = (labels.try_iter()?)
            .map(|l| Ok(l?.str()?.to_string()))
            .collect::<PyResult<_>>()?;
        let (joints, prismatic) = (arm.joints(), arm.prismatic());
        let readings = Readings::new(&q, &format!("{name}[1]"), joints, AngleUnit::Rad)?
            .with_prismatic(prismatic);
        if readings.rows() != labels.len() {
            return Err(Error::value(format!(
                "{name}: {} labels for {} rows of readings",
                labels.len(),
                readings.rows()
            ))
            .into());
        }
        let tools = match tools {
            None => Vec::new(),
            Some(t) => crate::positions::tool_names(&t, &format!("{name}[2]"), labels.len())?,
        };
        let known = ToolNames::of(&arm.arm.tools);
        let mut rows = Spheres::new(joints, prismatic);
        readings.for_chunks(py, |range, chunk| {
            for (k, i) in range.enumerate() {
                let q = &chunk[k * joints..(k + 1) * joints];
                if let Some(j) = q.iter().position(|v| !v.is_finite()) {
                    return Err(Error::value(format!(
                        "{name}: row {}: q{} is not a finite number",
                        i + 1,
                        j + 1
                    )));
                }
                rows.push(&labels[i], q, i + 1, None);
                if let Some(cell) = tools.get(i).map(|t| t.trim())
                    && known.of_cell(cell, ARRAYS, i + 1)? != 0
                {
                    rows.set_tool(&Tool {
                        name: cell.to_string(),
                        offset: known.offset(cell).unwrap_or([0.0; 3]),
                        ball_diameter_mm: known.ball_diameter(cell),
                    });
                }
            }
            Ok(())
        })?;
        Ok(SphereArg::Rows(Box::new(rows)))
    }

    /// What the report calls them: the file as given, or `<arrays>`.
    pub(crate) fn name(&self) -> String {
        match self {
            SphereArg::File(path, _) => aacmm_core::io::source_name(path),
            SphereArg::Rows(_) => ARRAYS.to_string(),
        }
    }

    /// `request` fitting these points on spheres.
    pub(crate) fn fitted(self, request: Request) -> Result<Request, Error> {
        Ok(match self {
            SphereArg::File(path, unit) => {
                let back = request.unit();
                request
                    .angle_unit(unit)
                    .read_spheres(path)?
                    .angle_unit(back)
            }
            SphereArg::Rows(rows) => request.spheres_of(*rows, ARRAYS)?,
        })
    }

    /// `request` validating on these points on spheres.
    pub(crate) fn held_out(self, request: Request) -> Result<Request, Error> {
        Ok(match self {
            SphereArg::File(path, unit) => {
                let back = request.unit();
                (request.angle_unit(unit).validate_on_spheres(path)?).angle_unit(back)
            }
            SphereArg::Rows(rows) => request.validate_on_spheres_of(*rows, ARRAYS)?,
        })
    }
}
