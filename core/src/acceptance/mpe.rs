//! The maximum permissible errors a user states: `--mpe SPEC`.
//!
//! ```text
//! P_Size=0.008,P_Form=0.012,L_Dia=0.030,E_Uni=0.016+L/60000,SPAT=0.020
//! E_Uni=min(0.016+L/60000,0.040)
//! ```
//!
//! Comma-separated `NAME=MPE`, mm, each test at most once, any subset:
//! `P_Size`, `P_Form`, `L_Dia`, `SPAT` take a number; `E_Uni` a number `A`,
//! `A+L/K` (ISO 10360-12's form: `L` the test length in mm, `K` a
//! dimensionless number) or `min(A+L/K,C)` (the same capped at `C`, as
//! makers state it: `E_Uni,MPE = min(A + L/K, B)`). Spaces are ignored; a
//! comma inside `min(…)` does not separate tests. A test not named has no
//! MPE: its figure is printed and not decided.

use serde::{Deserialize, Serialize};

use crate::error::OptionError;
use crate::setting::Setting;

/// The tests an MPE can be stated for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum TestKind {
    /// Probing size error on a sphere, 25 points.
    #[serde(rename = "P_Size")]
    PSize,
    /// Probing form error on a sphere, 25 points.
    #[serde(rename = "P_Form")]
    PForm,
    /// Articulated location test, 5 × 5 points.
    #[serde(rename = "L_Dia")]
    LDia,
    /// Length error between two sphere centres.
    #[serde(rename = "E_Uni")]
    EUni,
    /// ASME B89.4.22's single-point articulation test.
    #[serde(rename = "SPAT")]
    Spat,
}

impl TestKind {
    /// Every test, in the order reports list them.
    pub const ALL: [TestKind; 5] = [
        TestKind::PSize,
        TestKind::PForm,
        TestKind::LDia,
        TestKind::EUni,
        TestKind::Spat,
    ];

    /// The name an MPE spec uses.
    pub fn key(self) -> &'static str {
        match self {
            TestKind::PSize => "P_Size",
            TestKind::PForm => "P_Form",
            TestKind::LDia => "L_Dia",
            TestKind::EUni => "E_Uni",
            TestKind::Spat => "SPAT",
        }
    }
}

/// One test's MPE: `a + L/k`, capped at `cap` (a constant: `k` infinite).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Limit {
    /// The constant part, mm.
    pub a: f64,
    /// `K` of `L/K` (none: no length part).
    pub k: Option<f64>,
    /// The cap, mm.
    pub cap: Option<f64>,
}

impl Limit {
    /// The MPE at a test length `l` (mm; ignored by a constant).
    pub fn at(&self, l: f64) -> f64 {
        let v = self.a + self.k.map_or(0.0, |k| l / k);
        self.cap.map_or(v, |c| v.min(c))
    }
}

/// The MPEs stated, per test.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mpe {
    /// `(test, limit)`, in the spec's order.
    pub limits: Vec<(TestKind, Limit)>,
}

impl Mpe {
    /// The MPE of `test`, if stated.
    pub fn of(&self, test: TestKind) -> Option<&Limit> {
        self.limits.iter().find(|(t, _)| *t == test).map(|(_, l)| l)
    }

    /// Whether no MPE is stated.
    pub fn is_empty(&self) -> bool {
        self.limits.is_empty()
    }
}

/// Parses an MPE spec: see the module's documentation.
///
/// ```
/// use aacmm_core::acceptance::{TestKind, parse_mpe};
/// let m = parse_mpe("P_Size=0.008, E_Uni=min(0.016+L/60000,0.040)").unwrap();
/// assert_eq!(m.of(TestKind::PSize).unwrap().at(0.0), 0.008);
/// assert!((m.of(TestKind::EUni).unwrap().at(600.0) - 0.026).abs() < 1e-15);
/// assert_eq!(m.of(TestKind::EUni).unwrap().at(6000.0), 0.040);
/// let e = parse_mpe("P_Size=0.008,L_Dia=0.0x3").unwrap_err();
/// assert!(e.to_string().contains("`0.0x3`"), "{e}");
/// ```
///
/// # Errors
///
/// An [`OptionError`] on `mpe` naming the token that does not parse: an
/// unknown test, a test twice, a value that is not a positive number of
/// mm, a length part on a test other than `E_Uni`, an empty spec.
pub fn parse_mpe(spec: &str) -> Result<Mpe, OptionError> {
    let text: String = spec.chars().filter(|c| !c.is_whitespace()).collect();
    if text.is_empty() {
        return Err(bad(
            spec,
            "an empty spec: give NAME=MPE, e.g. `P_Size=0.008`",
        ));
    }
    let mut mpe = Mpe::default();
    for item in split_top(&text) {
        let Some((name, value)) = item.split_once('=') else {
            return Err(bad(item, "not NAME=MPE (e.g. `P_Form=0.012`)"));
        };
        let Some(&test) = TestKind::ALL.iter().find(|t| t.key() == name) else {
            let names: Vec<&str> = TestKind::ALL.iter().map(|t| t.key()).collect();
            return Err(bad(
                name,
                format!("no such test; the tests are {}", names.join(", ")),
            ));
        };
        if mpe.of(test).is_some() {
            return Err(bad(item, format!("{name} is stated twice")));
        }
        let limit = parse_limit(value)?;
        if test != TestKind::EUni && (limit.k.is_some() || limit.cap.is_some()) {
            return Err(bad(
                value,
                format!("{name} takes a number of mm; only E_Uni has a length part (A+L/K)"),
            ));
        }
        mpe.limits.push((test, limit));
    }
    Ok(mpe)
}

