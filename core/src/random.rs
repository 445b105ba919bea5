//! Every random draw of the toolkit comes from one generator per purpose:
//! `ChaCha8Rng::seed_from_u64(seed)` with the purpose's own stream number
//! ([`streams`]), so the same seed gives the same bytes whatever else drew,
//! and whatever the thread count.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The named random streams. The numbers are part of the output format:
/// changing one changes every file made with that seed.
pub(crate) mod streams {
    /// The true arm's random errors (simulator).
    pub(crate) const TRUE_ARM: u64 = 1;
    /// Socket placement (simulator).
    pub(crate) const SOCKETS: u64 = 2;
    /// Probe seating noise (simulator).
    pub(crate) const SEATING: u64 = 3;
    /// Inverse-kinematics starts (simulator).
    pub(crate) const IK_STARTS: u64 = 4;
    /// Encoder noise (simulator).
    pub(crate) const ENCODERS: u64 = 5;
    /// Reference-length pairs and their noise (simulator).
    pub(crate) const LENGTHS: u64 = 6;
    /// The order in which cross-validation deals points to folds.
    pub(crate) const FOLDS: u64 = 7;
    /// The order in which cross-validation deals reference positions.
    pub(crate) const POSITION_FOLDS: u64 = 8;
    /// An experiment plan's random subsets (its baseline) and sampled
    /// workspace poses.
    pub(crate) const PLAN: u64 = 9;
    /// The workspace sample of an uncertainty map.
    pub(crate) const WORKSPACE: u64 = 10;
    /// The pairs of points eq. 19 is summarised over, above its budget.
    pub(crate) const PAIRS: u64 = 11;
    /// The random nominal arm of a chain shape (`simulate --chain`).
    pub(crate) const CHAIN: u64 = 12;
    /// The order in which cross-validation deals points on spheres.
    pub(crate) const SPHERE_FOLDS: u64 = 13;
    /// The draws of an acceptance test's prediction from a calibration.
    pub(crate) const PREDICTION: u64 = 14;
    /// The solvers: annealing moves, global starts.
    pub(crate) const SOLVER: u64 = 0x50_4c_56;
}

/// The generator of one purpose's draws (see [`streams`]).
pub(crate) fn rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(stream);
    r
}

#[cfg(test)]
mod tests {
    use super::{rng, streams};
    use rand::RngExt;

    #[test]
    fn a_stream_repeats_itself_and_differs_from_the_others() {
        let a: f64 = rng(3, streams::SOCKETS).random();
        let b: f64 = rng(3, streams::SOCKETS).random();
        let c: f64 = rng(3, streams::ENCODERS).random();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }
}
