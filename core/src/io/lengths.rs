//! Reference-length files: calibrated distances between touched points, CSV
//! with the header `point_a,point_b,distance` and an optional fourth column
//! `uncertainty`.
//!
//! ```text
//! point_a,point_b,distance,uncertainty
//! S1,S2,500.0012,0.0005
//! S2,S3,299.9987,
//! ```
//!
//! Distances and uncertainties are in mm; the uncertainty is a standard
//! uncertainty (k = 1), `>= 0`. With the `uncertainty` column, an empty cell
//! means "not stated". The CSV dialect is described in the [`io`](super)
//! module docs.

use std::collections::{BTreeSet, HashMap};
use std::io::Write;
use std::path::Path;

use super::text::{check_header, fmt_f64, parse_f64, quote, read_text, scan_table};
use crate::domain::ReferenceLength;
use crate::error::{InputError, quoted, shown};

const COLUMNS: [&str; 4] = ["point_a", "point_b", "distance", "uncertainty"];
const SHAPE: &str = "point_a,point_b,distance` or `point_a,point_b,distance,uncertainty";

/// Reads a reference-length file (standard input for `-`); messages name the
/// file as [`source_name`](super::source_name) gives it.
///
/// ```no_run
/// let lengths = aacmm_core::io::read_lengths(std::path::Path::new("lengths.csv"))?;
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn read_lengths(path: &Path) -> Result<Vec<ReferenceLength>, InputError> {
    let (file, text) = read_text(path)?;
    parse_lengths(&text, &file)
}

/// Parses the text of a reference-length file; `file` is the name used in
/// messages. Each pair of points may be given once (in either order).
///
/// ```
/// use aacmm_core::io::parse_lengths;
/// let l = parse_lengths("point_a,point_b,distance\nS1,S2,500.25\n", "l.csv").unwrap();
/// assert_eq!((l[0].a.as_str(), l[0].b.as_str(), l[0].distance), ("S1", "S2", 500.25));
/// assert_eq!((l[0].uncertainty, l[0].line), (None, 2));
///
/// let e = parse_lengths("point_a,point_b,distance\nS1,S2,-1\n", "l.csv").unwrap_err();
/// assert_eq!(e.to_string(), "l.csv:2: field `distance`: must be positive, got -1");
/// ```
pub fn parse_lengths(text: &str, file: &str) -> Result<Vec<ReferenceLength>, InputError> {
    let mut pairs: HashMap<(String, String), usize> = HashMap::new();
    let mut out = Vec::new();
    let check = |header: &super::text::Record| {
        let ncols = if header.fields.len() >= 4 { 4 } else { 3 };
        check_header(header, file, &COLUMNS[..ncols], SHAPE)
    };
    scan_table(
        text,
        file,
        SHAPE,
        "one row per length",
        check,
        |_, line, f| {
            let error =
                |field: &str, message: String| Err(InputError::field(file, line, field, message));
            let (a, b, distance, uncertainty) = (f[0], f[1], f[2], f.get(3).copied());
            for (field, label) in [("point_a", a), ("point_b", b)] {
                if label.is_empty() {
                    return error(field, "empty point label".into());
                }
            }
            if a == b {
                return error(
                    "point_b",
                    format!(
                        "same point as point_a ({}): a length needs two points",
                        quoted(a)
                    ),
                );
            }
            let d = parse_f64(distance, file, line, "distance")?;
            if d <= 0.0 {
                return error(
                    "distance",
                    format!("must be positive, got {}", shown(distance)),
                );
            }
            let u = match uncertainty.filter(|s| !s.is_empty()) {
                None => None,
                Some(s) => match parse_f64(s, file, line, "uncertainty")? {
                    u if u < 0.0 => {
                        return error(
                            "uncertainty",
                            format!("must not be negative, got {}", shown(s)),
                        );
                    }
                    u => Some(u),
                },
            };
            let pair = if a < b { (a, b) } else { (b, a) };
            if let Some(first) = pairs.insert((pair.0.to_string(), pair.1.to_string()), line) {
                return error(
                    "point_b",
                    format!(
                        "the pair {}–{} is already given on line {first}",
                        quoted(a),
                        quoted(b)
                    ),
                );
            }
            let memory = |e| InputError::memory(file, e);
            crate::memory::try_grow(&mut out, "the lengths' rows", 1).map_err(memory)?;
            out.push(ReferenceLength {
                a: a.to_string(),
                b: b.to_string(),
                distance: d,
                uncertainty: u,
                line,
            });
            Ok(())
        },
    )?;
    Ok(out)
}

