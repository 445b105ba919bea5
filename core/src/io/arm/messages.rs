//! serde's messages about an arm file reworded: each names the key, its
//! line, and the joint or table it is in, with the choices where a value
//! has a few.

use std::ops::Range;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use crate::error::{InputError, quoted, shown};
use crate::io::text::{line_of, suggest};
use crate::io::units::{AngleUnit, LengthUnit};
use crate::params::MAX_JOINTS;

/// Why an arm with `n` joints cannot be used (`n` not supported).
pub(super) fn unsupported(n: usize) -> String {
    if n == 0 {
        return "no joints: add one [[joint]] table per joint, base to probe".into();
    }
    format!(
        "{n} joints; at most {MAX_JOINTS} are supported (the toolkit computes {})",
        crate::params::supported_joints_text()
    )
}

/// The tables of an arm file.
#[derive(Clone, Copy)]
enum Place {
    Top,
    Joint(usize),
    Probe,
}

/// Where `offset` is in the arm file: the table that holds it, and the key
/// there whose key or value spans it.
fn locate<'a>(root: &'a DeTable<'a>, offset: usize) -> (Place, &'a DeTable<'a>, Option<String>) {
    let covers = |s: Range<usize>| s.contains(&offset) || s.start == offset;
    let key_at = |t: &DeTable<'_>| {
        t.iter()
            .find(|(k, v)| covers(k.span()) || covers(v.span()))
            .map(|(k, _)| k.get_ref().to_string())
    };
    if let Some(DeValue::Array(items)) = root.get("joint").map(Spanned::get_ref) {
        for (i, item) in items.iter().enumerate() {
            match item.get_ref() {
                DeValue::Table(t) if covers(item.span()) || key_at(t).is_some() => {
                    return (Place::Joint(i + 1), t, key_at(t));
                }
                _ if covers(item.span()) => {
                    return (Place::Joint(i + 1), root, Some("joint".into()));
                }
                _ => {}
            }
        }
    }
    if let Some((_, v)) = root.get_key_value("probe")
        && let DeValue::Table(t) = v.get_ref()
        && (covers(v.span()) || key_at(t).is_some())
    {
        return (Place::Probe, t, key_at(t));
    }
    (Place::Top, root, key_at(root))
}

/// A serde error in the arm file's terms: the key, its line, the joint or
/// table it is in, and what is expected.
pub(super) fn schema_error(
    text: &str,
    file: &str,
    root: &DeTable<'_>,
    e: &toml::de::Error,
) -> InputError {
    let message = e.message();
    let span = e.span().unwrap_or(0..0);
    let line = line_of(text, span.start);
    let (place, table, key) = locate(root, span.start);
    let ctx = match place {
        Place::Top => String::new(),
        Place::Joint(i) => format!("joint {i}: "),
        Place::Probe => "[probe]: ".to_string(),
    };
    // serde puts names in backticks: "unknown field `alpah`, expected one of `theta`, …".
    let names: Vec<&str> = message.split('`').skip(1).step_by(2).collect();
    let name = names.first().copied().unwrap_or("?");
    if message.starts_with("unknown field") {
        let known = names.get(1..).unwrap_or_default();
        // serde reports the first unknown key in key order; report the first in the file.
        let first = (table.iter())
            .filter(|(k, _)| !known.contains(&&**k.get_ref()))
            .min_by_key(|(k, _)| k.span().start);
        let (key, line) = first.map_or((name.to_string(), line), |(k, _)| {
            (k.get_ref().to_string(), line_of(text, k.span().start))
        });
        let place = match place {
            Place::Top => "at the top level".to_string(),
            Place::Joint(i) => format!("in joint {i}"),
            Place::Probe => "in [probe]".to_string(),
        };
        let hint = suggest(&key, known).map(|s| format!(" (did you mean `{s}`?)"));
        let expected: Vec<String> = known.iter().map(|k| format!("`{k}`")).collect();
        let message = format!(
            "unknown key {place}{}; expected one of {}",
            hint.unwrap_or_default(),
            expected.join(", ")
        );
        return InputError::field(file, line, key, message);
    }
    if message.starts_with("missing field") {
        let whole_file = ["length_unit", "angle_unit", "joint", "probe"].contains(&name);
        let line = if whole_file { 0 } else { line };
        return InputError::field(file, line, name, missing(name, &ctx));
    }
    if message.starts_with("duplicate field `alpha`") {
        let beta = table.get_key_value("beta");
        let line = beta.map_or(line, |(k, _)| line_of(text, k.span().start));
        let message = format!(
            "{ctx}both `alpha` and `beta` given; they name the same parameter (the link \
             twist), keep one"
        );
        return InputError::field(file, line, "beta", message);
    }
    let Some(key) = key else {
        return InputError::line_error(file, line, format!("{ctx}{message}"));
    };
    let raw = text.get(span.clone()).unwrap_or("?");
    let problem = if message == "floating-point number overflowed" {
        format!("{} is not a finite number", quoted(raw))
    } else if message.starts_with("invalid type: integer") && message.contains(" as ") {
        format!("integer {} out of range; write it as a float", quoted(raw))
    } else if let Some((found, expected)) =
        (message.strip_prefix("invalid type: ")).and_then(|m| m.rsplit_once(", expected "))
    {
        // Where the error is about the whole value, its TOML type (serde
        // calls a datetime a map).
        let value = table.get(key.as_str()).filter(|v| v.span() == span);
        let found = value.map_or(found, |v| v.get_ref().type_str());
        // Limits are in the file's angle unit, if it names one.
        let angle_unit = match root.get("angle_unit").map(Spanned::get_ref) {
            Some(DeValue::String(unit)) => format!(" in {}", shown(unit)),
            _ => String::new(),
        };
        invalid_type(&key, found, expected, &angle_unit)
    } else {
        message.to_string()
    };
    InputError::field(file, line, key, format!("{ctx}{problem}"))
}

