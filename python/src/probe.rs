//! `aacmm.qualify_probe`: one probe of a measuring arm qualified on a
//! reference sphere, the arm's geometry held — `aacmm probe` from Python.

use aacmm_core::domain::Spheres;
use aacmm_core::io::spheres::read_spheres;
use aacmm_core::io::{AngleUnit, source_name};
use aacmm_core::residuals::Noise as CoreNoise;
use aacmm_core::session::probe::{DEFAULT_TOLERANCE_MM, ProbeSettings, qualify_probe as core};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arm::Arm;
use crate::error::{Error, detached};
use crate::noise::Noise;
use crate::spheres::SphereArg;
use crate::to_dict;

/// Qualifies the probe `tool` (`"probe"`, the arm's `[probe]`, or a
/// `[[tool]]`'s name) of `arm` on points touched on one reference sphere of
/// certified diameter `sphere_diameter_mm`: its tip offset and effective
/// ball diameter with their σ, the sphere's form as the probe sees it, and
/// the decision (`aacmm probe`'s). `spheres` is a sphere-surface file's
/// path (readings in `angle_unit`) or `(labels, q[, tools])` arrays (rad);
/// rows of other probes are left out. Returns the qualification as a dict
/// (its `usable` says whether it may be used; `refusals` why not) and the
/// arm with the qualified probe, or `None` when it is not usable. Runs
/// without the GIL.
#[pyfunction]
#[pyo3(signature = (arm, spheres, sphere_diameter_mm, *, tool = "probe", noise = None, tolerance_mm = DEFAULT_TOLERANCE_MM, max_form_mm = None, angle_unit = "deg"))]
#[allow(clippy::too_many_arguments)]
pub fn qualify_probe<'py>(
    py: Python<'py>,
    arm: &Arm,
    spheres: &Bound<'py, PyAny>,
    sphere_diameter_mm: f64,
    tool: &str,
    noise: Option<&Noise>,
    tolerance_mm: f64,
    max_form_mm: Option<f64>,
    angle_unit: &str,
) -> PyResult<(Bound<'py, PyDict>, Option<Arm>)> {
    let unit = crate::angle_unit(angle_unit)?;
    let (rows, file) = rows_of(py, spheres, arm, unit)?;
    let settings = ProbeSettings {
        tool: tool.to_string(),
        sphere_diameter_mm,
        noise: noise.map_or_else(CoreNoise::default, |n| n.noise),
        tolerance_mm,
        max_form_mm,
        spelling: aacmm_core::session::Spelling::Python,
    };
    let core_arm = &arm.arm;
    let q = detached(py, || Ok(core(core_arm, rows, &file, &settings)?))?;
    let qualified = if q.usable() {
        let source = format!("{} with the probe `{tool}` qualified", arm.source);
        Some(Arm::new(q.qualified_arm(core_arm), source, Vec::new())?)
    } else {
        None
    };
    let dict = to_dict(py, &q)?;
    dict.set_item("usable", q.usable())?;
    Ok((dict, qualified))
}

/// The rows `spheres` names, and the name messages give them.
fn rows_of(
    py: Python<'_>,
    spheres: &Bound<'_, PyAny>,
    arm: &Arm,
    unit: AngleUnit,
) -> PyResult<(Spheres, String)> {
    let arg = SphereArg::of(py, spheres, "spheres", arm, unit)?;
    let name = arg.name();
    Ok(match arg {
        SphereArg::File(path, unit) => {
            let (rows, warnings) = read_spheres(&path, unit, &arm.arm).map_err(Error::from)?;
            let text: Vec<String> = warnings.iter().map(|w| w.to_string()).collect();
            crate::arm::warn_all(py, &text)?;
            (rows, source_name(&path))
        }
        SphereArg::Rows(rows) => (*rows, name),
    })
}
