//! Point files: labelled coordinates, CSV with the header `point,x,y,z` (mm).
//!
//! ```text
//! point,x,y,z
//! S1,512.000000,-103.250000,88.125000
//! ```
//!
//! Written by `aacmm points` (computed probe centres) and read for socket
//! positions. Labels are unique within a file. The CSV dialect is described
//! in the [`io`](super) module docs.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use super::text::{check_header, invalid, parse_f64, quote, read_text, table};
use crate::error::InputError;

const COLUMNS: [&str; 4] = ["point", "x", "y", "z"];
const SHAPE: &str = "point,x,y,z";

/// Writes labelled points, mm, with a fixed 6 decimals (1 nm: far below any
/// arm's accuracy, so the file is exact for practical purposes but not a
/// bit-exact round trip). Deterministic bytes; labels quoted only where
/// needed. `labels` and `xyz` of different lengths, or a label with
/// surrounding whitespace (reading trims it), give an
/// [`std::io::ErrorKind::InvalidInput`] error.
///
/// ```
/// let mut out = Vec::new();
/// aacmm_core::io::write_points(&mut out, &["S1"], &[[1.0, -2.5, 1.0 / 3.0]]).unwrap();
/// assert_eq!(String::from_utf8(out).unwrap(), "point,x,y,z\nS1,1.000000,-2.500000,0.333333\n");
/// ```
pub fn write_points<S: AsRef<str>>(
    mut w: impl Write,
    labels: &[S],
    xyz: &[[f64; 3]],
) -> std::io::Result<()> {
    if labels.len() != xyz.len() {
        let message = format!("{} labels for {} points", labels.len(), xyz.len());
        return Err(invalid(message));
    }
    w.write_all(format!("{SHAPE}\n").as_bytes())?;
    for (label, [x, y, z]) in labels.iter().zip(xyz) {
        let line = format!("{},{x:.6},{y:.6},{z:.6}\n", quote(label.as_ref())?);
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// Reads a point file (standard input for `-`); messages name the file as
/// [`source_name`](super::source_name) gives it.
///
/// ```no_run
/// let sockets = aacmm_core::io::read_points(std::path::Path::new("sockets.csv"))?;
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn read_points(path: &Path) -> Result<Vec<(String, [f64; 3])>, InputError> {
    let (file, text) = read_text(path)?;
    parse_points(&text, &file)
}

/// Parses the text of a point file; `file` is the name used in messages.
///
/// ```
/// use aacmm_core::io::parse_points;
/// let p = parse_points("point,x,y,z\nS1,1,2,3.5\n", "s.csv").unwrap();
/// assert_eq!(p, [("S1".to_string(), [1.0, 2.0, 3.5])]);
/// let e = parse_points("point,x,y,z\nS1,1,2,3\nS1,4,5,6\n", "s.csv").unwrap_err();
/// assert!(e.to_string().starts_with("s.csv:3: field `point`: duplicate label `S1`"));
/// ```
pub fn parse_points(text: &str, file: &str) -> Result<Vec<(String, [f64; 3])>, InputError> {
    let (_, rows) = table(text, file, SHAPE, "one row per point", |header| {
        check_header(header, file, &COLUMNS, SHAPE)
    })?;
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::with_capacity(rows.len());
    for row in rows {
        let label = &row.fields[0];
        if label.is_empty() {
            return Err(InputError::field(file, row.line, "point", "empty label"));
        }
        if let Some(first) = seen.insert(label.clone(), row.line) {
            return Err(InputError::field(
                file,
                row.line,
                "point",
                format!("duplicate label `{label}` (first on line {first})"),
            ));
        }
        let mut xyz = [0.0; 3];
        for (v, (s, col)) in xyz
            .iter_mut()
            .zip(row.fields[1..].iter().zip(&COLUMNS[1..]))
        {
            *v = parse_f64(s, file, row.line, col)?;
        }
        out.push((label.clone(), xyz));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const F: &str = "sockets.csv";

    fn err(text: &str) -> InputError {
        parse_points(text, F).unwrap_err()
    }

    #[track_caller]
    fn assert_at(e: &InputError, line: usize, field: Option<&str>, needle: &str) {
        crate::io::testing::assert_at(e, F, line, field, needle);
    }

    #[test]
    fn errors() {
        assert_at(&err(""), 0, None, "empty file");
        assert_at(&err("point,x,y,z\n"), 0, None, "no data rows");
        assert_at(&err("point,x,y\nA,1,2\n"), 1, Some("z"), "missing column 4");
        assert_at(&err("point,x,z,y\nA,1,2,3\n"), 1, Some("z"), "expected `y`");
        assert_at(
            &err("point,x,y,z,w\nA,1,2,3,4\n"),
            1,
            Some("w"),
            "unexpected column 5",
        );
        assert_at(
            &err("point,x,x,z\nA,1,2,3\n"),
            1,
            Some("x"),
            "duplicate column",
        );
        assert_at(&err("point,x,y,z\nA,1,2\n"), 2, Some("z"), "missing");
        assert_at(
            &err("point,x,y,z\nA,1,2,3,4\n"),
            2,
            None,
            "the row has 5 columns",
        );
        assert_at(
            &err("point,x,y,z\n,1,2,3\n"),
            2,
            Some("point"),
            "empty label",
        );
        assert_at(
            &err("point,x,y,z\nA,1,2,3\nB,1,y,3\n"),
            3,
            Some("y"),
            "not a number",
        );
        assert_at(
            &err("point,x,y,z\nA,inf,2,3\n"),
            2,
            Some("x"),
            "not a finite number",
        );
        assert_at(
            &err("point,x,y,z\nA,1,2,3\n\nB,1,2,3\n"),
            3,
            None,
            "blank line",
        );
        assert_at(
            &err("point,x,y,z\nA,1,2,3\n#moved,1,2,3\nA,1,2,3\n"),
            4,
            Some("point"),
            "duplicate label `A` (first on line 2)",
        );
    }

    #[test]
    fn round_trip_6_decimals() {
        let labels = ["S1", "S,2", "#3"];
        let xyz = [
            [1.0, -2.0, 0.0],
            [123.456789, -0.0000004, 1e6],
            [1.0 / 3.0, 2.5, -7.25],
        ];
        let mut out = Vec::new();
        write_points(&mut out, &labels, &xyz).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(
            text.contains("\"S,2\",123.456789,-0.000000,1000000.000000\n"),
            "{text}"
        );
        let back = parse_points(&text, F).unwrap();
        for ((l, p), (wl, wp)) in back.iter().zip(labels.iter().zip(&xyz)) {
            assert_eq!(l, wl);
            for (a, b) in p.iter().zip(wp) {
                assert!((a - b).abs() <= 5e-7, "{a} {b}");
            }
        }
        // Values with at most 6 decimals come back identical, and so do the bytes.
        let mut again = Vec::new();
        let (l2, p2): (Vec<String>, Vec<[f64; 3]>) = back.into_iter().unzip();
        write_points(&mut again, &l2, &p2).unwrap();
        assert_eq!(String::from_utf8(again).unwrap(), text);
    }

    #[test]
    fn write_rejects_mismatch() {
        let e = write_points(Vec::new(), &["A", "B"], &[[0.0; 3]]).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        let e = write_points(Vec::new(), &["A "], &[[0.0; 3]]).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    }
}
