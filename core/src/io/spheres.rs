//! Sphere-surface files: points probed on the surface of reference
//! spheres — CSV with the header `sphere,q1,…,qn` and the optional column
//! `articulation`.
//!
//! ```text
//! sphere,q1,q2,q3,q4,q5,q6
//! S1,10,-45,120,-80,60,0
//! S1,12,-44,118,-78,61,5
//! ```
//!
//! Each row is one touch of the probe's ball on the surface of the sphere
//! its `sphere` label names (a placement of a reference sphere: the same
//! sphere moved is another label). The sphere's centre is unknown and
//! fitted; its diameter is stated on the command line (`--sphere-diameter`)
//! or fitted too; the probe's ball diameter is the arm file's (`[probe]
//! ball_diameter_mm`). Joint readings are in the unit the caller declares,
//! as in a poses file. `articulation` (a whole number ≥ 1, on every row or
//! none) groups a placement's points by the arm's articulation, for the
//! acceptance tests that need it; a fit ignores it. `tool` (after it, when
//! both are there) names the probe of a row: one of the arm file's
//! `[[tool]]` entries (its offset and `ball_diameter_mm`), an empty cell or
//! `probe` the arm's `[probe]`. A placement is probed by one tool: a
//! probe's placements are labelled apart from another's (`S1.long`).
//!
//! Refused by file, line and field: another header, an empty label, a value
//! that is not a finite number, a sphere with fewer than
//! [`MIN_SPHERE_POINTS`] points (at its first line); where the arm puts the
//! points is checked by `Spheres::check_geometry` (all of a sphere's
//! points on one circle or line cannot fix a sphere). Readings that, as
//! degrees, are all within ±2π give a warning (radians read as degrees), as
//! the poses reader's.

use std::path::Path;

use super::Warning;
use super::columns::JointColumns;
use super::text::{Record, check_header, parse_f64, read_text, scan_table};
use super::units::AngleUnit;
use crate::domain::{MIN_SPHERE_POINTS, Spheres, Tool, ToolNames};
use crate::error::InputError;

/// The optional column grouping a placement's points by articulation.
pub(crate) const ARTICULATION: &str = "articulation";

/// The optional column naming a row's probe.
pub(crate) const TOOL: &str = "tool";

const SHAPE: &str = "sphere,q1,...,qn[,articulation][,tool]";

/// Below this ratio of the smallest to the largest spread of a sphere's
/// points (the centred points' singular values), they lie on one circle (or
/// a line) and fix no sphere: the least squares would pick a centre
/// anywhere along the circle's axis. A 25-point ISO 10360-5 pattern over a
/// hemisphere has about 0.6; a cap of ±10° about its pole about 0.06.
pub(crate) const MIN_SPHERE_DEPTH_RATIO: f64 = 0.02;

/// What the reader adds to [`Spheres`]: the geometry of a file's points
/// checked, in the file's words.
impl Spheres {
    /// Refuses a sphere whose points, where an arm puts them (`positions`,
    /// one per row, mm), cannot fix a sphere: all on one circle or line —
    /// the smallest singular value of the sphere's centred points below
    /// [`MIN_SPHERE_DEPTH_RATIO`] of the largest (a plane through them
    /// leaves the centre anywhere along the circle's axis). Named by the
    /// sphere's first line and the field `sphere`; when the readings look
    /// like radians read as degrees, the message says so (the points then
    /// huddle together whatever was touched).
    ///
    /// # Errors
    ///
    /// As above, naming `file`.
    pub(crate) fn check_geometry(
        &self,
        file: &str,
        positions: &[[f64; 3]],
    ) -> Result<(), InputError> {
        for (s, name) in self.spheres().iter().enumerate() {
            let rows = self.rows_of(s);
            let points: Vec<[f64; 3]> = rows.iter().map(|&i| positions[i]).collect();
            let (depth, spread) = depth_and_spread(&points);
            if depth >= MIN_SPHERE_DEPTH_RATIO * spread && spread > 0.0 {
                continue;
            }
            let radians = super::poses::look_like_radians(
                self.readings(),
                self.len(),
                (self.joints(), self.prismatic_mask()),
                1f64.to_degrees(),
            );
            let message = format!(
                "sphere {}: its {} points lie on one circle (or line): they are {:.4} mm RMS \
                 off their best plane against a spread of {:.4} mm (less than {} %), and such \
                 points fix no sphere (its centre could be anywhere along the circle's axis); \
                 probe the sphere over a cap, e.g. ISO 10360-5's 25 points over a hemisphere{}",
                crate::error::quoted(name),
                rows.len(),
                depth,
                spread,
                MIN_SPHERE_DEPTH_RATIO * 100.0,
                if radians {
                    "; every joint reading, read as degrees, is within ±6.28°: the readings \
                     look like radians read as degrees (pass --angle-unit rad if so)"
                } else {
                    ""
                }
            );
            return Err(InputError::field(
                file,
                self.line(rows[0]),
                "sphere",
                message,
            ));
        }
        Ok(())
    }
}

