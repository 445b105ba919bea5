//! Reference-position files: where an instrument (a laser tracker, an
//! optical CMM) saw the probe or target, or the certified centre of an
//! artefact's sphere the arm touched — CSV with the header
//! `point,q1,…,qn,x,y,z` and the optional columns `qw,qx,qy,qz`,
//! `frame`, `tool`, `uncertainty`, `temperature`, `time` and `approach`
//! ([`super::approach`]), in that order.
//!
//! ```text
//! point,q1,q2,q3,q4,q5,q6,x,y,z,frame,uncertainty
//! P1,10,-45,120,-80,60,0,-430.3,-6.27,-98.6,tracker,0.015
//! P2,12,-44,118,-78,61,5,-463.7,-3.94,-104.9,tracker,
//! ```
//!
//! `x,y,z` are mm in the instrument's (or the artefact placement's) own
//! frame; every `frame` gets its own unknown rigid registration, found from
//! the data. Without a `frame` column every row is in one frame named
//! [`DEFAULT_FRAME`]. `qw,qx,qy,qz` (all four or none) is the tool's
//! orientation where the instrument sees it (a 6-D target, a rigid body):
//! a unit quaternion (length 1 within [`UNIT_QUATERNION_TOLERANCE`]), the
//! tool frame in the row's frame; a row with the four cells empty has a
//! position only. `uncertainty` is a standard uncertainty per
//! coordinate, mm, `> 0`; an empty cell means "not stated" (the noise model
//! of the command line applies). Rows with the same `point` label in one
//! frame are the same physical point (a sphere touched in several poses).
//! Joint readings are in the unit the caller declares, as in a poses file.
//! `temperature` (°C, of the arm when the row was taken) and `time` (s,
//! from any origin) are what a thermal expansion or a drift is fitted
//! against ([`crate::corrections`]); where a column is present every row
//! gives it. `tool` names the tool point the instrument saw (a marker, an
//! SMR, a stylus: the arm file's `[[tool]]`, [`super::tools`]); an empty
//! cell, or no column, is the default tool (the arm's `[probe]`, named
//! [`crate::domain::DEFAULT_TOOL`]); a name the arm does not know is an error
//! naming the line, the field and the arm's tools.

use std::path::Path;

use std::io::Write;

use super::approach::{APPROACH, approach_cell};
use super::columns::JointColumns;
use super::text::{Record, check_header, fmt_f64, parse_f64, quote, read_text, scan_table};
use super::units::AngleUnit;
use crate::domain::{DEFAULT_FRAME, Positions, UNIT_QUATERNION_TOLERANCE};
use crate::error::InputError;

/// The fewest rows a named tool's offset (three unknowns) is fitted from.
pub(crate) const MIN_TOOL_ROWS: usize = 2;

/// The orientation columns, in the order they follow `x,y,z`.
const ORIENTATION: [&str; 4] = ["qw", "qx", "qy", "qz"];