/// Checks that every point of `lengths` is among `known` (e.g. the labels of
/// a poses file); the error names `file` (the lengths file), the line and the
/// field (`point_a` or `point_b`) of the first unknown point.
pub(crate) fn check_lengths_against<S: AsRef<str>>(
    lengths: &[ReferenceLength],
    known: &[S],
    file: &str,
) -> Result<(), InputError> {
    let set: BTreeSet<&str> = known.iter().map(AsRef::as_ref).collect();
    let unknown = (lengths.iter())
        .flat_map(|l| [(l.line, "point_a", &l.a), (l.line, "point_b", &l.b)])
        .find(|(_, _, label)| !set.contains(label.as_str()));
    let Some((line, field, label)) = unknown else {
        return Ok(());
    };
    let shown: Vec<String> = set.iter().take(10).map(|n| quoted(n)).collect();
    let known_text = match set.len() {
        0 => "there are no known points".to_string(),
        n if n > 10 => format!("known points: {} and {} more", shown.join(", "), n - 10),
        _ => format!("known points: {}", shown.join(", ")),
    };
    let message = format!("unknown point {}; {known_text}", quoted(label));
    Err(InputError::field(file, line, field, message))
}

/// Writes reference lengths in the file format: deterministic bytes, numbers
/// in the shortest form that reads back bit-exactly. The `uncertainty` column
/// is written when any length states one (empty cells for the others).
/// `line` is not written. A label with surrounding whitespace (reading trims
/// it) gives an [`std::io::ErrorKind::InvalidInput`] error.
///
/// ```
/// use aacmm_core::domain::ReferenceLength;
/// use aacmm_core::io::write_lengths;
/// let l = ReferenceLength::new("S1", "S2", 500.0, None);
/// let mut out = Vec::new();
/// write_lengths(&mut out, &[l]).unwrap();
/// assert_eq!(String::from_utf8(out).unwrap(), "point_a,point_b,distance\nS1,S2,500.0\n");
/// ```
pub fn write_lengths(mut w: impl Write, lengths: &[ReferenceLength]) -> std::io::Result<()> {
    let with_u = lengths.iter().any(|l| l.uncertainty.is_some());
    let ncols = if with_u { 4 } else { 3 };
    w.write_all(format!("{}\n", COLUMNS[..ncols].join(",")).as_bytes())?;
    for l in lengths {
        let mut line = format!("{},{},{}", quote(&l.a)?, quote(&l.b)?, fmt_f64(l.distance));
        if with_u {
            line.push(',');
            if let Some(u) = l.uncertainty {
                line.push_str(&fmt_f64(u));
            }
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const F: &str = "ref-lengths.csv";

    fn err(text: &str) -> InputError {
        parse_lengths(text, F).unwrap_err()
    }

    #[track_caller]
    fn assert_at(e: &InputError, line: usize, field: Option<&str>, needle: &str) {
        crate::io::testing::assert_at(e, F, line, field, needle);
    }

    #[test]
    fn parses_with_and_without_uncertainty() {
        let l = parse_lengths(
            "# c\npoint_a,point_b,distance,uncertainty\nA,B,100.5,0.001\nB,C,200,\nC,A,300,0\n",
            F,
        )
        .unwrap();
        assert_eq!(l.len(), 3);
        assert_eq!(l[0].uncertainty, Some(0.001));
        assert_eq!(l[1].uncertainty, None);
        assert_eq!(l[2].uncertainty, Some(0.0));
        assert_eq!(l.iter().map(|l| l.line).collect::<Vec<_>>(), [3, 4, 5]);
    }

    #[test]
    fn header_errors() {
        assert_at(&err(""), 0, None, "empty file");
        assert_at(&err("point_a,point_b,distance\n"), 0, None, "no data rows");
        assert_at(
            &err("point_a,point_b\nA,B\n"),
            1,
            Some("distance"),
            "missing column 3",
        );
        assert_at(
            &err("point_a,point_b,dist\nA,B,1\n"),
            1,
            Some("dist"),
            "expected `distance`",
        );
        assert_at(
            &err("point_b,point_a,distance\nA,B,1\n"),
            1,
            Some("point_b"),
            "expected `point_a`",
        );
        assert_at(
            &err("point_a,point_b,distance,u\nA,B,1,0\n"),
            1,
            Some("u"),
            "expected `uncertainty`",
        );
        assert_at(
            &err("point_a,point_b,distance,uncertainty,x\nA,B,1,0,1\n"),
            1,
            Some("x"),
            "unexpected column 5",
        );
        assert_at(
            &err("point_a,point_a,distance\nA,B,1\n"),
            1,
            Some("point_a"),
            "duplicate column",
        );
        assert_at(
            &err("point_a,point_b,distance,distance\nA,B,1,1\n"),
            1,
            Some("distance"),
            "duplicate column",
        );
    }

    #[test]
    fn row_errors() {
        let h = "point_a,point_b,distance,uncertainty\n";
        let e = |row: &str| err(&format!("{h}A,B,1,0\n{row}\n"));
        assert_at(&e("A,A,5,"), 3, Some("point_b"), "same point");
        assert_at(&e(",B,5,"), 3, Some("point_a"), "empty point label");
        assert_at(&e("A,,5,"), 3, Some("point_b"), "empty point label");
        assert_at(&e("A,B,0,"), 3, Some("distance"), "must be positive, got 0");
        assert_at(&e("A,B,-2.5,"), 3, Some("distance"), "must be positive");
        assert_at(&e("A,B,inf,"), 3, Some("distance"), "not a finite number");
        assert_at(&e("A,B,nan,"), 3, Some("distance"), "not a finite number");
        assert_at(&e("A,B,ten,"), 3, Some("distance"), "not a number");
        assert_at(&e("A,B,,"), 3, Some("distance"), "missing value");
        assert_at(
            &e("A,B,5,-0.1"),
            3,
            Some("uncertainty"),
            "must not be negative",
        );
        assert_at(
            &e("A,B,5,NaN"),
            3,
            Some("uncertainty"),
            "not a finite number",
        );
        assert_at(&e("A,B,5"), 3, Some("uncertainty"), "missing");
        assert_at(&e("A,B,5,1,2"), 3, None, "the row has 5 columns");
    }

    #[test]
    fn a_pair_is_given_once() {
        // The same unordered pair twice (either order, any distance) was
        // silently counted twice.
        let h = "point_a,point_b,distance\n";
        for again in ["S1,S2,500", "S2,S1,500", "S1,S2,499.5", "S2,S1,1"] {
            let text = format!("{h}S1,S2,500\nS1,S3,300\n{again}\n");
            assert_at(
                &err(&text),
                4,
                Some("point_b"),
                "is already given on line 2",
            );
        }
        let e = err(&format!("{h}S1,S2,500\nS2,S3,1\nS2,S1,500\n"));
        assert_eq!(
            e.to_string(),
            "ref-lengths.csv:4: field `point_b`: the pair `S2`–`S1` is already given on line 2"
        );
        // Pairs sharing a point are distinct.
        let l = parse_lengths(&format!("{h}S1,S2,1\nS2,S3,1\nS3,S1,1\n"), F).unwrap();
        assert_eq!(l.len(), 3);
    }

    #[test]
    fn a_length_made_in_memory_is_named_by_its_source_alone() {
        let l = [ReferenceLength::new("A", "Z", 500.0, Some(0.002))];
        assert_eq!(l[0].line, 0);
        let e = check_lengths_against(&l, &["A", "B"], "<arrays>").unwrap_err();
        assert_eq!(
            e.to_string(),
            "<arrays>: field `point_b`: unknown point `Z`; known points: `A`, `B`"
        );
    }

    #[test]
    fn unknown_points() {
        let l = parse_lengths("point_a,point_b,distance\nA,B,1\nB,C,2\n", F).unwrap();
        let known = vec!["A".to_string(), "B".to_string(), "C".to_string()];
        assert!(check_lengths_against(&l, &known, F).is_ok());
        let e = check_lengths_against(&l, &["A", "C"], F).unwrap_err();
        assert_at(
            &e,
            2,
            Some("point_b"),
            "unknown point `B`; known points: `A`, `C`",
        );
        let e = check_lengths_against(&l, &["B", "C"], F).unwrap_err();
        assert_at(&e, 2, Some("point_a"), "unknown point `A`");
        let e = check_lengths_against::<&str>(&l, &[], F).unwrap_err();
        assert_at(&e, 2, Some("point_a"), "no known points");
        let many: Vec<String> = (0..15).map(|i| format!("P{i:02}")).collect();
        let e = check_lengths_against(&l, &many, F).unwrap_err();
        assert!(e.to_string().contains("and 5 more"), "{e}");
    }

    #[test]
    fn round_trip_bit_exact() {
        let lengths = vec![
            ReferenceLength {
                a: "A".into(),
                b: "B, 2".into(),
                distance: 0.1 + 0.2,
                uncertainty: Some(1e-4 / 3.0),
                line: 2,
            },
            ReferenceLength {
                a: "#c".into(),
                b: "A".into(),
                distance: 1234.567890123,
                uncertainty: None,
                line: 3,
            },
        ];
        let mut out = Vec::new();
        write_lengths(&mut out, &lengths).unwrap();
        let text = String::from_utf8(out).unwrap();
        let back = parse_lengths(&text, F).unwrap();
        assert_eq!(back, lengths);
        for (x, y) in back.iter().zip(&lengths) {
            assert_eq!(x.distance.to_bits(), y.distance.to_bits());
            assert_eq!(
                x.uncertainty.map(f64::to_bits),
                y.uncertainty.map(f64::to_bits)
            );
        }
        let mut again = Vec::new();
        write_lengths(&mut again, &back).unwrap();
        assert_eq!(String::from_utf8(again).unwrap(), text);
        let mut padded = lengths;
        padded[1].b = "\tA".into();
        let e = write_lengths(Vec::new(), &padded).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn io_lengths_check_lengths_against() {
        use crate::io::{check_lengths_against, parse_lengths};
        let l = parse_lengths("point_a,point_b,distance\nS1,S2,500\nS1,S9,300\n", "l.csv").unwrap();
        assert!(check_lengths_against(&l, &["S1", "S2", "S9"], "l.csv").is_ok());
        let e = check_lengths_against(&l, &["S1", "S2"], "l.csv").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("l.csv:3: field `point_b`: unknown point `S9`")
        );
    }
}
