//! What the commands print and write of the session's reports, in the
//! words of the command line: identify's, evaluate's and probe's tables and
//! JSON, and the calibration summary's lines of its spheres and tool points
//! (the rest of the calibration's words are in [`super::summary`] and
//! [`super::json`]).

mod evaluation;
mod identification;
mod positions;
mod probe;
mod spheres;
mod tools;
