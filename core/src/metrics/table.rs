//! Human-readable fixed-width rendering of an [`Evaluation`].

use std::io::{self, Write};

use super::{Evaluation, PairLengthError, Summary};
use crate::dataset::Point;

/// Writes eq. 19 for every pair as a table, row by row as `pairs` yields
/// them: the column widths come from the labels, so nothing is collected.
pub(crate) fn write_pair_table<W: Write + ?Sized>(
    w: &mut W,
    pairs: impl Iterator<Item = PairLengthError>,
    points: &[Point],
) -> io::Result<()> {
    let header = [
        "a",
        "b",
        "n",
        "|ca - cb| [mm]",
        "d_error [mm]",
        "|d|_error [mm]",
    ];
    let label = points
        .iter()
        .map(|p| p.label.chars().count())
        .max()
        .unwrap_or(0);
    let widths = [
        label.max(1),
        label.max(1),
        points
            .iter()
            .map(|p| p.touches.len().to_string().len())
            .max()
            .unwrap_or(1)
            .max(1),
        14,
        12,
        14,
    ];
    let line = |cells: [String; 6]| {
        let mut s = String::new();
        for (c, (cell, w)) in cells.iter().zip(widths).enumerate() {
            if c < 2 {
                s.push_str(&format!("  {cell:<w$}"));
            } else {
                s.push_str(&format!("  {cell:>w$}"));
            }
        }
        s.truncate(s.trim_end().len());
        s.push('\n');
        s
    };
    writeln!(
        w,
        "Length error per pair, paper eq. 19 (no reference length: repeatability, not scale)"
    )?;
    w.write_all(line(header.map(String::from)).as_bytes())?;
    for p in pairs {
        let row = [
            p.a,
            p.b,
            p.pairs.to_string(),
            mm(p.centroid_distance),
            mm(p.d_error),
            mm(p.d_error_abs),
        ];
        w.write_all(line(row).as_bytes())?;
    }
    Ok(())
}

impl Evaluation {
    /// Renders the report as fixed-width plain-text tables for a terminal:
    /// lengths in mm with 4 decimals (0.1 µm), units in the column headers,
    /// rows in the report's order.
    ///
    /// ```
    /// use aacmm_core::{dataset::DataSet, metrics::evaluate};
    /// let touches = [[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0]];
    /// let data = DataSet::from_labels(&["socket"; 4], "m.csv").unwrap();
    /// let ev = evaluate(&data, &touches).unwrap();
    /// let table = ev.to_table();
    /// assert!(table.contains("e [mm]"));
    /// assert!(table.contains("1.4142")); // e = √2
    /// assert!(table.contains("3.2660")); // 2s = 2·sqrt(4·2/3)
    /// ```
    pub fn to_table(&self) -> String {
        [
            self.points_table(),
            self.spread_table(),
            self.pair_table(),
            self.reference_table(),
        ]
        .join("\n")
    }

    fn points_table(&self) -> String {
        let mut table = Table::new(
            &[
                "point",
                "n",
                "X [mm]",
                "Y [mm]",
                "Z [mm]",
                "hr X [mm]",
                "hr Y [mm]",
                "hr Z [mm]",
            ],
            1,
        );
        for p in &self.points {
            table.cell(&p.label);
            table.count(p.touches);
            for &v in p.centroid.iter().chain(&p.half_range) {
                table.mm(v);
            }
        }
        table.render("Points: centroid and per-axis half-range (max - min)/2 (FARO SPAT routine)")
    }

    fn spread_table(&self) -> String {
        let mut table = Table::new(
            &[
                "point",
                "n",
                "e [mm]",
                "sigma [mm]",
                "e+3sigma [mm]",
                "delta_max [mm]",
                "2s [mm]",
            ],
            1,
        );
        for p in &self.points {
            table.cell(&p.label);
            table.count(p.touches);
            for v in [p.e, p.sigma, p.oa, p.delta_max, p.two_s] {
                table.mm(v);
            }
        }
        let per_point = table.render(
            "Single-point articulation: paper eq. 9-12 (e, sigma, OA) and ASME B89.4.22 SPAT \
             (delta_max, 2s: makers quote either; aacmm verify decides on delta_max)",
        );
        let summaries = [
            ("e (paper Fig. 6)", &self.single_point_e),
            ("delta_max", &self.single_point_delta_max),
            ("2s", &self.single_point_two_s),
        ];
        let across = render(
            "Across points (std = population)",
            &SUMMARY_HEADER,
            1,
            summaries.iter().map(|(name, s)| summary_row(name, s)),
        );
        format!("{per_point}\n{across}")
    }

