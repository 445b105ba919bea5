//! Python bindings of aacmm: the module `aacmm` (PyO3 + numpy), built by
//! maturin into an abi3 wheel for CPython 3.9 and newer (`pip install
//! ./python`).
//!
//! Arrays go in and out as numpy arrays without per-element Python work;
//! the GIL is released while the kernel, the metrics, the identification,
//! the simulator and the calibrator run; every error becomes a Python
//! exception with the library's message (module `error`), and no panic crosses
//! into Python. The typed surface is `aacmm.pyi` beside this crate.

mod arm;
mod calibrate;
mod data;
mod error;
mod noise;
mod positions;
mod probe;
mod readings;
mod simulate;
mod spheres;
mod study;
mod verdict;

use aacmm_core::io::AngleUnit;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::{Error, Result};

/// The unit of `angle_unit=` arguments: `"rad"` or `"deg"`.
pub(crate) fn angle_unit(s: &str) -> Result<AngleUnit> {
    s.parse()
        .map_err(|e: aacmm_core::io::UnknownUnit| Error::value(format!("angle_unit: {e}")))
}

/// A path a Python caller gave: always a file. The library's readers take
/// `-` for standard input (the command line's and C's convention), which
/// in Python blocked forever on an open pipe and made a file named `-`
/// unreachable but as `./-`; Python's own `open("-")` opens a file of that
/// name, and so does every `aacmm` function (issue 29).
pub(crate) fn file_path(path: std::path::PathBuf) -> std::path::PathBuf {
    if path.as_os_str() == "-" {
        std::path::PathBuf::from("./-")
    } else {
        path
    }
}

/// A serialisable value of the library as a Python object (through JSON,
/// so that Python sees exactly what the command line writes).
pub(crate) fn to_python<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| Error::new(error::Kind::Internal, format!("JSON: {e}")))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A serialisable value as a Python dict.
pub(crate) fn to_dict<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyDict>> {
    Ok(to_python(py, value)?.cast_into::<PyDict>()?)
}

/// The aacmm toolkit: forward kinematics, metrics, identifiability,
/// simulation and calibration of D-H arms (articulated-arm CMMs). Lengths in
/// mm; angles in rad unless an argument says otherwise.
#[pymodule]
#[pyo3(name = "aacmm")]
fn aacmm_py(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("AacmmError", py.get_type::<error::AacmmError>())?;
    m.add("InputError", py.get_type::<error::InputError>())?;
    m.add("CalibrationError", py.get_type::<error::CalibrationError>())?;
    m.add("UnsupportedError", py.get_type::<error::UnsupportedError>())?;
    m.add_class::<arm::Arm>()?;
    m.add_class::<data::DataSet>()?;
    m.add_class::<simulate::Campaign>()?;
    m.add_class::<noise::Noise>()?;
    m.add_class::<calibrate::Calibration>()?;
    m.add_class::<verdict::Verdict>()?;
    m.add_class::<verdict::VerdictEntry>()?;
    m.add_function(wrap_pyfunction!(arm::param_names, m)?)?;
    m.add_function(wrap_pyfunction!(study::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(study::identify, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(probe::qualify_probe, m)?)?;
    Ok(())
}
