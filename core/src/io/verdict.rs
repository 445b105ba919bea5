//! The `[verdict]` table a calibration writes into its arm file
//! (`calibrated.toml`), so that the file itself says whether it may be used.
//!
//! A script that ignores the calibration's exit code would otherwise carry
//! on with a wrong arm: a refused calibration's arm file looks like a good
//! one. So every reader of arm files ([`super::read_arm`] and the front ends
//! over it: `points`, `evaluate`, the C and Python loaders) refuses a file
//! whose verdict is NOT usable, naming the reasons and the remedy, unless
//! the caller asks for it ([`Rejected::Warn`]: it is then read with a
//! warning). A file without the table (a nominal arm, a hand-written one)
//! is read as before.
//!
//! ```toml
//! [verdict]
//! usable = false
//! reasons = ["the calibrated arm is worse than the nominal on its own data …"]
//! notes = []
//! ```

use serde::{Deserialize, Serialize};
use toml::de::{DeTable, DeValue};

use super::Warning;
use super::text::line_of;
use crate::domain::ArmVerdict;
use crate::error::InputError;

/// How a reader treats an arm file whose `[verdict]` says NOT usable.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Rejected {
    /// Refuse it with an error naming the reasons (the default).
    #[default]
    Refuse,
    /// Read it, with a warning naming the reasons (asked for:
    /// `--accept-rejected`, `accept_rejected=True`,
    /// `aacmm_arm_from_file_accepting_rejected`).
    Warn,
}

/// How each front end asks to read a rejected arm file anyway.
const ASK: &str = "to use it anyway, ask for it (`aacmm points` and `evaluate`: \
                   --accept-rejected; Python: Arm.from_file(path, accept_rejected=True); C: \
                   aacmm_arm_from_file_accepting_rejected); a new calibration starts from the \
                   nominal arm's file";

/// Longest reason quoted in a refusal: the full text is in the file.
const QUOTED_CHARS: usize = 300;

/// The `[verdict]` table of `verdict`, preceded (when NOT usable) by a
/// comment that says so at the top of what a reader sees of it.
pub(crate) fn verdict_to_toml(verdict: &ArmVerdict) -> String {
    #[derive(Serialize)]
    struct File<'a> {
        verdict: &'a ArmVerdict,
    }
    // Invariant: a bool and arrays of strings always serialize.
    let table = toml::to_string(&File { verdict }).expect("a bool and strings serialize to TOML");
    if verdict.usable {
        format!("\n{table}")
    } else {
        format!(
            "\n# NOT USABLE: the calibration that wrote this file was refused (reasons below); \
             aacmm refuses to read it unless asked.\n{table}"
        )
    }
}

/// A comment for the top of a refused calibration's arm file: the first
/// thing anyone opening it reads.
pub(crate) fn rejected_header() -> &'static str {
    "# NOT USABLE: this arm comes from a calibration that was refused — see [verdict] at the \
     end. Do not use it as a calibrated arm.\n"
}

/// The `[verdict]` table of an arm file's TOML, if any, checked: a file
/// whose verdict is NOT usable is an error under [`Rejected::Refuse`] and a
/// warning under [`Rejected::Warn`].
pub(crate) fn check(
    root: &DeTable<'_>,
    text: &str,
    file: &str,
    rejected: Rejected,
) -> Result<Option<Warning>, InputError> {
    let Some((key, value)) = root.get_key_value("verdict") else {
        return Ok(None);
    };
    let line = line_of(text, key.span().start);
    let bad = |message: String| InputError::field(file, line, "verdict", message);
    let DeValue::Table(_) = value.get_ref() else {
        return Err(bad(format!(
            "expected a [verdict] table (usable = true or false), found {}",
            value.get_ref().type_str()
        )));
    };
    let verdict = ArmVerdict::deserialize(toml::de::ValueDeserializer::from(value.clone()))
        .map_err(|e| bad(format!("[verdict]: {}", e.message())))?;
    if verdict.usable {
        return Ok(None);
    }
    let message = refusal(&verdict);
    match rejected {
        Rejected::Refuse => Err(bad(format!(
            "{message}; recalibrate (calibration.json's /verdict says why), or, {ASK}"
        ))),
        Rejected::Warn => Ok(Some(Warning {
            file: file.to_string(),
            line: Some(line),
            field: Some("verdict".to_string()),
            message: format!("{message}; read as asked — do not rely on it"),
        })),
    }
}

