//! Arm files: the nominal (or calibrated) geometry of a D-H chain, in TOML.
//!
//! ```toml
//! name = "paper-table-1"
//! length_unit = "mm"      # "mm" or "m"; required, never guessed
//! angle_unit = "deg"      # "deg" or "rad"; required, never guessed
//!
//! [[joint]]               # one per joint, base to probe (1 to 12 joints)
//! theta = 0.0             # encoder zero offset θ⁰
//! alpha = -90.0           # link twist (the paper's β; `beta` is accepted instead)
//! a = 50.0
//! d = 375.0
//! limits = [-180.0, 180.0]   # optional limits of the encoder reading q
//!
//! [[joint]]               # a slide: the reading is a length added to d
//! type = "prismatic"      # "revolute" (the default) or "prismatic"
//! theta = 0.0
//! alpha = 90.0
//! a = 0.0
//! d = 0.0                 # the offset of d at reading 0
//! limits = [0.0, 800.0]   # a slide's limits are lengths, in length_unit
//!
//! [[joint]]               # a joint whose axis is (nearly) parallel to the previous
//! model = "hayati"        # A = Rz(θ+q)·Tx(a)·Rx(α)·Ry(β): no `d`, `hbeta` instead
//! theta = 0.0
//! alpha = 0.2
//! a = 300.0
//! hbeta = 0.0             # rotation β about the link's y axis, in angle_unit
//!
//! [probe]                 # probe centre in the last joint's frame
//! x = 0.0
//! y = 0.0
//! z = 100.0
//!
//! [[tool]]                # optional: more tool points (markers, SMRs, styli)
//! name = "smr2"
//! offset_mm = [40.0, 0.0, 95.0]   # mm, in the last joint's frame
//! ```
//!
//! `[[tool]]` tables are described in [`super::tools`].
//!
//! `name` is optional (default empty). Lengths (`a`, `d`, probe) are in
//! `length_unit`, angles (`theta`, `alpha`, `hbeta`, `limits`) in `angle_unit`.
//! `type` is `"revolute"` (the default: the reading is an angle added to θ)
//! or `"prismatic"` (the reading is a length added to `d`, in `length_unit`,
//! as are its `limits`); see [`JointKind`](crate::params::JointKind).
//! `model` is `"dh"` (the default: `d` required, no `hbeta`) or `"hayati"`
//! (`hbeta` required, no `d`); see [`JointModel`](crate::params::JointModel).
//! `hbeta`, not `beta`: `beta` is the paper's name of the twist `α`.
//! Integers are accepted where numbers are expected. Unknown keys are errors
//! (a typo is never ignored), as are non-finite numbers, a missing key, a
//! joint count the toolkit has no kernel for (none, or more than
//! [`MAX_JOINTS`](crate::params::MAX_JOINTS)), and limits with
//! `min >= max`. A unit that looks wrong (lengths over 10 m in metres, angles
//! over a full turn in radians) gives a [`Warning`].
//!
//! The schema is a serde type (`schema`); serde's messages are reworded
//! (`messages`) so that every error names the key, its line, and the joint
//! or table it is in.

use std::path::Path;

use serde::Deserialize;

use super::Warning;
use super::text::{parse_toml, read_settings};
use super::units::{AngleUnit, LengthUnit};
use super::verdict::Rejected;
use crate::domain::Arm;
use crate::error::InputError;

mod messages;
mod schema;

use messages::schema_error;
pub(crate) use schema::ArmFile;

/// In an arm file in metres, a length above this (m) draws a warning: no
/// measuring arm is that long, so the lengths are likely millimetres.
pub(crate) const PLAUSIBLE_METRES: f64 = 10.0;

/// The largest probe ball an arm file may state, mm: a stylus ball is
/// 0.5–8 mm, a tracker's target 38.1 mm (1.5 in).
pub(crate) const MAX_BALL_DIAMETER_MM: f64 = 100.0;
/// The smallest, mm: below it the value was most likely written in metres
/// (a 6 mm ball as `0.006`); the field is in mm whatever `length_unit` says.
pub(crate) const MIN_BALL_DIAMETER_MM: f64 = 0.1;

/// Reads an arm file (standard input for `-`); returns the arm and any
/// warnings (for the caller to print). Messages name the file as
/// [`source_name`](super::source_name) gives it.
///
/// ```no_run
/// let (arm, warnings) = aacmm_core::io::read_arm(std::path::Path::new("arm.toml"))?;
/// println!("{} joints", arm.params.joint_count());
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn read_arm(path: &Path) -> Result<(Arm, Vec<Warning>), InputError> {
    read_arm_with(path, Rejected::Refuse)
}

/// [`read_arm`], with a file whose `[verdict]` says NOT usable (a refused
/// calibration's `calibrated.toml`) refused or read with a warning
/// ([`super::verdict`]).
pub fn read_arm_with(path: &Path, rejected: Rejected) -> Result<(Arm, Vec<Warning>), InputError> {
    let (file, text) = read_settings(path)?;
    parse_arm_with(&text, &file, rejected)
}

