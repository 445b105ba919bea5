//! What `aacmm evaluate` prints and writes of an [`EvaluationReport`]: its
//! tables and its JSON, the eq. 19 rows of every pair of points streamed
//! into both, never collected.

use std::io::{self, Write};

use serde::{Serialize, Serializer};

use crate::metrics::{Evaluation, write_pair_table};
use crate::session::EvaluationReport;

impl EvaluationReport<'_> {
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
