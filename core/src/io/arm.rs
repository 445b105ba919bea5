//! Arm files: the nominal (or calibrated) geometry of a D-H chain, in TOML.
//!
//! ```toml
//! name = "paper-table-1"
//! length_unit = "mm"      # "mm" or "m"; required, never guessed
//! angle_unit = "deg"      # "deg" or "rad"; required, never guessed
//!
//! [[joint]]               # one per joint, base to probe (1 to 7 joints)
//! theta = 0.0             # encoder zero offset θ⁰
//! alpha = -90.0           # link twist (the paper's β; `beta` is accepted instead)
//! a = 50.0
//! d = 375.0
//! limits = [-180.0, 180.0]   # optional limits of the encoder reading q
//!
//! [probe]                 # probe centre in the last joint's frame
//! x = 0.0
//! y = 0.0
//! z = 100.0
//! ```
//!
//! `name` is optional (default empty). Lengths (`a`, `d`, probe) are in
//! `length_unit`, angles (`theta`, `alpha`, `limits`) in `angle_unit`.
//! Integers are accepted where numbers are expected. Unknown keys are errors
//! (a typo is never ignored), as are non-finite numbers, a missing key, zero
//! or more than [`MAX_JOINTS`] joints, and limits with `min >= max`.
//! The toolkit's kernels are for 6- and 7-joint arms; 1 to 7 joints parse.

use std::fmt::Write as _;
use std::path::Path;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use super::text::{fmt_f64, line_of, read_text, suggest};
use super::units::{AngleUnit, LengthUnit};
use crate::error::InputError;
use crate::params::{DhJoint, DhParams};

/// The most joints an arm file may have.
pub const MAX_JOINTS: usize = 7;

/// An arm: its name, its geometry (mm, rad) and its optional joint limits.
#[derive(Clone, Debug, PartialEq)]
pub struct Arm {
    /// Free-form name (may be empty).
    pub name: String,
    /// Geometry, mm and rad.
    pub params: DhParams,
    /// Per joint, the optional `[min, max]` of the encoder reading `q`, rad.
    /// Has one entry per joint when read from a file.
    pub limits: Vec<Option<[f64; 2]>>,
}

impl Arm {
    /// An arm without joint limits.
    ///
    /// ```
    /// use aacmm_core::{io::Arm, params::DhParams};
    /// let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
    /// assert_eq!(arm.limits, vec![None; 6]);
    /// ```
    pub fn without_limits(name: impl Into<String>, params: DhParams) -> Arm {
        let n = params.joint_count();
        Arm {
            name: name.into(),
            params,
            limits: vec![None; n],
        }
    }
}

/// Reads an arm file; messages name the file as `path` displays.
///
/// ```no_run
/// let arm = aacmm_core::io::read_arm(std::path::Path::new("arm.toml"))?;
/// println!("{} joints", arm.params.joint_count());
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn read_arm(path: &Path) -> Result<Arm, InputError> {
    let (file, text) = read_text(path)?;
    parse_arm(&text, &file)
}

