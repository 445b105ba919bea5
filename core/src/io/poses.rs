//! Poses files: one touch per row, CSV with the header `point,q1,...,qn`.
//!
//! ```text
//! # socket touches, degrees
//! point,q1,q2,q3,q4,q5,q6
//! S1,10.5,-45.0,30.0,0.0,60.0,90.0
//! S1,-20.0,-40.0,35.5,10.0,55.0,-90.0
//! ```
//!
//! `point` labels the physical point (socket) touched; rows with the same
//! label touch the same point. The angles are the encoder readings `q` in the
//! unit the caller states (files do not carry it). Optional columns
//! after the joints: `tool` (the probe that touched: one of the arm file's
//! `[[tool]]`, [`super::tools`]; empty, the `[probe]`), `temperature`
//! (°C), `time` (s), then `approach` (the direction each joint approached
//! the touch from, [`super::approach`]).
//! The CSV dialect is described in the [`io`](super) module docs.

use std::io::Write;
use std::path::Path;

use super::Warning;
use super::approach::{APPROACH, approach_cell};
use super::columns::JointColumns;
use super::split::{PIECE, TableReader, scan_table_on};
use super::text::{Record, check_header, parse_f64, push_f64, quote, read_text};
use super::units::AngleUnit;
use crate::domain::{Poses, Positions};
use crate::error::InputError;
use crate::memory::try_vec;

/// The radians hint is given only for at least this many rows.
pub(crate) const RADIANS_HINT_MIN_ROWS: usize = 20;

/// What the readers add to [`Poses`]: refusals in a file's words, the
/// readings as typed for the unit warnings.
impl Poses {
    /// Refuses rows naming a tool other than the default for `what` (a
    /// command that sees every row through one probe), at `file`'s first
    /// such row, field `tool`.
    ///
    /// # Errors
    ///
    /// The first row naming another tool.
    pub fn refuse_tools(&self, file: &str, what: &str) -> Result<(), InputError> {
        let Some(row) = (0..self.len()).find(|&r| self.tool(r) != 0) else {
            return Ok(());
        };
        Err(tools_refused(
            file,
            self.line(row),
            &self.tools[self.tool(row)],
            what,
        ))
    }

    /// These readings as typed in `unit` (a revolute joint's in degrees
    /// for [`AngleUnit::Deg`]): what the readers' unit warnings look at.
    fn as_typed(&self, unit: AngleUnit) -> Poses {
        let mut typed = self.clone();
        if unit == AngleUnit::Deg {
            let joints = self.joints.max(1);
            let slides = |j: usize| j < 16 && self.prismatic & (1 << j) != 0;
            for (i, q) in typed.q.iter_mut().enumerate() {
                if !slides(i % joints) {
                    *q = q.to_degrees();
                }
            }
        }
        typed
    }
}

