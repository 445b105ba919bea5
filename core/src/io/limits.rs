//! Readings outside the arm file's joint limits: legal (a limit may be
//! stated loosely), but usually a sign of the wrong angle unit, the wrong
//! arm file or shifted encoder zeros — so one [`Warning`] says how many and
//! where the first one is, for every front end alike.

use super::{AngleUnit, Warning};
use crate::domain::{Arm, Poses};

/// Readings this far (rad) beyond a limit are still within it: a limit and a
/// reading written in different units may differ by rounding.
const LIMIT_SLACK: f64 = 1e-12;

/// One warning for the readings of `poses` outside `arm`'s joint limits, if
/// any: how many, on which joints, and the first one in file order (`file`
/// names the poses file in the message, `unit` is the unit its angles are
/// written in, so the reading is shown as written).
///
/// ```
/// use aacmm_core::domain::{Arm, Poses};
/// use aacmm_core::io::{AngleUnit, limit_warning};
/// use aacmm_core::params::DhParams;
/// let mut arm = Arm::without_limits("n", DhParams::paper_nominal());
/// arm.limits = vec![None, None, Some([-1.0, 1.0]), None, None, None];
/// let mut poses = Poses::new(6);
/// poses.push("A", &[0.0, 0.0, 0.5, 0.0, 0.0, 0.0], 2);
/// poses.push("A", &[0.0, 0.0, 1.5, 0.0, 0.0, 0.0], 3);
/// let w = limit_warning(&arm, &poses, "p.csv", AngleUnit::Rad).unwrap();
/// assert_eq!(
///     w.to_string(),
///     "p.csv:3: field `q3`: 1 reading outside the arm's joint limits (first: 1.5 rad > 1 rad); \
///      check the arm file, the angle unit and the encoder zeros"
/// );
/// ```
pub fn limit_warning(arm: &Arm, poses: &Poses, file: &str, unit: AngleUnit) -> Option<Warning> {
    let rows = poses
        .rows()
        .enumerate()
        .map(|(row, q)| (row, poses.line(row), q));
    let prismatic = arm.params.shape().map_or(0, |s| s.prismatic_mask());
    limit_warning_of((&arm.limits, prismatic), rows, file, unit)
}

/// [`limit_warning`] over readings given as `(row, line, readings)` in any
/// order (a data set holds its touches grouped by point): the first reading
/// named is the one of the lowest row, so the message is the same whatever
/// the order. A prismatic joint's (a bit of `prismatic`) reading and
/// limits are shown in mm.
pub(crate) fn limit_warning_of<'a>(
    (limits, prismatic): (&[Option<[f64; 2]>], u16),
    rows: impl Iterator<Item = (usize, usize, &'a [f64])>,
    file: &str,
    unit: AngleUnit,
) -> Option<Warning> {
    let mut count = 0;
    let mut joints: Vec<usize> = Vec::new();
    // (row, joint, line, reading, "<" or ">", bound) of the first outside.
    let mut first: Option<(usize, usize, usize, f64, &str, f64)> = None;
    for (row, line, q) in rows {
        for (j, (&x, limit)) in q.iter().zip(limits).enumerate() {
            let Some([lo, hi]) = *limit else { continue };
            let (bound, sign) = if x < lo - LIMIT_SLACK {
                (lo, "<")
            } else if x > hi + LIMIT_SLACK {
                (hi, ">")
            } else {
                continue;
            };
            count += 1;
            if !joints.contains(&j) {
                joints.push(j);
            }
            if first.is_none_or(|f| (row, j) < (f.0, f.1)) {
                first = Some((row, j, line, x, sign, bound));
            }
        }
    }
    let (_, j, line, x, sign, bound) = first?;
    let show = |v: f64| match unit {
        _ if j < 16 && prismatic & (1 << j) != 0 => format!("{v} mm"),
        AngleUnit::Deg => format!("{}°", unit.from_internal_exact(v)),
        AngleUnit::Rad => format!("{v} rad"),
    };
    let readings = if count == 1 { "reading" } else { "readings" };
    let more = if joints.len() > 1 {
        joints.sort_unstable();
        let names: Vec<String> = joints.iter().map(|j| format!("q{}", j + 1)).collect();
        format!(" in {}", names.join(", "))
    } else {
        String::new()
    };
    Some(Warning {
        file: file.to_string(),
        line: Some(line),
        field: Some(format!("q{}", j + 1)),
        message: format!(
            "{count} {readings}{more} outside the arm's joint limits (first: {} {sign} {}); \
             check the arm file, the angle unit and the encoder zeros",
            show(x),
            show(bound)
        ),
    })
}
