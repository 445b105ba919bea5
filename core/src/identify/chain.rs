//! What any chain of revolute and prismatic joints can identify: the
//! count of the complete minimal model (Everett, Hollerbach: `C = 4R + 2P +
//! 6`) for each kind of evidence, and the numerical rank of position or
//! full-pose evidence in an unknown instrument frame, from the kernel's
//! 6-row pose Jacobian (docs/calibration.md, "Any chain").
//!
//! The count: a revolute axis is a line in space (4 numbers), a prismatic
//! axis only a direction (2: where its line lies moves nothing), and the
//! tool's frame on the last axis 6 — the joints' zero offsets and the
//! link-by-link placement are absorbed by those. Full poses see all `4R +
//! 2P + 6`; positions lose the tool's orientation (3). The arm's D-H
//! parameters (`4n + 3`) with a fitted instrument frame (6) and, for poses,
//! a fitted tool rotation (3) can express every one of them (with Hayati
//! joints where consecutive axes are parallel), so the frame's and the
//! tool's columns, independent among themselves, take 6 (or 9) of the rank
//! and the arm keeps `4R + 2P − 3` either way. Touches of sockets of
//! unknown position see no base frame at all: a rigid motion of the whole
//! measurement (6) is unseen, which is exactly what a fitted frame
//! absorbs, so touches with reference lengths identify the same `4R + 2P −
//! 3` combinations of the arm; without a length the size is unseen too
//! (one less), unless a prismatic joint moves among the touches of a
//! point — its reading is a length that scaling the arm does not scale.
//! (On a SCARA it cannot: the quill alone sets the probe's height, so
//! every touch of a socket has the same quill reading.)

use nalgebra::{DMatrix, SVD};
use serde::{Deserialize, Serialize};

use super::{MAX_ITERATIONS, RANK_TOLERANCE};
use crate::kernel::{ArmKernel, KernelError};
use crate::params::{ChainShape, DhParams};

/// What a calibration measures, for the count of [`theory`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Evidence {
    /// The tool's full pose (orientation and position) in an unknown
    /// instrument frame: a tracker's 6-D target, a motion-capture body.
    Poses,
    /// The probe's position in an unknown instrument frame (a tracker's
    /// reflector).
    Positions,
    /// Touches of sockets of unknown position, with at least one
    /// reference length between them.
    TouchesAndLengths,
    /// Touches without any reference length; `slides_move` when some
    /// prismatic joint's reading differs between touches of one point
    /// (not so on a SCARA, whose quill alone sets the probe's height, so
    /// that every touch of a socket has the same quill reading).
    Touches {
        /// Whether a slide moves among the touches of a point.
        slides_move: bool,
    },
}

/// Kinematic evidence seen in an unknown instrument frame, what
/// [`kinematic_rank`] analyses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Seen {
    /// Probe positions.
    Positions,
    /// Tool poses (orientation and position).
    Poses,
}

impl From<Seen> for Evidence {
    fn from(seen: Seen) -> Evidence {
        match seen {
            Seen::Positions => Evidence::Positions,
            Seen::Poses => Evidence::Poses,
        }
    }
}

/// The identifiable counts the theory gives a chain of generic geometry
/// (no degenerate axes, data spread over the workspace).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Theory {
    /// Parameters of the complete minimal model the evidence sees, counting
    /// the instrument frame and (for poses) the tool's orientation as its
    /// own: `4R + 2P + 6` for poses, `4R + 2P + 3` for positions and
    /// touches with lengths (a rigid motion of the whole stands in for the
    /// frame), one less for touches alone unless a slide moves among the
    /// touches of a point.
    pub complete: usize,
    /// Combinations of the arm's own `4n + 3` parameters identified, the
    /// frame and the tool rotation fitted and eliminated: what
    /// [`identify`](super::identify) reports as the rank.
    pub arm: usize,
}

/// The counts of [`Theory`] for a chain of `shape` and `evidence`.
///
/// ```
/// use aacmm_core::identify::chain::{Evidence, theory};
/// let lift_7r = "PRRRRRRR".parse().unwrap();
/// assert_eq!(theory(lift_7r, Evidence::Positions).complete, 33);
/// assert_eq!(theory(lift_7r, Evidence::Poses).complete, 36);
/// assert_eq!(theory(lift_7r, Evidence::Poses).arm, 27);
/// let six = "RRRRRR".parse().unwrap();
/// let no_slide = Evidence::Touches { slides_move: false };
/// assert_eq!(theory(six, no_slide).arm, 20); // the paper arm's rank without a length
/// let track_6r = "PRRRRRR".parse().unwrap();
/// assert_eq!(theory(track_6r, Evidence::Touches { slides_move: true }).arm, 23);
/// ```
pub fn theory(shape: ChainShape, evidence: Evidence) -> Theory {
    let p = shape.prismatic_mask().count_ones() as usize;
    let r = shape.joints() - p;
    let axes = 4 * r + 2 * p;
    let (complete, eliminated) = match evidence {
        Evidence::Poses => (axes + 6, 9),
        Evidence::Positions | Evidence::TouchesAndLengths => (axes + 3, 6),
        // The size a touch campaign without lengths misses, unless a
        // slide's reading (a length) moving among a point's touches fixes it.
        Evidence::Touches { slides_move } => {
            let unseen_scale = usize::from(!(slides_move && p > 0));
            ((axes + 3).saturating_sub(unseen_scale), 6)
        }
    };
    Theory {
        complete,
        arm: complete.saturating_sub(eliminated),
    }
}