/// Parses the text of an arm file; `file` is the name used in messages.
///
/// ```
/// let text = r#"
/// length_unit = "m"
/// angle_unit = "deg"
/// [[joint]]
/// theta = 0
/// alpha = 90
/// a = 0.05
/// d = 0.375
/// limits = [-90, 90]
/// [probe]
/// x = 0
/// y = 0
/// z = 0.1
/// "#;
/// let arm = aacmm_core::io::parse_arm(text, "arm.toml").unwrap();
/// assert_eq!(arm.params.joints[0].d, 375.0);
/// assert_eq!(arm.params.joints[0].alpha, std::f64::consts::FRAC_PI_2);
/// assert_eq!(arm.params.probe, [0.0, 0.0, 100.0]);
/// assert_eq!(arm.limits[0].unwrap()[1], std::f64::consts::FRAC_PI_2);
///
/// let err = aacmm_core::io::parse_arm(&text.replace("alpha", "alpah"), "arm.toml");
/// assert!(err.unwrap_err().to_string().starts_with("arm.toml:6: field `alpah`: unknown key"));
/// ```
pub fn parse_arm(text: &str, file: &str) -> Result<Arm, InputError> {
    let doc = DeTable::parse(text).map_err(|e| syntax_error(text, file, &e))?;
    let p = Parser { text, file };
    let root = doc.get_ref();
    p.deny_unknown(
        root,
        &["name", "length_unit", "angle_unit", "joint", "probe"],
        "at the top level",
    )?;

    let name = match root.get_key_value("name") {
        None => String::new(),
        Some((_, v)) => match v.get_ref() {
            DeValue::String(s) => s.to_string(),
            other => {
                return Err(p.err(v, "name", format!("expected a string, found {}", a(other))));
            }
        },
    };
    let length_unit: LengthUnit = p.unit(root, "length_unit", LengthUnit::NAMES)?;
    let angle_unit: AngleUnit = p.unit(root, "angle_unit", AngleUnit::NAMES)?;

    let joint_tables = p.joint_tables(root)?;
    let mut joints = Vec::with_capacity(joint_tables.len());
    let mut limits = Vec::with_capacity(joint_tables.len());
    for (i, &(at, table)) in joint_tables.iter().enumerate() {
        let (joint, lim) = p.joint(i + 1, at, table, length_unit, angle_unit)?;
        joints.push(joint);
        limits.push(lim);
    }

    let probe = p.probe(root, length_unit)?;
    Ok(Arm {
        name,
        params: DhParams { joints, probe },
        limits,
    })
}

/// Writes an arm in the arm-file schema with the given units: deterministic
/// bytes, numbers in the shortest form that reads back to the same value
/// (bit-exact in mm and rad; in deg and m bit-exact whenever some decimal
/// converts back exactly, else within 1 ulp — see
/// [`AngleUnit::from_internal_exact`]). Missing `limits` entries are written
/// as no limits; non-finite values are written as TOML `nan`/`inf`, which the
/// reader rejects.
///
/// ```
/// use aacmm_core::io::{Arm, AngleUnit, LengthUnit, arm_to_toml, parse_arm};
/// use aacmm_core::params::DhParams;
/// let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
/// let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
/// assert!(text.contains("alpha = -90.0\na = 50.0\nd = 375.0\n"));
/// assert_eq!(parse_arm(&text, "out.toml").unwrap(), arm);
/// ```
pub fn arm_to_toml(arm: &Arm, length_unit: LengthUnit, angle_unit: AngleUnit) -> String {
    let len = |x: f64| toml_f64(length_unit.from_internal_exact(x));
    let ang = |x: f64| toml_f64(angle_unit.from_internal_exact(x));
    let mut s = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(s, "name = {}", toml_string(&arm.name));
    let _ = writeln!(s, "length_unit = \"{}\"", length_unit.name());
    let _ = writeln!(s, "angle_unit = \"{}\"", angle_unit.name());
    for (i, j) in arm.params.joints.iter().enumerate() {
        let _ = writeln!(s, "\n[[joint]]");
        let _ = writeln!(s, "theta = {}", ang(j.theta));
        let _ = writeln!(s, "alpha = {}", ang(j.alpha));
        let _ = writeln!(s, "a = {}", len(j.a));
        let _ = writeln!(s, "d = {}", len(j.d));
        if let Some([lo, hi]) = arm.limits.get(i).copied().flatten() {
            let _ = writeln!(s, "limits = [{}, {}]", ang(lo), ang(hi));
        }
    }
    let [x, y, z] = arm.params.probe;
    let _ = writeln!(s, "\n[probe]");
    let _ = writeln!(s, "x = {}", len(x));
    let _ = writeln!(s, "y = {}", len(y));
    let _ = writeln!(s, "z = {}", len(z));
    s
}