    fn pair_table(&self) -> String {
        let title = "Length error, paper eq. 19 (no reference length: repeatability, not scale)";
        if self.pair_length_summary.is_none() {
            return format!("{title}\n  no pairs: a single point was measured\n");
        }
        let summary = [
            ("d_error (eq. 19 as printed)", &self.pair_length_summary),
            (
                "|d|_error (abs. values, Fig. 7?)",
                &self.pair_length_abs_summary,
            ),
        ]
        .into_iter()
        .filter_map(|(name, s)| s.as_ref().map(|s| summary_row(name, s)));
        let across = match &self.pair_sample {
            None => "all pairs of points".to_string(),
            Some(s) => format!("a sample of the pairs of points ({})", s.describe()),
        };
        render(
            &format!("{title}, across {across} (std = population)"),
            &SUMMARY_HEADER,
            1,
            summary,
        )
    }

    fn reference_table(&self) -> String {
        let title = "Reference lengths: error = measured - reference (ISO 10360-12 E_Uni)";
        let Some(summary) = &self.reference_summary else {
            return format!("{title}\n  none given\n");
        };
        let rows = self.reference.iter().map(|r| {
            vec![
                r.a.clone(),
                r.b.clone(),
                mm(r.reference),
                mm(r.measured),
                mm(r.error),
            ]
        });
        let header = ["a", "b", "reference [mm]", "measured [mm]", "error [mm]"];
        let errors = render(title, &header, 2, rows);
        let mut row = summary_row("error", &summary.error);
        row.extend([summary.max_abs, summary.rms, summary.two_rms].map(mm));
        let mut header = SUMMARY_HEADER.to_vec();
        header.extend(["max |error| [mm]", "RMS [mm]", "2 RMS [mm]"]);
        let across = render(
            "Across references (ASME B89.4.22 volumetric-style summaries; aacmm verify decides each length as E_Uni)",
            &header,
            1,
            [row],
        );
        format!("{errors}\n{across}")
    }
}

/// Columns of a summary row (the text tables and the HTML report).
pub(crate) const SUMMARY_HEADER: [&str; 6] = [
    "figure",
    "count",
    "min [mm]",
    "mean [mm]",
    "max [mm]",
    "std [mm]",
];

fn summary_row(name: &str, s: &Summary) -> Vec<String> {
    let mut row = vec![name.to_owned(), s.count.to_string()];
    row.extend([s.min, s.mean, s.max, s.std].map(mm));
    row
}

/// A length in mm to 4 decimals, without a "-0.0000".
fn mm(v: f64) -> String {
    let mut s = String::new();
    push_mm(&mut s, v);
    s
}

/// [`mm`] written at the end of `out`.
fn push_mm(out: &mut String, v: f64) {
    let start = out.len();
    push_fixed4(out, v);
    if &out[start..] == "-0.0000" {
        out.remove(start);
    }
}

/// [`push_fixed4`] as a string of its own.
#[cfg(test)]
fn fixed4(v: f64) -> String {
    let mut s = String::new();
    push_fixed4(&mut s, v);
    s
}

/// `format!("{v:.4}")`, the same string (a test compares them), from the
/// exact binary value in integer arithmetic: the general formatter's
/// exact mode fell back to big-number arithmetic for most values, a third
/// of `evaluate` on 10⁴ points (6 of these per point). Written at the end
/// of `out`.
fn push_fixed4(out: &mut String, v: f64) {
    // Beyond 2⁴⁷ mm the scaled value may not fit below; no length is.
    if !v.is_finite() || v.abs() >= (1u64 << 47) as f64 {
        use std::fmt::Write as _;
        // Writing into a `String` does not fail.
        _ = write!(out, "{v:.4}");
        return;
    }
    let bits = v.to_bits();
    let negative = bits >> 63 == 1;
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    // v = m · 2^e exactly.
    let (m, e) = if exponent == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1u64 << 52), exponent - 1075)
    };
    let scaled = u128::from(m) * 10_000;
    // n = m · 10⁴ · 2^e rounded to the nearest integer, ties to even (as
    // the formatter rounds the exact value).
    let n = if e >= 0 {
        scaled << e
    } else if -e >= 128 {
        0
    } else {
        let shift = (-e) as u32;
        let (q, r) = (scaled >> shift, scaled & ((1u128 << shift) - 1));
        let half = 1u128 << (shift - 1);
        if r > half || (r == half && q & 1 == 1) {
            q + 1
        } else {
            q
        }
    };
    // Below 2⁴⁷·10⁴ < 2⁶⁴: u64 prints faster than u128.
    push_decimal4(out, n as u64, negative);
}