/// Reads a poses file (standard input for `-`) with angles in `unit`;
/// `joints` says how many columns the file must have and which are
/// lengths ([`JointColumns`]: a count, a shape or the arm). Returns the
/// poses and any warnings (for the caller to print).
///
/// ```no_run
/// use aacmm_core::io::{AngleUnit, read_poses};
/// let (poses, warnings) = read_poses(std::path::Path::new("poses.csv"), AngleUnit::Deg, Some(6))?;
/// for w in &warnings {
///     eprintln!("warning: {w}");
/// }
/// # Ok::<(), aacmm_core::error::InputError>(())
/// ```
pub fn read_poses(
    path: &Path,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<(Poses, Vec<Warning>), InputError> {
    let (file, text) = read_text(path)?;
    parse_poses(&text, &file, unit, joints)
}

/// What a file of joint readings held: the readings as [`Poses`] (a touch
/// per row, of the row's `point`), and, for a reference-positions file, its
/// rows whole (positions, frames; [`super::parse_positions`]).
pub(crate) type PosesOrPositions = (Poses, Vec<Warning>, Option<Positions>);

/// Reads a poses file or a reference-positions file (standard input for
/// `-`): [`parse_poses_or_positions`].
///
/// # Errors
///
/// As [`parse_poses_or_positions`].
pub fn read_poses_or_positions(
    path: &Path,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<PosesOrPositions, InputError> {
    let (file, text) = read_text(path)?;
    parse_poses_or_positions(&text, &file, unit, joints)
}

/// Parses a poses file, or a reference-positions file (a header with an
/// `x` column: `point,q1,...,qn,x,y,z[,frame][,uncertainty]`) whose
/// readings are taken as poses — for the commands that need only the
/// readings (`points`, `plan --candidates`) or score the positions
/// themselves (`evaluate --positions`). A positions file is checked whole
/// ([`super::parse_positions`]), and its readings warned about as a poses
/// file's.
///
/// # Errors
///
/// As [`parse_poses`] or [`super::parse_positions`], naming file, line
/// and field.
pub fn parse_poses_or_positions(
    text: &str,
    file: &str,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<PosesOrPositions, InputError> {
    if !has_position_columns(text) {
        let (poses, warnings) = parse_poses(text, file, unit, joints)?;
        return Ok((poses, warnings, None));
    }
    let positions = super::parse_positions(text, file, unit, joints)?;
    let poses = Poses::from_positions(&positions).map_err(|e| InputError::memory(file, e))?;
    let warnings = unit_warnings(&poses.as_typed(unit), file, unit);
    Ok((poses, warnings, Some(positions)))
}

/// Whether the header (the first line that is not blank) names an `x`
/// column: a reference-positions file's.
fn has_position_columns(text: &str) -> bool {
    (text.lines().find(|l| !l.trim().is_empty()))
        .is_some_and(|h| h.split(',').any(|f| f.trim().trim_matches('"') == "x"))
}

/// Parses the text of a poses file; `file` is the name used in messages.
///
/// ```
/// use aacmm_core::io::{AngleUnit, parse_poses};
/// let text = "point,q1,q2\nS1,90,0\nS1,0,-180\n";
/// let (poses, warnings) = parse_poses(text, "p.csv", AngleUnit::Deg, Some(2)).unwrap();
/// assert_eq!(poses.labels().collect::<Vec<_>>(), ["S1", "S1"]);
/// assert_eq!(poses.reading(0)[0], std::f64::consts::FRAC_PI_2);
/// assert_eq!(poses.lines(), [2, 3]);
/// assert!(warnings.is_empty());
///
/// let err = parse_poses(text, "p.csv", AngleUnit::Deg, Some(6)).unwrap_err();
/// assert!(err.to_string().starts_with("p.csv:1: field `q3`: the header has 2 joint columns"));
/// ```
pub fn parse_poses(
    text: &str,
    file: &str,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<(Poses, Vec<Warning>), InputError> {
    let pieces = (crate::parallel::every_core(), PIECE);
    parse_poses_on(text, (file, unit), joints.into(), pieces)
}

/// [`parse_poses`] on up to `threads` threads, in pieces of about `piece`
/// bytes ([`scan_table_on`]): the same poses, warnings and errors.
pub(crate) fn parse_poses_on(
    text: &str,
    (file, unit): (&str, AngleUnit),
    columns_of: JointColumns,
    (threads, piece): (usize, usize),
) -> Result<(Poses, Vec<Warning>), InputError> {
    let expected_joints = columns_of.expected();
    let shape = "point,q1,...,qn[,tool][,temperature][,time][,approach]";
    let per_row = "one row per touch";
    // At most one row per line, and per 2 bytes a field (a digit or a
    // label, and its comma or line end): room for them all, so that the
    // readings are never copied to grow; the unused room is given back.
    let rows_bound = |header: &Record, (bytes, lines): (usize, usize)| {
        lines.min(1 + bytes / (2 * header.fields.len()).max(1))
    };
    // Each table keeps its header's layout, found once.
    let reader = TableReader {
        new: |header: &Record, rows| {
            let l = PosesLayout::of(header);
            let poses = room(file, (l.joints, rows), l.extra, (l.approach, l.tool))?;
            Ok((poses, l))
        },
        row: |(poses, l): &mut (Poses, PosesLayout), header: &Record, line, fields: &[&str]| {
            let names = &header.fields[..l.columns];
            read_row(poses, (file, &columns_of), (*l, names), (line, fields))
        },
    };
    let append = |(into, _): &mut (Poses, PosesLayout), (rows, _): (Poses, PosesLayout)| {
        (into.append(rows)).map_err(|e| InputError::memory(file, e))
    };
    let (header, poses) = scan_table_on(
        text,
        (file, shape, per_row),
        |h| check_poses_header(h, file, expected_joints),
        reader,
        (rows_bound, append),
        (threads, piece),
    )?;
    let l = PosesLayout::of(&header);
    let mut poses = poses.map(|(p, _)| p).unwrap_or_else(|| {
        let mut empty = Poses::new(l.joints);
        empty.approach = l.approach.then(Vec::new);
        empty.tool_of = l.tool.then(Vec::new);
        empty
    });
    poses.q.shrink_to_fit();
    poses.point_of.shrink_to_fit();
    poses.lines.shrink_to_fit();
    poses.prismatic = columns_of.prismatic_mask();
    let warnings = unit_warnings(&poses, file, unit);
    let joints = poses.joints.max(1);
    for (i, x) in poses.q.iter_mut().enumerate() {
        *x = columns_of.to_internal(i % joints, *x, unit);
    }
    Ok((poses, warnings))
}

/// Where a poses file's header puts its columns.
#[derive(Clone, Copy)]
struct PosesLayout {
    /// The header's fields before `approach`.
    columns: usize,
    joints: usize,
    /// The condition columns after the joints (and the tool), in order.
    extra: &'static [&'static str],
    tool: bool,
    approach: bool,
}

impl PosesLayout {
    fn of(header: &Record) -> PosesLayout {
        let (columns, approach) = split_approach(&header.fields);
        let extra = condition_columns(columns);
        let tool = has_tool_column(columns, extra.len());
        PosesLayout {
            columns: columns.len(),
            joints: columns.len() - 1 - extra.len() - usize::from(tool),
            extra,
            tool,
            approach,
        }
    }
}

/// Reads the data row `fields` on `line` into `poses` (`names`: the
/// header's columns before `approach`); on an error the poses are as they
/// were.
fn read_row(
    poses: &mut Poses,
    (file, columns_of): (&str, &JointColumns),
    (l, names): (PosesLayout, &[String]),
    (line, fields): (usize, &[&str]),
) -> Result<(), InputError> {
    let joints = l.joints;
    let extra_at = 1 + joints + usize::from(l.tool);
    let label = fields[0];
    if label.is_empty() {
        return Err(InputError::field(
            file,
            line,
            "point",
            "empty label: each row must name the point touched",
        ));
    }
    let start = poses.q.len();
    let row = (&fields[1..=joints], &names[1..=joints]);
    read_readings(row, columns_of, (file, line), &mut poses.q)?;
    let mut values = [0.0; 2];
    for (k, c) in l.extra.iter().enumerate() {
        let v = fields[extra_at + k];
        values[k] = match parse_f64(v, file, line, c) {
            Ok(t) if *c == "temperature" && !(-100.0..=200.0).contains(&t) => {
                poses.q.truncate(start);
                let message = format!("{t} °C: not an arm's temperature (°C, −100 to 200)");
                return Err(InputError::field(file, line, *c, message));
            }
            Ok(t) => t,
            Err(e) => {
                poses.q.truncate(start);
                return Err(e);
            }
        };
    }
    if let Some(signs) = &mut poses.approach {
        let cell = fields[l.columns];
        if let Err(e) = super::approach::parse_approach(cell, joints, (file, line), signs) {
            poses.q.truncate(start);
            return Err(e);
        }
    }
    for (k, c) in l.extra.iter().enumerate() {
        if let Some(column) = poses.condition_mut(c) {
            column.push(values[k]);
        }
    }
    if l.tool {
        poses.push_tool(fields[1 + joints].trim());
    }
    let id = poses
        .intern(label)
        .map_err(|e| InputError::memory(file, e))?;
    poses.point_of.push(id);
    poses.lines.push(line);
    Ok(())
}

/// Appends a row's readings `fields` (columns named `names`) as written to
/// `q`, each checked against a prismatic joint's stroke; on an error `q`
/// is as it was.
fn read_readings(
    (fields, names): (&[&str], &[String]),
    columns: &JointColumns,
    (file, line): (&str, usize),
    q: &mut Vec<f64>,
) -> Result<(), InputError> {
    let start = q.len();
    for (j, (s, name)) in fields.iter().zip(names).enumerate() {
        let x = parse_f64(s, file, line, name)
            .and_then(|x| columns.check_stroke(j, x, file, line).map(|_| x));
        match x {
            Ok(x) => q.push(x),
            Err(e) => {
                q.truncate(start);
                return Err(e);
            }
        }
    }
    Ok(())
}

/// Empty poses of `joints` joints with room for `rows` rows, the
/// condition columns `extra` and, if `approach`, the directions of
/// approach, if `tool`, the rows' tools, or an [`InputError::Memory`] for
/// `file`.
fn room(
    file: &str,
    (joints, rows): (usize, usize),
    extra: &[&str],
    (approach, tool): (bool, bool),
) -> Result<Poses, InputError> {
    let memory = |e| InputError::memory(file, e);
    let mut p = Poses::try_with_capacity(joints, rows).map_err(memory)?;
    for c in extra {
        *p.condition_mut(c) = Some(try_vec(c, rows).map_err(memory)?);
    }
    if approach {
        let directions = try_vec(APPROACH, rows.saturating_mul(joints)).map_err(memory)?;
        p.approach = Some(directions);
    }
    if tool {
        p.tool_of = Some(try_vec("the rows' tools", rows).map_err(memory)?);
    }
    Ok(p)
}

/// The header's fields before a last `approach` column, and whether it has
/// one (after the conditions: [`super::approach`]).
fn split_approach(fields: &[String]) -> (&[String], bool) {
    match fields.split_last() {
        Some((last, rest)) if last == APPROACH && !rest.is_empty() => (rest, true),
        _ => (fields, false),
    }
}

/// The optional columns after the joints' a header ends with, in order:
/// `temperature` (°C) then `time` (s).
fn condition_columns(fields: &[String]) -> &'static [&'static str] {
    let ends =
        |name: &str, rest: &[String]| rest.len() > 1 && rest.last().is_some_and(|f| f == name);
    let n = fields.len();
    if ends("time", fields) {
        if ends("temperature", &fields[..n - 1]) {
            &["temperature", "time"]
        } else {
            &["time"]
        }
    } else if ends("temperature", fields) {
        &["temperature"]
    } else {
        &[]
    }
}

/// The refusal of rows naming the tool `name` (first at `file:line`) by
/// `what`, which sees every row through one probe.
pub(crate) fn tools_refused(file: &str, line: usize, name: &str, what: &str) -> InputError {
    InputError::field(
        file,
        line,
        "tool",
        format!(
            "{}: touches by several tools are fitted by `calibrate` (each tool's offset), but \
             {what} sees every row through one probe (--tool): give it one tool's rows, \
             without a `tool` column",
            crate::error::quoted(name)
        ),
    )
}

/// Whether the header's `columns` (without `approach`) have a `tool`
/// column, just before their `extra` condition columns and after at least
/// one joint's.
fn has_tool_column(columns: &[String], extra: usize) -> bool {
    columns.len() >= 3 + extra && columns[columns.len() - 1 - extra] == "tool"
}

/// Checks the header `point,q1,...,qn[,tool][,temperature][,time][,approach]`,
/// and `n` against `expected_joints`.
fn check_poses_header(
    header: &Record,
    file: &str,
    expected_joints: Option<usize>,
) -> Result<(), InputError> {
    let (fields, approach) = split_approach(&header.fields);
    let mut extra = condition_columns(fields).to_vec();
    let tool = has_tool_column(fields, extra.len());
    let n = fields.len() - 1 - extra.len() - usize::from(tool);
    if tool {
        extra.insert(0, "tool");
    }
    if approach {
        extra.push(APPROACH);
    }
    let tail: String = extra.iter().map(|c| format!(",{c}")).collect();
    let shape = |n: usize| match n {
        0 => format!("point,q1,...,qn{tail}"),
        n => format!("point,q1,...,q{n}{tail}"),
    };
    let want = shape(expected_joints.unwrap_or(n));
    let names: Vec<String> = (1..=n).map(|j| format!("q{j}")).collect();
    let expected: Vec<&str> = ["point"]
        .into_iter()
        .chain(names.iter().map(String::as_str))
        .chain(extra.iter().copied())
        .collect();
    check_header(header, file, &expected, &want)?;
    let error =
        |field: String, message: String| Err(InputError::field(file, header.line, field, message));
    if n == 0 {
        let message = format!("missing joint columns in the header; the header must be `{want}`");
        return error("q1".into(), message);
    }
    match expected_joints {
        Some(m) if m != n => {
            let (field, what) = if n > m {
                (format!("q{}", m + 1), "unexpected column")
            } else {
                (format!("q{}", n + 1), "missing column")
            };
            error(
                field,
                format!(
                    "the header has {n} joint columns (q1..q{n}) but the arm has {m} joints \
                     ({what}); the header must be `{want}`"
                ),
            )
        }
        _ => Ok(()),
    }
}

/// Whether `rows` rows of readings `q` of `joints` joints, in degrees
/// once multiplied by `to_deg`, look like radians read as degrees: at
/// least [`RADIANS_HINT_MIN_ROWS`] rows, every |q| of a revolute joint
/// (not in the bits of `prismatic`, whose readings are mm) below 2π
/// degrees — no arm is moved through a campaign within ±6.3° on every
/// joint. The reader's warning and the calibration's refusal ask the same
/// question, so that the refusal names the cause the warning named.
pub(crate) fn look_like_radians(
    q: &[f64],
    rows: usize,
    (joints, prismatic): (usize, u16),
    to_deg: f64,
) -> bool {
    let turn = std::f64::consts::TAU;
    let revolute = |i: &usize| {
        let j = i % joints.max(1);
        j >= 16 || prismatic & (1 << j) == 0
    };
    rows >= RADIANS_HINT_MIN_ROWS
        && prismatic.count_ones() < joints as u32
        && (q.iter().enumerate())
            .filter(|(i, _)| revolute(i))
            .all(|(_, x)| (x * to_deg).abs() < turn)
}

/// Hints when the angles look like the other unit (`q` still in `unit`).
fn unit_warnings(poses: &Poses, file: &str, unit: AngleUnit) -> Vec<Warning> {
    let turn = std::f64::consts::TAU;
    let warning = |line, field, message| Warning {
        file: file.to_string(),
        line,
        field,
        message,
    };
    match unit {
        AngleUnit::Deg
            if look_like_radians(&poses.q, poses.len(), (poses.joints, poses.prismatic), 1.0) =>
        {
            let message = format!(
                "angles declared in degrees, but every |q| in all {} rows is below 2π (6.28°): \
                 these angles look like radians; pass --angle-unit rad if so",
                poses.len()
            );
            vec![warning(None, None, message)]
        }
        AngleUnit::Deg => vec![],
        AngleUnit::Rad => (poses.rows().zip(&poses.lines))
            .find_map(|(q, &line)| {
                let slide = |j: usize| j < 16 && poses.prismatic & (1 << j) != 0;
                let j = (q.iter().enumerate()).position(|(j, x)| !slide(j) && x.abs() > turn)?;
                let message = format!(
                    "angles declared in radians, but |{}| is more than a full turn (2π): these \
                     angles look like degrees; pass --angle-unit deg if so",
                    q[j]
                );
                Some(warning(Some(line), Some(format!("q{}", j + 1)), message))
            })
            .into_iter()
            .collect(),
    }
}

/// Writes poses in the poses-file format with angles in `unit`:
/// deterministic bytes, numbers in the shortest form that reads back to the
/// same value (bit-exact in rad; in deg see
/// [`AngleUnit::from_internal_exact`]), labels quoted only where needed.
/// The lines are not written. A label with surrounding whitespace (reading
/// trims it) gives an [`std::io::ErrorKind::InvalidInput`] error.
///
/// ```
/// use aacmm_core::domain::Poses;
/// use aacmm_core::io::{AngleUnit, write_poses};
/// let mut poses = Poses::new(2);
/// poses.push("S1", &[std::f64::consts::FRAC_PI_2, 0.0], 2);
/// poses.push("S2", &[-0.5, 1e-9], 3);
/// let mut out = Vec::new();
/// write_poses(&mut out, &poses, AngleUnit::Rad).unwrap();
/// assert_eq!(
///     String::from_utf8(out).unwrap(),
///     "point,q1,q2\nS1,1.5707963267948966,0.0\nS2,-0.5,1e-9\n"
/// );
/// ```
pub fn write_poses(mut w: impl Write, poses: &Poses, unit: AngleUnit) -> std::io::Result<()> {
    let mut header = String::from("point");
    for j in 1..=poses.joints {
        header.push_str(&format!(",q{j}"));
    }
    let conditions = [
        ("temperature", poses.temperatures()),
        ("time", poses.times()),
    ];
    if poses.tool_of.is_some() {
        header.push_str(",tool");
    }
    for (name, column) in conditions {
        if column.is_some() {
            header.push(',');
            header.push_str(name);
        }
    }
    if poses.approach.is_some() {
        header.push(',');
        header.push_str(APPROACH);
    }
    header.push('\n');
    w.write_all(header.as_bytes())?;
    write_rows(w, poses, unit, WRITE_BLOCK_ROWS)
}

/// The rows of [`write_poses`], in blocks of `block_rows` formatted side
/// by side, a window of them at a time, and written in row order: the
/// same bytes as one row after another (a row's text depends on that row
/// alone), in a bounded buffer. Formatting is most of a large file's
/// writing (`simulate`'s 10⁶ touches: the shortest decimal of each reading
/// in degrees).
fn write_rows(
    mut w: impl Write,
    poses: &Poses,
    unit: AngleUnit,
    block_rows: usize,
) -> std::io::Result<()> {
    let rows = poses.len();
    let threads = crate::parallel::every_core();
    let window = block_rows * threads * crate::parallel::MIN_ITEMS_PER_THREAD;
    let columns = [poses.temperatures(), poses.times()];
    for start in (0..rows).step_by(window) {
        let blocks: Vec<std::ops::Range<usize>> = (start..rows.min(start + window))
            .step_by(block_rows)
            .map(|b| b..rows.min(b + block_rows))
            .collect();
        let texts = crate::parallel::parallel_map(&blocks, threads, |rows| {
            let mut text = String::new();
            // A refused row is cut whole.
            let refused = (rows.clone()).try_for_each(|row| {
                let start = text.len();
                push_row(&mut text, poses, row, unit, columns).inspect_err(|_| text.truncate(start))
            });
            (text, refused)
        });
        for (text, refused) in texts {
            // A refused label ends the block where the rows before it end,
            // as it would end a row-by-row writing.
            w.write_all(text.as_bytes())?;
            refused?;
        }
    }
    Ok(())
}

/// The rows [`write_poses`] formats as one block: a few megabytes of text,
/// enough to outweigh handing the block to another thread.
const WRITE_BLOCK_ROWS: usize = 8192;

/// Row `row` of `poses` as a line of the file (readings in `unit`, then the
/// tool, the `conditions` recorded and the approach) appended to `out`; a
/// label (the point's, the tool's) that does not read back ends it part
/// way, for the caller to cut.
fn push_row(
    out: &mut String,
    poses: &Poses,
    row: usize,
    unit: AngleUnit,
    conditions: [Option<&[f64]>; 2],
) -> std::io::Result<()> {
    out.push_str(&quote(poses.label(row))?);
    for (j, &x) in poses.reading(row).iter().enumerate() {
        let written = JointColumns::to_written(poses.prismatic, j, x, unit);
        push_f64(out, written);
    }
    if poses.tool_of.is_some() {
        // The default tool's cell empty: as a file without tools reads.
        out.push(',');
        if poses.tool(row) != 0 {
            out.push_str(&quote(&poses.tools[poses.tool(row)])?);
        }
    }
    for column in conditions.iter().filter_map(|c| *c) {
        push_f64(out, column[row]);
    }
    if let Some(a) = &poses.approach {
        out.push(',');
        out.push_str(&approach_cell(
            &a[row * poses.joints..(row + 1) * poses.joints],
        ));
    }
    out.push('\n');
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    const F: &str = "touches.csv";

    /// `approach` after the conditions: one sign per joint read per row
    /// (`0`, `.` and an empty cell not known), written back as read; a
    /// cell of the wrong length or character refused by line and field.
    /// `tool` after the joints, before the conditions: each row's probe
    /// by name (empty or `probe`: the default), written back as read; the
    /// points keyed by (label, tool), the default tool's first.
    #[test]
    fn the_tool_column_is_read_written_and_keys_the_points() {
        let text = "point,q1,tool,time\nA,1,long,0\nA,2,,1\nB,3,probe,2\nA,4,long,3\n";
        let (p, _) = parse_poses(text, F, AngleUnit::Rad, Some(1)).unwrap();
        assert_eq!(p.tools(), ["probe", "long"]);
        assert_eq!((0..4).map(|r| p.tool(r)).collect::<Vec<_>>(), [1, 0, 0, 1]);
        assert_eq!(p.times(), Some(&[0.0, 1.0, 2.0, 3.0][..]));
        let mut out = Vec::new();
        write_poses(&mut out, &p, AngleUnit::Rad).unwrap();
        let back = String::from_utf8(out).unwrap();
        assert_eq!(
            back,
            "point,q1,tool,time\nA,1.0,long,0.0\nA,2.0,,1.0\nB,3.0,,2.0\nA,4.0,long,3.0\n"
        );
        let (keyed, of_point) = p.keyed_by_tool().unwrap().unwrap();
        assert_eq!(keyed.points().collect::<Vec<_>>(), ["A", "B", "A"]);
        assert_eq!(of_point, [0, 0, 1]);
        assert_eq!(
            (0..4).map(|r| keyed.point(r)).collect::<Vec<_>>(),
            [2, 0, 1, 2]
        );
        // Without the column, or every cell empty: nothing keyed.
        let (plain, _) = parse_poses("point,q1,tool\nA,1,\n", F, AngleUnit::Rad, None).unwrap();
        assert_eq!((plain.joints(), plain.has_tools()), (1, false));
        assert!(plain.keyed_by_tool().unwrap().is_none());
    }

    #[test]
    fn the_approach_column_is_read_written_and_checked() {
        let text =
            "point,q1,q2,q3,temperature,approach\nA,1,2,3,20,+-.\nA,1,2,3,20,\nB,4,5,6,21,0-+\n";
        let (p, _) = parse_poses(text, F, AngleUnit::Deg, Some(3)).unwrap();
        assert_eq!(p.approaches(), Some(&[1, -1, 0, 0, 0, 0, 0, -1, 1][..]));
        assert_eq!(p.temperatures(), Some(&[20.0, 20.0, 21.0][..]));
        let mut out = Vec::new();
        write_poses(&mut out, &p, AngleUnit::Deg).unwrap();
        let written = String::from_utf8(out).unwrap();
        assert!(written.starts_with("point,q1,q2,q3,temperature,approach\n"));
        assert!(
            written.ends_with(",+-0\n") || written.contains(",+-0\n"),
            "{written}"
        );
        let (back, _) = parse_poses(&written, F, AngleUnit::Deg, Some(3)).unwrap();
        assert_eq!(back.approaches(), p.approaches());
        let refused = |cell: &str| {
            let t = format!("point,q1,q2,q3,approach\nA,1,2,3,+++\nA,1,2,3,{cell}\n");
            parse_poses(&t, F, AngleUnit::Deg, Some(3))
                .unwrap_err()
                .to_string()
        };
        let e = refused("+-");
        assert!(
            e.starts_with(
                "touches.csv:3: field `approach`: `+-` has 2 directions but the arm \
                 has 3 joints"
            ),
            "{e}"
        );
        let e = refused("+x-");
        assert!(
            e.starts_with("touches.csv:3: field `approach`: `+x-`: joint 2's direction `x`"),
            "{e}"
        );
        // Before the conditions it is an unexpected column.
        let t = "point,q1,approach,time\nA,1,+,0\n";
        assert!(parse_poses(t, F, AngleUnit::Deg, Some(1)).is_err());
    }

    /// `temperature` and `time` after the joints: read per row, written
    /// back, a bad value refused by line and field, a column out of order
    /// refused by the header.
    #[test]
    fn conditions_are_read_written_and_checked() {
        let text = "point,q1,q2,temperature,time\nA,1,2,20.5,0\nA,3,4,21,60\n";
        let (p, _) = parse_poses(text, F, AngleUnit::Rad, Some(2)).unwrap();
        assert_eq!(p.joints(), 2);
        assert_eq!(p.temperatures(), Some(&[20.5, 21.0][..]));
        assert_eq!(p.times(), Some(&[0.0, 60.0][..]));
        let mut out = Vec::new();
        write_poses(&mut out, &p, AngleUnit::Rad).unwrap();
        let written = String::from_utf8(out).unwrap();
        assert!(
            written.starts_with("point,q1,q2,temperature,time\n"),
            "{written}"
        );
        assert_eq!(
            parse_poses(&written, F, AngleUnit::Rad, Some(2)).unwrap().0,
            p
        );
        let hot = text.replace("21,60", "2100,60");
        let e = parse_poses(&hot, F, AngleUnit::Rad, Some(2)).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("touches.csv:3: field `temperature`"),
            "{e}"
        );
        let only_time = "point,q1,q2,time\nA,1,2,5\n";
        let (p, _) = parse_poses(only_time, F, AngleUnit::Rad, Some(2)).unwrap();
        assert_eq!((p.temperatures(), p.times()), (None, Some(&[5.0][..])));
        let swapped = "point,q1,q2,time,temperature\nA,1,2,5,20\n";
        assert!(parse_poses(swapped, F, AngleUnit::Rad, Some(2)).is_err());
    }

    fn err(text: &str, expected: Option<usize>) -> InputError {
        parse_poses(text, F, AngleUnit::Deg, expected).unwrap_err()
    }

    /// The error names the file, the line (0 = none) and the field.
    #[track_caller]
    fn assert_at(e: &InputError, line: usize, field: Option<&str>, needle: &str) {
        crate::io::testing::assert_at(e, F, line, field, needle);
    }

    #[test]
    fn parses_comments_quotes_units() {
        // Comments only before the header (a `# mid comment` row would be data).
        let text = "# header comment\n# more\npoint,q1,q2\nS1,180,-90\n\"S 2\", 0.5 ,1e-3\n\n\n";
        let (p, w) = parse_poses(text, F, AngleUnit::Deg, Some(2)).unwrap();
        assert!(w.is_empty());
        assert_eq!(p.joints, 2);
        assert_eq!(p.labels().collect::<Vec<_>>(), ["S1", "S 2"]);
        assert_eq!(p.lines(), [4, 5]);
        assert_eq!(
            p.reading(0),
            [std::f64::consts::PI, -std::f64::consts::FRAC_PI_2]
        );
        assert_eq!(p.reading(1), [0.5f64.to_radians(), 1e-3f64.to_radians()]);
        let (r, _) = parse_poses(text, F, AngleUnit::Rad, None).unwrap();
        assert_eq!(r.reading(1), [0.5, 1e-3]);
    }

    #[test]
    fn hash_labelled_rows_are_data() {
        // Only before the header is a `#` line a comment; a row labelled `#S1`
        // was silently dropped as one.
        let text = "# touches\npoint,q1\nS0,1\n#S1,2\n # S2 ,3\n";
        let (p, _) = parse_poses(text, F, AngleUnit::Rad, None).unwrap();
        assert_eq!(p.labels().collect::<Vec<_>>(), ["S0", "#S1", "# S2"]);
        assert_eq!(p.lines(), [3, 4, 5]);
        assert_eq!(p.reading(1), [2.0]);
        // A comment-like line after the header is a row like any other.
        assert_at(
            &err("point,q1,q2\nS,1,2\n# note\n", None),
            3,
            Some("q1"),
            "missing: the row has 1 columns, the header 3",
        );
    }

    #[test]
    fn empty_file_and_no_rows() {
        assert_at(&err("", None), 0, None, "empty file");
        assert_at(&err("# only a comment\n", None), 0, None, "empty file");
        assert_at(&err("point,q1\n", None), 0, None, "no data rows");
        assert_at(&err("# c\npoint,q1\n\n \n", None), 0, None, "no data rows");
    }

    #[test]
    fn header_errors() {
        assert_at(
            &err("point,q1,q1\nS,1,2\n", None),
            1,
            Some("q1"),
            "duplicate column",
        );
        assert_at(
            &err("point,q1,point\nS,1,2\n", None),
            1,
            Some("point"),
            "duplicate column",
        );
        assert_at(
            &err("label,q1\nS,1\n", None),
            1,
            Some("label"),
            "expected `point`",
        );
        assert_at(
            &err("q1,point\nS,1\n", None),
            1,
            Some("q1"),
            "expected `point`",
        );
        assert_at(
            &err("point\nS\n", None),
            1,
            Some("q1"),
            "missing joint columns",
        );
        assert_at(
            &err("point,q1,q3\nS,1,2\n", None),
            1,
            Some("q3"),
            "expected `q2`; the header must be `point,q1,...,q2`",
        );
        assert_at(
            &err("point,q1,x\nS,1,2\n", None),
            1,
            Some("x"),
            "expected `q2`",
        );
        assert_at(
            &err("point,Q1\nS,1\n", None),
            1,
            Some("Q1"),
            "expected `q1`",
        );
        // Header on a later line, after comments.
        assert_at(
            &err("# c\n# d\npoint,q2\nS,1\n", None),
            3,
            Some("q2"),
            "expected `q1`",
        );
    }

    #[test]
    fn joint_count_mismatch() {
        let e = err("point,q1,q2,q3,q4,q5\nS,1,2,3,4,5\n", Some(6));
        assert_at(&e, 1, Some("q6"), "the header has 5 joint columns");
        assert!(e.to_string().contains("the arm has 6 joints"));
        assert!(e.to_string().contains("point,q1,...,q6"));
        let e = err("point,q1,q2,q3,q4,q5,q6,q7\nS,1,2,3,4,5,6,7\n", Some(6));
        assert_at(&e, 1, Some("q7"), "has 7 joint columns");
    }

    #[test]
    fn row_errors() {
        assert_at(
            &err("point,q1,q2\nS,1,2\nS,1\n", None),
            3,
            Some("q2"),
            "the row has 2 columns, the header 3",
        );
        assert_at(
            &err("point,q1,q2\nS,1,2,3\n", None),
            2,
            None,
            "the row has 4 columns, the header 3",
        );
        assert_at(
            &err("point,q1,q2\n,1,2\n", None),
            2,
            Some("point"),
            "empty label",
        );
        assert_at(
            &err("point,q1,q2\n\"\" ,1,2\n", None),
            2,
            Some("point"),
            "empty label",
        );
        assert_at(
            &err("point,q1,q2\nS,1,x2\n", None),
            2,
            Some("q2"),
            "`x2` is not a number",
        );
        assert_at(
            &err("point,q1,q2\nS,1,\n", None),
            2,
            Some("q2"),
            "missing value",
        );
        assert_at(
            &err("point,q1,q2\nS,NaN,1\n", None),
            2,
            Some("q1"),
            "not a finite number",
        );
        assert_at(
            &err("point,q1,q2\nS,1,-inf\n", None),
            2,
            Some("q2"),
            "not a finite number",
        );
        assert_at(
            &err("point,q1,q2\nS,1,1e999\n", None),
            2,
            Some("q2"),
            "out of range",
        );
        assert_at(
            &err("point,q1,q2\nS,\"1,2\n", None),
            2,
            None,
            "unterminated quote",
        );
        assert_at(&err("point,q1\nS,1\n\nS,2\n", None), 3, None, "blank line");
        assert_at(
            &err("point,q1\nS,1\n   \nS,2\n", None),
            3,
            None,
            "blank line",
        );
        assert_at(&err("\npoint,q1\nS,1\n", None), 1, None, "blank line");
        // CRLF line endings count lines the same way.
        assert_at(
            &err("point,q1\r\nS,1\r\nS,x\r\n", None),
            3,
            Some("q1"),
            "`x` is not a number",
        );
    }

    fn rows(n: usize, value: f64) -> String {
        let mut s = String::from("point,q1,q2\n");
        for i in 0..n {
            s.push_str(&format!("P{},{value},{}\n", i % 3, -value));
        }
        s
    }

    #[test]
    fn radians_hint() {
        let (_, w) = parse_poses(&rows(20, 1.5), F, AngleUnit::Deg, None).unwrap();
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].file, F);
        assert!(w[0].to_string().starts_with("touches.csv: "));
        assert!(
            w[0].message
                .contains("look like radians; pass --angle-unit rad")
        );
        // Too few rows, large angles, or radians declared: no hint.
        assert!(
            parse_poses(&rows(19, 1.5), F, AngleUnit::Deg, None)
                .unwrap()
                .1
                .is_empty()
        );
        assert!(
            parse_poses(&rows(30, 45.0), F, AngleUnit::Deg, None)
                .unwrap()
                .1
                .is_empty()
        );
        assert!(
            parse_poses(&rows(30, 1.5), F, AngleUnit::Rad, None)
                .unwrap()
                .1
                .is_empty()
        );
    }

    #[test]
    fn degrees_hint() {
        let text = "point,q1,q2\nS,1,2\nS,0.5,-90\nS,1,2\n";
        let (_, w) = parse_poses(text, F, AngleUnit::Rad, None).unwrap();
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].line, Some(3));
        assert_eq!(w[0].field.as_deref(), Some("q2"));
        assert!(w[0].to_string().starts_with("touches.csv:3: field `q2`: "));
        assert!(w[0].message.contains("look like degrees"));
    }

    fn random_poses(seed: u64, joints: usize, rows: usize) -> Poses {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let labels = ["S1", "socket 2", "#3", "a,b", "q\"x", "\"q\""];
        let mut poses = Poses::new(joints);
        for i in 0..rows {
            let q: Vec<f64> = (0..joints).map(|_| rng.random_range(-4.0..4.0)).collect();
            poses.push(labels[i % labels.len()], &q, i + 2);
        }
        poses
    }

    #[test]
    fn round_trip_rad_bit_exact() {
        let p = random_poses(1, 7, 50);
        let mut out = Vec::new();
        write_poses(&mut out, &p, AngleUnit::Rad).unwrap();
        let text = String::from_utf8(out).unwrap();
        let (back, _) = parse_poses(&text, F, AngleUnit::Rad, Some(7)).unwrap();
        assert!(back.labels().eq(p.labels()));
        assert_eq!(back.lines(), p.lines());
        for (a, b) in back.readings().iter().zip(p.readings()) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        // Writing again gives identical bytes.
        let mut again = Vec::new();
        write_poses(&mut again, &back, AngleUnit::Rad).unwrap();
        assert_eq!(String::from_utf8(again).unwrap(), text);
    }

    #[test]
    fn round_trip_deg() {
        // Values read from a degree file are written back exactly.
        let text = "point,q1,q2,q3\nA,0.1,-90.0,179.999\nB,12.345,1e-5,-0.0\n";
        let (p, _) = parse_poses(text, F, AngleUnit::Deg, None).unwrap();
        let mut out = Vec::new();
        write_poses(&mut out, &p, AngleUnit::Deg).unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), text);
        // Arbitrary radians through degrees: within 1 ulp, mostly exact.
        let p = random_poses(2, 6, 200);
        let mut out = Vec::new();
        write_poses(&mut out, &p, AngleUnit::Deg).unwrap();
        let (back, _) =
            parse_poses(std::str::from_utf8(&out).unwrap(), F, AngleUnit::Deg, None).unwrap();
        let (mut exact, mut total) = (0, 0);
        for (a, b) in back.readings().iter().zip(p.readings()) {
            assert!((a - b).abs() <= b.abs() * f64::EPSILON, "{a} {b}");
            exact += usize::from(a.to_bits() == b.to_bits());
            total += 1;
        }
        assert!(exact * 10 >= total * 9, "{exact}/{total} exact");
    }

    #[test]
    fn write_rejects_padded_labels() {
        let mut p = random_poses(3, 2, 3);
        p.push(" pad ", &[0.0, 1.0], 5);
        let e = write_poses(Vec::new(), &p, AngleUnit::Rad).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
    }

    /// Rows formatted in blocks side by side are the bytes of one row after
    /// another, whatever the block size (blocks of 7 rows: windows of
    /// several, on every core), and a refused label ends the writing right
    /// after the rows before it, as a row-by-row writing would.
    #[test]
    fn rows_written_in_blocks_are_the_rows_one_by_one() {
        let one_by_one = |p: &Poses, rows: std::ops::Range<usize>| {
            let mut out = String::new();
            for row in rows {
                let columns = [p.temperatures(), p.times()];
                push_row(&mut out, p, row, AngleUnit::Deg, columns).unwrap();
            }
            out
        };
        let mut p = random_poses(11, 6, 103);
        p.set_tool("smr");
        let whole = one_by_one(&p, 0..p.len());
        for block in [1, 2, 7, 64, 1000] {
            let mut out = Vec::new();
            write_rows(&mut out, &p, AngleUnit::Deg, block).unwrap();
            assert_eq!(String::from_utf8(out).unwrap(), whole, "blocks of {block}");
        }
        let mut bad = random_poses(11, 6, 50);
        bad.push(" pad ", &[0.0; 6], 60);
        for q in random_poses(12, 6, 60).rows() {
            bad.push("S9", q, 70);
        }
        let before = one_by_one(&bad, 0..50);
        let mut out = Vec::new();
        let e = write_rows(&mut out, &bad, AngleUnit::Deg, 7).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput);
        assert_eq!(String::from_utf8(out).unwrap(), before);
        // A tool's name refused after the row's readings: the row is cut
        // whole all the same.
        let mut bad = random_poses(11, 6, 50);
        bad.set_tool("smr");
        let before = one_by_one(&bad, 0..50);
        bad.push("S9", &[0.0; 6], 60);
        bad.set_tool(" pad ");
        bad.push("S9", &[0.0; 6], 61);
        let mut out = Vec::new();
        write_rows(&mut out, &bad, AngleUnit::Deg, 7).unwrap_err();
        assert_eq!(String::from_utf8(out).unwrap(), before);
    }

    /// Labels are stored once; rows refer to them, in order of first
    /// appearance, whether rows of one point follow each other or not.
    #[test]
    fn labels_are_interned() {
        let text = "point,q1\nB,1\nB,2\nA,3\nB,4\nC,5\nA,6\n";
        let (p, _) = parse_poses(text, F, AngleUnit::Rad, None).unwrap();
        assert_eq!(p.points().collect::<Vec<_>>(), ["B", "A", "C"]);
        let ids: Vec<usize> = (0..p.len()).map(|r| p.point(r)).collect();
        assert_eq!(ids, [0, 0, 1, 0, 2, 1]);
        assert_eq!(
            p.labels().collect::<Vec<_>>(),
            ["B", "B", "A", "B", "C", "A"]
        );
    }

    /// Quoted fields (the `csv` crate's path) and plain ones (the byte
    /// splitter) read the same file the same way.
    #[test]
    fn quoted_and_plain_files_agree() {
        let plain = "# c\npoint,q1,q2\r\nS1, 1.5 ,-2\r\n S2 ,3e-3,4\r\n\n";
        let quoted = "# c\npoint,q1,q2\r\n\"S1\", 1.5 ,-2\r\n S2 ,3e-3,4\r\n\n";
        let (a, _) = parse_poses(plain, F, AngleUnit::Deg, None).unwrap();
        let (b, _) = parse_poses(quoted, F, AngleUnit::Deg, None).unwrap();
        assert_eq!(a, b);
        assert_eq!(a.lines(), [3, 4]);
        for (text, line) in [(plain, 3), (quoted, 3)] {
            let bad = text.replace("1.5", "1.5.");
            assert_at(&err(&bad, None), line, Some("q1"), "`1.5.` is not a number");
        }
    }

    /// The first error is the one of the stage that checks first (a blank
    /// line, the header, a row's width, its values), not the first line.
    #[test]
    fn errors_in_stage_order() {
        let width_after_value = "point,q1,q2\nS,x,2\nS,1\n";
        assert_at(
            &err(width_after_value, None),
            3,
            Some("q2"),
            "missing: the row has 2",
        );
        let blank_after_width = "point,q1,q2\nS,1\nS,1,2\n\nS,1,2\n";
        assert_at(&err(blank_after_width, None), 4, None, "blank line");
        let blank_after_header = "point,q\nS,1\n\nS,2\n";
        assert_at(&err(blank_after_header, None), 3, None, "blank line");
        let value_then_value = "point,q1\nS,y\nS,x\n";
        assert_at(
            &err(value_then_value, None),
            2,
            Some("q1"),
            "`y` is not a number",
        );
        let label_before_value = "point,q1,q2\n,x,2\n";
        assert_at(
            &err(label_before_value, None),
            2,
            Some("point"),
            "empty label",
        );
    }

    /// Numbers the fast path reads and those it leaves to the standard
    /// parser give the standard parser's bits.
    #[test]
    fn numbers_match_the_standard_parser() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let mut text = String::from("point,q1\n");
        let mut want = Vec::new();
        for i in 0..2000 {
            let x: f64 = rng.random_range(-400.0..400.0) * 10f64.powi(rng.random_range(-12..12));
            let s = match i % 6 {
                0 => format!("{x:?}"),
                1 => format!("{x:e}"),
                2 => format!("{x:.3}"),
                3 => format!("+{}", x.abs()),
                4 => format!("{:.0}.", x.trunc()),
                _ => format!("{x:E}"),
            };
            want.push(s.parse::<f64>().unwrap());
            text.push_str(&format!("S,{s}\n"));
        }
        for s in [
            ".5",
            "-.5e+3",
            "1e-320",
            "0.0000000000000000000001",
            "00012",
            "1E5",
        ] {
            want.push(s.parse::<f64>().unwrap());
            text.push_str(&format!("S,{s}\n"));
        }
        let (p, _) = parse_poses(&text, F, AngleUnit::Rad, None).unwrap();
        for (a, b) in p.readings().iter().zip(&want) {
            assert_eq!(a.to_bits(), b.to_bits(), "{b}");
        }
        for s in [
            "1e", "e5", ".", "+", "1.2.3", "0x10", "1_0", "--1", "1e+-2", "inf", "+nan",
        ] {
            let e = err(&format!("point,q1\nS,{s}\n"), None);
            assert_eq!(e.line(), Some(2), "{s}: {e}");
        }
    }

    #[test]
    fn read_from_disk() {
        let dir = std::env::temp_dir().join(format!("aacmm-io-poses-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.csv");
        std::fs::write(&path, "point,q1\nS,1\nS,oops\n").unwrap();
        let e = read_poses(&path, AngleUnit::Deg, None).unwrap_err();
        let s = e.to_string();
        assert!(
            s.starts_with(&format!("{}:3: field `q1`", path.display())),
            "{s}"
        );
        std::fs::write(&path, b"point,q1\nS,1\n\xff,2\n").unwrap();
        let e = read_poses(&path, AngleUnit::Deg, None).unwrap_err();
        assert_eq!(e.line(), Some(3), "{e}");
        assert!(e.to_string().contains("UTF-8"));
        let missing = dir.join("missing.csv");
        let e = read_poses(&missing, AngleUnit::Deg, None).unwrap_err();
        assert!(matches!(e, InputError::Io { .. }));
        assert!(e.to_string().starts_with(&missing.display().to_string()));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn io_poses_parse_poses_or_positions() {
        use crate::io::{AngleUnit, poses::parse_poses_or_positions};
        let text = "point,q1,q2,x,y,z\nP,0,90,1,2,3\nQ,10,0,4,5,6\nR,0,45,0,9,1\n";
        let (poses, warnings, positions) =
            parse_poses_or_positions(text, "t.csv", AngleUnit::Deg, Some(2)).unwrap();
        assert_eq!(poses.labels().collect::<Vec<_>>(), ["P", "Q", "R"]);
        assert_eq!(
            (poses.reading(0)[1], poses.line(2)),
            (std::f64::consts::FRAC_PI_2, 4)
        );
        assert!(warnings.is_empty() && positions.unwrap().len() == 3);
        let (poses, _, positions) =
            parse_poses_or_positions("point,q1\nS,1\n", "p.csv", AngleUnit::Deg, None).unwrap();
        assert!(poses.len() == 1 && positions.is_none());
    }
}
