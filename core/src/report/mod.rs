//! Everything aacmm renders and writes of what the session found: a
//! calibration's text summary ([`crate::session::CalibrationReport::summary`]),
//! its JSON and its calibrated arm file, the files a command writes and the
//! rule that none is overwritten silently ([`result_files`]), and (with the
//! `report` feature) one self-contained HTML page (inline SVG and CSS; no
//! script, no network, no other file) with each figure as its own SVG file.
//! The session returns data; this module is above it and turns it into
//! words and files.
//!
//! Data flows one way (files → data set → kernel → residuals → solver →
//! report): this module takes plain data — a [`Calibration`](crate::calibrate::Calibration), the data sets
//! with the probe positions the compared arms give for them,
//! the validation figures ([`BeforeAfter`](crate::calibrate::validate::BeforeAfter)) — and computes nothing but what
//! it shows, with [`crate::metrics`]. It never runs a solver.
//!
//! | figure | file | calibration | evaluation |
//! |---|---|---|---|
//! | single-point error `e` per point (paper Fig. 6) | [`SINGLE_POINT_SVG`] | ✓ | ✓ |
//! | length errors: eq. 19 `\|d\|_error` per pair, reference lengths (Fig. 7) | [`LENGTHS_SVG`] | ✓ | ✓ |
//! | parameter corrections ± 2σ, fixed ones with the reason | [`PARAMETERS_SVG`] | ✓ | |
//! | singular values and threshold; correlation heat map | [`IDENTIFIABILITY_SVG`] | ✓ | |
//! | histogram of the per-touch residual lengths `δ = \|x − x̄\|` | [`RESIDUALS_SVG`] | ✓ | ✓ |
//! | LM cost per iteration; annealing energy against temperature | [`SOLVER_SVG`] | ✓ | |
//! | predicted 95 % radius of the position error per sampled pose against the distance from the shoulder, RMS per band | [`UNCERTAINTY_MAP_SVG`] | ✓ (with a map) | |
//!
//! Before calibration is drawn grey, after in colour (blue for fitted
//! points, vermillion for held-out ones); fitted points are dots, held-out
//! points triangles. Every axis and table header states its unit.
//!
//! **Agreement with the JSON.** Where a number of the report is also in a
//! JSON file written beside it, its cell carries `data-json` (a JSON Pointer,
//! RFC 6901, into that file) and `data-value` (the number, shortest
//! round-trip form), so a tool can check that both say the same.
//!
//! **Determinism.** The same input gives the same bytes: no time, no
//! randomness, integer pixel coordinates.
//!
//! **Size.** Memory and output are linear in the touches: eq. 19's pairs,
//! which grow as the square of the points, are streamed and drawn one
//! marker per pair only up to 2000 per series; beyond, as
//! the mean per distance bin.

// The HTML report (the `report` feature).
#[cfg(feature = "report")]
mod acceptance;
#[cfg(feature = "report")]
mod calibration;
#[cfg(feature = "report")]
mod data;
#[cfg(feature = "report")]
mod figures;
#[cfg(feature = "report")]
mod html;
#[cfg(feature = "report")]
mod page;
#[cfg(feature = "report")]
mod svg;
#[cfg(feature = "report")]
mod tables;
#[cfg(feature = "report")]
mod verdict;

#[cfg(all(test, feature = "report"))]
mod tests;

// Text, JSON and files, with or without the page.
mod files;
mod json;
mod summary;
mod text;

#[cfg(feature = "report")]
pub use acceptance::{ACCEPTANCE_FILES, acceptance_report};
#[cfg(feature = "report")]
pub use calibration::session_report;
#[cfg(feature = "report")]
pub use page::*;

pub use files::{WriteError, earlier_results, result_files};
pub use json::{CALIBRATED_FILE, REPORT_FILE, TIMING_FILE};
