//! The toolkit's nouns: an arm, and the evidence recorded on it — the
//! touches of points ([`Poses`]), reference lengths between them
//! ([`ReferenceLength`]), positions an instrument saw ([`Positions`]),
//! points probed on spheres ([`Spheres`]) — and the verdict an arm carries
//! ([`ArmVerdict`]). Mm and radians throughout.
//!
//! These are what a program builds in memory and what the files are read
//! into: [`crate::io`] reads and writes them (its module docs are the file
//! formats), [`crate::DataSet`] gathers them for a fit. Nothing here reads
//! a file or knows a file's units.

mod arm;
pub(crate) mod labels;
mod lengths;
mod poses;
mod positions;
mod spheres;
mod tools;
mod verdict;

pub use arm::Arm;
pub use lengths::ReferenceLength;
pub use poses::Poses;
pub(crate) use positions::MIN_TOOL_ROWS;
pub use positions::{DEFAULT_FRAME, MIN_FRAME_POSITIONS, Positions, UNIT_QUATERNION_TOLERANCE};
pub use spheres::{MIN_SPHERE_POINTS, Spheres};
pub use tools::{DEFAULT_TOOL, Tool, arm_with_tool};
pub(crate) use tools::{TOOL_BLOCK_PREFIX, block_name};
pub use verdict::ArmVerdict;
