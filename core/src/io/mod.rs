//! Reading and writing the toolkit's files: the nouns of [`crate::domain`]
//! (an arm, its touches, lengths, positions and spheres) from and to text.
//!
//! | file | format | module |
//! |---|---|---|
//! | arm (geometry, units, joint limits) | TOML | [`arm`] |
//! | poses (one touch per row) | CSV `point,q1,...,qn` | [`poses`] |
//! | direction of approach (a column of poses and positions) | `+-0` per joint | [`approach`] |
//! | reference lengths | CSV `point_a,point_b,distance[,uncertainty]` | [`lengths`] |
//! | points (e.g. socket positions) | CSV `point,x,y,z` | [`points`] |
//! | points probed on reference spheres | CSV `sphere,q1,...,qn` | [`spheres`] |
//! | positions an instrument saw | CSV `point,q1,...,qn,x,y,z[,qw,qx,qy,qz]…` | [`positions`] |
//! | tool points of an arm | the arm file's `[[tool]]` | [`tools`] |
//!
//! Discipline shared by all readers: units are stated, never guessed; every
//! error is an [`InputError`] naming the file and, where known, the 1-based line
//! and the field; nothing panics on bad input; nothing is dropped silently
//! (unknown keys and columns are errors). Legal but suspicious data yields a
//! [`Warning`], returned to the caller to print. Every `read_*` function reads
//! standard input for the path `-` (the Unix convention), named `<stdin>` in
//! messages ([`source_name`]).
//!
//! CSV dialect (all CSV files), that of the `csv` crate, which reads text
//! with double quotes (text without them is split byte by byte, the same way,
//! at a few hundred MB/s): comma-separated,
//! one record per line (`\n` or `\r\n`). A double quote opens a quoted field
//! only as the field's first character (elsewhere, even after a space, it is
//! an ordinary character); inside quotes, commas and line breaks are kept and
//! `""` is one `"`; text after the closing quote is appended to the field
//! (`"a"b` reads `ab`); a quote left open is an error. Fields are trimmed of
//! surrounding whitespace, quoted or not. Lines whose first non-blank
//! character is `#` are comments only before the header: after the header
//! every non-blank line is a record, so a row labelled `#S1` is data. Blank
//! lines are allowed only at the end of the file. A UTF-8 byte-order mark is
//! ignored (at the start of the file or of the header). A message names a
//! record by its first line. Writers produce this dialect, deterministically,
//! with numbers in the shortest form that reads back bit-exactly (except
//! [`points`], fixed 6 decimals); they refuse labels with surrounding
//! whitespace, which would not read back.

pub mod approach;
pub mod arm;
pub(crate) mod atomic;
pub mod columns;
pub mod frames;
pub mod lengths;
pub(crate) mod limits;
pub mod points;
pub mod poses;
pub mod positions;
pub mod prior;
pub mod spheres;
mod split;
pub(crate) mod text;
pub mod tools;
pub(crate) mod units;
pub mod verdict;

use std::fmt;

pub use crate::error::InputError;
pub use arm::{arm_to_toml, parse_arm, read_arm, read_arm_with, write_arm};
pub use atomic::{write_atomic, write_atomic_with};
pub use columns::JointColumns;
pub(crate) use lengths::check_lengths_against;
pub use lengths::{parse_lengths, read_lengths, write_lengths};
pub use limits::limit_warning;
pub use points::{parse_points, read_points, write_points, write_points_u95, write_tool_poses};
pub use poses::{parse_poses, read_poses, read_poses_or_positions, write_poses};
pub(crate) use positions::parse_positions;
pub use positions::read_positions;
pub use prior::parse_prior;
pub use text::source_name;

pub use units::{AngleUnit, LengthUnit, UnknownUnit};
pub use verdict::Rejected;

