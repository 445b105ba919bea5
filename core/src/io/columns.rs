//! What the joint columns `q1..qn` of a readings file (poses, reference
//! positions) mean: how many there must be, and which are lengths.
//!
//! The arm decides: a revolute joint's reading is an angle in the unit the
//! caller states (`--angle-unit`), a prismatic joint's reading is a length
//! in mm whatever the angle unit says — it is stored as it is written.
//!
//! A prismatic reading outside the joint's stroke (the arm file's limits
//! of a prismatic joint) is refused, not warned about as a revolute
//! reading beyond its limits is: a slide cannot pass its end stops, so
//! such a number is not the slide's position in mm (an angle, a reading in
//! metres or inches, or the columns in another order than the arm's
//! joints), and every result computed from it would be wrong. An arm file
//! that states no limits for a prismatic joint leaves its readings
//! unchecked.

use super::InputError;
use super::units::AngleUnit;
use crate::domain::Arm;
use crate::params::ChainShape;

/// Readings this far (mm) beyond a prismatic joint's stroke are still
/// within it: a limit and a reading written in different length units may
/// differ by rounding.
const STROKE_SLACK_MM: f64 = 1e-9;

/// The joint columns a readings file must have and what each holds (see
/// the [module docs](self)). Made from a joint count (`Some(6)`: six
/// revolute joints; `None`: any count, all revolute), a [`ChainShape`], or
/// an [`Arm`] (its shape and the strokes of its prismatic joints).
///
/// ```
/// use aacmm_core::io::{AngleUnit, JointColumns, parse_poses};
/// use aacmm_core::params::ChainShape;
/// let track: ChainShape = "PR".parse().unwrap();
/// let text = "point,q1,q2\nA,1500,90\n";
/// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Deg, track).unwrap();
/// // The slide's reading is mm as written, the angle is converted.
/// assert_eq!(poses.reading(0), [1500.0, std::f64::consts::FRAC_PI_2]);
/// assert_eq!(JointColumns::from(track).expected(), Some(2));
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointColumns {
    /// The joint count required, if any.
    count: Option<usize>,
    /// The prismatic joints, bit `j` for joint `j`.
    prismatic: u16,
    /// Per joint, the stroke `[min, max]` (mm) of a prismatic joint.
    strokes: Vec<Option<[f64; 2]>>,
    /// The tools a `tool` cell may name, when an arm says
    /// ([`super::tools`]); `None`: any name.
    tools: Option<crate::domain::ToolNames>,
}

impl From<Option<usize>> for JointColumns {
    fn from(count: Option<usize>) -> JointColumns {
        JointColumns {
            count,
            ..JointColumns::default()
        }
    }
}

impl From<usize> for JointColumns {
    fn from(count: usize) -> JointColumns {
        JointColumns::from(Some(count))
    }
}

impl From<ChainShape> for JointColumns {
    fn from(shape: ChainShape) -> JointColumns {
        JointColumns {
            count: Some(shape.joints()),
            prismatic: shape.prismatic_mask(),
            strokes: Vec::new(),
            tools: None,
        }
    }
}

impl From<&Arm> for JointColumns {
    /// The arm's shape and its prismatic joints' strokes (an arm whose
    /// shape is not one — no joints, too many — asks for its joint count,
    /// all revolute, so that the header check names the mismatch).
    fn from(arm: &Arm) -> JointColumns {
        let tools = Some(crate::domain::ToolNames::of(&arm.tools));
        let Ok(shape) = arm.params.shape() else {
            return JointColumns {
                tools,
                ..JointColumns::from(arm.params.joint_count())
            };
        };
        let strokes = (arm.limits.iter().enumerate())
            .map(|(j, l)| l.filter(|_| shape.is_prismatic(j)))
            .collect();
        JointColumns {
            strokes,
            tools,
            ..JointColumns::from(shape)
        }
    }
}

impl JointColumns {
    /// The joint count required, if any.
    pub fn expected(&self) -> Option<usize> {
        self.count
    }

    /// The prismatic joints, bit `j` for joint `j`.
    pub(crate) fn prismatic_mask(&self) -> u16 {
        self.prismatic
    }

    /// The tools a `tool` cell may name (the arm's), when known.
    pub(crate) fn tools(&self) -> Option<&crate::domain::ToolNames> {
        self.tools.as_ref()
    }

    /// Whether joint `j` (0-based) is prismatic: its column is mm.
    pub(crate) fn is_prismatic(&self, j: usize) -> bool {
        j < 16 && self.prismatic & (1 << j) != 0
    }

    /// Reading `x` of joint `j` as written, in the toolkit's units (rad;
    /// mm for a prismatic joint, as written).
    #[inline]
    pub(crate) fn to_internal(&self, j: usize, x: f64, unit: AngleUnit) -> f64 {
        if self.is_prismatic(j) {
            x
        } else {
            unit.to_internal(x)
        }
    }