/// Writes an arm file (see [`arm_to_toml`]).
///
/// ```no_run
/// use aacmm_core::io::{Arm, AngleUnit, LengthUnit, write_arm};
/// let arm = Arm::without_limits("nominal", aacmm_core::params::DhParams::paper_nominal());
/// write_arm(std::path::Path::new("arm.toml"), &arm, LengthUnit::Mm, AngleUnit::Deg)?;
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn write_arm(
    path: &Path,
    arm: &Arm,
    length_unit: LengthUnit,
    angle_unit: AngleUnit,
) -> Result<(), InputError> {
    std::fs::write(path, arm_to_toml(arm, length_unit, angle_unit))
        .map_err(|e| InputError::io(path.display().to_string(), e))
}

/// A TOML float literal that reads back to exactly `x`.
fn toml_f64(x: f64) -> String {
    if x.is_nan() {
        "nan".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        fmt_f64(x)
    }
}

/// A TOML basic string.
fn toml_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A TOML syntax error, located.
fn syntax_error(text: &str, file: &str, e: &toml::de::Error) -> InputError {
    let message = format!("TOML syntax: {}", e.message());
    match e.span() {
        Some(span) => InputError::line_error(file, line_of(text, span.start), message),
        None => InputError::file_error(file, message),
    }
}

/// "a string", "an integer", ...
fn a(v: &DeValue<'_>) -> String {
    let t = v.type_str();
    let article = if t.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("{article} {t}")
}

type Val<'i> = Spanned<DeValue<'i>>;

/// The joint fields, in file order.
const JOINT_KEYS: [&str; 6] = ["theta", "alpha", "beta", "a", "d", "limits"];
const PROBE_KEYS: [&str; 3] = ["x", "y", "z"];

struct Parser<'t> {
    text: &'t str,
    file: &'t str,
}