/// Writes positions in the file format, readings in `unit`: deterministic
/// bytes, numbers in the shortest form that reads back to the same value.
/// The `frame` column is written unless every row is in [`DEFAULT_FRAME`],
/// the `qw,qx,qy,qz` columns when any row gives an orientation, the
/// `uncertainty` column when any row states one.
///
/// ```
/// use aacmm_core::domain::Positions;
/// use aacmm_core::io::{AngleUnit, positions::write_positions};
/// let mut p = Positions::new(1);
/// p.push("P1", "instrument", &[0.5], [1.0, 2.0, 3.0], None, 0);
/// let mut out = Vec::new();
/// write_positions(&mut out, &p, AngleUnit::Rad).unwrap();
/// assert_eq!(String::from_utf8(out).unwrap(), "point,q1,x,y,z\nP1,0.5,1.0,2.0,3.0\n");
/// ```
///
/// # Errors
///
/// The writer's; a label with surrounding whitespace (reading trims it).
pub fn write_positions(mut w: impl Write, p: &Positions, unit: AngleUnit) -> std::io::Result<()> {
    let with_frame = p.frames().iter().any(|f| f != DEFAULT_FRAME);
    let with_u = p.uncertainty.iter().any(Option::is_some);
    let with_orientation = p.oriented_rows() > 0;
    let with_tool = p.has_tools();
    let mut header = String::from("point");
    for j in 1..=p.joints {
        header.push_str(&format!(",q{j}"));
    }
    header.push_str(",x,y,z");
    if with_orientation {
        header.push_str(",qw,qx,qy,qz");
    }
    if with_frame {
        header.push_str(",frame");
    }
    if with_tool {
        header.push_str(",tool");
    }
    if with_u {
        header.push_str(",uncertainty");
    }
    let conditions = [("temperature", p.temperatures()), ("time", p.times())];
    for (name, column) in conditions {
        if column.is_some() {
            header.push(',');
            header.push_str(name);
        }
    }
    if p.approach.is_some() {
        header.push(',');
        header.push_str(APPROACH);
    }
    header.push('\n');
    w.write_all(header.as_bytes())?;
    for i in 0..p.len() {
        let mut line = quote(p.label(i))?.into_owned();
        for (j, &x) in p.reading(i).iter().enumerate() {
            line.push(',');
            let written = JointColumns::to_written(p.prismatic, j, x, unit);
            line.push_str(&fmt_f64(written));
        }
        for v in p.position(i) {
            line.push(',');
            line.push_str(&fmt_f64(v));
        }
        if with_orientation {
            match p.orientation(i) {
                Some(o) => o.iter().for_each(|&v| {
                    line.push(',');
                    line.push_str(&fmt_f64(v));
                }),
                None => line.push_str(",,,,"),
            }
        }
        if with_frame {
            line.push(',');
            line.push_str(&quote(&p.frames()[p.frame(i)])?);
        }
        if with_tool {
            line.push(',');
            if p.tool(i) != 0 {
                line.push_str(&quote(&p.tools()[p.tool(i)])?);
            }
        }
        if with_u {
            line.push(',');
            if let Some(u) = p.uncertainty(i) {
                line.push_str(&fmt_f64(u));
            }
        }
        for (_, column) in conditions {
            if let Some(c) = column {
                line.push(',');
                line.push_str(&fmt_f64(c[i]));
            }
        }
        if let Some(a) = &p.approach {
            line.push(',');
            line.push_str(&approach_cell(&a[i * p.joints..(i + 1) * p.joints]));
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// The columns after the joints: `x,y,z` and which optional ones.
struct Layout {
    joints: usize,
    /// The column of `qw` (`qx,qy,qz` follow it).
    orientation: Option<usize>,
    frame: Option<usize>,
    tool: Option<usize>,
    uncertainty: Option<usize>,
    temperature: Option<usize>,
    time: Option<usize>,
    approach: Option<usize>,
}

const SHAPE: &str = "point,q1,...,qn,x,y,z[,qw,qx,qy,qz][,frame][,tool][,uncertainty][,temperature][,time][,approach]";

/// Reads a reference-position file (standard input for `-`), readings in
/// `unit` (a prismatic joint's in mm, [`JointColumns`]); messages name the
/// file as [`super::source_name`] gives it.
///
/// # Errors
///
/// As [`parse_positions`].
pub fn read_positions(
    path: &Path,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<Positions, InputError> {
    let (file, text) = read_text(path)?;
    parse_positions(&text, &file, unit, joints)
}

/// Parses the text of a reference-position file; `file` names it in
/// messages.
///
/// # Errors
///
/// A header other than `point,q1,...,qn,x,y,z[,qw,qx,qy,qz][,frame][,uncertainty]`
/// (or another joint count than `expected_joints`, or only some of the
/// orientation columns), an empty label or frame, a value that is not a
/// finite number, an uncertainty that is not positive, a row with some but
/// not all of its orientation cells, a quaternion whose length is not 1
/// within [`UNIT_QUATERNION_TOLERANCE`], and a frame with fewer
/// than [`MIN_FRAME_POSITIONS`](crate::domain::MIN_FRAME_POSITIONS) rows or with positions on one line (a
/// registration needs three points that span a plane): each naming the
/// line and field.
pub fn parse_positions(
    text: &str,
    file: &str,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<Positions, InputError> {
    let columns = joints.into();
    let expected_joints = columns.expected();
    let mut layout: Option<Layout> = None;
    let mut out: Option<Positions> = None;
    let mut q = Vec::new();
    scan_table(
        text,
        file,
        SHAPE,
        "one row per position",
        |h| header_layout(h, file, expected_joints).map(|_| ()),
        |h, line, f| {
            let l = match &layout {
                Some(l) => l,
                None => layout.insert(header_layout(h, file, expected_joints)?),
            };
            let out = out.get_or_insert_with(|| {
                let mut first = Positions::new(l.joints);
                first.prismatic = columns.prismatic_mask();
                first
            });
            parse_row(l, f, (file, line), (unit, &columns), &mut q, out)
        },
    )?;
    let mut out = out.unwrap_or_else(|| Positions::new(0));
    if let Some(known) = columns.tools() {
        out.resolve_tools(known, file)?;
    }
    check_frames(&out, file)?;
    Ok(out)
}

/// The header's joint count and optional columns, checked.
fn header_layout(
    h: &Record,
    file: &str,
    expected_joints: Option<usize>,
) -> Result<Layout, InputError> {
    let fields = &h.fields;
    let optional = |name: &str| fields.iter().position(|f| f == name);
    let (frame, uncertainty) = (optional("frame"), optional("uncertainty"));
    let tool = optional("tool");
    let (temperature, time) = (optional("temperature"), optional("time"));
    let approach = optional(APPROACH);
    let orientation = orientation_columns(h, file)?;
    let extra = [frame, tool, uncertainty, temperature, time, approach]
        .iter()
        .filter(|c| c.is_some())
        .count()
        + 4 * usize::from(orientation);
    let joints = fields.len().saturating_sub(4 + extra);
    let want = expected_joints.unwrap_or(joints);
    let mut expected: Vec<String> = vec!["point".into()];
    expected.extend((1..=want).map(|j| format!("q{j}")));
    expected.extend(["x", "y", "z"].map(String::from));
    if orientation {
        expected.extend(ORIENTATION.map(String::from));
    }
    if frame.is_some() {
        expected.push("frame".into());
    }
    if tool.is_some() {
        expected.push("tool".into());
    }
    for (column, name) in [
        (uncertainty, "uncertainty"),
        (temperature, "temperature"),
        (time, "time"),
        (approach, APPROACH),
    ] {
        if column.is_some() {
            expected.push(name.into());
        }
    }
    let names: Vec<&str> = expected.iter().map(String::as_str).collect();
    let shape = format!("point,q1,...,q{want},x,y,z{}", {
        let tail: Vec<&str> = names[1 + want + 3..].to_vec();
        tail.iter().map(|n| format!(",{n}")).collect::<String>()
    });
    check_header(h, file, &names, &shape)?;
    if want == 0 {
        return Err(InputError::field(
            file,
            h.line,
            "q1",
            format!("missing joint columns in the header; the header must be `{SHAPE}`"),
        ));
    }
    Ok(Layout {
        joints: want,
        orientation: orientation.then_some(1 + want + 3),
        frame,
        tool,
        uncertainty,
        temperature,
        time,
        approach,
    })
}

/// Whether the header has the orientation columns: all four, or none —
/// some of them is an error naming the first missing.
fn orientation_columns(h: &Record, file: &str) -> Result<bool, InputError> {
    let present = ORIENTATION.map(|name| h.fields.iter().any(|f| f == name));
    match present.iter().position(|&p| !p) {
        None => Ok(true),
        Some(_) if !present.contains(&true) => Ok(false),
        Some(missing) => Err(InputError::field(
            file,
            h.line,
            ORIENTATION[missing],
            "orientation columns incomplete: a tool's orientation is the four columns \
             `qw,qx,qy,qz` (a unit quaternion) after `x,y,z`; give all four or none",
        )),
    }
}

/// Row's orientation cells (from column `c`): all four empty is none, a
/// quaternion of length 1 within [`UNIT_QUATERNION_TOLERANCE`] is read;
/// anything else an error naming the line and field.
fn parse_orientation(
    f: &[&str],
    c: usize,
    (file, line): (&str, usize),
) -> Result<Option<[f64; 4]>, InputError> {
    let cells = &f[c..c + 4];
    if cells.iter().all(|s| s.is_empty()) {
        return Ok(None);
    }
    if let Some(k) = cells.iter().position(|s| s.is_empty()) {
        let message = "empty: an orientation gives all four of `qw,qx,qy,qz` (or none)";
        return Err(InputError::field(file, line, ORIENTATION[k], message));
    }
    let mut q = [0.0; 4];
    for (k, name) in ORIENTATION.iter().enumerate() {
        q[k] = parse_f64(cells[k], file, line, name)?;
    }
    let length = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if (length - 1.0).abs() > UNIT_QUATERNION_TOLERANCE {
        let message = format!(
            "the quaternion ({}) has length {length}, not 1 (within \
             {UNIT_QUATERNION_TOLERANCE}): the orientation must be a unit quaternion, \
             scalar first",
            cells.join(", ")
        );
        return Err(InputError::field(file, line, "qw,qx,qy,qz", message));
    }
    Ok(Some(q))
}

/// One data row into `out`.
fn parse_row(
    l: &Layout,
    f: &[&str],
    (file, line): (&str, usize),
    (unit, columns): (AngleUnit, &JointColumns),
    q: &mut Vec<f64>,
    out: &mut Positions,
) -> Result<(), InputError> {
    let error = |field: &str, message: &str| Err(InputError::field(file, line, field, message));
    if f[0].is_empty() {
        return error(
            "point",
            "empty label: each row must name the point or target seen",
        );
    }
    q.clear();
    for j in 0..l.joints {
        let v = parse_f64(f[1 + j], file, line, &format!("q{}", j + 1))?;
        columns.check_stroke(j, v, file, line)?;
        q.push(columns.to_internal(j, v, unit));
    }
    let mut xyz = [0.0; 3];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        xyz[k] = parse_f64(f[1 + l.joints + k], file, line, name)?;
    }
    let frame = match l.frame {
        Some(c) if f[c].is_empty() => {
            return error("frame", "empty frame: name the station or placement");
        }
        Some(c) => f[c],
        None => DEFAULT_FRAME,
    };
    let uncertainty = match l.uncertainty.map(|c| f[c]).filter(|s| !s.is_empty()) {
        None => None,
        Some(s) => match parse_f64(s, file, line, "uncertainty")? {
            u if u > 0.0 => Some(u),
            _ => {
                let message = format!(
                    "must be positive (a standard uncertainty, mm), got {}",
                    crate::error::shown(s)
                );
                return error("uncertainty", &message);
            }
        },
    };
    let orientation = match l.orientation {
        Some(c) => parse_orientation(f, c, (file, line))?,
        None => None,
    };
    (out.try_push(f[0], frame, q, xyz, uncertainty, line))
        .map_err(|e| InputError::memory(file, e))?;
    out.set_orientation(orientation);
    if let Some(c) = l.tool {
        let cell = f[c];
        if let Some(known) = columns.tools() {
            known.of_cell(cell, file, line)?;
        }
        out.set_tool(cell);
    }
    let condition = |c: Option<usize>, name: &str| match c {
        None => Ok(None),
        Some(c) if f[c].is_empty() => Err(InputError::field(
            file,
            line,
            name,
            "empty: where the column is given, every row gives it",
        )),
        Some(c) => parse_f64(f[c], file, line, name).map(Some),
    };
    let (t, s) = (
        condition(l.temperature, "temperature")?,
        condition(l.time, "time")?,
    );
    if let Some(t) = t.filter(|t| !(-100.0..=200.0).contains(t)) {
        let message = format!("{t} °C: not an arm's temperature (°C expected, −100 to 200)");
        return error("temperature", &message);
    }
    let mut signs = Vec::with_capacity(l.joints);
    if let Some(c) = l.approach {
        super::approach::parse_approach(f[c], l.joints, (file, line), &mut signs)?;
    }
    out.record(t, s);
    out.record_approach(l.approach.map(|_| &signs[..]));
    Ok(())
}

/// What the reader adds to [`Positions`]: the tools it names, checked
/// against an arm's in a file's words.
impl Positions {
    /// Takes each named tool's nominal offset from `known` (an arm's
    /// tools); `file` names the rows' file in messages.
    ///
    /// # Errors
    ///
    /// The first row naming a tool `known` does not have; a named tool
    /// seen in fewer than [`MIN_TOOL_ROWS`] rows (its offset, three
    /// unknowns, would absorb its one row whole and nothing would check
    /// it) — each by line and field `tool`.
    pub(crate) fn resolve_tools(
        &mut self,
        known: &crate::domain::ToolNames,
        file: &str,
    ) -> Result<(), InputError> {
        let mut count = vec![0usize; self.tools.len()];
        for i in 0..self.len() {
            let name = &self.tools[self.tool(i)];
            known.of_cell(name, file, self.lines[i])?;
            count[self.tool(i)] += 1;
        }
        if let Some(k) = (1..count.len()).find(|&k| (1..MIN_TOOL_ROWS).contains(&count[k])) {
            let first = (0..self.len()).find(|&i| self.tool(i) == k).unwrap_or(0);
            let message = format!(
                "tool {} is seen in {} row(s): its offset (three unknowns) would absorb them \
                 whole and no residual would check it; give it at least {MIN_TOOL_ROWS} rows",
                crate::error::quoted(&self.tools[k]),
                count[k]
            );
            return Err(InputError::field(file, self.lines[first], "tool", message));
        }
        self.tool_offsets = self.tools.iter().map(|t| known.offset(t)).collect();
        Ok(())
    }
}

/// Refuses a frame whose rows cannot determine its registration
/// ([`Positions::unregistrable_frame`]), at the frame's first line.
fn check_frames(p: &Positions, file: &str) -> Result<(), InputError> {
    match p.unregistrable_frame() {
        Some((row, why)) => Err(InputError::field(file, p.line(row), "frame", why)),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::testing::assert_at;

    const F: &str = "positions.csv";

    fn parse(text: &str) -> Result<Positions, InputError> {
        parse_positions(text, F, AngleUnit::Rad, Some(2))
    }

    const GOOD: &str = "point,q1,q2,x,y,z,frame,uncertainty\n\
                        A,0,1,100,0,0,s1,0.01\n\
                        B,1,0,0,100,0,s1,\n\
                        C,1,1,0,0,100,s1,0.02\n\
                        A,0,1,10,0,0,s2,\n\
                        B,1,0,0,10,0,s2,\n\
                        C,2,1,0,0,10,s2,\n";

    /// `approach` last: read per row, kept by a subset, written back; a
    /// bad cell refused by line and field.
    #[test]
    fn the_approach_column_is_read_and_written() {
        let text = "point,q1,q2,x,y,z,time,approach\n\
                    A,0,1,100,0,0,0,+-\n\
                    B,1,0,0,100,0,1,-0\n\
                    C,1,1,0,0,100,2,\n";
        let p = parse(text).unwrap();
        assert_eq!(p.approaches(), Some(&[1, -1, -1, 0, 0, 0][..]));
        assert_eq!(p.subset(&[2, 0]).approaches(), Some(&[0, 0, 1, -1][..]));
        let mut out = Vec::new();
        write_positions(&mut out, &p, AngleUnit::Rad).unwrap();
        let written = String::from_utf8(out).unwrap();
        assert!(written.starts_with("point,q1,q2,x,y,z,time,approach\nA,0.0,1.0,"));
        assert_eq!(parse(&written).unwrap(), p);
        let e = parse(&text.replace("-0", "-+-")).unwrap_err();
        assert_at(
            &e,
            F,
            3,
            Some("approach"),
            "`-+-` has 3 directions but the arm has 2",
        );
    }

    #[test]
    fn frames_uncertainties_and_lines_are_read() {
        let p = parse(GOOD).unwrap();
        assert_eq!(p.frames(), ["s1", "s2"]);
        assert_eq!((p.frame(0), p.frame(3)), (0, 1));
        assert_eq!((p.uncertainty(0), p.uncertainty(1)), (Some(0.01), None));
        assert_eq!(
            (p.line(5), p.label(5), p.reading(5)),
            (7, "C", &[2.0, 1.0][..])
        );
        let s = p.subset(&[3, 4, 5]);
        assert_eq!((s.frames(), s.line(0)), (&["s2".to_string()][..], 5));
    }

    #[test]
    fn written_positions_read_back_the_same() {
        let p = parse(GOOD).unwrap();
        let mut out = Vec::new();
        write_positions(&mut out, &p, AngleUnit::Deg).unwrap();
        let text = String::from_utf8(out).unwrap();
        let back = parse_positions(&text, F, AngleUnit::Deg, Some(2)).unwrap();
        assert_eq!(back.frames(), p.frames());
        for i in 0..p.len() {
            assert_eq!(back.position(i), p.position(i));
            assert_eq!(back.uncertainty(i), p.uncertainty(i));
            assert_eq!(back.reading(i), p.reading(i), "row {i}");
        }
    }

    #[test]
    fn bad_rows_name_their_line_and_field() {
        let e = parse(&GOOD.replace("0,0,100,s1,0.02", "0,0,inf,s1,0.02")).unwrap_err();
        assert_at(&e, F, 4, Some("z"), "not a finite number");
        let e = parse(&GOOD.replace("s1,0.02", "s1,0")).unwrap_err();
        assert_at(&e, F, 4, Some("uncertainty"), "must be positive");
        let e = parse(&GOOD.replace("0,1,10,0,0,s2,", "0,1,10,0,0,,")).unwrap_err();
        assert_at(&e, F, 5, Some("frame"), "empty frame");
        let e = parse("point,q1,x,y,z\nA,1,2,3,4\n").unwrap_err();
        assert_at(&e, F, 1, Some("x"), "expected `q2`");
    }

    const ORIENTED: &str = "point,q1,q2,x,y,z,qw,qx,qy,qz,frame\n\
                            A,0,1,100,0,0,1,0,0,0,s1\n\
                            B,1,0,0,100,0,0.6,0,0.8,0,s1\n\
                            C,1,1,0,0,100,,,,,s1\n";

    /// Orientation columns after `x,y,z`: read per row (a row of four
    /// empty cells has none), kept by a subset, written back to the same
    /// rows; a file without them writes none.
    #[test]
    fn orientations_are_read_kept_and_written() {
        let p = parse(ORIENTED).unwrap();
        assert_eq!(p.orientation(0), Some([1.0, 0.0, 0.0, 0.0]));
        assert_eq!(p.orientation(1), Some([0.6, 0.0, 0.8, 0.0]));
        assert_eq!((p.orientation(2), p.oriented_rows()), (None, 2));
        assert_eq!(p.frames(), ["s1"]);
        let s = p.subset(&[2, 1]);
        assert_eq!(
            (s.orientation(0), s.orientation(1)),
            (None, p.orientation(1))
        );
        let mut out = Vec::new();
        write_positions(&mut out, &p, AngleUnit::Rad).unwrap();
        let written = String::from_utf8(out).unwrap();
        assert!(written.starts_with("point,q1,q2,x,y,z,qw,qx,qy,qz,frame\n"));
        assert!(written.contains(",100.0,,,,,s1\n"), "{written}");
        assert_eq!(parse(&written).unwrap(), p);
        let mut plain = Vec::new();
        write_positions(&mut plain, &parse(GOOD).unwrap(), AngleUnit::Rad).unwrap();
        assert!(!String::from_utf8(plain).unwrap().contains("qw"));
    }

    /// A quaternion off unit length beyond 1e-6, a row with some of its
    /// orientation cells, a header with some of the columns: each refused
    /// by line and field.
    #[test]
    fn bad_orientations_name_their_line_and_field() {
        let long = ORIENTED.replace("0.6,0,0.8,0", "0.6,0,0.8,0.002");
        let e = parse(&long).unwrap_err();
        assert_at(&e, F, 3, Some("qw,qx,qy,qz"), "not 1");
        // Within the tolerance: read as written.
        let near = ORIENTED.replace("1,0,0,0,s1", "1.0000005,0,0,0,s1");
        assert_eq!(parse(&near).unwrap().orientation(0).unwrap()[0], 1.0000005);
        let e = parse(&ORIENTED.replace("0.6,0,0.8,0", "0.6,0,0.8,")).unwrap_err();
        assert_at(&e, F, 3, Some("qz"), "all four");
        let e = parse(&ORIENTED.replace("1,0,0,0,s1", "1,x,0,0,s1")).unwrap_err();
        assert_at(&e, F, 2, Some("qx"), "");
        let header = "point,q1,q2,x,y,z,qw,qx,qz\nA,0,1,1,0,0,1,0,0\n";
        let e = parse(header).unwrap_err();
        assert_at(&e, F, 1, Some("qy"), "orientation columns incomplete");
        let misplaced = "point,q1,q2,x,y,z,frame,qw,qx,qy,qz\nA,0,1,1,0,0,s,1,0,0,0\n";
        let e = parse(misplaced).unwrap_err();
        assert_at(&e, F, 1, Some("frame"), "expected `qw`");
    }

    /// A frame column with one row per frame, and a frame on one line.
    #[test]
    fn frames_that_cannot_be_registered_are_refused() {
        let text = "point,q1,q2,x,y,z,frame\nA,0,1,1,0,0,a\nB,1,0,0,1,0,b\nC,1,1,0,0,1,c\n";
        let e = parse(text).unwrap_err();
        assert_at(&e, F, 2, Some("frame"), "frame `a` has 1 distinct position");
        let line = "point,q1,q2,x,y,z\nA,0,1,0,0,0\nB,1,0,1,1,1\nC,1,1,2,2,2\nD,2,2,5,5,5\n";
        assert_at(
            &parse(line).unwrap_err(),
            F,
            2,
            Some("frame"),
            "lie on one line",
        );
        // The same sphere seen three times is one position.
        let same = "point,q1,q2,x,y,z\nA,0,1,1,2,3\nA,1,0,1,2,3\nA,1,1,1,2,3\n";
        assert_at(&parse(same).unwrap_err(), F, 2, Some("frame"), "1 distinct");
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn io_positions_parse_positions() {
        use crate::io::{AngleUnit, parse_positions};
        let text = "point,q1,q2,x,y,z\nP,0,90,1,2,3\nQ,10,0,4,5,6\nR,0,45,0,9,1\n";
        let p = parse_positions(text, "t.csv", AngleUnit::Deg, Some(2)).unwrap();
        assert_eq!((p.len(), p.frames()), (3, &["instrument".to_string()][..]));
        assert_eq!(p.reading(0)[1], std::f64::consts::FRAC_PI_2);
        assert_eq!((p.position(1), p.line(1)), ([4.0, 5.0, 6.0], 3));

        let e = parse_positions(
            "point,q1,q2,x,y,z\nP,0,90,1,NaN,3\n",
            "t.csv",
            AngleUnit::Deg,
            None,
        );
        assert!(
            e.unwrap_err()
                .to_string()
                .starts_with("t.csv:2: field `y`: `NaN` is not a finite number")
        );
    }
}
