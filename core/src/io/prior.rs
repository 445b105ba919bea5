//! The optional `[prior]` table of an arm file: stated 1σ tolerances of the
//! nominal geometry ([`crate::tolerances`]).
//!
//! ```toml
//! [prior]              # optional; every key NAME_UNIT, unit mm or m / deg or rad
//! length_mm = 0.5      # every a, d and probe coordinate
//! angle_deg = 0.1      # every alpha and theta
//! probe_mm = 2.0       # a kind: a_mm, d_mm, alpha_deg, theta_deg, probe_mm
//! theta5_deg = 0.05    # one parameter (a1 … Bz); the most specific applies
//! ```
//!
//! A key without a unit, with the wrong kind of unit, an unknown name, and a
//! value that is not a finite number > 0 are errors naming the file, line
//! and key. [`crate::io::read_arm`] reads the table into
//! [`crate::domain::Arm::prior`].

use toml::Spanned;
use toml::de::DeValue;

use super::text::{line_of, parse_toml};
use crate::error::{InputError, quoted};
use crate::tolerances::{Target, Tolerances, not_in_arm, unknown_target};

/// The `[prior]` table of an arm file's text for an arm of `joints` joints
/// (`None` without one). `file` names the file in messages.
///
/// ```
/// use aacmm_core::io::parse_prior;
/// let text = "length_unit = \"mm\"\n[prior]\nlength_mm = 0.5\nangle_deg = 0.1\ntheta5_deg = 0.05\n";
/// let t = parse_prior(text, "arm.toml", 6).unwrap().unwrap();
/// assert_eq!(t.sigmas(6)[0], Some(0.5));
/// let e = parse_prior(&text.replace("0.05", "0"), "arm.toml", 6).unwrap_err();
/// assert!(e.to_string().starts_with("arm.toml:5: field `theta5_deg`: "), "{e}");
/// let e = parse_prior(&text.replace("theta5_deg", "theta9_deg"), "arm.toml", 6).unwrap_err();
/// assert!(e.to_string().contains("unknown target `theta9`"), "{e}");
/// ```
///
/// # Errors
///
/// A syntax error, a `prior` that is not a table, and any bad entry: an
/// unknown name, a missing or wrong unit, a value that is not a finite
/// number > 0.
pub fn parse_prior(
    text: &str,
    file: &str,
    joints: usize,
) -> Result<Option<Tolerances>, InputError> {
    parse_prior_of(text, file, joints, None)
}

/// [`parse_prior`], and with the arm `arm` each parameter named must be
/// one of its own (a Hayati joint has `hbeta…`, not `d…`).
pub(crate) fn parse_prior_of(
    text: &str,
    file: &str,
    joints: usize,
    arm: Option<&crate::params::DhParams>,
) -> Result<Option<Tolerances>, InputError> {
    let doc = parse_toml(text, file)?;
    let root = doc.get_ref();
    let Some((key, value)) = root.get_key_value("prior") else {
        return Ok(None);
    };
    let DeValue::Table(table) = value.get_ref() else {
        return Err(InputError::field(
            file,
            line_of(text, key.span().start),
            "prior",
            format!(
                "expected a [prior] table of tolerances (e.g. length_mm = 0.5), found {}",
                value.get_ref().type_str()
            ),
        ));
    };
    let mut entries: Vec<(&Spanned<_>, &Spanned<DeValue>)> = table.iter().collect();
    entries.sort_by_key(|(k, _)| k.span().start);
    let mut tolerances = Tolerances::new();
    for (k, v) in entries {
        let name: &str = k.get_ref();
        let line = line_of(text, k.span().start);
        let err =
            |message: String| InputError::field(file, line, name, format!("[prior]: {message}"));
        let (target_name, unit) = name.rsplit_once('_').ok_or_else(|| {
            err(format!(
                "{} has no unit; write NAME_UNIT, e.g. length_mm, angle_deg or \
                 theta5_deg",
                quoted(name)
            ))
        })?;
        let target = Target::parse(target_name, joints)
            .ok_or_else(|| err(unknown_target(target_name, joints)))?;
        if let Some(why) = arm.and_then(|a| not_in_arm(target, target_name, a)) {
            return Err(err(why));
        }
        let value = match v.get_ref() {
            DeValue::Float(f) => f.as_str().replace('_', "").parse::<f64>().ok(),
            DeValue::Integer(i) => i64::from_str_radix(&i.as_str().replace('_', ""), i.radix())
                .ok()
                .map(|i| i as f64),
            _ => None,
        }
        .ok_or_else(|| {
            let raw = text.get(v.span()).unwrap_or("?");
            err(format!(
                "{} is not a number (a tolerance, 1σ, in {unit})",
                quoted(raw)
            ))
        })?;
        tolerances.set(target, value, unit).map_err(err)?;
    }
    Ok((!tolerances.is_empty()).then_some(tolerances))
}