/// Legal but suspicious input, located like an [`InputError`]. Readers
/// return warnings; the caller prints them.
///
/// ```
/// use aacmm_core::io::Warning;
/// let w = Warning {
///     file: "p.csv".into(),
///     line: Some(3),
///     field: Some("q2".into()),
///     message: "odd".into(),
/// };
/// assert_eq!(w.to_string(), "p.csv:3: field `q2`: odd");
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// File name as given by the caller.
    pub file: String,
    /// 1-based line, if the warning concerns one line.
    pub line: Option<usize>,
    /// The field (TOML key, CSV column), if the warning concerns one.
    pub field: Option<String>,
    /// What looks wrong, and what to do about it.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        write!(f, ": ")?;
        if let Some(field) = &self.field {
            write!(f, "field `{field}`: ")?;
        }
        f.write_str(&self.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::Arm;
    use rand::{RngExt, SeedableRng};

    /// Random edits of valid files never panic, and every error names the file.
    #[test]
    fn mutated_inputs_never_panic() {
        let arm = arm_to_toml(
            &Arm::without_limits("n", crate::params::DhParams::paper_nominal()),
            LengthUnit::Mm,
            AngleUnit::Deg,
        );
        let seeds = [
            arm.as_str(),
            "point,q1,q2\nS1,1.5,-2\n\"S,2\",3,4e-3\n",
            "point_a,point_b,distance,uncertainty\nA,B,100,0.1\nB,C,5,\n",
            "point,x,y,z\nA,1,2,3\nB,4,5,6\n",
            "point,q1,q2,x,y,z,frame,uncertainty\nA,1,2,3,0,0,f,0.1\nB,4,5,0,6,0,f,\nC,0,0,0,0,9,f,1\n",
        ];
        let alphabet: Vec<char> = "\"',#[]={}\n\r .-+e0123456789abqxyzé\t\\".chars().collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for _ in 0..3000 {
            let seed = seeds[rng.random_range(0..seeds.len())];
            let mut chars: Vec<char> = seed.chars().collect();
            for _ in 0..rng.random_range(1..4) {
                let at = rng.random_range(0..=chars.len());
                let c = alphabet[rng.random_range(0..alphabet.len())];
                match rng.random_range(0..3) {
                    0 => chars.insert(at, c),
                    1 if at < chars.len() => {
                        chars.remove(at);
                    }
                    _ if at < chars.len() => chars[at] = c,
                    _ => chars.push(c),
                }
            }
            let text: String = chars.into_iter().collect();
            let f = "fuzz.txt";
            let errors = [
                parse_arm(&text, f).err(),
                parse_poses(&text, f, AngleUnit::Deg, Some(2)).err(),
                parse_poses(&text, f, AngleUnit::Rad, None).err(),
                parse_lengths(&text, f).err(),
                parse_points(&text, f).err(),
                parse_positions(&text, f, AngleUnit::Deg, Some(2)).err(),
            ];
            for e in errors.into_iter().flatten() {
                assert!(e.to_string().starts_with(f), "{e}");
                assert_eq!(e.file(), f);
            }
        }
    }
}

/// What the readers' tests share.
#[cfg(test)]
pub(crate) mod testing {
    use super::InputError;

    /// The error names `file`, the line (0 = none) and the field, and its
    /// message contains `needle`.
    #[track_caller]
    pub(crate) fn assert_at(
        e: &InputError,
        file: &str,
        line: usize,
        field: Option<&str>,
        needle: &str,
    ) {
        let s = e.to_string();
        assert!(s.starts_with(file), "{s}");
        assert_eq!(e.file(), file);
        assert_eq!(e.line(), (line > 0).then_some(line), "{s}");
        if line > 0 {
            assert!(s.starts_with(&format!("{file}:{line}: ")), "{s}");
        }
        assert_eq!(e.field_name(), field, "{s}");
        if let Some(field) = field {
            assert!(s.contains(&format!("field `{field}`")), "{s}");
        }
        assert!(s.contains(needle), "expected {needle:?} in {s}");
    }
}
