//! The verdict an arm carries: whether the calibration that made it may be
//! used. Its `[verdict]` table and the readers' refusal are in
//! [`crate::io::verdict`].

use serde::{Deserialize, Serialize};

/// Whether a calibration may be used (exit 0 of the command line), in
/// words: the session's typed verdict as its arm file records it
/// ([`crate::session::Verdict::words`]), and as a reader reads it back.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmVerdict {
    /// Usable.
    pub usable: bool,
    /// Why not (empty when usable).
    #[serde(default)]
    pub reasons: Vec<String>,
    /// What a metrologist should know although the result is usable (a χ²
    /// verdict outside its range, a poor fit accepted on request).
    #[serde(default)]
    pub notes: Vec<String>,
}