/// `n / 10⁴` written with four decimals, `-` first when `negative`: the
/// digits by hand — the formatter's machinery cost ten times the
/// arithmetic (`format!` was a tenth of `evaluate` on 10⁴ points).
/// Written at the end of `out`.
fn push_decimal4(out: &mut String, n: u64, negative: bool) {
    // 20 digits of a u64, the point, the sign.
    let mut buf = [0u8; 22];
    let mut i = buf.len();
    let mut x = n;
    for k in 0.. {
        if k == 4 {
            i -= 1;
            buf[i] = b'.';
        }
        i -= 1;
        buf[i] = b'0' + (x % 10) as u8;
        x /= 10;
        if x == 0 && k >= 4 {
            break;
        }
    }
    if negative {
        i -= 1;
        buf[i] = b'-';
    }
    // ASCII digits, a point and a sign: one char a byte.
    out.extend(buf[i..].iter().map(|&b| char::from(b)));
}

/// A titled table: each column as wide as its widest cell, the first `left`
/// columns left-aligned (labels), the others right-aligned (numbers).
fn render(
    title: &str,
    header: &[&str],
    left: usize,
    rows: impl IntoIterator<Item = Vec<String>>,
) -> String {
    let mut table = Table::new(header, left);
    for row in rows {
        for cell in &row {
            table.cell(cell);
        }
    }
    table.render(title)
}

/// A table's cells, row after row, in one buffer — no string per cell
/// (the per-point tables of 10⁴ points were 1.5·10⁵ of them, allocated
/// and freed, most of the time writing them took) — with each column's
/// width in characters so far.
struct Table<'h> {
    header: &'h [&'h str],
    /// The first `left` columns are left-aligned.
    left: usize,
    text: String,
    /// Where each cell ends in `text`.
    ends: Vec<usize>,
    widths: Vec<usize>,
}

impl<'h> Table<'h> {
    fn new(header: &'h [&'h str], left: usize) -> Table<'h> {
        Table {
            header,
            left,
            text: String::new(),
            ends: Vec::new(),
            widths: header.iter().map(|h| chars(h)).collect(),
        }
    }

    /// The next cell; rows are `header.len()` cells each.
    fn cell(&mut self, cell: &str) {
        self.text.push_str(cell);
        self.ended();
    }

    /// A count as the next cell.
    fn count(&mut self, n: usize) {
        use std::fmt::Write as _;
        // Writing into a `String` does not fail.
        _ = write!(self.text, "{n}");
        self.ended();
    }

    /// A length in mm to 4 decimals ([`mm`]) as the next cell.
    fn mm(&mut self, v: f64) {
        push_mm(&mut self.text, v);
        self.ended();
    }

    fn ended(&mut self) {
        let start = self.ends.last().copied().unwrap_or(0);
        let column = self.ends.len() % self.header.len();
        let width = chars(&self.text[start..]);
        self.widths[column] = self.widths[column].max(width);
        self.ends.push(self.text.len());
    }

    /// The table under `title`, each cell padded to its column's width in
    /// characters as `{:<w$}` / `{:>w$}` pad, without the formatter.
    fn render(&self, title: &str) -> String {
        let mut out = format!("{title}\n");
        let cells = (self.ends.iter().scan(0, |start, &end| {
            let cell = &self.text[*start..end];
            *start = end;
            Some(cell)
        }))
        .collect::<Vec<&str>>();
        let lines = std::iter::once(self.header).chain(cells.chunks(self.header.len()));
        // One line written into one buffer, its trailing blanks trimmed.
        let mut text = String::new();
        for line in lines {
            text.clear();
            for (c, (cell, &w)) in line.iter().zip(&self.widths).enumerate() {
                if c > 0 {
                    text.push_str("  ");
                }
                let pad = w.saturating_sub(chars(cell));
                if c >= self.left {
                    text.extend(std::iter::repeat_n(' ', pad));
                }
                text.push_str(cell);
                if c < self.left {
                    text.extend(std::iter::repeat_n(' ', pad));
                }
            }
            out.push_str("  ");
            out.push_str(text.trim_end());
            out.push('\n');
        }
        out
    }
}