/// The spec's items: split at commas outside parentheses.
fn split_top(text: &str) -> Vec<&str> {
    let (mut out, mut depth, mut from) = (Vec::new(), 0i32, 0);
    for (i, c) in text.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&text[from..i]);
                from = i + 1;
            }
            _ => {}
        }
    }
    out.push(&text[from..]);
    out
}

/// `A`, `A+L/K` or `min(A+L/K,C)`.
fn parse_limit(value: &str) -> Result<Limit, OptionError> {
    if let Some(inner) = value.strip_prefix("min(") {
        let Some(inner) = inner.strip_suffix(')') else {
            return Err(bad(value, "`min(` without its `)`: min(A+L/K,C)"));
        };
        let Some((expr, cap)) = inner.rsplit_once(',') else {
            return Err(bad(value, "min takes two values: min(A+L/K,C)"));
        };
        let mut limit = parse_linear(expr)?;
        limit.cap = Some(number(cap)?);
        return Ok(limit);
    }
    parse_linear(value)
}

/// `A` or `A+L/K`.
fn parse_linear(expr: &str) -> Result<Limit, OptionError> {
    match expr.split_once('+') {
        Some((a, tail)) => {
            let Some(k) = tail.strip_prefix("L/") else {
                return Err(bad(tail, "the length part is `L/K` (e.g. 0.016+L/60000)"));
            };
            Ok(Limit {
                a: number(a)?,
                k: Some(number(k)?),
                cap: None,
            })
        }
        None => Ok(Limit {
            a: number(expr)?,
            k: None,
            cap: None,
        }),
    }
}

/// A positive, finite number.
fn number(token: &str) -> Result<f64, OptionError> {
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(bad(
            token,
            "not a positive number (mm; K of L/K dimensionless)",
        )),
    }
}

fn bad(token: &str, why: impl Into<String>) -> OptionError {
    OptionError::new(Setting::Mpe, format!("`{token}`"), why)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_and_their_bad_tokens() {
        let m = parse_mpe("P_Size=0.008,P_Form=0.012,L_Dia=0.030,E_Uni=0.016+L/60000").unwrap();
        assert_eq!(m.limits.len(), 4);
        assert!((m.of(TestKind::EUni).unwrap().at(1200.0) - 0.036).abs() < 1e-15);
        assert_eq!(m.of(TestKind::Spat), None);
        assert_eq!(
            parse_mpe("SPAT=0.02")
                .unwrap()
                .of(TestKind::Spat)
                .unwrap()
                .a,
            0.02
        );
        for (spec, token) in [
            ("P_Sise=0.008", "`P_Sise`"),
            ("P_Size=0.008,P_Size=0.009", "stated twice"),
            ("P_Size=-1", "`-1`"),
            ("P_Size", "`P_Size`"),
            ("E_Uni=0.016+M/6", "`M/6`"),
            ("E_Uni=0.016+L/x", "`x`"),
            ("E_Uni=min(0.016+L/60000", "`min(`"),
            ("E_Uni=min(0.016+L/60000)", "two values"),
            ("L_Dia=0.01+L/1000", "only E_Uni"),
            ("", "empty"),
            ("P_Size=0.008,", "``"),
        ] {
            let e = parse_mpe(spec).unwrap_err();
            assert_eq!(e.field(), "mpe");
            assert!(e.to_string().contains(token), "{spec}: {e}");
        }
    }
}
