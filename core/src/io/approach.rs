//! The optional `approach` column of the readings files (poses and
//! positions): per row, the direction each joint last moved in before the
//! reading was taken, where the controller or the operator knows it.
//!
//! A reducer's play lets the link stop anywhere within `±b` of where its
//! motor's encoder says; which flank it rests on is the side it approached
//! the pose from (a servo that always ends its move in one direction rests
//! on that flank whatever gravity does). Without the column the flank is
//! taken from the gravity torque ([`crate::corrections`]); with it, a known
//! direction replaces the torque's sign joint by joint.
//!
//! One text cell per row holding one character per joint, in joint order:
//!
//! | character | meaning |
//! |---|---|
//! | `+` | the joint's reading was increasing when it stopped |
//! | `-` | decreasing |
//! | `0` or `.` | not known: the gravity torque's sign is used |
//!
//! ```text
//! point,q1,q2,q3,q4,q5,q6,approach
//! S1,10.5,-45.0,30.0,0.0,60.0,90.0,+-+000
//! ```
//!
//! An empty cell is "not known" for every joint. One column rather than one
//! per joint (`s1..sn`): the header keeps the shape `point,q1..qn` plus named
//! optional columns at the end whatever the joint count, a row's directions
//! read at a glance next to each other, and a cell of the wrong length is
//! caught as one error naming the column.

use crate::error::{InputError, quoted};

/// The column's name in a header.
pub(crate) const APPROACH: &str = "approach";

/// Appends the directions of one cell `cell` (a row of `joints` joints) to
/// `out` as `+1`, `−1` or `0` (not known); on an error `out` is as it was.
///
/// # Errors
///
/// A cell of another length than `joints` (unless empty), a character
/// other than `+`, `-`, `0`, `.`: each naming the file, line and column.
pub(crate) fn parse_approach(
    cell: &str,
    joints: usize,
    (file, line): (&str, usize),
    out: &mut Vec<i8>,
) -> Result<(), InputError> {
    let error = |message: String| Err(InputError::field(file, line, APPROACH, message));
    if cell.is_empty() {
        out.extend(std::iter::repeat_n(0, joints));
        return Ok(());
    }
    let count = cell.chars().count();
    if count != joints {
        return error(format!(
            "{} has {count} directions but the arm has {joints} joints: one of `+`, `-`, `0` \
             per joint, in joint order",
            quoted(cell)
        ));
    }
    let start = out.len();
    for (j, c) in cell.chars().enumerate() {
        let sign = match c {
            '+' => 1,
            '-' => -1,
            '0' | '.' => 0,
            _ => {
                out.truncate(start);
                return error(format!(
                    "{}: joint {}'s direction `{c}` is not `+` (increasing), `-` (decreasing) \
                     or `0` (not known)",
                    quoted(cell),
                    j + 1
                ));
            }
        };
        out.push(sign);
    }
    Ok(())
}

/// The cell of one row's directions (`+`, `-`, `0`), as
/// [`parse_approach`] reads it back.
pub(crate) fn approach_cell(signs: &[i8]) -> String {
    (signs.iter())
        .map(|s| match s.signum() {
            1 => '+',
            -1 => '-',
            _ => '0',
        })
        .collect()
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn io_approach_parse_approach() {
        use crate::io::approach::parse_approach;
        let mut out = Vec::new();
        parse_approach("+-0.", 4, ("p.csv", 2), &mut out).unwrap();
        assert_eq!(out, [1, -1, 0, 0]);
        parse_approach("", 2, ("p.csv", 3), &mut out).unwrap();
        assert_eq!(out[4..], [0, 0]);
        let e = parse_approach("+-", 3, ("p.csv", 4), &mut out).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("p.csv:4: field `approach`: `+-` has 2 directions")
        );
    }

    #[test]
    fn io_approach_approach_cell() {
        assert_eq!(crate::io::approach::approach_cell(&[1, 0, -1]), "+0-");
    }
}
