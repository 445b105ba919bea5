//! aacmm: calibration of articulated arm coordinate measuring machines.
//!
//! The facade over [`aacmm_core`]: parameters, the generated kinematic kernel
//! and its generic oracle, data files, metrics. The `aacmm` binary is the
//! command-line front end.

pub use aacmm_core::*;
