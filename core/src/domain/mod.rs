//! The toolkit's nouns: an arm ([`Arm`], its tool points [`Tool`]), and
//! the evidence recorded on it — the touches of points ([`Poses`]),
//! reference lengths between them ([`ReferenceLength`]), positions an
//! instrument saw ([`Positions`]), points probed on spheres ([`Spheres`]) —
//! and the verdict an arm carries ([`ArmVerdict`]). Mm and radians
//! throughout; a row's line is its file's, 0 for one made in memory.
//!
//! These are what a program builds in memory and what the files are read
//! into: [`crate::io`] reads and writes them (its module docs are the file
//! formats), [`crate::DataSet`] gathers them for a fit. Nothing here reads
//! a file or knows a file's units.
//!
//! ```
//! use aacmm_core::DataSet;
//! use aacmm_core::domain::{Arm, Poses, ReferenceLength};
//! use aacmm_core::params::DhParams;
//!
//! // An arm and its evidence built in memory, no file involved: two points
//! // touched three times each (readings in rad; line 0: made in memory),
//! // and a reference length between them.
//! let arm = Arm::without_limits("mine", DhParams::paper_nominal());
//! let mut poses = Poses::new(arm.params.joint_count());
//! for (k, point) in ["S1", "S1", "S1", "S2", "S2", "S2"].into_iter().enumerate() {
//!     poses.push(point, &[0.1 * k as f64, -0.5, 0.8, 0.0, 0.7, 0.2], 0);
//! }
//! let lengths = [ReferenceLength::new("S1", "S2", 500.0, Some(0.002))];
//! let data = DataSet::from_poses(&poses, "memory")?.with_lengths(&lengths, "memory")?;
//! assert_eq!((data.len(), data.points().len(), data.references().len()), (6, 2, 1));
//! # Ok::<(), aacmm_core::error::InputError>(())
//! ```

mod arm;
mod labels;
mod lengths;
mod poses;
mod positions;
mod spheres;
mod tools;
mod verdict;

pub use arm::Arm;
pub use lengths::ReferenceLength;
pub use poses::Poses;
pub use positions::{DEFAULT_FRAME, MIN_FRAME_POSITIONS, Positions, UNIT_QUATERNION_TOLERANCE};
pub use spheres::{MIN_SPHERE_POINTS, Spheres};
pub use tools::{DEFAULT_TOOL, Tool, ToolNames, arm_with_tool};
pub(crate) use tools::{TOOL_BLOCK_PREFIX, block_name};
pub use verdict::ArmVerdict;
