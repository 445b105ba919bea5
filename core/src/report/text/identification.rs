//! What `aacmm identify` prints and writes of an [`IdentifyReport`]: its
//! tables and its JSON.

use crate::identify::Identification;
use crate::session::IdentifyReport;
use crate::session::identification::{CorrectionColumn, NOT_STATED};

impl IdentifyReport {
    /// The JSON `aacmm identify --json` writes: pretty, with a final
    /// newline.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self)
            .expect("the report holds only strings, numbers, arrays and maps");
        s.push('\n');
        s
    }

    /// The text `aacmm identify` prints: the inputs and the noise, the
    /// singular values, the rules, the rank, the unidentifiable directions,
    /// the recommended fixed set, the predicted σ, the correlations, and
    /// the prior's rank and conditioning.
    pub fn summary(&self) -> String {
        let positions = match self.positions {
            0 => String::new(),
            n => format!(", {n} reference positions (each frame's registration eliminated)"),
        };
        let positions = match &self.spheres {
            Some(s) => format!(
                "{positions}, {} points on {} spheres of {} (each sphere's centre{} eliminated)",
                s.points,
                s.spheres,
                s.file,
                match s.stated_diameter {
                    Some(d) => format!(", its diameter stated as {d} mm,"),
                    None => " and diameter".to_string(),
                }
            ),
            None => positions,
        };
        let mut s = format!(
            "arm `{}` ({}) on {}: {} touches of {} points, {} reference lengths{positions}\nnoise: \
             {}\n\n",
            self.arm,
            self.arm_file,
            self.data_file,
            self.touches,
            self.points,
            self.reference_lengths,
            self.noise
        );
        s += &table(&self.identification);
        s += &corrections_table(&self.corrections);
        if let Some(p) = &self.prior {
            // Unstated noise weighs every touch as 0.01 mm: say how little
            // the prior then counts.
            let weighed = if self.noise.starts_with(NOT_STATED) {
                "touches weighed as 0.01 mm, so the prior weighs little here: state \
                 --probe-noise/--encoder-noise for its real weight"
            } else {
                "touches weighed from the stated noise"
            };
            s += &format!(
                "\nWith the prior ({}; {} of {} parameters; {weighed}):\n  \
                 rank {} of {} (data alone: {} after the rules)\n  condition number over the \
                 free parameters {:.1} (data alone: {:.1})\n",
                p.tolerances,
                p.parameters_with_tolerance,
                p.parameters,
                p.rank_with,
                p.parameters,
                p.rank_without,
                p.condition_with,
                p.condition_without
            );
        }
        s
    }
}

/// The corrections' table of `aacmm identify`.
fn corrections_table(columns: &[CorrectionColumn]) -> String {
    if columns.is_empty() {
        return String::new();
    }
    let mut s = String::from(
        "
Beyond geometry (judged after the free geometry and the frames; predicted sigma k = 1):\n",
    );
    for c in columns {
        let line = match (&c.held, c.sigma) {
            (Some(why), _) => format!("  {:<16} held: {why}", c.name),
            (None, Some(sigma)) => {
                let rho = (c.most_correlated.as_ref()).map_or(String::new(), |(n, r)| {
                    format!("  most correlated: {n} {r:+.3}")
                });
                format!("  {:<16} sigma {sigma:.4} {}{rho}", c.name, c.unit)
            }
            (None, None) => format!("  {:<16} sigma not finite", c.name),
        };
        s += &line;
        s.push('\n');
    }
    s
}

/// The tables of an identification.
fn table(id: &Identification) -> String {
    let mut s = String::new();
    let sv: Vec<String> = id
        .singular_values
        .iter()
        .map(|v| format!("{v:.3e}"))
        .collect();
    s += &format!("Scaling: {}\n", id.scaling);
    s += &format!(
        "Singular values of the scaled Jacobian (all {} columns):\n",
        sv.len()
    );
    for chunk in sv.chunks(9) {
        s += &format!("  {}\n", chunk.join("  "));
    }
    if !id.recommendations.is_empty() {
        s += "\nModel (nearly parallel axes):\n";
        for r in &id.recommendations {
            s += &format!("  {r}\n");
        }
    }
    s += "\nStructural rules (hold whatever the noise does to the singular values):\n";
    for r in &id.rules {
        s += &format!("  {}: {}\n", r.name, r.explanation);
    }
    s += &format!(
        "\nRank: {} identifiable combinations (threshold {:.2e} = 1e-7 × s_max, after the rules); \
         condition number of the identifiable part {:.1}\n",
        id.rank, id.threshold, id.condition_number
    );
    s += &directions(id);
    s += &fixed_and_free(id);
    if id.correlations.is_empty() {
        s += "\nNo pair of free parameters correlates with |rho| > 0.9.\n";
    } else {
        s += "\nCorrelations |rho| > 0.9:\n";
        for c in &id.correlations {
            s += &format!("  {:<8} {:<8} {:+.4}\n", c.a, c.b, c.rho);
        }
    }
    s
}

/// The unidentifiable and the weak directions.
fn directions(id: &Identification) -> String {
    let mut s = String::new();
    if !id.null_relations.is_empty() {
        s += "\nUnidentifiable directions (one per redundant parameter; s = singular value of the scaled direction):\n";
        for r in &id.null_relations {
            s += &format!("  s = {:.1e}  {}\n", r.singular_value, r.text);
        }
    }
    if !id.weak_relations.is_empty() {
        s += "\nWeak directions (s < 1e-3 s_max):\n";
        for r in &id.weak_relations {
            s += &format!("  s = {:.1e}  {}\n", r.singular_value, r.text);
        }
    }
    s
}

/// The recommended fixed set with its reasons, and the free parameters'
/// predicted σ.
fn fixed_and_free(id: &Identification) -> String {
    let names: Vec<String> = id.fixed.iter().map(|f| f.id.to_string()).collect();
    let mut s = format!(
        "\nRecommended fixed set (--fix auto): {}\n",
        names.join(",")
    );
    let w = names.iter().map(String::len).max().unwrap_or(0);
    for (f, name) in id.fixed.iter().zip(&names) {
        s += &format!("  {name:<w$}  {}\n", f.reason);
    }
    s += "\nFree parameters at the stated noise:\n  parameter  unit   predicted sigma  identifiability\n";
    for f in &id.free {
        s += &format!(
            "  {:<9}  {:<4}  {:>15.3e}  {:>15.4}\n",
            f.id.to_string(),
            f.unit,
            f.sigma,
            f.identifiability
        );
    }
    s
}