/// Parses the text of an arm file; `file` is the name used in messages.
/// Returns the arm and any warnings.
///
/// ```
/// let joint = "[[joint]]\ntheta = 0\nalpha = 90\na = 0.05\nd = 0.375\nlimits = [-90, 90]\n";
/// let text = format!(
///     "length_unit = \"m\"\nangle_unit = \"deg\"\n{}[probe]\nx = 0\ny = 0\nz = 0.1\n",
///     joint.repeat(6)
/// );
/// let (arm, warnings) = aacmm_core::io::parse_arm(&text, "arm.toml").unwrap();
/// assert_eq!(arm.params.joints[0].d, 375.0);
/// assert_eq!(arm.params.joints[0].alpha, std::f64::consts::FRAC_PI_2);
/// assert_eq!(arm.params.probe, [0.0, 0.0, 100.0]);
/// assert_eq!(arm.limits[0].unwrap()[1], std::f64::consts::FRAC_PI_2);
/// assert!(warnings.is_empty());
///
/// let err = aacmm_core::io::parse_arm(&text.replacen("alpha", "alpah", 1), "arm.toml");
/// assert!(err.unwrap_err().to_string().starts_with("arm.toml:5: field `alpah`: unknown key"));
/// let thirteen = text.replace("[probe]", &format!("{}[probe]", joint.repeat(7)));
/// assert_eq!(
///     aacmm_core::io::parse_arm(&thirteen, "arm.toml").unwrap_err().to_string(),
///     "arm.toml:75: field `joint`: 13 joints; at most 12 are supported (the toolkit \
///      computes chains of 1 to 12 joints)"
/// );
/// ```
pub fn parse_arm(text: &str, file: &str) -> Result<(Arm, Vec<Warning>), InputError> {
    parse_arm_with(text, file, Rejected::Refuse)
}

/// [`parse_arm`], with a file whose `[verdict]` says NOT usable refused or
/// read with a warning ([`super::verdict`]).
pub(crate) fn parse_arm_with(
    text: &str,
    file: &str,
    rejected: Rejected,
) -> Result<(Arm, Vec<Warning>), InputError> {
    let doc = parse_toml(text, file)?;
    // First: a refused calibration's file is refused for that, whatever
    // else it holds.
    let verdict = super::verdict::check(doc.get_ref(), text, file, rejected)?;
    let schema = ArmFile::deserialize(toml::de::Deserializer::from(doc.clone()))
        .map_err(|e| schema_error(text, file, doc.get_ref(), &e))?;
    let (mut arm, mut warnings) = schema.to_arm(text, file)?;
    warnings.extend(verdict);
    if doc.get_ref().contains_key("prior") {
        // Read with the arm, so every front end fits with it: a typo is
        // never ignored, and no reader can leave the tolerances behind.
        arm.prior =
            super::prior::parse_prior_of(text, file, arm.params.joint_count(), Some(&arm.params))?;
    }
    Ok((arm, warnings))
}

/// Writes an arm in the arm-file schema with the given units: deterministic
/// bytes, numbers with the fewest digits that read back to the same value
/// (bit-exact in mm and rad; in deg and m bit-exact whenever some decimal
/// converts back exactly, else within 1 ulp — see
/// [`AngleUnit::from_internal_exact`]). Missing `limits` entries are written
/// as no limits; non-finite values are written as TOML `nan`/`inf`, which the
/// reader rejects.
///
/// ```
/// use aacmm_core::domain::Arm;
/// use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml, parse_arm};
/// use aacmm_core::params::DhParams;
/// let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
/// let text = arm_to_toml(&arm, LengthUnit::Mm, AngleUnit::Deg);
/// assert!(text.contains("alpha = -90.0\na = 50.0\nd = 375.0\n"));
/// assert_eq!(parse_arm(&text, "out.toml").unwrap().0, arm);
/// ```
pub fn arm_to_toml(arm: &Arm, length_unit: LengthUnit, angle_unit: AngleUnit) -> String {
    // Invariant: an `ArmFile` holds only strings, floats (TOML has inf and
    // nan), arrays and tables, which always serialize.
    toml::to_string(&ArmFile::new(arm, length_unit, angle_unit))
        .expect("strings, numbers, arrays and tables always serialize to TOML")
}

/// Writes an arm file (see [`arm_to_toml`]).
///
/// ```no_run
/// use aacmm_core::domain::Arm;
/// use aacmm_core::io::{AngleUnit, LengthUnit, write_arm};
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
    super::write_atomic(path, arm_to_toml(arm, length_unit, angle_unit))
        .map_err(|e| InputError::io(path.display().to_string(), e))
}

#[cfg(test)]
mod tests;
