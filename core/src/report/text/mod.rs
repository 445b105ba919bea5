//! What the commands other than `calibrate` print and write of the
//! session's reports: each report's tables and JSON, in the words of the
//! command line (the calibration's are in [`super::summary`] and
//! [`super::json`]).

mod evaluation;
mod identification;
mod positions;
mod probe;
mod spheres;
