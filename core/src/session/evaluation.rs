//! What `evaluate` reports, built once for every front end: the figures of
//! an arm on measured touches ([`crate::metrics`]) with what was evaluated,
//! as the JSON of `aacmm evaluate --json` ([`EvaluationReport::write_json`])
//! and the tables it prints ([`EvaluationReport::write_summary`]), both
//! rendered in [`crate::report`]. The eq. 19 rows of every pair of points,
//! which grow as the square of the points, are streamed into both, never
//! collected.

use super::Sources;
use crate::dataset::DataSet;
use crate::domain::Arm;
use crate::metrics::{
    Evaluation, MetricsError, PairLengthError, evaluate_threads, pair_length_errors,
};

/// The figures of an arm on a data set, with the positions they were
/// computed from (borrowed: a campaign's touches are not copied): what
/// `evaluate` reports, built once for every front end, as the JSON of
/// `aacmm evaluate --json` ([`EvaluationReport::write_json`]) and the tables
/// it prints ([`EvaluationReport::write_summary`]). The eq. 19 rows of every
/// pair of points, which grow as the square of the points, are streamed
/// into both, never collected.
#[derive(Clone, Debug)]
pub struct EvaluationReport<'a> {
    /// The arm's name.
    pub arm: String,
    /// Its file.
    pub arm_file: String,
    /// The poses file.
    pub data_file: String,
    /// The lengths file, if any.
    pub(crate) lengths_file: Option<String>,
    /// Every figure (lengths in mm).
    pub(crate) evaluation: Evaluation,
    pub(crate) data: &'a DataSet,
    pub(crate) xyz: &'a [[f64; 3]],
    pub(crate) pairs: bool,
}

impl<'a> EvaluationReport<'a> {
    /// Evaluates the probe positions `xyz` the arm `arm` gives for the
    /// touches of `data` (in its touch order), the pairs of points on
    /// `threads` threads (the same bits whatever the count); `sources`
    /// names the inputs.
    ///
    /// # Errors
    ///
    /// The metrics' ([`evaluate_threads`]): positions that do not fit the
    /// data, or are not finite, or figures that overflow.
    ///
    /// ```
    /// use aacmm_core::{Arm, dataset::DataSet, params::DhParams, session::{EvaluationReport, Sources}};
    /// let arm = Arm::without_limits("n", DhParams::paper_nominal());
    /// let data = DataSet::from_labels(&["a", "a", "a", "b", "b", "b"], "m.csv").unwrap();
    /// let xyz = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0; 3], [10.0, 0.0, 10.0]];
    /// let sources = Sources { arm_file: "n.toml".into(), data_file: "m.csv".into(), ..Sources::default() };
    /// let report = EvaluationReport::new(&arm, &data, &xyz, &sources, 1).unwrap().with_pairs(true);
    /// assert!(report.summary().starts_with("arm `n` (n.toml) on m.csv\n"));
    /// assert!(report.to_json().contains("\"pair_length\": ["));
    /// ```
    pub fn new(
        arm: &Arm,
        data: &'a DataSet,
        xyz: &'a [[f64; 3]],
        sources: &Sources,
        threads: usize,
    ) -> Result<EvaluationReport<'a>, MetricsError> {
        let evaluation = evaluate_threads(data, xyz, threads)?;
        Ok(EvaluationReport {
            arm: arm.name.clone(),
            arm_file: sources.arm_file.clone(),
            data_file: sources.data_file.clone(),
            lengths_file: sources.lengths_file.clone(),
            evaluation,
            data,
            xyz,
            pairs: false,
        })
    }

    /// Also lists eq. 19 for every pair of points, in the tables and the
    /// JSON (`pair_length`).
    pub fn with_pairs(mut self, pairs: bool) -> EvaluationReport<'a> {
        self.pairs = pairs;
        self
    }

    /// Eq. 19 for every pair of points, as computed.
    pub(crate) fn pair_rows(&self) -> impl Iterator<Item = PairLengthError> + '_ {
        pair_length_errors(self.data, self.xyz, &self.evaluation.points)
    }
}