/// "written by a calibration that was NOT usable: …", the first reason
/// (bounded) and how many more there are.
fn refusal(verdict: &ArmVerdict) -> String {
    let first = verdict.reasons.first().map_or_else(
        || "no reason recorded".to_string(),
        |r| {
            if r.chars().count() > QUOTED_CHARS {
                let cut: String = r.chars().take(QUOTED_CHARS).collect();
                format!("{cut}… ({} characters in the file)", r.chars().count())
            } else {
                r.clone()
            }
        },
    );
    let more = match verdict.reasons.len() {
        0 | 1 => String::new(),
        n => format!(
            " (and {} more reason{})",
            n - 1,
            if n == 2 { "" } else { "s" }
        ),
    };
    format!("this arm file was written by a calibration that was NOT usable: {first}{more}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root(text: &str) -> toml::Spanned<DeTable<'_>> {
        DeTable::parse(text).unwrap()
    }

    #[test]
    fn a_rejected_file_is_refused_unless_asked_and_a_usable_one_is_read() {
        let v = ArmVerdict {
            usable: false,
            reasons: vec!["worse than the nominal".into(), "χ² far outside".into()],
            notes: vec![],
        };
        let text = format!("name = \"x\"\n{}", verdict_to_toml(&v));
        let doc = root(&text);
        let e = check(doc.get_ref(), &text, "c.toml", Rejected::Refuse).unwrap_err();
        let m = e.to_string();
        assert!(
            m.starts_with("c.toml:4: field `verdict`: this arm file"),
            "{m}"
        );
        assert!(m.contains("NOT usable: worse than the nominal (and 1 more reason)"));
        assert!(m.contains("--accept-rejected"), "{m}");
        let w = check(doc.get_ref(), &text, "c.toml", Rejected::Warn).unwrap();
        assert!(w.unwrap().message.contains("NOT usable"));
        let ok = verdict_to_toml(&ArmVerdict {
            usable: true,
            ..ArmVerdict::default()
        });
        let doc = root(&ok);
        assert!(
            check(doc.get_ref(), &ok, "c.toml", Rejected::Refuse)
                .unwrap()
                .is_none()
        );
    }

    #[test]
    fn a_malformed_verdict_is_an_error_naming_it() {
        for text in [
            "verdict = 3\n",
            "[verdict]\nusable = \"no\"\n",
            "[verdict]\nok = 1\n",
        ] {
            let doc = root(text);
            let e = check(doc.get_ref(), text, "c.toml", Rejected::Warn).unwrap_err();
            assert!(e.to_string().contains("field `verdict`"), "{e}");
        }
    }

    #[test]
    fn a_long_reason_is_cut_and_its_length_said() {
        let v = ArmVerdict {
            usable: false,
            reasons: vec!["x".repeat(10_000)],
            notes: vec![],
        };
        let m = refusal(&v);
        assert!(
            m.len() < 500 && m.contains("(10000 characters in the file)"),
            "{m}"
        );
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn io_verdict_verdict_to_toml() {
        use crate::domain::ArmVerdict;
        use crate::io::verdict::verdict_to_toml;
        let v = ArmVerdict {
            usable: false,
            reasons: vec!["worse than \"nominal\"".into()],
            notes: vec![],
        };
        let t = verdict_to_toml(&v);
        assert!(t.contains("[verdict]\nusable = false\n"));
        assert!(t.starts_with("\n# NOT USABLE") && t.contains(r#"worse than "nominal""#));
    }
}