    /// Reading `x` (internal units) of joint `j` as it is written in
    /// `unit`: bit-exact in rad and mm ([`AngleUnit::from_internal_exact`]).
    pub(crate) fn to_written(prismatic: u16, j: usize, x: f64, unit: AngleUnit) -> f64 {
        if j < 16 && prismatic & (1 << j) != 0 {
            x
        } else {
            unit.from_internal_exact(x)
        }
    }

    /// Refuses a prismatic reading `x` (mm) of joint `j` outside its
    /// stroke, naming `file`, `line` and the column.
    pub(crate) fn check_stroke(
        &self,
        j: usize,
        x: f64,
        file: &str,
        line: usize,
    ) -> Result<(), InputError> {
        let Some(Some([lo, hi])) = self.strokes.get(j) else {
            return Ok(());
        };
        if (lo - STROKE_SLACK_MM..=hi + STROKE_SLACK_MM).contains(&x) {
            return Ok(());
        }
        let message = format!(
            "{x} mm is outside joint {}'s stroke [{lo}, {hi}] mm: a prismatic joint's reading is \
             its slide's position in mm (whatever the angle unit), within its limits in the \
             arm file; check the column order, the unit and the arm file",
            j + 1
        );
        Err(InputError::field(
            file,
            line,
            format!("q{}", j + 1),
            message,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{parse_poses, parse_positions};
    use crate::params::{DhJoint, DhParams, JointKind};

    fn track_arm() -> Arm {
        let mut params = DhParams::paper_nominal();
        let slide = DhJoint::dh(0.0, 0.0, 0.0, 0.0).with_kind(JointKind::Prismatic);
        params.joints.insert(0, slide);
        let mut arm = Arm::without_limits("track", params);
        arm.limits[0] = Some([0.0, 3000.0]);
        arm.limits[1] = Some([-1.0, 1.0]);
        arm
    }

    /// A prismatic column is mm whatever the angle unit; one outside the
    /// stroke is refused by file, line and field; the revolute columns
    /// are converted and their limits are not a refusal.
    #[test]
    fn prismatic_columns_are_lengths_within_their_stroke() {
        let arm = track_arm();
        let text = "point,q1,q2,q3,q4,q5,q6,q7\nA,2500,90,0,0,0,0,0\nA,10,-90,0,0,0,0,0\n";
        for unit in [AngleUnit::Deg, AngleUnit::Rad] {
            let (p, _) = parse_poses(text, "t.csv", unit, &arm).unwrap();
            assert_eq!((p.reading(0)[0], p.reading(1)[0]), (2500.0, 10.0));
            assert_eq!(p.prismatic_mask(), 1);
        }
        let (p, _) = parse_poses(text, "t.csv", AngleUnit::Deg, &arm).unwrap();
        assert_eq!(p.reading(0)[1], std::f64::consts::FRAC_PI_2);
        let beyond = text.replace("A,10,", "A,-45,");
        let e = parse_poses(&beyond, "t.csv", AngleUnit::Deg, &arm).unwrap_err();
        assert!(
            e.to_string().starts_with(
                "t.csv:3: field `q1`: -45 mm is outside joint 1's stroke [0, 3000] mm"
            ),
            "{e}"
        );
        let positions = "point,q1,q2,q3,q4,q5,q6,q7,x,y,z\nA,3500,0,0,0,0,0,0,1,2,3\n";
        let e = parse_positions(positions, "r.csv", AngleUnit::Deg, &arm).unwrap_err();
        assert!(
            e.to_string().starts_with("r.csv:2: field `q1`: 3500 mm"),
            "{e}"
        );
        // Without a stroke in the arm file, any length is read.
        let mut free = arm.clone();
        free.limits[0] = None;
        assert!(parse_poses(&beyond, "t.csv", AngleUnit::Deg, &free).is_ok());
    }

    /// A file with another column count than the arm's joints names the
    /// first column missing or unexpected.
    #[test]
    fn column_counts_follow_the_arm() {
        let arm = track_arm();
        let six = "point,q1,q2,q3,q4,q5,q6\nA,0,0,0,0,0,0\n";
        let e = parse_poses(six, "t.csv", AngleUnit::Deg, &arm).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("t.csv:1: field `q7`: the header has 6 joint columns"),
            "{e}"
        );
        let eight = "point,q1,q2,q3,q4,q5,q6,q7,q8\nA,0,0,0,0,0,0,0,0\n";
        let e = parse_poses(eight, "t.csv", AngleUnit::Deg, &arm).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("t.csv:1: field `q8`: the header has 8 joint columns"),
            "{e}"
        );
    }
}