/// The RMS distance of `points` from their best plane, and the RMS of their
/// largest spread (the centred points' smallest and largest singular
/// values over `√n`), mm.
fn depth_and_spread(points: &[[f64; 3]]) -> (f64, f64) {
    let c = crate::geometry::centroid(points);
    let mut m = nalgebra::Matrix3::<f64>::zeros();
    for p in points {
        let d = nalgebra::Vector3::new(p[0] - c[0], p[1] - c[1], p[2] - c[2]);
        m += d * d.transpose();
    }
    let n = points.len().max(1) as f64;
    let e = m.symmetric_eigenvalues();
    let (lo, hi) = (e.min().max(0.0), e.max().max(0.0));
    ((lo / n).sqrt(), (hi / n).sqrt())
}

/// Reads a sphere-surface file (standard input for `-`), readings in
/// `unit` (a prismatic joint's in mm); messages name the file as
/// [`super::source_name`] gives it.
///
/// # Errors
///
/// As [`parse_spheres`].
pub fn read_spheres(
    path: &Path,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<(Spheres, Vec<Warning>), InputError> {
    let (file, text) = read_text(path)?;
    parse_spheres(&text, &file, unit, joints)
}

/// Parses the text of a sphere-surface file; `file` names it in messages.
/// Returns the rows and a warning when the readings look like radians read
/// as degrees.
///
/// ```
/// use aacmm_core::io::{AngleUnit, spheres::parse_spheres};
/// let rows: String = (0..4).map(|i| format!("S1,{i},90\n")).collect();
/// let (s, warnings) = parse_spheres(&format!("sphere,q1,q2\n{rows}"), "s.csv", AngleUnit::Deg, 2).unwrap();
/// assert_eq!((s.len(), s.spheres(), s.line(3)), (4, &["S1".to_string()][..], 5));
/// assert!(warnings.is_empty());
/// let e = parse_spheres("sphere,q1,q2\nS1,0,90\n", "s.csv", AngleUnit::Deg, 2).unwrap_err();
/// assert!(e.to_string().starts_with("s.csv:2: field `sphere`: sphere `S1` has 1 point"), "{e}");
/// ```
///
/// # Errors
///
/// A header other than `sphere,q1,...,qn[,articulation]` (or another joint
/// count than `joints` asks, or a `tool` column), an empty label, a value
/// that is not a finite number, an articulation that is not a whole number
/// from 1, a file without rows, and a sphere with fewer than
/// [`MIN_SPHERE_POINTS`] points: each naming the line and field.
pub fn parse_spheres(
    text: &str,
    file: &str,
    unit: AngleUnit,
    joints: impl Into<JointColumns>,
) -> Result<(Spheres, Vec<Warning>), InputError> {
    let columns = joints.into();
    let expected = columns.expected();
    let mut layout: Option<Header> = None;
    let tools = columns
        .tools()
        .cloned()
        .unwrap_or_else(|| ToolNames::of(&[]));
    let mut out: Option<Spheres> = None;
    let mut q = Vec::new();
    scan_table(
        text,
        file,
        SHAPE,
        "one row per point probed",
        |h| header_layout(h, file, expected).map(|_| ()),
        |h, line, f| {
            let header = match &mut layout {
                Some(l) => *l,
                None => *layout.insert(header_layout(h, file, expected)?),
            };
            let out =
                out.get_or_insert_with(|| Spheres::new(header.joints, columns.prismatic_mask()));
            parse_row(
                f,
                (file, line),
                header,
                (unit, &columns, &tools),
                &mut q,
                out,
            )
        },
    )?;
    let out = out.unwrap_or_else(|| Spheres::new(0, 0));
    check_counts(&out, file)?;
    check_one_tool_per_sphere(&out, file)?;
    let radians = super::poses::look_like_radians(
        out.readings(),
        out.len(),
        (out.joints(), out.prismatic_mask()),
        1f64.to_degrees(),
    );
    let warnings = match unit {
        AngleUnit::Deg if radians => vec![Warning {
            file: file.to_string(),
            line: None,
            field: None,
            message: format!(
                "angles declared in degrees, but every |q| in all {} rows is below 2π (6.28°): \
                 these angles look like radians; pass --angle-unit rad if so",
                out.len()
            ),
        }],
        _ => Vec::new(),
    };
    Ok((out, warnings))
}

/// What a header says: the joint count and the optional columns present.
#[derive(Clone, Copy, Debug)]
struct Header {
    joints: usize,
    articulated: bool,
    tooled: bool,
}

/// The header's joint count and its optional columns (`articulation`,
/// then `tool`).
fn header_layout(h: &Record, file: &str, expected: Option<usize>) -> Result<Header, InputError> {
    let tooled = h.fields.last().is_some_and(|f| f == TOOL);
    let before_tool = h.fields.len() - usize::from(tooled);
    let articulated = before_tool > 0 && h.fields[before_tool - 1] == ARTICULATION;
    let joints = before_tool.saturating_sub(1 + usize::from(articulated));
    let want = expected.unwrap_or(joints);
    let mut names: Vec<String> = vec!["sphere".into()];
    names.extend((1..=want).map(|j| format!("q{j}")));
    let mut tail = String::new();
    if articulated {
        names.push(ARTICULATION.into());
        tail += ",articulation";
    }
    if tooled {
        names.push(TOOL.into());
        tail += ",tool";
    }
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    check_header(h, file, &names, &format!("sphere,q1,...,q{want}{tail}"))?;
    if want == 0 {
        return Err(InputError::field(
            file,
            h.line,
            "q1",
            format!("missing joint columns in the header; the header must be `{SHAPE}`"),
        ));
    }
    Ok(Header {
        joints: want,
        articulated,
        tooled,
    })
}

/// One data row into `out`.
fn parse_row(
    f: &[&str],
    (file, line): (&str, usize),
    header: Header,
    (unit, columns, tools): (AngleUnit, &JointColumns, &ToolNames),
    q: &mut Vec<f64>,
    out: &mut Spheres,
) -> Result<(), InputError> {
    let joints = header.joints;
    if f[0].is_empty() {
        let message = "empty label: each row names the sphere (placement) probed";
        return Err(InputError::field(file, line, "sphere", message));
    }
    q.clear();
    for j in 0..joints {
        let v = parse_f64(f[1 + j], file, line, &format!("q{}", j + 1))?;
        columns.check_stroke(j, v, file, line)?;
        q.push(columns.to_internal(j, v, unit));
    }
    let articulation = if header.articulated {
        let cell = f[1 + joints];
        match cell.parse::<u32>() {
            Ok(a) if a >= 1 => Some(a),
            _ => {
                let message = format!(
                    "{} is not an articulation: a whole number from 1, on every row",
                    crate::error::quoted(cell)
                );
                return Err(InputError::field(file, line, ARTICULATION, message));
            }
        }
    } else {
        None
    };
    out.push(f[0], q, line, articulation);
    if header.tooled {
        let cell = f[1 + joints + usize::from(header.articulated)];
        if tools.of_cell(cell, file, line)? != 0 {
            out.set_tool(&Tool {
                name: cell.to_string(),
                offset: tools.offset(cell).unwrap_or([0.0; 3]),
                ball_diameter_mm: tools.ball_diameter(cell),
            });
        }
    }
    Ok(())
}

/// Refuses a sphere probed by more than one tool, at the first row of a
/// second tool: the fits take a placement's points as one probe's (one
/// ball, one set of offsets to the sphere's centre).
///
/// # Errors
///
/// As above, naming `file`, the line and the field `tool`.
pub(crate) fn check_one_tool_per_sphere(s: &Spheres, file: &str) -> Result<(), InputError> {
    for (k, name) in s.spheres().iter().enumerate() {
        let rows = s.rows_of(k);
        let first = s.tool(rows[0]);
        if let Some(&i) = rows.iter().find(|&&i| s.tool(i) != first) {
            let message = format!(
                "sphere {} is probed by {} (line {}) and by {}: each placement is one probe's; \
                 label each probe's placements apart (e.g. `{}.{}`)",
                crate::error::quoted(name),
                crate::error::quoted(&s.tools()[first].name),
                s.line(rows[0]),
                crate::error::quoted(&s.tools()[s.tool(i)].name),
                name,
                s.tools()[s.tool(i)].name
            );
            return Err(InputError::field(file, s.line(i), TOOL, message));
        }
    }
    Ok(())
}

/// Refuses a sphere with fewer than [`MIN_SPHERE_POINTS`] points, at its
/// first line (the reader's check, for rows made in memory too).
///
/// # Errors
///
/// As above, naming `file`, the line and the field `sphere`.
pub(crate) fn check_counts(s: &Spheres, file: &str) -> Result<(), InputError> {
    for (k, name) in s.spheres().iter().enumerate() {
        let rows = s.rows_of(k);
        if rows.len() < MIN_SPHERE_POINTS {
            let message = format!(
                "sphere {} has {} point{}: a sphere of unknown centre needs at least \
                 {MIN_SPHERE_POINTS} points on its surface, not on one circle",
                crate::error::quoted(name),
                rows.len(),
                if rows.len() == 1 { "" } else { "s" }
            );
            return Err(InputError::field(file, s.line(rows[0]), "sphere", message));
        }
    }
    Ok(())
}

/// Writes `s` (readings in `unit`; a slide's in mm) in the format
/// [`parse_spheres`] reads, numbers read back bit-exactly in rad and mm.
///
/// # Errors
///
/// The writer's; a label with surrounding whitespace (reading trims it).
pub fn write_spheres(
    mut w: impl std::io::Write,
    s: &Spheres,
    unit: AngleUnit,
) -> std::io::Result<()> {
    use super::text::{fmt_f64, quote};
    let mut header = String::from("sphere");
    for j in 1..=s.joints() {
        header.push_str(&format!(",q{j}"));
    }
    if s.has_articulation() {
        header.push_str(",articulation");
    }
    let tooled = s.has_tools();
    if tooled {
        header.push_str(",tool");
    }
    header.push('\n');
    w.write_all(header.as_bytes())?;
    for i in 0..s.len() {
        let mut line = quote(&s.spheres()[s.sphere(i)])?.into_owned();
        for (j, &x) in s.reading(i).iter().enumerate() {
            line.push(',');
            line.push_str(&fmt_f64(JointColumns::to_written(
                s.prismatic_mask(),
                j,
                x,
                unit,
            )));
        }
        if let Some(a) = s.articulation(i) {
            line.push_str(&format!(",{a}"));
        }
        if tooled {
            line.push(',');
            line.push_str(&quote(&s.tools()[s.tool(i)].name)?);
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const F: &str = "s.csv";

    fn parse(text: &str) -> Result<Spheres, InputError> {
        parse_spheres(text, F, AngleUnit::Deg, 2).map(|(s, _)| s)
    }

    fn rows(label: &str, n: usize) -> String {
        (0..n)
            .map(|i| format!("{label},{},{}\n", 10 * i, 90 + i))
            .collect()
    }

    fn assert_at(e: &InputError, line: usize, field: &str, needle: &str) {
        crate::io::testing::assert_at(e, F, line, Some(field), needle);
    }

    #[test]
    fn spheres_lines_and_articulations_are_read_and_written() {
        let text = format!("sphere,q1,q2\n{}{}", rows("A", 4), rows("B", 5));
        let s = parse(&text).unwrap();
        assert_eq!((s.len(), s.spheres().len(), s.rows_of(1).len()), (9, 2, 5));
        assert_eq!((s.sphere(4), s.line(4), s.articulation(0)), (1, 6, None));
        assert_eq!(s.reading(1)[0], 10f64.to_radians());
        let mut out = Vec::new();
        write_spheres(&mut out, &s, AngleUnit::Rad).unwrap();
        let (back, _) =
            parse_spheres(std::str::from_utf8(&out).unwrap(), F, AngleUnit::Rad, 2).unwrap();
        assert_eq!(back, s);
        let art: String = (0..4).map(|i| format!("A,{i},1,{}\n", 1 + i % 2)).collect();
        let s = parse(&format!("sphere,q1,q2,articulation\n{art}")).unwrap();
        assert_eq!((s.articulation(0), s.articulation(3)), (Some(1), Some(2)));
        let sub = s.subset(&[3, 1]);
        assert_eq!(
            (sub.len(), sub.line(0), sub.articulation(1)),
            (2, 5, Some(2))
        );
    }

    #[test]
    fn bad_files_name_their_line_and_field() {
        let e = parse(&format!("sphere,q1,q2\n{}{}", rows("A", 4), rows("B", 3))).unwrap_err();
        assert_at(&e, 6, "sphere", "sphere `B` has 3 points");
        let e = parse(&format!("sphere,q1,q2,tool\n{}", "A,1,2,t\n")).unwrap_err();
        assert_at(
            &e,
            2,
            "tool",
            "`t`: a tool the arm does not know (its tools: `probe`;",
        );
        let e = parse("sphere,q1,q2,tool,articulation\nA,1,2,,1\n").unwrap_err();
        assert_at(&e, 1, "tool", "expected `articulation`");
        let e = parse("sphere,q1,q2,colour\nA,1,2,red\n").unwrap_err();
        assert!(e.to_string().contains("colour"), "{e}");
        let e = parse("point,q1,q2\nA,1,2\n").unwrap_err();
        assert!(e.to_string().contains("sphere"), "{e}");
        let e = parse("sphere,q1,q2\nA,1,x\n").unwrap_err();
        assert_at(&e, 2, "q2", "");
        let e = parse(",q1,q2\n").map(|_| ()).unwrap_err();
        assert!(e.to_string().contains("sphere"), "{e}");
        let e = parse("sphere,q1,q2\n,1,2\n").unwrap_err();
        assert_at(&e, 2, "sphere", "empty label");
        let e = parse("sphere,q1,q2,articulation\nA,1,2,0\n").unwrap_err();
        assert_at(&e, 2, "articulation", "whole number from 1");
        let e = parse("sphere,q1,q2\n").unwrap_err();
        assert_eq!(e.line(), None, "{e}");
        let e = parse("").unwrap_err();
        assert!(e.to_string().starts_with(F), "{e}");
        // Another joint count than the arm's.
        let e = parse_spheres("sphere,q1,q2,q3\nA,1,2,3\n", F, AngleUnit::Deg, 2).unwrap_err();
        assert!(e.to_string().contains("q3"), "{e}");
    }

    #[test]
    fn points_on_one_circle_fix_no_sphere() {
        let s = parse(&format!("sphere,q1,q2\n{}{}", rows("A", 5), rows("B", 4))).unwrap();
        // A: a cap of a sphere of radius 10; B: a circle (z constant).
        let mut xyz: Vec<[f64; 3]> = (0..5)
            .map(|i| {
                let (a, b) = (i as f64 * 1.2, 0.3 + 0.25 * i as f64);
                [
                    10.0 * b.sin() * a.cos(),
                    10.0 * b.sin() * a.sin(),
                    10.0 * b.cos(),
                ]
            })
            .collect();
        xyz.extend((0..4).map(|i| {
            let a = i as f64 * 1.5;
            [5.0 * a.cos(), 5.0 * a.sin(), 3.0 + 1e-4 * i as f64]
        }));
        let e = s.check_geometry(F, &xyz).unwrap_err();
        assert_at(
            &e,
            7,
            "sphere",
            "sphere `B`: its 4 points lie on one circle",
        );
        assert!(!e.to_string().contains("radians"), "{e}");
        xyz[8][2] = 6.0;
        assert!(s.check_geometry(F, &xyz).is_ok());
        // Readings within ±6.28° read as degrees: said so, and warned of.
        let small: String = (0..24)
            .map(|i| format!("A,{},{}\n", i % 5, 1 + i % 3))
            .collect();
        let (r, warnings) =
            parse_spheres(&format!("sphere,q1,q2\n{small}"), F, AngleUnit::Deg, 2).unwrap();
        assert!(
            warnings[0].message.contains("look like radians"),
            "{warnings:?}"
        );
        let e = r.check_geometry(F, &vec![[1.0, 2.0, 3.0]; 24]).unwrap_err();
        assert!(e.to_string().contains("radians read as degrees"), "{e}");
    }
}
