//! What `evaluate` reports, built once for every front end: the figures of
//! an arm on measured touches ([`crate::metrics`]) with what was evaluated,
//! as the JSON of `aacmm evaluate --json` ([`EvaluationReport::write_json`])
//! and the tables it prints ([`EvaluationReport::write_summary`]). The
//! eq. 19 rows of every pair of points, which grow as the square of the
//! points, are streamed into both, never collected.

use std::io::{self, Write};

use serde::{Serialize, Serializer};

use super::Sources;
use crate::dataset::DataSet;
use crate::io::Arm;
use crate::metrics::{
    Evaluation, MetricsError, PairLengthError, evaluate_threads, pair_length_errors,
    write_pair_table,
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
    pairs: bool,
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
    fn pair_rows(&self) -> impl Iterator<Item = PairLengthError> + '_ {
        pair_length_errors(self.data, self.xyz, &self.evaluation.points)
    }

    /// Writes the tables `aacmm evaluate` prints: what was evaluated, the
    /// points, the single-point figures, the length errors, the reference
    /// lengths, and (with pairs) every pair's row as it is computed.
    ///
    /// # Errors
    ///
    /// The writer's.
    pub fn write_summary(&self, w: &mut dyn Write) -> io::Result<()> {
        write!(
            w,
            "arm `{}` ({}) on {}\n{}",
            self.arm,
            self.arm_file,
            self.data_file,
            self.evaluation.to_table()
        )?;
        if self.pairs {
            write_pair_table(w, self.pair_rows(), self.data.points())?;
        }
        Ok(())
    }

    /// [`EvaluationReport::write_summary`] as text.
    pub fn summary(&self) -> String {
        let mut text = Vec::new();
        self.write_summary(&mut text)
            .expect("writing to memory cannot fail");
        String::from_utf8(text).expect("the tables are UTF-8")
    }

    /// Writes the JSON `aacmm evaluate --json` writes: pretty, with a final
    /// newline; the pairs' rows streamed.
    ///
    /// # Errors
    ///
    /// The writer's.
    pub fn write_json(&self, mut w: impl Write) -> io::Result<()> {
        serde_json::to_writer_pretty(&mut w, self).map_err(io::Error::from)?;
        w.write_all(b"\n")
    }

    /// [`EvaluationReport::write_json`] as text.
    pub fn to_json(&self) -> String {
        let mut text = Vec::new();
        self.write_json(&mut text)
            .expect("writing to memory cannot fail");
        String::from_utf8(text).expect("JSON is UTF-8")
    }
}

/// The JSON envelope: what was evaluated, and the figures.
#[derive(Serialize)]
struct Envelope<'r> {
    arm: &'r str,
    arm_file: &'r str,
    data_file: &'r str,
    lengths_file: Option<&'r str>,
    length_unit: &'static str,
    evaluation: &'r Evaluation,
    #[serde(skip_serializing_if = "Option::is_none")]
    pair_length: Option<Pairs<'r>>,
}

/// Eq. 19 rows serialised as they are computed, never collected.
struct Pairs<'r>(&'r EvaluationReport<'r>);

impl Serialize for Pairs<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.pair_rows())
    }
}

impl Serialize for EvaluationReport<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        Envelope {
            arm: &self.arm,
            arm_file: &self.arm_file,
            data_file: &self.data_file,
            lengths_file: self.lengths_file.as_deref(),
            length_unit: "mm",
            evaluation: &self.evaluation,
            pair_length: self.pairs.then_some(Pairs(self)),
        }
        .serialize(s)
    }
}