/// What to say about the missing key `key` (`ctx`: the joint it is missing from).
fn missing(key: &str, ctx: &str) -> String {
    match key {
        "joint" => "no joints: add one [[joint]] table per joint, base to probe".to_string(),
        "probe" => "missing [probe] table: the probe centre `x`, `y`, `z` in the last joint's \
                    frame, in length_unit"
            .to_string(),
        "x" | "y" | "z" => "[probe]: missing; [probe] needs `x`, `y` and `z`".to_string(),
        _ => match unit_choices(key) {
            Some(choices) => format!("missing; add {choices} (units are never guessed)"),
            None => format!(
                "{ctx}missing; every [[joint]] needs `theta`, `alpha` (or `beta`), `a` and `d`"
            ),
        },
    }
}

/// "expected …, found …" for a value of the wrong type; `found` and
/// `expected` are serde's words (`integer `7``, `f64`, `a sequence`) or a
/// TOML type name; `in_angle_unit` (` in deg`) completes the limits' shape.
fn invalid_type(key: &str, found: &str, expected: &str, in_angle_unit: &str) -> String {
    let expected = match (expected, key) {
        ("a sequence", "joint") => "[[joint]] tables (an array of tables, one per joint)".into(),
        ("a sequence", _) => format!("`[min, max]`{in_angle_unit}"),
        ("f64", _) => "a number".into(),
        (e, k) => unit_choices(k).map_or(e.to_string(), |c| format!("{e} ({c})")),
    };
    let serde_words = [
        ("floating point", "float"),
        ("sequence", "array"),
        ("map", "table"),
    ];
    let found = serde_words
        .iter()
        .find(|(w, _)| found.starts_with(w))
        .map_or(found, |(_, t)| t);
    let found = found.split(' ').next().unwrap_or(found);
    let article = if found.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    };
    format!("expected {expected}, found {article} {found}")
}

/// `` `length_unit = "mm"` or `length_unit = "m"` `` for a unit key.
fn unit_choices(key: &str) -> Option<String> {
    let names = match key {
        "length_unit" => LengthUnit::NAMES,
        "angle_unit" => AngleUnit::NAMES,
        _ => return None,
    };
    let choices: Vec<String> = names.iter().map(|n| format!("`{key} = \"{n}\"`")).collect();
    Some(choices.join(" or "))
}
