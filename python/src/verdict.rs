//! `Calibration.verdict`: the library's typed verdict in Python's words —
//! each reason and note a `VerdictEntry` with its `kind`, its data as a
//! dict and its sentence, whose remedies name this module's keyword
//! arguments (`robust="huber"`), not the command line's flags.

use aacmm_core::session::{self, Spelling};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::to_dict;

/// Whether a calibration may be used, and why not: `usable`, `reasons`
/// (the first cause first) and `notes`, each a `VerdictEntry`.
#[pyclass(frozen, get_all, module = "aacmm")]
pub struct Verdict {
    /// The calibration may be used (`Calibration.successful`).
    usable: bool,
    /// Why not: empty when usable.
    reasons: Vec<Py<VerdictEntry>>,
    /// What to know although it may be used.
    notes: Vec<Py<VerdictEntry>>,
}

/// One reason or note: `kind` (`"chi_square"`, `"outliers"`, …), `data`
/// (its figures as a dict) and `text` (the sentence, in Python's words).
#[pyclass(frozen, get_all, module = "aacmm")]
pub struct VerdictEntry {
    /// A short stable name of what it says.
    kind: &'static str,
    /// Its figures.
    data: Py<PyDict>,
    /// The sentence.
    text: String,
}

#[pymethods]
impl Verdict {
    fn __repr__(&self) -> String {
        format!(
            "Verdict(usable={}, reasons={}, notes={})",
            if self.usable { "True" } else { "False" },
            self.reasons.len(),
            self.notes.len()
        )
    }
}

#[pymethods]
impl VerdictEntry {
    fn __repr__(&self) -> String {
        format!("VerdictEntry(kind={:?}, text={:?})", self.kind, self.text)
    }
}

/// `value`'s data: its JSON object without the `kind` tag.
fn data<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyDict>> {
    let d = to_dict(py, value)?;
    if d.contains("kind")? {
        d.del_item("kind")?;
    }
    Ok(d)
}

/// One entry: its `kind`, `value`'s data and its `text`.
fn entry(
    py: Python<'_>,
    kind: &'static str,
    value: &impl serde::Serialize,
    text: String,
) -> PyResult<Py<VerdictEntry>> {
    let data = data(py, value)?.unbind();
    Py::new(py, VerdictEntry { kind, data, text })
}

impl Verdict {
    /// `verdict` in Python's words.
    pub(crate) fn of(py: Python<'_>, verdict: &session::Verdict) -> PyResult<Verdict> {
        let python = Spelling::Python;
        let reasons = (verdict.reasons.iter())
            .map(|r| entry(py, r.kind(), r, r.describe(python)))
            .collect::<PyResult<Vec<_>>>()?;
        let notes = (verdict.notes.iter())
            .map(|n| entry(py, n.kind(), n, n.describe(python)))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Verdict {
            usable: verdict.usable,
            reasons,
            notes,
        })
    }
}
