//! `aacmm.evaluate` and `aacmm.identify`: the figures of an arm on data, and
//! what the data can determine.

use aacmm_core::calibrate::{SolverSettings, available_threads};
use aacmm_core::identify::identify as core_identify;
use aacmm_core::metrics::evaluate as core_evaluate;
use aacmm_core::residuals::Noise as CoreNoise;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arm::Arm;
use crate::data::DataSet;
use crate::error::{Error, detached};
use crate::noise::Noise;
use crate::to_dict;

/// Worker threads: `threads`, or one per core (`None`); the library's check
/// refuses 0.
pub(crate) fn threads(threads: Option<usize>) -> PyResult<usize> {
    match threads {
        Some(n) => {
            let settings = SolverSettings {
                threads: n,
                ..SolverSettings::default()
            };
            settings.check().map_err(Error::from)?;
            Ok(n)
        }
        None => Ok(available_threads()),
    }
}

/// The figures of `arm` on `data` (`aacmm evaluate`'s JSON `evaluation`):
/// per point `e`, `2s`, `δ_max`; their summaries across points; the length
/// errors between points (eq. 19) and against the reference lengths. mm.
/// Touches only: reference positions alone are refused (`ValueError`;
/// their figures are a calibration's). Runs without the GIL.
#[pyfunction]
pub fn evaluate<'py>(py: Python<'py>, arm: &Arm, data: &DataSet) -> PyResult<Bound<'py, PyDict>> {
    if data.data.is_empty() {
        return Err(Error::value(
            "data: no touches to evaluate (reference positions alone): the figures at the \
             positions are a calibration's, summary[\"fitted\"][...][\"positions\"]",
        )
        .into());
    }
    aacmm_core::metrics::room_to_evaluate(&data.data).map_err(Error::from)?;
    let evaluation = detached(py, || {
        let d = &data.data;
        let mut xyz = vec![[0.0; 3]; d.len()];
        arm.kernel.positions(d.poses(), 0..d.len(), &mut xyz)?;
        // Lengths in another unit than the arm: refused, as calibrate does.
        aacmm_core::session::check_units(&arm.arm.params, d, &arm.source)?;
        core_evaluate(d, &xyz).map_err(|e| Error::from(e).prefixed(&arm.source))
    })?;
    to_dict(py, &evaluation)
}

/// Identifiability of `arm`'s parameters from `data` (`aacmm identify`'s
/// JSON `identification`): singular values, structural rules, rank, the
/// recommended fixed set with reasons, predicted σ of the free parameters
/// at the stated `noise`, strong correlations. Without stated noise the
/// figures are for a 0.01 mm touch. Runs without the GIL.
#[pyfunction]
#[pyo3(signature = (arm, data, noise = None, threads = None))]
pub fn identify<'py>(
    py: Python<'py>,
    arm: &Arm,
    data: &DataSet,
    noise: Option<&Noise>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let noise = noise.map_or_else(CoreNoise::default, |n| n.noise);
    let threads = self::threads(threads)?;
    aacmm_core::identify::room_to_identify(&data.data).map_err(Error::from)?;
    let id = detached(py, || {
        // Lengths in another unit than the arm: refused, as calibrate
        // does (a joint count that differs is identify's to refuse).
        if data.data.joints() == arm.arm.params.joint_count() {
            aacmm_core::session::check_units(&arm.arm.params, &data.data, &arm.source)?;
        }
        core_identify(&arm.arm.params, &data.data, &noise, threads)
            .map_err(|e| Error::from(e).prefixed(&arm.source))
    })?;
    to_dict(py, &id)
}
