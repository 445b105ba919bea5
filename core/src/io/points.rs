//! Point files: labelled coordinates, CSV with the header `point,x,y,z` (mm).
//!
//! ```text
//! point,x,y,z
//! S1,512.000000,-103.250000,88.125000
//! ```
//!
//! Written by `aacmm points` (computed probe centres; with `--pose` also
//! the tool's orientation, `point,x,y,z,qw,qx,qy,qz`: [`write_tool_poses`]) and
//! read for socket positions. Labels are unique within a file. The CSV dialect is described
//! in the [`io`](super) module docs.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use super::text::{check_header, invalid, parse_f64, quote, read_text, scan_table};
use crate::error::{InputError, quoted};
use crate::kernel::Pose;

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
    w: impl Write,
    labels: impl IntoIterator<Item = S, IntoIter: ExactSizeIterator>,
    xyz: &[[f64; 3]],
) -> std::io::Result<()> {
    write_rows(w, labels, xyz.len(), SHAPE, |line, i| {
        push_xyz(line, xyz[i])
    })
}

/// [`write_points`] or, with `poses`, [`write_tool_poses`] (their
/// positions), with one more column `u95_mm` from `u95`: the radius that
/// holds each position's error with 95 % probability (mm, 6 decimals).
/// Errors as [`write_points`], also for `u95` of another length.
///
/// ```
/// let mut out = Vec::new();
/// aacmm_core::io::write_points_u95(&mut out, &["S1"], &[[1.0, 2.0, 3.0]], None, &[0.0125]).unwrap();
/// assert_eq!(String::from_utf8(out).unwrap(), "point,x,y,z,u95_mm\nS1,1.000000,2.000000,3.000000,0.012500\n");
/// ```
pub fn write_points_u95<S: AsRef<str>>(
    w: impl Write,
    labels: impl IntoIterator<Item = S, IntoIter: ExactSizeIterator>,
    xyz: &[[f64; 3]],
    poses: Option<&[Pose]>,
    u95: &[f64],
) -> std::io::Result<()> {
    if u95.len() != xyz.len() || poses.is_some_and(|p| p.len() != xyz.len()) {
        return Err(invalid(format!(
            "{} radii for {} points",
            u95.len(),
            xyz.len()
        )));
    }
    let header = match poses {
        Some(_) => format!("{SHAPE},qw,qx,qy,qz,u95_mm"),
        None => format!("{SHAPE},u95_mm"),
    };
    write_rows(w, labels, xyz.len(), &header, |line, i| {
        match poses {
            Some(p) => push_pose(line, &p[i]),
            None => push_xyz(line, xyz[i]),
        }
        line.push(',');
        push_fixed6(line, u95[i]);
    })
}