/// The numerical rank of [`kinematic_rank`], beside the theory's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KinematicRank {
    /// Columns analysed: the arm's `4n + 3`, the frame's 6 and, for poses,
    /// the tool rotation's 3.
    pub columns: usize,
    /// Singular values of the scaled Jacobian, descending.
    pub singular_values: Vec<f64>,
    /// `1e-7 × s_max`.
    pub(crate) threshold: f64,
    /// Singular values above the threshold: the identifiable combinations
    /// of the arm, the frame and the tool rotation together.
    pub rank: usize,
    /// Of them, the arm's: `rank` less the rank of the frame's and the
    /// tool's columns alone.
    pub arm_rank: usize,
    /// What the theory says ([`theory`]).
    pub theory: Theory,
}

impl KinematicRank {
    /// Whether the numerical ranks are the theory's.
    pub fn agrees(&self) -> bool {
        self.rank == self.theory.complete && self.arm_rank == self.theory.arm
    }
}

/// The numerical rank of the arm `params` seen at readings `rows` (rad; mm
/// for a prismatic joint) through an unknown instrument frame: the Jacobian
/// of every seen coordinate over the arm's parameters, the frame's small
/// step `[δω, δt]` and, for poses, a rotation of the tool on the last link
/// (the tool's own orientation, which the D-H chain leaves to its last
/// frame). Rows of a pose are its position (mm) and its small rotation in
/// the frame (rad, times the reach `R`); angle columns are divided by `R`,
/// as [`identify`](super::identify) scales them, so an angle counts as the
/// arc it sweeps at the reach. Unit weights: the rank is a matter of
/// structure, not of noise.
///
/// ```
/// use aacmm_core::identify::chain::{Seen, kinematic_rank};
/// use aacmm_core::params::DhParams;
/// let rows: Vec<Vec<f64>> = (0..40)
///     .map(|i| (0..6).map(|j| ((7 * i + 3 * j) as f64 * 0.77).sin() * 2.5).collect())
///     .collect();
/// let k = kinematic_rank(&DhParams::paper_nominal(), &rows, Seen::Poses).unwrap();
/// assert_eq!((k.columns, k.rank, k.arm_rank), (36, 30, 21));
/// assert!(k.agrees());
/// ```
///
/// # Errors
///
/// The kernel's: an arm it cannot compute, rows of another joint count.
pub fn kinematic_rank<R: AsRef<[f64]>>(
    params: &DhParams,
    rows: &[R],
    seen: Seen,
) -> Result<KinematicRank, KernelError> {
    let kernel = ArmKernel::new(params)?;
    let shape = kernel.shape();
    let arm = kernel.param_count();
    let aux = match seen {
        Seen::Positions => 6,
        Seen::Poses => 9,
    };
    let row_len = match seen {
        Seen::Positions => 3,
        Seen::Poses => 6,
    };
    let reach = params.reach();
    let columns = arm + aux;
    let mut j = DMatrix::<f64>::zeros(row_len * rows.len(), columns);
    let mut cols = vec![[0.0; 6]; arm];
    for (i, q) in rows.iter().enumerate() {
        let tool = kernel.pose_jacobian(q.as_ref(), &mut cols)?;
        let p = tool.position;
        for r in 0..row_len {
            let row = row_len * i + r;
            // Rotation rows in mm at the reach.
            let w = if r < 3 { 1.0 } else { reach };
            for (c, col) in cols.iter().enumerate() {
                let id = params.param_id(c);
                let angle = id.is_some_and(|id| !id.kind.is_length());
                j[(row, c)] = w * col[r] / if angle { reach } else { 1.0 };
            }
            for (c, v) in aux_row(&tool.rotation, p, r).iter().take(aux).enumerate() {
                // The frame's and the tool's rotations are angles too.
                let angle = !(3..6).contains(&c);
                j[(row, arm + c)] = w * v / if angle { reach } else { 1.0 };
            }
        }
    }
    let sv = singular_values(j.clone());
    let smax = sv.first().copied().unwrap_or(0.0);
    let threshold = RANK_TOLERANCE * smax;
    let rank = sv.iter().filter(|&&s| s > threshold).count();
    let aux_block = j.columns(arm, aux).into_owned();
    let aux_rank = singular_values(aux_block)
        .iter()
        .filter(|&&s| s > threshold)
        .count();
    Ok(KinematicRank {
        columns,
        singular_values: sv,
        threshold,
        rank,
        arm_rank: rank.saturating_sub(aux_rank),
        theory: theory(shape, seen.into()),
    })
}

/// Row `r` of the auxiliary columns at a tool of orientation `rot` and
/// probe `p`, the frame at the identity: the frame's step `[δω, δt]` moves
/// the position by `δω × p + δt` and turns the tool by `δω`; a rotation `φ`
/// of the tool on its last link (in the tool's axes) turns it by `R φ` and
/// leaves the probe where it is.
fn aux_row(rot: &[[f64; 3]; 3], p: [f64; 3], r: usize) -> [f64; 9] {
    let mut out = [0.0; 9];
    if r < 3 {
        // δω × p = −[p]× δω.
        let cross = [[0.0, p[2], -p[1]], [-p[2], 0.0, p[0]], [p[1], -p[0], 0.0]];
        out[..3].copy_from_slice(&cross[r]);
        out[3 + r] = 1.0;
    } else {
        out[r - 3] = 1.0;
        out[6..9].copy_from_slice(&rot[r - 3]);
    }
    out
}

/// Singular values of `m`, descending; none for a matrix that is not
/// finite or does not converge.
fn singular_values(m: DMatrix<f64>) -> Vec<f64> {
    if !m.iter().all(|v| v.is_finite()) {
        return Vec::new();
    }
    let Some(svd) = SVD::try_new(m, false, false, f64::EPSILON, MAX_ITERATIONS) else {
        return Vec::new();
    };
    let mut s: Vec<f64> = svd.singular_values.iter().copied().collect();
    s.sort_by(|a, b| b.total_cmp(a));
    s
}
