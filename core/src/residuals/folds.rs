//! How a term's observations take part in cross-validation: a term deals
//! them to folds itself ([`super::Term::split`]) — only it knows which of
//! its observations must stay together and what its nuisance unknowns
//! need — and hands back, per fold, the term over the training share and
//! a scorer of the held-out share ([`HeldOutScorer`]).

use super::{At, Term, TermError};

/// One fold of a term's observations.
#[derive(Clone, Debug)]
pub struct TermFold {
    /// The term over the fold's training observations, on the same blocks
    /// as the whole term (the fold fits the same layout).
    pub training: Box<dyn Term>,
    /// Scores the observations the fold holds out.
    pub held_out: Box<dyn HeldOutScorer>,
}

/// The held-out observations of one fold, scored against an arm.
pub trait HeldOutScorer: dyn_clone::DynClone + Send + Sync + std::fmt::Debug {
    /// Where each held-out observation came from (`file:line`), in order.
    fn labels(&self) -> Vec<String>;

    /// What its errors are, for a report's title: which observations,
    /// which error (its absolute value is reported), and what `before`
    /// refitted.
    fn what(&self) -> String;

    /// Per held-out observation, its error (mm) at the fold's fit `at`:
    /// the arm and the term's own blocks (its nuisance unknowns) as the
    /// fold fitted them on its training observations.
    ///
    /// # Errors
    ///
    /// The kernel's.
    fn fitted(&self, at: &At<'_>) -> Result<Vec<f64>, TermError>;

    /// The same at `at`'s arm (a start arm that fitted nothing) with the
    /// term's own unknowns refitted, the arm fixed, on the fold's training
    /// observations only: the held-out ones never set what scores them.
    ///
    /// # Errors
    ///
    /// The kernel's; training observations that no longer fix the
    /// unknowns.
    fn refitted(&self, at: &At<'_>) -> Result<Vec<f64>, TermError>;
}

dyn_clone::clone_trait_object!(HeldOutScorer);