/// A cell's width in characters (as the formatter pads), at once for ASCII.
fn chars(s: &str) -> usize {
    if s.is_ascii() {
        s.len()
    } else {
        s.chars().count()
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::eval;
    use super::*;

    /// Cells are padded as the formatter pads them: to the column's width
    /// in characters, left of `left` to the left, the others to the right.
    #[test]
    fn cells_are_padded_as_the_formatter_pads() {
        let rows = vec![
            vec!["Ω₁".to_string(), "1.5".to_string(), "x".to_string()],
            vec![
                "point-long".to_string(),
                "-12.25".to_string(),
                "éé".to_string(),
            ],
        ];
        let got = render("T", &["pt", "value", "n"], 1, rows.clone());
        let widths = [10, 6, 2];
        let mut want = String::from("T\n");
        for line in [vec!["pt".to_string(), "value".into(), "n".into()]]
            .iter()
            .chain(&rows)
        {
            let cells = [
                format!("{:<w$}", line[0], w = widths[0]),
                format!("{:>w$}", line[1], w = widths[1]),
                format!("{:>w$}", line[2], w = widths[2]),
            ];
            want.push_str(&format!("  {}\n", cells.join("  ").trim_end()));
        }
        assert_eq!(got, want);
    }

    #[test]
    fn negative_zero_is_printed_as_zero() {
        assert_eq!(mm(-1e-9), "0.0000");
        // The integer formatter is the formatter's string: random values
        // over many magnitudes, both signs, ties (k/32 is exact and ends
        // in 5 at the fifth decimal), subnormals, zeros and the specials.
        let mut rng = crate::random::rng(4, 0);
        let mut values: Vec<f64> = vec![
            0.0,
            -0.0,
            0.03125,
            -0.03125,
            0.09375,
            2.5e-5,
            5e-5,
            1.5e-4,
            1e-300,
            -5e-324,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            1.4e14,
            -3e15,
            1.23456,
            2.00005,
        ];
        values.extend((0..4096).map(|k| f64::from(k) / 32.0 - 64.0));
        for _ in 0..200_000 {
            let mantissa: f64 = rand::RngExt::random_range(&mut rng, -1.0..1.0);
            let power: i32 = rand::RngExt::random_range(&mut rng, -12..16);
            values.push(mantissa * 10f64.powi(power));
        }
        for v in values {
            assert_eq!(fixed4(v), format!("{v:.4}"), "{v:e}");
        }
        assert_eq!(mm(-0.00005001), "-0.0001");
        assert_eq!(mm(1.23456), "1.2346");
    }

    #[test]
    fn columns_are_aligned() {
        let t = render(
            "T",
            &["name", "v"],
            1,
            [vec!["long-name".into(), "1.0000".into()]],
        );
        assert_eq!(t, "T\n  name            v\n  long-name  1.0000\n");
    }

    #[test]
    fn full_report_has_every_section() {
        // p at the origin, q at (0, 0, 100.001): centroid distance 100.001
        let labels = ["p", "p", "p", "q", "q", "q"];
        let points = [
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [0.0, 0.0, 100.001],
            [0.0, 0.0, 100.001],
            [0.0, 0.0, 100.001],
        ];
        let t = eval(&labels, &points, &[("p", "q", 100.0)])
            .unwrap()
            .to_table();
        for needle in [
            "Points",
            "Single-point",
            "eq. 19",
            "Reference lengths",
            "100.0010",
            "0.0010",
        ] {
            assert!(t.contains(needle), "missing {needle:?} in\n{t}");
        }
        assert!(t.contains("aacmm verify decides each length as E_Uni"));
        assert!(!t.contains("unverified"), "{t}");
    }

    #[test]
    fn single_point_report_says_what_is_missing() {
        let t = eval(&["p"; 3], &[[0.0; 3]; 3], &[]).unwrap().to_table();
        assert!(t.contains("no pairs"));
        assert!(t.contains("none given"));
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn metrics_table_write_pair_table() {
        use crate::{
            dataset::DataSet,
            metrics::{evaluate, pair_length_errors, write_pair_table},
        };
        let data = DataSet::from_labels(&["a", "a", "a", "bb", "bb", "bb"], "m.csv").unwrap();
        let xyz = [
            [0.0; 3],
            [0.0; 3],
            [0.0; 3],
            [3.0, 4.0, 0.0],
            [3.0, 4.0, 0.0],
            [3.0, 4.0, 0.0],
        ];
        let ev = evaluate(&data, &xyz).unwrap();
        let mut out = Vec::new();
        write_pair_table(
            &mut out,
            pair_length_errors(&data, &xyz, &ev.points),
            data.points(),
        )
        .unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(
            text.lines().nth(2).unwrap().starts_with("  a   bb  3"),
            "{text}"
        );
        assert!(text.contains("5.0000"));
    }
}