impl Parser<'_> {
    fn line<T>(&self, s: &Spanned<T>) -> usize {
        line_of(self.text, s.span().start)
    }

    fn err<T>(&self, at: &Spanned<T>, field: &str, message: impl Into<String>) -> InputError {
        InputError::field(self.file, self.line(at), field, message)
    }

    /// Errors on the first key (in file order) not in `known`.
    fn deny_unknown(
        &self,
        table: &DeTable<'_>,
        known: &[&str],
        place: &str,
    ) -> Result<(), InputError> {
        let unknown = table
            .iter()
            .filter(|(k, _)| !known.contains(&k.get_ref().as_ref()))
            .min_by_key(|(k, _)| k.span().start);
        if let Some((k, _)) = unknown {
            let key: &str = k.get_ref();
            let expected = known
                .iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ");
            let hint = suggest(key, known)
                .map(|s| format!(" (did you mean `{s}`?)"))
                .unwrap_or_default();
            let msg = format!("unknown key {place}{hint}; expected one of {expected}");
            return Err(self.err(k, key, msg));
        }
        Ok(())
    }

    /// A required unit key at the top level.
    fn unit<U>(&self, root: &DeTable<'_>, key: &str, names: &[&str]) -> Result<U, InputError>
    where
        U: std::str::FromStr<Err = super::units::UnknownUnit>,
    {
        let choices = names
            .iter()
            .map(|n| format!("`{key} = \"{n}\"`"))
            .collect::<Vec<_>>()
            .join(" or ");
        let Some((_, v)) = root.get_key_value(key) else {
            return Err(InputError::field(
                self.file,
                0,
                key,
                format!("missing; add {choices} (units are never guessed)"),
            ));
        };
        match v.get_ref() {
            DeValue::String(s) => s.parse::<U>().map_err(|e| self.err(v, key, e.to_string())),
            other => Err(self.err(
                v,
                key,
                format!("expected a string ({choices}), found {}", a(other)),
            )),
        }
    }

    /// The `[[joint]]` tables, checked for count.
    fn joint_tables<'d, 'i>(
        &self,
        root: &'d DeTable<'i>,
    ) -> Result<Vec<(&'d Val<'i>, &'d DeTable<'i>)>, InputError> {
        let Some((key, v)) = root.get_key_value("joint") else {
            return Err(InputError::field(
                self.file,
                0,
                "joint",
                "no joints: add one [[joint]] table per joint, base to probe",
            ));
        };
        let DeValue::Array(items) = v.get_ref() else {
            return Err(self.err(
                key,
                "joint",
                format!(
                    "expected [[joint]] tables (an array of tables, one per joint), found {}",
                    a(v.get_ref())
                ),
            ));
        };
        if items.is_empty() {
            return Err(self.err(
                key,
                "joint",
                "no joints: add one [[joint]] table per joint, base to probe",
            ));
        }
        let mut tables = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            let DeValue::Table(table) = item.get_ref() else {
                return Err(self.err(
                    item,
                    "joint",
                    format!(
                        "joint {}: expected a table, found {}",
                        i + 1,
                        a(item.get_ref())
                    ),
                ));
            };
            if i == MAX_JOINTS {
                return Err(self.err(
                    item,
                    "joint",
                    format!(
                        "{} joints; at most {MAX_JOINTS} are supported (the kernels are for \
                         6- and 7-joint arms)",
                        items.len()
                    ),
                ));
            }
            tables.push((item, table));
        }
        Ok(tables)
    }

    /// A finite number (float or integer).
    fn number(&self, v: &Val<'_>, field: &str, ctx: &str) -> Result<f64, InputError> {
        let x = match v.get_ref() {
            DeValue::Float(f) => f.as_str().parse::<f64>().ok(),
            DeValue::Integer(i) => match i64::from_str_radix(i.as_str(), i.radix()) {
                Ok(i) => Some(i as f64),
                Err(_) => {
                    return Err(self.err(
                        v,
                        field,
                        format!("{ctx}integer `{i}` out of range; write it as a float"),
                    ));
                }
            },
            other => {
                return Err(self.err(
                    v,
                    field,
                    format!("{ctx}expected a number, found {}", a(other)),
                ));
            }
        };
        match x {
            Some(x) if x.is_finite() => Ok(x),
            _ => {
                let raw = self.text.get(v.span()).unwrap_or("?");
                Err(self.err(v, field, format!("{ctx}`{raw}` is not a finite number")))
            }
        }
    }

    /// A required number in a table.
    fn required(
        &self,
        table: &DeTable<'_>,
        at: &Val<'_>,
        key: &str,
        ctx: &str,
        needs: &str,
    ) -> Result<f64, InputError> {
        match table.get_key_value(key) {
            Some((_, v)) => self.number(v, key, ctx),
            None => Err(self.err(at, key, format!("{ctx}missing; {needs}"))),
        }
    }

    /// One `[[joint]]` table (`n` 1-based).
    fn joint(
        &self,
        n: usize,
        at: &Val<'_>,
        t: &DeTable<'_>,
        lu: LengthUnit,
        au: AngleUnit,
    ) -> Result<(DhJoint, Option<[f64; 2]>), InputError> {
        let ctx = format!("joint {n}: ");
        self.deny_unknown(t, &JOINT_KEYS, &format!("in joint {n}"))?;
        let needs = "every [[joint]] needs `theta`, `alpha` (or `beta`), `a` and `d`";
        let alpha_key = match (t.get_key_value("alpha"), t.get_key_value("beta")) {
            (Some(_), Some((kb, _))) => {
                return Err(self.err(
                    kb,
                    "beta",
                    format!(
                        "{ctx}both `alpha` and `beta` given; they name the same parameter \
                         (the link twist), keep one"
                    ),
                ));
            }
            (None, Some(_)) => "beta",
            _ => "alpha",
        };
        let theta = au.to_internal(self.required(t, at, "theta", &ctx, needs)?);
        let alpha = au.to_internal(self.required(t, at, alpha_key, &ctx, needs)?);
        let a = lu.to_internal(self.required(t, at, "a", &ctx, needs)?);
        let d = lu.to_internal(self.required(t, at, "d", &ctx, needs)?);
        let limits = match t.get_key_value("limits") {
            None => None,
            Some((_, v)) => Some(self.limits(v, &ctx, au)?),
        };
        Ok((DhJoint { a, d, alpha, theta }, limits))
    }

    /// `limits = [min, max]`, converted to rad.
    fn limits(&self, v: &Val<'_>, ctx: &str, au: AngleUnit) -> Result<[f64; 2], InputError> {
        let shape = format!("expected `[min, max]` in {au}");
        let DeValue::Array(items) = v.get_ref() else {
            return Err(self.err(
                v,
                "limits",
                format!("{ctx}{shape}, found {}", a(v.get_ref())),
            ));
        };
        if items.len() != 2 {
            return Err(self.err(
                v,
                "limits",
                format!("{ctx}{shape}, found {} values", items.len()),
            ));
        }
        let lo = self.number(&items[0], "limits", ctx)?;
        let hi = self.number(&items[1], "limits", ctx)?;
        if lo >= hi {
            return Err(self.err(
                v,
                "limits",
                format!("{ctx}min {lo} must be less than max {hi}"),
            ));
        }
        Ok([au.to_internal(lo), au.to_internal(hi)])
    }

    /// The `[probe]` table, mm.
    fn probe(&self, root: &DeTable<'_>, lu: LengthUnit) -> Result<[f64; 3], InputError> {
        let Some((key, v)) = root.get_key_value("probe") else {
            return Err(InputError::field(
                self.file,
                0,
                "probe",
                "missing [probe] table: the probe centre `x`, `y`, `z` in the last \
                 joint's frame, in length_unit",
            ));
        };
        let DeValue::Table(t) = v.get_ref() else {
            return Err(self.err(
                key,
                "probe",
                format!(
                    "expected a table ([probe] with x, y, z), found {}",
                    a(v.get_ref())
                ),
            ));
        };
        self.deny_unknown(t, &PROBE_KEYS, "in [probe]")?;
        let mut out = [0.0; 3];
        for (o, key) in out.iter_mut().zip(PROBE_KEYS) {
            *o = lu.to_internal(self.required(
                t,
                v,
                key,
                "[probe]: ",
                "[probe] needs `x`, `y` and `z`",
            )?);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    const F: &str = "my-arm.toml";

    const GOOD: &str = r#"name = "paper-table-1"
length_unit = "mm"
angle_unit = "deg"

[[joint]]
theta = 0.0
alpha = -90.0
a = 50.0
d = 375.0
limits = [-180.0, 180.0]

[[joint]]
theta = 0.5
beta = 90
a = -55.0
d = 0.0

[probe]
x = 0.0
y = 0.0
z = 100.0
"#;

    fn err(text: &str) -> InputError {
        parse_arm(text, F).unwrap_err()
    }

    /// `GOOD` with `from` replaced by `to` (which must occur).
    fn edit(from: &str, to: &str) -> String {
        assert!(GOOD.contains(from), "{from}");
        GOOD.replacen(from, to, 1)
    }

    #[track_caller]
    fn assert_at(e: &InputError, line: usize, field: Option<&str>, needle: &str) {
        crate::io::testing::assert_at(e, F, line, field, needle);
    }

    #[test]
    fn parses_good_file() {
        let arm = parse_arm(GOOD, F).unwrap();
        assert_eq!(arm.name, "paper-table-1");
        let j = &arm.params.joints;
        assert_eq!(j.len(), 2);
        assert_eq!(j[0].alpha, -std::f64::consts::FRAC_PI_2);
        assert_eq!((j[0].a, j[0].d, j[0].theta), (50.0, 375.0, 0.0));
        assert_eq!(j[1].alpha, std::f64::consts::FRAC_PI_2); // from `beta`, an integer
        assert_eq!(j[1].theta, 0.5f64.to_radians());
        assert_eq!(arm.params.probe, [0.0, 0.0, 100.0]);
        let pi = std::f64::consts::PI;
        assert_eq!(arm.limits, vec![Some([-pi, pi]), None]);
    }

    #[test]
    fn units_convert() {
        let text = edit("length_unit = \"mm\"", "length_unit = \"m\"")
            .replace("angle_unit = \"deg\"", "angle_unit = \"rad\"");
        let arm = parse_arm(&text, F).unwrap();
        assert_eq!(arm.params.joints[0].d, 375_000.0);
        assert_eq!(arm.params.joints[0].alpha, -90.0);
        assert_eq!(arm.params.probe[2], 100_000.0);
        assert_eq!(arm.limits[0], Some([-180.0, 180.0]));
    }

    #[test]
    fn name_is_optional() {
        let arm = parse_arm(&edit("name = \"paper-table-1\"\n", ""), F).unwrap();
        assert_eq!(arm.name, "");
        assert_at(
            &err(&edit("\"paper-table-1\"", "7")),
            1,
            Some("name"),
            "expected a string, found an integer",
        );
    }

    #[test]
    fn syntax_errors_are_located() {
        assert_at(
            &err(&edit("d = 375.0", "d = 375.0.0")),
            9,
            None,
            "TOML syntax",
        );
        assert_at(
            &err(&edit("a = -55.0", "a = -55.0\na = 1")),
            16,
            None,
            "TOML syntax: duplicate key",
        );
        assert_at(
            &err(&edit("limits = [-180.0, 180.0]", "limits = [-180.0,")),
            13, // where the parser notices: arrays may span lines
            None,
            "TOML syntax",
        );
        assert_at(&err("x = \"unterminated\n"), 1, None, "TOML syntax");
    }

    #[test]
    fn units_are_required_and_checked() {
        assert_at(
            &err(&edit("length_unit = \"mm\"\n", "")),
            0,
            Some("length_unit"),
            "missing; add `length_unit = \"mm\"` or `length_unit = \"m\"` (units are never guessed)",
        );
        assert_at(
            &err(&edit("angle_unit = \"deg\"\n", "")),
            0,
            Some("angle_unit"),
            "units are never guessed",
        );
        assert_at(
            &err(&edit("\"mm\"", "\"inch\"")),
            2,
            Some("length_unit"),
            "unknown length unit `inch`; accepted: `mm`, `m`",
        );
        assert_at(
            &err(&edit("\"deg\"", "\"degrees\"")),
            3,
            Some("angle_unit"),
            "unknown angle unit `degrees`; accepted: `deg`, `rad`",
        );
        assert_at(
            &err(&edit("\"deg\"", "1")),
            3,
            Some("angle_unit"),
            "expected a string",
        );
    }

    #[test]
    fn unknown_keys_are_errors() {
        assert_at(
            &err(&edit("alpha", "alpah")),
            7,
            Some("alpah"),
            "unknown key in joint 1 (did you mean `alpha`?)",
        );
        assert_at(
            &err(&edit("theta = 0.5", "theta = 0.5\nbeta_err = 1")),
            14,
            Some("beta_err"),
            "unknown key in joint 2",
        );
        assert_at(
            &err(&edit("z = 100.0", "z = 100.0\nw = 1")),
            22,
            Some("w"),
            "unknown key in [probe]",
        );
        assert_at(
            &err(&format!("units = 1\n{GOOD}")),
            1,
            Some("units"),
            "unknown key at the top level",
        );
        assert_at(
            &err(&format!("{GOOD}[extra]\n")),
            22,
            Some("extra"),
            "unknown key at the top level",
        );
        // The first unknown key in file order is reported.
        assert_at(
            &err(&edit("a = 50.0", "zz = 1\na = 50.0\nbb = 2")),
            8,
            Some("zz"),
            "unknown key",
        );
    }

    #[test]
    fn missing_joint_fields() {
        assert_at(
            &err(&edit("d = 375.0\n", "")),
            5,
            Some("d"),
            "joint 1: missing; every [[joint]] needs",
        );
        assert_at(
            &err(&edit("theta = 0.5\n", "")),
            12,
            Some("theta"),
            "joint 2: missing",
        );
        assert_at(
            &err(&edit("beta = 90\n", "")),
            12,
            Some("alpha"),
            "joint 2: missing",
        );
        assert_at(
            &err(&edit("a = -55.0\n", "")),
            12,
            Some("a"),
            "joint 2: missing",
        );
    }

    #[test]
    fn alpha_and_beta_both() {
        assert_at(
            &err(&edit("alpha = -90.0", "alpha = -90.0\nbeta = -90.0")),
            8,
            Some("beta"),
            "both `alpha` and `beta`",
        );
    }

    #[test]
    fn bad_values() {
        assert_at(
            &err(&edit("a = 50.0", "a = nan")),
            8,
            Some("a"),
            "joint 1: `nan` is not a finite number",
        );
        assert_at(
            &err(&edit("d = 375.0", "d = -inf")),
            9,
            Some("d"),
            "`-inf` is not a finite number",
        );
        assert_at(
            &err(&edit("d = 375.0", "d = 1e400")),
            9,
            Some("d"),
            "`1e400` is not a finite number",
        );
        assert_at(
            &err(&edit("a = 50.0", "a = \"50\"")),
            8,
            Some("a"),
            "expected a number, found a string",
        );
        assert_at(
            &err(&edit("z = 100.0", "z = true")),
            21,
            Some("z"),
            "[probe]: expected a number, found a boolean",
        );
        assert_at(
            &err(&edit("z = 100.0", "z = 99999999999999999999")),
            21,
            Some("z"),
            "[probe]: integer `99999999999999999999` out of range; write it as a float",
        );
        // Integers in other radixes are numbers.
        let arm = parse_arm(&edit("d = 375.0", "d = 0x10"), F).unwrap();
        assert_eq!(arm.params.joints[0].d, 16.0);
    }

    #[test]
    fn limits() {
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[180.0, -180.0]")),
            10,
            Some("limits"),
            "min 180 must be less than max -180",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[10, 10]")),
            10,
            Some("limits"),
            "must be less than",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[-180.0]")),
            10,
            Some("limits"),
            "expected `[min, max]` in deg, found 1 values",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "180.0")),
            10,
            Some("limits"),
            "found a float",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[-180.0, inf]")),
            10,
            Some("limits"),
            "not a finite number",
        );
        assert_at(
            &err(&edit("[-180.0, 180.0]", "[-180.0, \"x\"]")),
            10,
            Some("limits"),
            "expected a number",
        );
    }

    #[test]
    fn joint_count() {
        let no_joints =
            "length_unit = \"mm\"\nangle_unit = \"deg\"\n[probe]\nx = 0\ny = 0\nz = 0\n";
        assert_at(&err(no_joints), 0, Some("joint"), "no joints");
        assert_at(
            &err(&format!("joint = []\n{no_joints}")),
            1,
            Some("joint"),
            "no joints",
        );
        assert_at(
            &err(&format!("{no_joints}[joint]\na = 1\n")),
            7,
            Some("joint"),
            "expected [[joint]] tables",
        );
        assert_at(
            &err(&format!("joint = [1]\n{no_joints}")),
            1,
            Some("joint"),
            "joint 1: expected a table, found an integer",
        );
        let joint = "[[joint]]\ntheta = 0\nalpha = 0\na = 0\nd = 1\n";
        let seven = format!("{no_joints}{}", joint.repeat(7));
        assert_eq!(parse_arm(&seven, F).unwrap().params.joint_count(), 7);
        let eight = format!("{seven}{joint}");
        // The eighth [[joint]] header is on line 6 + 7 * 5 + 1.
        assert_at(
            &err(&eight),
            42,
            Some("joint"),
            "8 joints; at most 7 are supported",
        );
    }

    #[test]
    fn probe_required() {
        let text = GOOD[..GOOD.find("[probe]").unwrap()].to_string();
        assert_at(&err(&text), 0, Some("probe"), "missing [probe] table");
        assert_at(
            &err(&edit("y = 0.0\n", "")),
            18,
            Some("y"),
            "[probe]: missing",
        );
        assert_at(
            &err(&format!("probe = 3\n{text}")),
            1,
            Some("probe"),
            "expected a table",
        );
        // Other TOML spellings of the same table are fine.
        let arm = parse_arm(&format!("probe = {{ x = 1, y = 2, z = 3 }}\n{text}"), F).unwrap();
        assert_eq!(arm.params.probe, [1.0, 2.0, 3.0]);
    }

    #[test]
    fn write_is_deterministic_and_round_trips_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for n in 1..=MAX_JOINTS {
            let joints = (0..n)
                .map(|_| DhJoint {
                    a: rng.random_range(-100.0..100.0),
                    d: rng.random_range(-400.0..400.0),
                    alpha: rng.random_range(-3.2..3.2),
                    theta: rng.random_range(-0.1..0.1),
                })
                .collect();
            let limits = (0..n)
                .map(|i| {
                    (i % 2 == 0).then(|| [rng.random_range(-3.0..-1.0), rng.random_range(1.0..3.0)])
                })
                .collect();
            let arm = Arm {
                name: "quote \" backslash \\ tab\t nl\n ctl\u{1} é".to_string(),
                params: DhParams {
                    joints,
                    probe: [rng.random(), rng.random(), 1e-12],
                },
                limits,
            };
            let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Rad);
            let back = parse_arm(&text, F).unwrap();
            assert_eq!(back.name, arm.name);
            assert_eq!(back.limits, arm.limits);
            let bits = |a: &Arm| {
                a.params
                    .to_vec()
                    .iter()
                    .map(|x| x.to_bits())
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&back), bits(&arm));
            assert_eq!(arm_to_toml(&back, LengthUnit::Mm, AngleUnit::Rad), text);
            // Through deg and m: within 1 ulp.
            let back = parse_arm(&arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg), F).unwrap();
            for (x, y) in back.params.to_vec().iter().zip(arm.params.to_vec()) {
                assert!((x - y).abs() <= y.abs() * f64::EPSILON, "{x} {y}");
            }
        }
    }

    #[test]
    fn user_file_round_trips_in_its_units() {
        let arm = parse_arm(GOOD, F).unwrap();
        let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
        // The user's numbers come back as written (integers as floats, `beta` as `alpha`).
        let expected = GOOD.replace("beta = 90", "alpha = 90.0");
        assert_eq!(text, expected);
        assert_eq!(parse_arm(&text, F).unwrap(), arm);
    }

    #[test]
    fn nominal_in_metres() {
        let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
        let text = arm_to_toml(&arm, LengthUnit::M, AngleUnit::Deg);
        assert!(text.contains("a = 0.05\nd = 0.375\n"), "{text}");
        assert!(text.contains("z = 0.1\n"), "{text}");
        assert_eq!(parse_arm(&text, F).unwrap(), arm);
    }

    #[test]
    fn non_finite_written_as_toml_and_rejected() {
        let mut arm = Arm::without_limits("x", DhParams::paper_nominal());
        arm.params.joints[2].a = f64::NAN;
        arm.params.probe[0] = f64::NEG_INFINITY;
        let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
        assert!(
            text.contains("a = nan\n") && text.contains("x = -inf\n"),
            "{text}"
        );
        let e = parse_arm(&text, F).unwrap_err();
        assert_eq!(e.field_name(), Some("a"));
        assert!(
            e.to_string()
                .contains("joint 3: `nan` is not a finite number"),
            "{e}"
        );
    }

    #[test]
    fn files_on_disk() {
        let dir = std::env::temp_dir().join(format!("aacmm-io-arm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("arm.toml");
        let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
        write_arm(&path, &arm, LengthUnit::Mm, AngleUnit::Deg).unwrap();
        assert_eq!(read_arm(&path).unwrap(), arm);
        std::fs::write(
            &path,
            "length_unit = \"mm\"\nangle_unit = \"deg\"\n[[joint]]\nalpah = 1\n",
        )
        .unwrap();
        let e = read_arm(&path).unwrap_err();
        assert!(
            e.to_string()
                .starts_with(&format!("{}:4: field `alpah`", path.display())),
            "{e}"
        );
        let e = read_arm(&dir.join("nope.toml")).unwrap_err();
        assert!(matches!(e, InputError::Io { .. }), "{e}");
        let e = write_arm(
            &dir.join("no/such/dir.toml"),
            &arm,
            LengthUnit::Mm,
            AngleUnit::Deg,
        )
        .unwrap_err();
        assert!(e.to_string().contains("no/such/dir.toml"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