/// Writes `header`, then per label its quoted label and what `row` adds
/// for its index.
fn write_rows<S: AsRef<str>>(
    mut w: impl Write,
    labels: impl IntoIterator<Item = S, IntoIter: ExactSizeIterator>,
    n: usize,
    header: &str,
    row: impl Fn(&mut String, usize),
) -> std::io::Result<()> {
    let labels = labels.into_iter();
    if labels.len() != n {
        let message = format!("{} labels for {n} points", labels.len());
        return Err(invalid(message));
    }
    w.write_all(format!("{header}\n").as_bytes())?;
    let mut line = String::new();
    for (i, label) in labels.enumerate() {
        line.clear();
        line.push_str(&quote(label.as_ref())?);
        row(&mut line, i);
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// `,x,y,z`, 6 decimals.
fn push_xyz(line: &mut String, xyz: [f64; 3]) {
    for v in xyz {
        line.push(',');
        push_fixed6(line, v);
    }
}

/// `,x,y,z,qw,qx,qy,qz`: 6 and 9 decimals.
fn push_pose(line: &mut String, pose: &Pose) {
    use std::fmt::Write as _;
    push_xyz(line, pose.position);
    for v in pose.quaternion() {
        _ = write!(line, ",{v:.9}");
    }
}

/// Writes labelled tool poses: `point,x,y,z,qw,qx,qy,qz`, the probe's
/// position (mm, 6 decimals as [`write_points`]) and the tool frame's
/// orientation as a unit quaternion (9 decimals: 10⁻⁹ of a unit
/// quaternion is 2·10⁻⁹ rad, 0.4 mas, far below any arm's repeatability),
/// `w ≥ 0` ([`Pose::quaternion`]'s sign convention). Errors as
/// [`write_points`].
///
/// ```
/// use aacmm_core::kernel::Pose;
/// let half_turn = Pose {
///     rotation: [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
///     position: [1.0, 2.0, 3.0],
/// };
/// let mut out = Vec::new();
/// aacmm_core::io::write_tool_poses(&mut out, &["S1"], &[half_turn]).unwrap();
/// assert_eq!(
///     String::from_utf8(out).unwrap(),
///     "point,x,y,z,qw,qx,qy,qz\nS1,1.000000,2.000000,3.000000,0.000000000,0.000000000,0.000000000,1.000000000\n"
/// );
/// ```
pub fn write_tool_poses<S: AsRef<str>>(
    w: impl Write,
    labels: impl IntoIterator<Item = S, IntoIter: ExactSizeIterator>,
    poses: &[Pose],
) -> std::io::Result<()> {
    let header = format!("{SHAPE},qw,qx,qy,qz");
    write_rows(w, labels, poses.len(), &header, |line, i| {
        push_pose(line, &poses[i]);
    })
}

/// Appends `x` with 6 decimals, the bytes of `format!("{x:.6}")`: the
/// exact binary value rounded half to even, the sign kept (`-0.000000`).
/// Integer arithmetic where it is exact (|x| < 2⁴⁹), the standard
/// formatter elsewhere.
fn push_fixed6(out: &mut String, x: f64) {
    use std::fmt::Write as _;
    const SCALE: u128 = 1_000_000;
    if !x.is_finite() || x.abs() >= (1u64 << 49) as f64 {
        _ = write!(out, "{x:.6}");
        return;
    }
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1 << 52) - 1);
    // x = m·2^-shift exactly, shift > 0 below 2⁴⁹.
    let (m, shift) = match biased {
        0 => (fraction, 1074),
        _ => (fraction | (1 << 52), 1075 - biased),
    };
    // m·10⁶ < 2⁷³: exact in u128; below 2^-74 the value rounds to 0.
    let scaled = u128::from(m) * SCALE;
    let micro = if shift >= 127 {
        0
    } else {
        let (q, r) = (scaled >> shift, scaled & ((1u128 << shift) - 1));
        let half = 1u128 << (shift - 1);
        q + u128::from(r > half || (r == half && q & 1 == 1))
    };
    if bits >> 63 == 1 {
        out.push('-');
    }
    // Both parts fit in u64 (the integer part is below 2⁴⁹); digits by
    // hand, the formatting machinery costs more than the rounding.
    let (int, frac) = ((micro / SCALE) as u64, (micro % SCALE) as u64);
    let mut digits = [b'0'; 20];
    let mut at = digits.len();
    let mut rest = int;
    loop {
        at -= 1;
        digits[at] = b'0' + (rest % 10) as u8;
        rest /= 10;
        if rest == 0 {
            break;
        }
    }
    let mut fraction = [b'.', 0, 0, 0, 0, 0, 0];
    let mut rest = frac;
    for d in fraction[1..].iter_mut().rev() {
        *d = b'0' + (rest % 10) as u8;
        rest /= 10;
    }
    // Invariant: every byte written above is an ASCII digit or the point.
    for part in [&digits[at..], &fraction[..]] {
        out.push_str(std::str::from_utf8(part).expect("ASCII digits"));
    }
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
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::new();
    let check = |header: &super::text::Record| check_header(header, file, &COLUMNS, SHAPE);
    scan_table(
        text,
        file,
        SHAPE,
        "one row per point",
        check,
        |_, line, fields| {
            let label = fields[0];
            if label.is_empty() {
                return Err(InputError::field(file, line, "point", "empty label"));
            }
            if let Some(first) = seen.insert(label.to_string(), line) {
                return Err(InputError::field(
                    file,
                    line,
                    "point",
                    format!("duplicate label {} (first on line {first})", quoted(label)),
                ));
            }
            let mut xyz = [0.0; 3];
            for (v, (s, col)) in xyz.iter_mut().zip(fields[1..].iter().zip(&COLUMNS[1..])) {
                *v = parse_f64(s, file, line, col)?;
            }
            let memory = |e| InputError::memory(file, e);
            crate::memory::try_grow(&mut out, "the points' rows", 1).map_err(memory)?;
            out.push((label.to_string(), xyz));
            Ok(())
        },
    )?;
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

    /// The fixed-point writer gives the standard formatter's bytes: ties
    /// (multiples of 2⁻⁷), tiny, negative, huge and random values.
    #[test]
    fn six_decimals_as_the_standard_formatter() {
        use rand::{RngExt, SeedableRng};
        let mut values = vec![
            0.0,
            -0.0,
            1e-300,
            -1e-300,
            f64::MIN_POSITIVE / 3.0,
            -4e-7,
            5e-7,
            4.999999999e-7,
            0.5,
            (1u64 << 49) as f64,
            (1u64 << 49) as f64 - 0.5,
            1e300,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        values.extend((0..4096).map(|k| f64::from(k) / 128.0 - 16.0));
        values.extend((0..4096).map(|k| f64::from(k) * 1e-6 + 2.5e-7));
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for _ in 0..200_000 {
            let v: f64 = rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-10..16));
            values.push(v);
            values.push(f64::from_bits(rng.random::<u64>()));
        }
        for v in values {
            let mut s = String::new();
            push_fixed6(&mut s, v);
            assert_eq!(s, format!("{v:.6}"), "{v:e}");
        }
    }

    #[test]
    fn write_rejects_mismatch() {
        let e = write_points(Vec::new(), &["A", "B"], &[[0.0; 3]]).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        let e = write_points(Vec::new(), &["A "], &[[0.0; 3]]).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    }
}
