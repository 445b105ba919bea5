//! aacmm-core: the geometric model of D-H measuring arms and everything that
//! evaluates it — parameters, the generic (autodiff) model, the generated kernel,
//! data files, metrics, the campaign simulator.
//!
//! Data flows one way: files → typed data set → kernel → residuals/metrics →
//! solver → report; no module reaches back up that chain.

pub mod calibrate;
pub mod dataset;
pub mod error;
#[cfg(feature = "reference-model")]
pub mod generic;
pub mod geometry;
pub mod identify;
pub mod io;
pub mod kernel;
pub mod metrics;
pub mod params;
pub mod placements;
pub mod report;
pub mod residuals;
pub mod simulate;
pub mod urdf;
