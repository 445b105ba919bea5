//! The data set: what every stage after the files works on.
//!
//! Files → [`DataSet`] → kernel → residuals → solver → report. A data set
//! holds the touches grouped by point (each point's touches contiguous, points
//! in order of first appearance, touches in file order within a point), their
//! readings with sin/cos prepared once for the kernel, and the reference
//! lengths by point index. Labels are checked once, here: every point has at
//! least [`MIN_TOUCHES`] touches and every reference names known points (the
//! lengths reader refuses self-pairs and repeated pairs). Where each value came from lives
//! in a separate [`SourceMap`], so a later stage (metrics, a solver) can
//! report a problem at `file:line` without the caller translating errors.

use std::borrow::Cow;
use std::collections::HashMap;
use std::fmt;
use std::ops::Range;

use crate::corrections::{Beyond, Conditions, Effects, Physics};
use crate::domain::{Poses, Positions, ReferenceLength};
use crate::error::InputError;
use crate::kernel::PreparedPoses;
use crate::params::DhParams;

mod origins;
use origins::{Origins, TooMany};

/// Fewest touches a point needs: the sample spread `2s` divides by `n − 1`,
/// and fewer than three touches say next to nothing about articulation error.
pub const MIN_TOUCHES: usize = 3;

/// Least joint-angle range (degrees) that counts as articulation: a data set
/// in which no point's touches span this much in any joint was taken
/// without moving the arm (the same pose read again, encoder noise at most),
/// and cannot say anything about its geometry.
pub const MIN_ARTICULATION_DEG: f64 = 1.0;

/// Least range of a prismatic joint's readings (mm) that counts as
/// articulation, the slide's counterpart of [`MIN_ARTICULATION_DEG`]: a 1°
/// turn moves the probe about 10 mm at an arm's typical lever of 0.57 m
/// (1° × 573 mm = 10 mm), so a slide must move the probe as far; that is
/// 10⁴ times a linear scale's noise (1 µm, as the simulator's), where 1° is
/// 200 times an angle encoder's (0.005°). Compared with the degrees
/// threshold, a slide's range in mm would count 0.02 mm as a degree.
pub(crate) const MIN_SLIDE_ARTICULATION_MM: f64 = 10.0;

/// One physical point (cone socket) and its touches.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The label used in the files.
    pub label: String,
    /// Its touches: indices into the data set's touch order.
    pub touches: Range<usize>,
}

/// A calibrated distance between two points of the data set, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    /// Index of the first point.
    pub a: usize,
    /// Index of the second point (different from `a`).
    pub b: usize,
    /// The calibrated distance `L`, mm, `> 0`.
    pub distance: f64,
    /// Its standard uncertainty (k = 1), mm, if stated.
    pub uncertainty: Option<f64>,
}

/// A place in an input file: `file:line`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location<'a> {
    /// The file's name as given by the user.
    pub file: &'a str,
    /// 1-based line; 0 when unknown.
    pub line: usize,
}

impl fmt::Display for Location<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            0 => write!(f, "{}", self.file),
            line => write!(f, "{}:{line}", self.file),
        }
    }
}

/// Where the values of a data set came from.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SourceMap {
    poses_file: String,
    /// Per touch (data-set order), its row in the poses file (0-based) and
    /// line. A data set is refused past `u32::MAX` rows or lines (see
    /// [`DataSet::from_poses`]).
    touches: Origins,
    lengths_file: String,
    /// Per reference, its line in the lengths file.
    reference_lines: Vec<usize>,
}

impl SourceMap {
    /// Where touch `i` (data-set order) came from.
    pub fn touch(&self, i: usize) -> Location<'_> {
        Location {
            file: &self.poses_file,
            line: self.touches.line(i),
        }
    }

    /// The row of the poses file that touch `i` (data-set order) was read
    /// from, 0-based: how to put results back in file order.
    pub(crate) fn touch_row(&self, i: usize) -> usize {
        self.touches.row(i)
    }

    /// Where reference `r` came from.
    pub fn reference(&self, r: usize) -> Location<'_> {
        Location {
            file: &self.lengths_file,
            line: self.reference_lines.get(r).copied().unwrap_or(0),
        }
    }

    /// The poses file's name.
    pub(crate) fn poses_file(&self) -> &str {
        &self.poses_file
    }
}

/// Rows of a poses file that repeat, reading for reading (and temperature
/// and direction of approach),
/// the previous row of the same point — a logger that wrote a line twice,
/// or a touch recorded again without the arm moving. Such a row is no
/// independent touch: it adds no scatter, so counted it would lower `e`
/// and understate the noise; the data set counts it once and says so.
/// Only the previous row of the same point is compared (linear time,
/// memory per point), which catches every run of repeats however long.
struct Repeats {
    /// The rows counted once, ascending.
    rows: Vec<usize>,
    /// Per repeated row (same order), the row it repeats.
    of: Vec<usize>,
}

impl Repeats {
    fn of(poses: &Poses) -> Repeats {
        let mut last = vec![usize::MAX; poses.points().len()];
        let (mut rows, mut of) = (Vec::new(), Vec::new());
        if poses.joints() == 0 {
            // Labels without readings (`from_labels`): nothing repeats.
            return Repeats { rows, of };
        }
        let temperature = poses.temperatures();
        let approach = poses.approaches();
        let n = poses.joints();
        let directions = |a: &[i8], row: usize| a[row * n..(row + 1) * n].to_vec();
        for row in 0..poses.len() {
            let p = poses.point(row);
            let prev = last[p];
            let same = prev != usize::MAX
                && poses.reading(row) == poses.reading(prev)
                && temperature.is_none_or(|t| t[row] == t[prev])
                && approach.is_none_or(|a| directions(a, row) == directions(a, prev));
            if same {
                rows.push(row);
                of.push(prev);
            } else {
                last[p] = row;
            }
        }
        Repeats { rows, of }
    }

    /// Whether `row` is counted once (a repeat).
    fn contains(&self, row: usize) -> bool {
        self.rows.binary_search(&row).is_ok()
    }

    /// Per point its touches, repeats counted once; a point with fewer
    /// than [`MIN_TOUCHES`] refused at its first line, saying how many of
    /// its rows repeated.
    fn touch_counts(&self, poses: &Poses, file: &str) -> Result<Vec<usize>, InputError> {
        let labels = poses.points();
        let mut count = vec![0usize; labels.len()];
        let mut first = vec![usize::MAX; labels.len()];
        for row in (0..poses.len()).filter(|&r| !self.contains(r)) {
            let p = poses.point(row);
            count[p] += 1;
            first[p] = first[p].min(row);
        }
        let Some(p) = (0..labels.len()).find(|&p| count[p] < MIN_TOUCHES) else {
            return Ok(count);
        };
        let also = match self.of_point_in(poses, p) {
            0 => String::new(),
            n => format!(
                " ({n} more row{} repeat its readings and count once)",
                plural(n)
            ),
        };
        Err(InputError::field(
            file,
            poses.line(first[p]),
            "point",
            format!(
                "point {} has {} touch{}{also}; at least {MIN_TOUCHES} are needed",
                crate::error::quoted(poses.point_label(p)),
                count[p],
                if count[p] == 1 { "" } else { "es" }
            ),
        ))
    }

    /// How many rows of point `p` were counted once (`poses` as read).
    fn of_point_in(&self, poses: &Poses, p: usize) -> usize {
        self.rows.iter().filter(|&&r| poses.point(r) == p).count()
    }

    /// One warning per point with repeats, at its first repeated line, in
    /// the order of the points' first repeat.
    fn warnings(&self, poses: &Poses, file: &str) -> Vec<crate::io::Warning> {
        let mut by_point: Vec<(usize, Vec<usize>, usize)> = Vec::new();
        for (&row, &of) in self.rows.iter().zip(&self.of) {
            let p = poses.point(row);
            match by_point.iter_mut().find(|(q, ..)| *q == p) {
                Some((_, lines, _)) => lines.push(poses.line(row)),
                None => by_point.push((p, vec![poses.line(row)], poses.line(of))),
            }
        }
        by_point
            .into_iter()
            .map(|(p, lines, first_of)| {
                let n = lines.len();
                crate::io::Warning {
                    file: file.to_string(),
                    line: Some(lines[0]),
                    field: Some("point".to_string()),
                    message: format!(
                        "point {}: {n} row{s} repeat{v} the readings of the point's row before \
                         {them} exactly (line{s} {}; the first repeats line {first_of}) — a logger \
                         that wrote a line twice?; each counted once: {n} row{s} not used, as \
                         repeated rows are no independent touches and would understate the \
                         scatter",
                        crate::error::quoted(poses.point_label(p)),
                        line_ranges(&lines),
                        s = plural(n),
                        v = if n == 1 { "s" } else { "" },
                        them = if n == 1 { "it" } else { "them" },
                    ),
                }
            })
            .collect()
    }
}

/// `""` for one, `"s"` for more.
fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Ascending line numbers as ranges (`12–20, 31`), the first
/// [`MAX_LISTED_RANGES`] ranges and how many lines more.
fn line_ranges(lines: &[usize]) -> String {
    let mut ranges: Vec<(usize, usize)> = Vec::new();
    for &l in lines {
        match ranges.last_mut() {
            Some((_, end)) if *end + 1 == l => *end = l,
            _ => ranges.push((l, l)),
        }
    }
    let shown: Vec<String> = ranges
        .iter()
        .take(MAX_LISTED_RANGES)
        .map(|&(a, b)| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}–{b}")
            }
        })
        .collect();
    let rest: usize = ranges[shown.len()..].iter().map(|(a, b)| b - a + 1).sum();
    match rest {
        0 => shown.join(", "),
        n => format!("{} and {n} more", shown.join(", ")),
    }
}

/// Line ranges a repeat warning lists before counting the rest.
const MAX_LISTED_RANGES: usize = 8;

/// Touches grouped by point, prepared for the kernel, with reference lengths
/// and the source of every value.
#[derive(Clone, Debug, PartialEq)]
pub struct DataSet {
    joints: usize,
    points: Vec<Point>,
    /// Readings (rad), touch-major: `q[i·joints + j]`.
    q: Vec<f64>,
    poses: PreparedPoses,
    references: Vec<Reference>,
    source: SourceMap,
    /// Reference positions seen by an instrument, if any.
    positions: Option<PositionData>,
    /// Per touch (touch order), its temperature (°C) and time (s), when
    /// the poses file recorded them.
    temperature: Option<Vec<f64>>,
    time: Option<Vec<f64>>,
    /// Per touch and joint (touch order, touch-major), the direction of
    /// approach, when the poses file recorded it ([`crate::io::approach`]).
    approach: Option<Vec<i8>>,
    /// One warning per point some of whose rows repeated the row before
    /// them and were counted once ([`DataSet::repeat_warnings`]).
    repeats: Vec<crate::io::Warning>,
    /// Which tool touched each point, when some touch names a tool other
    /// than the default (a `tool` column, [`crate::io::tools`]).
    tools: Option<TouchTools>,
}

/// The tools that touched a data set's points: several probes. A point
/// touched by two tools is two points (the ball's centre in a socket
/// depends on the ball), each tool's points contiguous, the default
/// tool's first ([`crate::domain::Poses`]'s order of tools).
#[derive(Clone, Debug, PartialEq)]
pub struct TouchTools {
    /// The tools' names, the default ([`crate::domain::DEFAULT_TOOL`]) first.
    names: Vec<String>,
    /// Per tool, its nominal offset (mm, the last joint's frame) once
    /// resolved against the arm's ([`DataSet::with_tools`]); `None` for
    /// the default tool (the arm's probe) and before.
    offsets: Vec<Option<[f64; 3]>>,
    /// Per point, its tool (an index into `names`).
    of_point: Vec<u32>,
}

impl TouchTools {
    /// The tools' names, the default first.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Point `p`'s tool (an index into [`TouchTools::names`]).
    pub(crate) fn of_point(&self, p: usize) -> usize {
        self.of_point[p] as usize
    }

    /// Tool `k`'s nominal offset (mm), `None` for the default tool or
    /// before [`DataSet::with_tools`].
    pub(crate) fn offset(&self, k: usize) -> Option<[f64; 3]> {
        self.offsets[k]
    }

    /// The runs of points of one tool, in point order: `(tool, points)`.
    pub fn runs(&self) -> Vec<(usize, Range<usize>)> {
        let mut out: Vec<(usize, Range<usize>)> = Vec::new();
        for (p, &k) in self.of_point.iter().enumerate() {
            match out.last_mut() {
                Some((last, r)) if *last == k as usize => r.end = p + 1,
                _ => out.push((k as usize, p..p + 1)),
            }
        }
        out
    }

    /// The tools some point has, other than the default, in order.
    pub(crate) fn used(&self) -> Vec<usize> {
        (1..self.names.len())
            .filter(|k| self.of_point.iter().any(|&t| t as usize == *k))
            .collect()
    }
}

/// Reference positions prepared for the kernel: the rows of a
/// reference-position file ([`crate::io::positions`]), their readings'
/// sin/cos, and the file.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionData {
    rows: Positions,
    poses: PreparedPoses,
    file: String,
}

impl PositionData {
    /// The rows, in file order.
    pub fn rows(&self) -> &Positions {
        &self.rows
    }

    /// Their readings with sin/cos, for the kernel.
    pub fn poses(&self) -> &PreparedPoses {
        &self.poses
    }

    /// The file they came from.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// Where row `i` came from.
    pub fn at(&self, i: usize) -> Location<'_> {
        Location {
            file: &self.file,
            line: self.rows.line(i),
        }
    }

    /// Rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there is no row (never, once read).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The rows `keep`, in that order.
    pub(crate) fn subset(&self, keep: &[usize]) -> PositionData {
        PositionData::new(
            self.rows.subset(keep),
            &self.file,
            self.poses.prismatic_mask(),
        )
    }

    /// The temperature and time of every row, when recorded.
    pub fn conditions(&self) -> Conditions<'_> {
        Conditions {
            temperature_c: self.rows.temperatures(),
            time_s: self.rows.times(),
            approach: self.rows.approaches(),
        }
    }

    /// The rows of `file` prepared for a chain whose joints of the bits
    /// `prismatic` slide.
    fn new(rows: Positions, file: &str, prismatic: u16) -> PositionData {
        let poses =
            PreparedPoses::from_flat_with(rows.joints(), prismatic, rows.len(), rows.readings());
        PositionData {
            rows,
            poses,
            file: file.to_string(),
        }
    }
}

/// The rows of `poses` grouped by point, in row order within a point:
/// point `p`'s are `order[start[p]..start[p + 1]]`.
fn rows_by_point(poses: &Poses) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; poses.points().len() + 1];
    for row in 0..poses.len() {
        start[poses.point(row) + 1] += 1;
    }
    for p in 1..start.len() {
        start[p] += start[p - 1];
    }
    let mut next = start.clone();
    let mut order = vec![0usize; poses.len()];
    for row in 0..poses.len() {
        let p = poses.point(row);
        order[next[p]] = row;
        next[p] += 1;
    }
    (start, order)
}

/// Refuses readings in which no point is articulated: every point's touches
/// lie within [`MIN_ARTICULATION_DEG`] of each other in every revolute
/// joint, [`MIN_SLIDE_ARTICULATION_MM`] in every prismatic one. Such a
/// campaign (each socket touched in one pose, perhaps read several times)
/// has a Jacobian of rounding and noise only. `q` holds the readings (rad)
/// in touch order, `points` each point's touches. A data set without
/// readings is exempt.
fn check_articulation(poses: &Poses, file: &str) -> Result<(), InputError> {
    let joints = poses.joints();
    if joints == 0 {
        return Ok(());
    }
    // The widest range of a joint at one point, as a fraction of its
    // threshold: (fraction, range in rad or mm, joint, point label),
    // points and joints in order. Each point's rows are
    // visited together (a counting sort), so what this holds grows with the
    // rows (8 bytes each), not with points × joints — a file of as many
    // labels as rows would have taken 16 bytes a joint per row.
    let slides = |j: usize| j < 16 && poses.prismatic_mask() & (1 << j) != 0;
    let fraction = |j: usize, range: f64| {
        if slides(j) {
            range / MIN_SLIDE_ARTICULATION_MM
        } else {
            range.to_degrees() / MIN_ARTICULATION_DEG
        }
    };
    let mut widest = (0.0_f64, 0.0_f64, 0, "");
    let (start, order) = rows_by_point(poses);
    // When no point has the touches it needs, the touch count refuses the
    // file for that (the clearer cause), not this check.
    if start.windows(2).all(|w| w[1] - w[0] < MIN_TOUCHES) {
        return Ok(());
    }
    let mut bounds = vec![(f64::INFINITY, f64::NEG_INFINITY); joints];
    for (p, label) in poses.points().enumerate() {
        bounds.fill((f64::INFINITY, f64::NEG_INFINITY));
        for &row in &order[start[p]..start[p + 1]] {
            for (b, &x) in bounds.iter_mut().zip(poses.reading(row)) {
                *b = (b.0.min(x), b.1.max(x));
            }
        }
        for (j, &(lo, hi)) in bounds.iter().enumerate() {
            let range = hi - lo;
            let f = fraction(j, range);
            if f > widest.0 {
                widest = (f, range, j, label);
            }
        }
    }
    if widest.0 >= 1.0 {
        return Ok(());
    }
    let (_, range, j, label) = widest;
    let (value, unit) = match slides(j) {
        true => (range, " mm"),
        false => (range.to_degrees(), "°"),
    };
    let at = if range > 0.0 {
        format!(
            "the widest range of a joint at one point is {value:.4}{unit} (q{} at point {})",
            j + 1,
            crate::error::quoted(label)
        )
    } else {
        "every point's touches have identical readings".to_string()
    };
    // A slide's threshold is said only where there is a slide: a revolute
    // arm's message is what it always was.
    let slide = match poses.prismatic_mask() {
        0 => String::new(),
        _ => format!(", {MIN_SLIDE_ARTICULATION_MM} mm of a slide"),
    };
    Err(InputError::file_error(
        file,
        format!(
            "no articulation: {at}; each point must be touched in many different poses \
             (joint ranges of at least {MIN_ARTICULATION_DEG}°{slide}, in practice tens of \
             degrees) for the touches to say anything about the arm"
        ),
    ))
}

impl DataSet {
    /// Groups the rows of a poses file by point; `file` names it in errors.
    ///
    /// # Errors
    /// A point with fewer than [`MIN_TOUCHES`] touches (at its first line,
    /// field `point`); an empty file; readings without articulation (no
    /// point's touches span [`MIN_ARTICULATION_DEG`] in any joint).
    ///
    /// ```
    /// use aacmm_core::{dataset::DataSet, io::{AngleUnit, parse_poses}};
    /// let text = "point,q1\nA,1\nB,2\nA,3\nB,4\nA,5\nB,6\n";
    /// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Rad, None).unwrap();
    /// let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    /// assert_eq!(data.points()[1].label, "B");
    /// assert_eq!(data.points()[1].touches, 3..6);
    /// assert_eq!(data.reading(4), &[4.0]);
    /// assert_eq!(data.source().touch(4).to_string(), "p.csv:5");
    ///
    /// let (few, _) = parse_poses("point,q1\nA,1\nA,2\n", "f.csv", AngleUnit::Rad, None).unwrap();
    /// let e = DataSet::from_poses(&few, "f.csv").unwrap_err();
    /// assert!(e.to_string().starts_with("f.csv:2: field `point`: point `A` has 2 touches"));
    /// ```
    pub fn from_poses(poses: &Poses, file: &str) -> Result<DataSet, InputError> {
        match poses
            .keyed_by_tool()
            .map_err(|e| InputError::memory(file, e))?
        {
            Some((keyed, of_point)) => Ok(DataSet::grouped(Cow::Owned(keyed), file)?
                .touched_by(poses, of_point)
                .prepared()),
            None => Ok(DataSet::grouped(Cow::Borrowed(poses), file)?.prepared()),
        }
    }

    /// This data set with its points' tools `of_point` (per point, an
    /// index into `poses`' tools).
    fn touched_by(mut self, poses: &Poses, of_point: Vec<u32>) -> DataSet {
        self.tools = Some(TouchTools {
            names: poses.tools().to_vec(),
            offsets: vec![None; poses.tools().len()],
            of_point,
        });
        self
    }

    /// As [`DataSet::from_poses`], taking the poses: they are freed before
    /// the joints' trig is prepared, so a large file's readings are never
    /// held three times (the reader's, the data set's, its trig).
    ///
    /// # Errors
    /// As [`DataSet::from_poses`].
    pub fn from_poses_owned(poses: Poses, file: &str) -> Result<DataSet, InputError> {
        if poses.has_tools() {
            return DataSet::from_poses(&poses, file);
        }
        Ok(DataSet::grouped(Cow::Owned(poses), file)?.prepared())
    }

    /// The rows grouped by point, readings copied in touch order; the trig
    /// not prepared yet (an empty [`PreparedPoses`]). Poses given to keep
    /// are freed before this returns, their readings kept as they are when
    /// the rows are in touch order already (each point's rows together, no
    /// repeats: a logger's or the simulator's file) rather than copied.
    fn grouped(poses: Cow<'_, Poses>, file: &str) -> Result<DataSet, InputError> {
        if poses.is_empty() {
            return Err(InputError::file_error(file, "no touches"));
        }
        room_for_touches(&poses, file)?;
        // A campaign without articulation is refused as such before its
        // repeated rows are counted once (a static campaign is all repeats).
        check_articulation(&poses, file)?;
        // Rows that repeat the readings of their point's row before them
        // are counted once (see `Repeats`), in the counts and the order.
        let repeats = Repeats::of(&poses);
        let is_repeat = |row: usize| repeats.contains(row);
        // The poses' points are in order of first appearance already: a
        // counting sort by point puts the rows in touch order.
        let labels = poses.points();
        let count = repeats.touch_counts(&poses, file)?;
        let warnings = repeats.warnings(&poses, file);
        let mut start = 0;
        let points: Vec<Point> = (labels.zip(&count))
            .map(|(label, &n)| {
                let touches = start..start + n;
                start = touches.end;
                Point {
                    label: label.to_string(),
                    touches,
                }
            })
            .collect();
        // `next[p]`: where point p's next touch goes.
        let mut next: Vec<usize> = points.iter().map(|p| p.touches.start).collect();
        drop(count);
        let mut order = vec![0usize; poses.len() - repeats.rows.len()];
        for row in (0..poses.len()).filter(|&r| !is_repeat(r)) {
            let p = poses.point(row);
            order[next[p]] = row;
            next[p] += 1;
        }
        let joints = poses.joints();
        let touches = Origins::new(&order, poses.len(), |r| poses.line(r)).map_err(|e| {
            let what = match e {
                TooMany::Touches => "touches",
                TooMany::Lines => "lines",
            };
            InputError::file_error(
                file,
                format!("more than {} {what}: split the campaign", u32::MAX),
            )
        })?;
        let in_touch_order = |c: Option<&[f64]>| c.map(|c| order.iter().map(|&r| c[r]).collect());
        let (temperature, time) = (
            in_touch_order(poses.temperatures()),
            in_touch_order(poses.times()),
        );
        let approach = (poses.approaches()).map(|a| {
            (order.iter())
                .flat_map(|&r| &a[r * joints..(r + 1) * joints])
                .copied()
                .collect()
        });
        let mask = poses.prismatic_mask();
        let in_order =
            order.len() == poses.len() && order.iter().enumerate().all(|(i, &row)| i == row);
        let q = match poses {
            Cow::Owned(poses) if in_order => poses.into_readings(),
            poses => {
                let mut q = Vec::with_capacity(order.len() * joints);
                for &row in &order {
                    q.extend_from_slice(poses.reading(row));
                }
                q
            }
        };
        drop(order);
        Ok(DataSet {
            joints,
            points,
            q,
            // Empty, but of the poses' shape, which `prepared` keeps.
            poses: PreparedPoses::from_flat_with(joints, mask, 0, &[]),
            references: Vec::new(),
            source: SourceMap {
                poses_file: file.to_string(),
                touches,
                ..SourceMap::default()
            },
            positions: None,
            temperature,
            time,
            approach,
            repeats: warnings,
            tools: None,
        })
    }

    /// This data set with its joints' trig prepared from its readings.
    /// [`DataSet::grouped`] checked there is room for it.
    fn prepared(mut self) -> DataSet {
        // `len()` counts the prepared poses: not yet; the source map has
        // every touch (also when there are no joints, `from_labels`).
        let touches = self.source.touches.len();
        let mask = self.poses.prismatic_mask();
        // Every core: the sin and cos of a large file's readings are a
        // good part of reading it, and the same bits on any thread count.
        let threads = crate::parallel::every_core();
        self.poses = PreparedPoses::from_flat_on(self.joints, mask, touches, &self.q, threads);
        self
    }

    /// A data set read from a poses file (angles in `unit`) and an optional
    /// lengths file, for an arm of `joints` joints (a count, a shape or the
    /// arm itself, [`crate::io::JointColumns`]: which columns are lengths;
    /// `-` reads standard input), with the readers' warnings, in the order read — for the
    /// caller to show and to keep in its report.
    ///
    /// # Errors
    ///
    /// The readers' errors, naming file, line and field.
    ///
    /// ```
    /// # std::env::set_current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).unwrap();
    /// use aacmm_core::{DataSet, io::AngleUnit};
    /// let poses = std::path::Path::new("examples/paper-campaign/poses.csv");
    /// let (data, warnings) = DataSet::read(poses, None, AngleUnit::Deg, 6).unwrap();
    /// assert_eq!((data.len(), warnings.len()), (100, 0));
    /// // The same file read as radians: readings that look like degrees.
    /// let (_, warnings) = DataSet::read(poses, None, AngleUnit::Rad, 6).unwrap();
    /// assert!(warnings[0].to_string().starts_with("examples/paper-campaign/poses.csv"), "{warnings:?}");
    /// ```
    pub fn read(
        poses: &std::path::Path,
        lengths: Option<&std::path::Path>,
        unit: crate::io::AngleUnit,
        joints: impl Into<crate::io::JointColumns>,
    ) -> Result<(DataSet, Vec<crate::io::Warning>), InputError> {
        let (p, warnings) = crate::io::read_poses(poses, unit, joints)?;
        let data = DataSet::from_poses_owned(p, &crate::io::source_name(poses))?;
        let mut warnings = warnings;
        warnings.extend_from_slice(data.repeat_warnings());
        let data = match lengths {
            Some(l) => {
                data.with_lengths(&crate::io::read_lengths(l)?, &crate::io::source_name(l))?
            }
            None => data,
        };
        Ok((data, warnings))
    }

    /// One warning for the readings outside the joint `limits` (rad, one
    /// entry per joint, as an arm file's), if any: the warning
    /// [`crate::io::limit_warning`] gives for the poses file, whose first
    /// reading outside is the first in file order (`unit`: the one the
    /// readings were written in, for the message).
    ///
    /// ```
    /// use aacmm_core::{DataSet, io::{AngleUnit, parse_poses}};
    /// let text = "point,q1\nA,0.1\nB,0.2\nA,0.3\nB,2.5\nA,0.5\nB,0.6\nA,3.5\n";
    /// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Rad, None).unwrap();
    /// let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    /// let w = data.limit_warning(&[Some([-2.0, 2.0])], AngleUnit::Rad).unwrap();
    /// assert!(w.to_string().starts_with("p.csv:5: field `q1`: 2 readings outside"), "{w}");
    /// assert!(data.limit_warning(&[None], AngleUnit::Rad).is_none());
    /// ```
    pub fn limit_warning(
        &self,
        limits: &[Option<[f64; 2]>],
        unit: crate::io::AngleUnit,
    ) -> Option<crate::io::Warning> {
        let touches = (0..self.len()).map(|i| {
            let at = self.source.touch(i);
            (self.source.touch_row(i), at.line, self.reading(i))
        });
        let prismatic = self.poses.prismatic_mask();
        let file = self.source.poses_file();
        crate::io::limits::limit_warning_of((limits, prismatic), touches, file, unit)
    }

    /// A data set from arrays: a point label per touch, the touch's joint
    /// readings (rad, one row per touch, every row as long), and reference
    /// lengths between labels. Messages name `<arrays>` and the 1-based
    /// row (touch) or length.
    ///
    /// ```
    /// use aacmm_core::{DataSet, domain::ReferenceLength};
    /// let labels = ["A", "A", "A", "B", "B", "B"];
    /// let q: Vec<Vec<f64>> = (0..6).map(|i| vec![0.1 * i as f64; 6]).collect();
    /// let ab = ReferenceLength::new("A", "B", 500.0, None);
    /// let data = DataSet::from_touches(&labels, &q, &[ab]).unwrap();
    /// assert_eq!((data.len(), data.points().len(), data.references().len()), (6, 2, 1));
    /// let e = DataSet::from_touches(&labels[..5], &q[..5], &[]).unwrap_err();
    /// assert!(e.to_string().starts_with("<arrays>:4: field `point`: point `B` has 2 touches"), "{e}");
    /// ```
    ///
    /// # Errors
    ///
    /// Rows of unequal length, non-finite readings, too few touches per
    /// point, lengths that are not positive or name unknown points.
    pub fn from_touches<S: AsRef<str>, Q: AsRef<[f64]>>(
        labels: &[S],
        readings: &[Q],
        lengths: &[ReferenceLength],
    ) -> Result<DataSet, InputError> {
        const FILE: &str = "<arrays>";
        if labels.len() != readings.len() {
            return Err(InputError::file_error(
                FILE,
                format!(
                    "{} labels for {} rows of readings",
                    labels.len(),
                    readings.len()
                ),
            ));
        }
        let joints = readings.first().map_or(0, |r| r.as_ref().len());
        let memory = |e| InputError::memory(FILE, e);
        let mut poses = Poses::try_with_capacity(joints, readings.len()).map_err(memory)?;
        for (i, (label, row)) in labels.iter().zip(readings).enumerate() {
            let row = row.as_ref();
            if row.len() != joints {
                return Err(InputError::line_error(
                    FILE,
                    i + 1,
                    format!("{} readings, the first row has {joints}", row.len()),
                ));
            }
            if let Some(j) = row.iter().position(|v| !v.is_finite()) {
                return Err(InputError::field(
                    FILE,
                    i + 1,
                    format!("q{}", j + 1),
                    format!("{}: readings must be finite", row[j]),
                ));
            }
            poses.try_push(label.as_ref(), row, i + 1).map_err(memory)?;
        }
        check_length_values(lengths, FILE, |i, _| i + 1)?;
        let lengths: Vec<ReferenceLength> = lengths
            .iter()
            .enumerate()
            .map(|(i, l)| ReferenceLength {
                line: i + 1,
                ..l.clone()
            })
            .collect();
        DataSet::from_poses(&poses, FILE)?.with_checked_lengths(&lengths, FILE)
    }

    /// A data set from flat arrays, as a C caller holds them: `q` the
    /// readings (rad) of `points.len()` touches, `joints` per touch,
    /// row-major (`q[i·joints + j]` is joint `j` of touch `i`); `points[i]`
    /// the id of the point touch `i` touched; `lengths` between point ids.
    /// Labels are the ids in decimal. Checked as the file readers check
    /// files, with messages that name the array and its 0-based index
    /// (`q[5]`, `points[3]`, `lengths[0]`, each [`InputError::file`]);
    /// afterwards a touch `i` is located at `points:i+1` and a length `r` at
    /// `lengths:r+1` (reports count from 1, as for a file's lines).
    ///
    /// ```
    /// use aacmm_core::dataset::{ArrayLength, DataSet};
    /// let points = [7, 7, 7, 3, 3, 3];
    /// let q: Vec<f64> = (0..12).map(|i| 0.1 * i as f64).collect();
    /// let l = ArrayLength { point_a: 3, point_b: 7, distance_mm: 500.0, uncertainty_mm: None };
    /// let data = DataSet::from_arrays(2, &q, &points, &[l]).unwrap();
    /// assert_eq!(data.points()[1].label, "3");
    /// assert_eq!((data.references()[0].a, data.references()[0].b), (1, 0));
    /// let e = DataSet::from_arrays(2, &q[..10], &points[..5], &[]).unwrap_err();
    /// assert_eq!(e.to_string(), "points[3]: point 3 has 2 touches; at least 3 are needed");
    /// ```
    ///
    /// # Errors
    ///
    /// `q` of another length than `joints · points.len()`, no touches,
    /// non-finite readings, a point with fewer than [`MIN_TOUCHES`]
    /// touches, readings without articulation, a length that names an
    /// unknown point, joins a point to itself, repeats a pair, or has a
    /// distance that is not positive or an uncertainty below 0.
    pub fn from_arrays(
        joints: usize,
        q: &[f64],
        points: &[u32],
        lengths: &[ArrayLength],
    ) -> Result<DataSet, InputError> {
        let touches = check_touch_arrays(joints, q, points)?;
        let memory = |e| InputError::memory("points", e);
        let mut poses = Poses::try_with_capacity(joints, points.len()).map_err(memory)?;
        for (i, id) in points.iter().enumerate() {
            let row = &q[i * joints..(i + 1) * joints];
            poses
                .try_push(&id.to_string(), row, i + 1)
                .map_err(memory)?;
        }
        let data = DataSet::from_poses_owned(poses, "points")?;
        if lengths.is_empty() {
            return Ok(data);
        }
        data.with_checked_lengths(&array_lengths(lengths, &touches)?, "lengths")
    }

    /// A data set of labelled points without readings (`joints() == 0`): for
    /// figures computed from positions measured elsewhere, and for tests.
    ///
    /// ```
    /// use aacmm_core::dataset::DataSet;
    /// let data = DataSet::from_labels(&["A", "B", "A", "B", "A", "B"], "m.csv").unwrap();
    /// assert_eq!(data.to_touch_order(&[0, 1, 2, 3, 4, 5]), [0, 2, 4, 1, 3, 5]);
    /// ```
    pub fn from_labels<S: AsRef<str>>(labels: &[S], file: &str) -> Result<DataSet, InputError> {
        let memory = |e| InputError::memory(file, e);
        let mut poses = Poses::try_with_capacity(0, labels.len()).map_err(memory)?;
        for (i, label) in labels.iter().enumerate() {
            poses.try_push(label.as_ref(), &[], i + 2).map_err(memory)?;
        }
        DataSet::from_poses(&poses, file)
    }

    /// Values given per row of the poses file, put in touch order.
    pub fn to_touch_order<T: Copy>(&self, by_row: &[T]) -> Vec<T> {
        self.source.touches.rows().map(|r| by_row[r]).collect()
    }

    /// Adds reference lengths read from `file`, naming the points by label.
    ///
    /// # Errors
    /// An unknown point (field `point_a` or `point_b`); a pair given twice, a
    /// length from a point to itself, a distance that is not positive or an
    /// uncertainty that is not a finite number ≥ 0 (which
    /// [`parse_lengths`](crate::io::parse_lengths) refuses already, and
    /// lengths made in memory meet here).
    ///
    /// ```
    /// use aacmm_core::{dataset::DataSet, io::{AngleUnit, parse_lengths, parse_poses}};
    /// let text = "point,q1\nA,1\nA,2\nA,3\nB,4\nB,5\nB,6\n";
    /// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Rad, None).unwrap();
    /// let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    /// let l = parse_lengths("point_a,point_b,distance\nB,A,100\n", "l.csv").unwrap();
    /// let data = data.with_lengths(&l, "l.csv").unwrap();
    /// assert_eq!((data.references()[0].a, data.references()[0].b), (1, 0));
    ///
    /// let bad = parse_lengths("point_a,point_b,distance\nA,C,100\n", "l.csv").unwrap();
    /// let e = DataSet::from_poses(&poses, "p.csv").unwrap().with_lengths(&bad, "l.csv").unwrap_err();
    /// assert!(e.to_string().starts_with("l.csv:2: field `point_b`: unknown point `C`"));
    /// ```
    pub fn with_lengths(
        self,
        lengths: &[ReferenceLength],
        file: &str,
    ) -> Result<DataSet, InputError> {
        // Lengths made in memory have met no reader: their values are
        // checked here as a file's are when it is read.
        check_length_values(lengths, file, |_, l| l.line)?;
        self.with_checked_lengths(lengths, file)
    }

    /// [`DataSet::with_lengths`] of lengths whose values the caller has
    /// checked already (the arrays' constructors check theirs with their
    /// own row numbers and names): what is left is whether the labels
    /// exist and name one point each.
    fn with_checked_lengths(
        mut self,
        lengths: &[ReferenceLength],
        file: &str,
    ) -> Result<DataSet, InputError> {
        let labels: Vec<&str> = self.points.iter().map(|p| p.label.as_str()).collect();
        crate::io::check_lengths_against(lengths, &labels, file)?;
        self.check_lengths_unambiguous(lengths, file)?;
        let index: HashMap<&str, usize> = labels.iter().enumerate().map(|(i, l)| (*l, i)).collect();
        let mut references = Vec::with_capacity(lengths.len());
        for l in lengths {
            let (a, b) = (index[l.a.as_str()], index[l.b.as_str()]);
            references.push(Reference {
                a,
                b,
                distance: l.distance,
                uncertainty: l.uncertainty,
            });
        }
        self.references = references;
        self.source.lengths_file = file.to_string();
        self.source.reference_lines = lengths.iter().map(|l| l.line).collect();
        Ok(self)
    }

    /// Refuses a length naming a label touched by several tools: two
    /// points, whose ball centres differ (the balls' sizes), so which one
    /// the length ends at is not known.
    fn check_lengths_unambiguous(
        &self,
        lengths: &[ReferenceLength],
        file: &str,
    ) -> Result<(), InputError> {
        let Some(t) = &self.tools else {
            return Ok(());
        };
        let mut tools_of: HashMap<&str, Vec<&str>> = HashMap::new();
        for (p, point) in self.points.iter().enumerate() {
            tools_of
                .entry(point.label.as_str())
                .or_default()
                .push(t.names[t.of_point(p)].as_str());
        }
        for l in lengths {
            for (field, label) in [("point_a", &l.a), ("point_b", &l.b)] {
                let Some(named) = tools_of.get(label.as_str()).filter(|n| n.len() > 1) else {
                    continue;
                };
                let named: Vec<String> = named.iter().map(|n| crate::error::quoted(n)).collect();
                return Err(InputError::field(
                    file,
                    l.line,
                    field,
                    format!(
                        "point {} was touched by several tools ({}): each tool's touches are \
                         a point of their own (a ball's centre in a socket depends on the \
                         ball), so which one the length ends at is ambiguous; touch the \
                         lengths' points with one tool",
                        crate::error::quoted(label),
                        named.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// A data set without observations of its own, for an arm of `joints`
    /// joints (`prismatic`: bit `j` for a slide): the evidence is in terms
    /// added to the problem (points probed on spheres,
    /// [`crate::residuals::spheres`]; a term of the caller's).
    pub fn without_touches(joints: usize, prismatic: u16) -> DataSet {
        DataSet {
            joints,
            points: Vec::new(),
            q: Vec::new(),
            poses: PreparedPoses::from_flat_with(joints, prismatic, 0, &[]),
            references: Vec::new(),
            source: SourceMap::default(),
            positions: None,
            temperature: None,
            time: None,
            approach: None,
            repeats: Vec::new(),
            tools: None,
        }
    }

    /// A data set of reference positions only (no touch): the rows of
    /// `positions`, read from `file`.
    ///
    /// # Errors
    ///
    /// A file without rows.
    pub fn from_positions(positions: Positions, file: &str) -> Result<DataSet, InputError> {
        if positions.is_empty() {
            return Err(InputError::file_error(file, "no positions"));
        }
        let joints = positions.joints();
        let prismatic = positions.prismatic_mask();
        Ok(DataSet {
            joints,
            points: Vec::new(),
            q: Vec::new(),
            poses: PreparedPoses::from_flat_with(joints, prismatic, 0, &[]),
            references: Vec::new(),
            source: SourceMap {
                poses_file: String::new(),
                ..SourceMap::default()
            },
            positions: Some(PositionData::new(positions, file, prismatic)),
            temperature: None,
            time: None,
            approach: None,
            repeats: Vec::new(),
            tools: None,
        })
    }

    /// These touches with the reference positions of `positions` (from
    /// `file`), fitted together.
    ///
    /// # Errors
    ///
    /// Positions with another joint count than the touches, naming the
    /// file's header.
    pub fn with_positions(
        mut self,
        positions: Positions,
        file: &str,
    ) -> Result<DataSet, InputError> {
        if positions.joints() != self.joints {
            return Err(InputError::field(
                file,
                1,
                format!("q{}", positions.joints().min(self.joints) + 1),
                format!(
                    "{} joint columns, the poses {}: positions and touches must be of one arm",
                    positions.joints(),
                    self.joints
                ),
            ));
        }
        self.positions = Some(PositionData::new(
            positions,
            file,
            self.poses.prismatic_mask(),
        ));
        Ok(self)
    }

    /// This data set as readings of a chain of `shape`: its prismatic
    /// joints' readings (mm) used as they are, not through their sin/cos.
    /// The readers read every column as an angle of a revolute joint; a
    /// caller holding the arm gives its shape here (touches and reference
    /// positions alike). Nothing is prepared again when the shape's
    /// joints are all revolute, as the readers assume.
    ///
    /// # Errors
    ///
    /// A shape of another joint count than the readings', naming the poses
    /// file.
    ///
    /// ```
    /// use aacmm_core::{DataSet, io::{AngleUnit, parse_poses}, params::ChainShape};
    /// let text = "point,q1,q2\nA,100,0.1\nA,200,0.2\nA,300,0.3\n";
    /// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Rad, None).unwrap();
    /// let slide: ChainShape = "PR".parse().unwrap();
    /// let data = DataSet::from_poses(&poses, "p.csv").unwrap().for_shape(slide).unwrap();
    /// assert_eq!(data.shape(), Some(slide));
    /// let e = DataSet::from_poses(&poses, "p.csv").unwrap().for_shape("PRR".parse().unwrap());
    /// assert!(e.unwrap_err().to_string().starts_with("p.csv: the arm's chain PRR has 3 joints"));
    /// ```
    pub fn for_shape(mut self, shape: crate::params::ChainShape) -> Result<DataSet, InputError> {
        if shape.joints() != self.joints {
            return Err(InputError::file_error(
                &self.source.poses_file,
                format!(
                    "the arm's chain {shape} has {} joints, the readings {}",
                    shape.joints(),
                    self.joints
                ),
            ));
        }
        let mask = shape.prismatic_mask();
        if mask != self.poses.prismatic_mask() {
            let len = self.poses.len();
            self.poses = PreparedPoses::from_flat_with(self.joints, mask, len, &self.q);
            if let Some(p) = self.positions.take() {
                self.positions = Some(PositionData::new(p.rows, &p.file, mask));
            }
        }
        Ok(self)
    }

    /// The shape of chain the readings were prepared for (all revolute
    /// unless [`DataSet::for_shape`] said otherwise); `None` without
    /// readings.
    pub fn shape(&self) -> Option<crate::params::ChainShape> {
        self.poses.shape()
    }

    /// The reference positions, if any.
    pub fn positions(&self) -> Option<&PositionData> {
        self.positions.as_ref()
    }

    /// These data with each tool their positions name given its nominal
    /// offset from `tools` (an arm's, [`crate::io::tools`]).
    ///
    /// # Errors
    ///
    /// As `Positions::resolve_tools` (in [`crate::io::positions`]): a row
    /// naming a tool `tools` does not have (with the known tools), a tool
    /// seen in one row only.
    pub fn with_tools(mut self, tools: &crate::domain::ToolNames) -> Result<DataSet, InputError> {
        if let Some(p) = &mut self.positions {
            p.rows.resolve_tools(tools, &p.file)?;
        }
        if let Some(t) = &self.tools {
            let mut offsets = vec![None; t.names.len()];
            for (k, offset) in offsets.iter_mut().enumerate().skip(1) {
                // The first touch (in file order) of the tool: where an
                // unknown name is reported.
                let line = (self.points.iter().zip(&t.of_point))
                    .filter(|(_, of)| **of as usize == k)
                    .flat_map(|(p, _)| p.touches.clone())
                    .map(|i| self.source.touches.line(i))
                    .min();
                let Some(line) = line else { continue };
                tools.of_cell(&t.names[k], &self.source.poses_file, line)?;
                *offset = tools.offset(&t.names[k]);
            }
            if let Some(t) = &mut self.tools {
                t.offsets = offsets;
            }
        }
        Ok(self)
    }

    /// The tools that touched the points, when some touch names a tool
    /// other than the default (the arm's probe).
    pub fn touch_tools(&self) -> Option<&TouchTools> {
        self.tools.as_ref()
    }

    /// These data measured with the tool `name` (an arm's `[[tool]]`,
    /// resolved by [`DataSet::with_tools`]): every touch's and reference
    /// position's tool set to it — what files without a `tool` column hold
    /// when every row was made with that tool.
    ///
    /// # Errors
    ///
    /// Touches or positions that name their tools already (a `tool`
    /// column): the tool of every row is stated once, by the file or here.
    pub(crate) fn measured_with(mut self, name: &str) -> Result<DataSet, InputError> {
        if self.tools.is_some() {
            return Err(InputError::file_error(
                &self.source.poses_file,
                format!(
                    "the touches name their probes (a `tool` column): a probe for every touch, \
                     {}, is for a file without one",
                    crate::error::quoted(name)
                ),
            ));
        }
        if !self.points.is_empty() {
            // Every point the tool's: one run of points, in today's order.
            self.tools = Some(TouchTools {
                names: vec![crate::domain::DEFAULT_TOOL.to_string(), name.to_string()],
                offsets: vec![None, None],
                of_point: vec![1; self.points.len()],
            });
        }
        if let Some(p) = &mut self.positions {
            if p.rows.has_tools() {
                return Err(InputError::file_error(
                    &p.file,
                    format!(
                        "the rows name their tools (a `tool` column): a tool for every row, {}, \
                         is for a file without one",
                        crate::error::quoted(name)
                    ),
                ));
            }
            for i in 0..p.rows.len() {
                p.rows.set_tool_of(i, name);
            }
        }
        Ok(self)
    }

    /// This data set with its positions replaced by `positions` (none: the
    /// touches alone).
    pub fn with_position_data(mut self, positions: Option<PositionData>) -> DataSet {
        self.positions = positions;
        self
    }

    /// Touches and reference positions: the observations a fit weighs
    /// (lengths aside).
    pub(crate) fn observation_count(&self) -> usize {
        self.len() + self.positions().map_or(0, |p| p.len())
    }

    /// Readings per touch.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// Number of touches.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether there are no touches (never, for a data set that was built).
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// The points, in order of first appearance.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// The readings of touch `i` (rad).
    pub fn reading(&self, i: usize) -> &[f64] {
        &self.q[i * self.joints..(i + 1) * self.joints]
    }

    /// The warnings of rows counted once because they repeated the readings
    /// of their point's row before them, one per point, naming file, lines
    /// and label: a front end shows them with the reader's warnings (which
    /// [`DataSet::read`] does). Empty for data not built from a poses file.
    ///
    /// ```
    /// use aacmm_core::{DataSet, io::{AngleUnit, parse_poses}};
    /// let text = "point,q1\nA,1\nA,2\nA,2\nA,2\nA,3\n";
    /// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Rad, None).unwrap();
    /// let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    /// assert_eq!(data.len(), 3); // lines 4 and 5 repeat line 3
    /// let w = data.repeat_warnings()[0].to_string();
    /// assert!(w.starts_with("p.csv:4: field `point`: point `A`: 2 rows repeat"), "{w}");
    /// assert!(w.contains("(lines 4–5; the first repeats line 3)"), "{w}");
    /// assert!(w.contains("each counted once: 2 rows not used"), "{w}");
    /// ```
    pub fn repeat_warnings(&self) -> &[crate::io::Warning] {
        &self.repeats
    }

    /// The readings with their sin/cos, for the kernel.
    pub fn poses(&self) -> &PreparedPoses {
        &self.poses
    }

    /// The reference lengths, in file order.
    pub fn references(&self) -> &[Reference] {
        &self.references
    }

    /// Where every value came from.
    pub fn source(&self) -> &SourceMap {
        &self.source
    }

    /// The data set restricted to the points `keep` (indices, in the order
    /// given) and the references among them: a cross-validation fold.
    ///
    /// ```
    /// use aacmm_core::{dataset::DataSet, io::{AngleUnit, parse_poses}};
    /// let text = "point,q1\nA,1\nA,2\nA,3\nB,4\nB,5\nB,6\n";
    /// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Rad, None).unwrap();
    /// let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    /// let b = data.subset(&[1]);
    /// assert_eq!((b.len(), b.points()[0].touches.clone()), (3, 0..3));
    /// assert_eq!(b.source().touch(0).to_string(), "p.csv:5");
    /// ```
    pub fn subset(&self, keep: &[usize]) -> DataSet {
        let mut new_index = vec![usize::MAX; self.points.len()];
        let mut points = Vec::with_capacity(keep.len());
        let mut touches: Vec<usize> = Vec::new();
        for (n, &p) in keep.iter().enumerate() {
            new_index[p] = n;
            let range = &self.points[p].touches;
            points.push(Point {
                label: self.points[p].label.clone(),
                touches: touches.len()..touches.len() + range.len(),
            });
            touches.extend(range.clone());
        }
        let q: Vec<f64> = touches
            .iter()
            .flat_map(|&i| self.reading(i).iter().copied())
            .collect();
        let poses = PreparedPoses::from_flat_with(
            self.joints,
            self.poses.prismatic_mask(),
            touches.len(),
            &q,
        );
        let mut reference_lines = Vec::new();
        let references = self
            .references
            .iter()
            .enumerate()
            .filter(|(_, r)| new_index[r.a] != usize::MAX && new_index[r.b] != usize::MAX)
            .map(|(i, r)| {
                reference_lines.push(self.source.reference_lines[i]);
                Reference {
                    a: new_index[r.a],
                    b: new_index[r.b],
                    ..*r
                }
            })
            .collect();
        DataSet {
            joints: self.joints,
            points,
            q,
            poses,
            references,
            source: SourceMap {
                poses_file: self.source.poses_file.clone(),
                touches: self.source.touches.subset(&touches),
                lengths_file: self.source.lengths_file.clone(),
                reference_lines,
            },
            positions: self.positions.clone(),
            temperature: (self.temperature.as_ref())
                .map(|t| touches.iter().map(|&i| t[i]).collect()),
            time: (self.time.as_ref()).map(|t| touches.iter().map(|&i| t[i]).collect()),
            approach: (self.approach.as_ref()).map(|a| {
                let n = self.joints;
                (touches.iter())
                    .flat_map(|&i| &a[i * n..(i + 1) * n])
                    .copied()
                    .collect()
            }),
            repeats: self.repeats.clone(),
            tools: self.tools.as_ref().map(|t| TouchTools {
                of_point: keep.iter().map(|&p| t.of_point[p]).collect(),
                ..t.clone()
            }),
        }
    }

    /// The readings of every touch (rad), touch-major.
    pub(crate) fn readings(&self) -> &[f64] {
        &self.q
    }

    /// Each set of poses — the touches, the reference positions — by its
    /// file's name, with its conditions: what a model beyond geometry is
    /// checked against ([`crate::corrections::Beyond::check_inputs`]).
    pub(crate) fn condition_sets(&self) -> Vec<(String, Conditions<'_>)> {
        let mut sets = Vec::new();
        if !self.is_empty() {
            sets.push((self.source.poses_file.clone(), self.conditions()));
        }
        if let Some(p) = &self.positions {
            sets.push((p.file.clone(), p.conditions()));
        }
        sets
    }

    /// The temperature and time of every touch, when recorded.
    pub fn conditions(&self) -> Conditions<'_> {
        Conditions {
            temperature_c: self.temperature.as_deref(),
            time_s: self.time.as_deref(),
            approach: self.approach.as_deref(),
        }
    }

    /// This data set as the arm `arm` with the corrections of `physics`
    /// sees it: every pose's readings corrected (and, for an expansion or
    /// a drift, its position transformed) once, so that whatever evaluates
    /// the arm on these data — the metrics, a validation, a report — sees
    /// what the fit saw. Unchanged when `physics` corrects nothing.
    ///
    /// # Errors
    ///
    /// A correction whose conditions were not recorded.
    pub fn corrected(&self, arm: &DhParams, physics: &Physics) -> Result<DataSet, String> {
        if !physics.corrects() {
            return Ok(self.clone());
        }
        let none = Beyond::default();
        let mut out = self.clone();
        if !self.is_empty() {
            out.poses = Effects::new(arm, physics, &none, &self.poses, self.conditions())
                .map_err(|e| format!("{}: {e}", self.source.poses_file))?
                .poses;
        }
        if let Some(p) = &mut out.positions {
            p.poses = Effects::new(arm, physics, &none, &p.poses, p.conditions())
                .map_err(|e| format!("{}: {e}", p.file))?
                .poses;
        }
        Ok(out)
    }
}

/// One reference length of [`DataSet::from_arrays`]: a distance between two
/// point ids. The field names are the ones its messages use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArrayLength {
    /// Id of the first point (as in the `points` array).
    pub point_a: u32,
    /// Id of the second point (another than `point_a`).
    pub point_b: u32,
    /// The distance, mm, `> 0`.
    pub distance_mm: f64,
    /// Its standard uncertainty (k = 1), mm, `≥ 0`; `None` when not stated.
    pub uncertainty_mm: Option<f64>,
}

/// The touch arrays of [`DataSet::from_arrays`], checked: per point id, the
/// index of its first touch and its touch count.
fn check_touch_arrays(
    joints: usize,
    q: &[f64],
    points: &[u32],
) -> Result<HashMap<u32, (usize, usize)>, InputError> {
    if Some(q.len()) != points.len().checked_mul(joints) {
        return Err(InputError::file_error(
            "q",
            format!(
                "{} readings for {} touches of {joints} joints: expected one row of {joints} \
                 per point id",
                q.len(),
                points.len()
            ),
        ));
    }
    if points.is_empty() {
        return Err(InputError::file_error("points", "no touches"));
    }
    if let Some(k) = q.iter().position(|v| !v.is_finite()) {
        return Err(InputError::file_error(
            format!("q[{k}]"),
            format!(
                "{}: readings must be finite (touch {}, joint {})",
                q[k],
                k / joints,
                k % joints + 1
            ),
        ));
    }
    let mut touches: HashMap<u32, (usize, usize)> = HashMap::new();
    for (i, &id) in points.iter().enumerate() {
        touches.entry(id).or_insert((i, 0)).1 += 1;
    }
    // The point that comes first in `points`, so that the message does not
    // depend on the map's order.
    let few = (touches.iter())
        .filter(|(_, (_, count))| *count < MIN_TOUCHES)
        .map(|(&id, &(first, count))| (first, id, count))
        .min();
    if let Some((first, id, count)) = few {
        return Err(InputError::file_error(
            format!("points[{first}]"),
            format!(
                "point {id} has {count} touch{}; at least {MIN_TOUCHES} are needed",
                if count == 1 { "" } else { "es" }
            ),
        ));
    }
    Ok(touches)
}

/// The lengths of [`DataSet::from_arrays`], checked against the point ids
/// `touched`, as the lengths reader's rows.
fn array_lengths(
    lengths: &[ArrayLength],
    touched: &HashMap<u32, (usize, usize)>,
) -> Result<Vec<ReferenceLength>, InputError> {
    let mut pairs = std::collections::HashSet::new();
    let mut refs = Vec::with_capacity(lengths.len());
    for (i, l) in lengths.iter().enumerate() {
        let refuse = |m: String| Err(InputError::file_error(format!("lengths[{i}]"), m));
        if let Some(id) = [l.point_a, l.point_b]
            .into_iter()
            .find(|id| !touched.contains_key(id))
        {
            return refuse(format!("unknown point {id}: no touch has this id"));
        }
        if l.point_a == l.point_b {
            return refuse(format!(
                "point_b = point_a = {}: a length needs two points",
                l.point_a
            ));
        }
        if !(l.distance_mm.is_finite() && l.distance_mm > 0.0) {
            return refuse(format!(
                "distance_mm = {}: must be a positive number",
                crate::error::short(l.distance_mm)
            ));
        }
        if let Some(u) = l.uncertainty_mm.filter(|u| !(u.is_finite() && *u >= 0.0)) {
            return refuse(format!(
                "uncertainty_mm = {}: must be a finite number ≥ 0, or not stated",
                crate::error::short(u)
            ));
        }
        let (a, b) = (l.point_a.min(l.point_b), l.point_a.max(l.point_b));
        if !pairs.insert((a, b)) {
            return refuse(format!("the pair {a}–{b} is given twice"));
        }
        refs.push(ReferenceLength {
            a: l.point_a.to_string(),
            b: l.point_b.to_string(),
            distance: l.distance_mm,
            uncertainty: l.uncertainty_mm,
            line: i + 1,
        });
    }
    Ok(refs)
}

/// Checks, before the data set is built, that what it holds per touch
/// ([`crate::memory::data_set_bytes_per_touch`]) can be allocated: an
/// [`InputError::Memory`] naming `file`, rather than an abort, for a file
/// larger than the process can hold as a data set.
fn room_for_touches(poses: &Poses, file: &str) -> Result<(), InputError> {
    let conditions =
        usize::from(poses.temperatures().is_some()) + usize::from(poses.times().is_some());
    let per_touch = crate::memory::data_set_bytes_per_touch(poses.joints(), conditions);
    let what = format!("a data set of {} touches", poses.len());
    crate::memory::bytes_for(&what, poses.len(), per_touch)
        .and_then(|bytes| crate::memory::room_for(&what, bytes))
        .map_err(|e| InputError::memory(file, e))
}

/// Refuses a pair of points given twice (either order), a distance that is
/// not a positive number, an uncertainty that is not a finite number ≥ 0,
/// and a length from a point to itself; `line(i, l)` places length `i` in
/// `file` for the message.
fn check_length_values(
    lengths: &[ReferenceLength],
    file: &str,
    line: impl Fn(usize, &ReferenceLength) -> usize,
) -> Result<(), InputError> {
    let mut pairs = std::collections::HashSet::new();
    for (i, l) in lengths.iter().enumerate() {
        let bad = |field: &str, m: String| Err(InputError::field(file, line(i, l), field, m));
        let pair = if l.a < l.b {
            (&l.a, &l.b)
        } else {
            (&l.b, &l.a)
        };
        if !pairs.insert(pair) {
            return bad(
                "point_b",
                format!(
                    "the pair {}–{} is given twice",
                    crate::error::shown(&l.a),
                    crate::error::shown(&l.b)
                ),
            );
        }
        if !(l.distance.is_finite() && l.distance > 0.0) {
            return bad(
                "distance",
                format!(
                    "{}: must be a positive number",
                    crate::error::short(l.distance)
                ),
            );
        }
        if let Some(u) = l.uncertainty.filter(|u| !(u.is_finite() && *u >= 0.0)) {
            return bad(
                "uncertainty",
                format!("{}: must be a finite number ≥ 0", crate::error::short(u)),
            );
        }
        if l.a == l.b {
            return bad(
                "point_b",
                format!(
                    "{} again: a length needs two points",
                    crate::error::quoted(&l.a)
                ),
            );
        }
    }
    Ok(())
}

/// Data sets the tests of other modules share.
#[cfg(test)]
pub(crate) mod testing {
    use super::DataSet;

    /// `touches` touches of `points` points in turn (`p0`, `p1`, …), six
    /// readings each spread over ±3 rad without trigonometry of their own.
    pub(crate) fn spread_touches(touches: usize, points: usize) -> DataSet {
        let labels: Vec<String> = (0..touches).map(|i| format!("p{}", i % points)).collect();
        let readings: Vec<Vec<f64>> = (0..touches)
            .map(|i| {
                (0..6)
                    .map(|j| ((i * 7 + j * 13) % 31) as f64 * 0.2 - 3.0)
                    .collect()
            })
            .collect();
        DataSet::from_touches(&labels, &readings, &[]).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{AngleUnit, parse_poses};

    /// Lengths made in memory meet the checks a file's reader makes, each
    /// refusal naming the source alone (they have no line).
    #[test]
    fn lengths_made_in_memory_are_checked_as_a_files_are() {
        let data = || DataSet::from_labels(&["A", "A", "A", "B", "B", "B"], "m").unwrap();
        let refused = |lengths: &[ReferenceLength]| {
            data()
                .with_lengths(lengths, "<memory>")
                .unwrap_err()
                .to_string()
        };
        let l = |a: &str, b: &str, d: f64, u: Option<f64>| ReferenceLength::new(a, b, d, u);
        assert_eq!(
            refused(&[l("A", "B", -1.0, None)]),
            "<memory>: field `distance`: -1: must be a positive number"
        );
        assert_eq!(
            refused(&[l("A", "B", 500.0, Some(f64::NAN))]),
            "<memory>: field `uncertainty`: NaN: must be a finite number ≥ 0"
        );
        assert_eq!(
            refused(&[l("A", "A", 500.0, None)]),
            "<memory>: field `point_b`: `A` again: a length needs two points"
        );
        assert_eq!(
            refused(&[l("A", "B", 500.0, None), l("B", "A", 500.0, None)]),
            "<memory>: field `point_b`: the pair B–A is given twice"
        );
        let ok = data().with_lengths(&[l("A", "B", 500.0, Some(0.002))], "<memory>");
        assert_eq!(ok.unwrap().references().len(), 1);
    }

    /// The orientations a positions file gives travel with its rows: into
    /// the data set, through a shape that re-prepares the readings, and
    /// into a subset (a fold).
    #[test]
    fn positions_keep_their_orientations() {
        let text = "point,q1,q2,q3,x,y,z,qw,qx,qy,qz\n\
                    A,0,1,2,100,0,0,0,1,0,0\n\
                    B,1,0,2,0,100,0,,,,\n\
                    C,1,1,2,0,0,100,0,0,0.6,0.8\n";
        let rows = crate::io::parse_positions(text, "t.csv", AngleUnit::Deg, Some(3)).unwrap();
        let data = DataSet::from_positions(rows, "t.csv").unwrap();
        let data = data.for_shape("PRR".parse().unwrap()).unwrap();
        let p = data.positions().unwrap();
        assert_eq!(p.rows().orientation(0), Some([0.0, 1.0, 0.0, 0.0]));
        let fold = p.subset(&[2, 1]);
        let seen: Vec<_> = (0..2).map(|i| fold.rows().orientation(i)).collect();
        assert_eq!(seen, [Some([0.0, 0.0, 0.6, 0.8]), None]);
    }

    /// A data set made from poses it keeps is the one made from poses it
    /// borrows: rows already in touch order (whose readings it keeps as
    /// they are), rows of points interleaved, a repeated row last (fewer
    /// touches than rows, the rows otherwise in order) or first.
    #[test]
    fn poses_kept_or_borrowed_make_the_same_data_set() {
        let files = [
            "point,q1,q2\nA,0,0\nA,10,5\nA,20,9\nB,1,2\nB,30,4\nB,12,40\n",
            "point,q1,q2\nA,0,0\nB,1,2\nA,10,5\nB,30,4\nA,20,9\nB,12,40\n",
            "point,q1,q2\nA,0,0\nA,10,5\nA,20,9\nB,1,2\nB,30,4\nB,12,40\nB,12,40\n",
            "point,q1,q2\nA,0,0\nA,0,0\nA,10,5\nA,20,9\nB,1,2\nB,30,4\nB,12,40\n",
        ];
        for text in files {
            let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Deg, 2usize).unwrap();
            let borrowed = DataSet::from_poses(&poses, "p.csv").unwrap();
            let kept = DataSet::from_poses_owned(poses, "p.csv").unwrap();
            assert_eq!(kept, borrowed, "{text}");
            assert_eq!(kept.len(), 6, "{text}");
        }
    }

    /// A slide's range is judged in mm against its own threshold: half a
    /// millimetre of carriage (28.6 "degrees" if taken for radians) with
    /// the revolute joints still is no articulation, and says so in mm;
    /// 20 mm is.
    #[test]
    fn a_slide_articulates_by_its_own_threshold_in_mm() {
        let shape: crate::params::ChainShape = "PRR".parse().unwrap();
        let rows = |stroke: f64| {
            let mut t = String::from("point,q1,q2,q3\n");
            for (k, p) in ["A", "A", "A", "B", "B", "B"].iter().enumerate() {
                let x = 100.0 + stroke * (k % 3) as f64 / 2.0;
                t += &format!("{p},{x},10,{}\n", 20.0 + 0.01 * (k % 3) as f64);
            }
            parse_poses(&t, "p.csv", AngleUnit::Deg, shape).unwrap().0
        };
        let e = DataSet::from_poses(&rows(0.5), "p.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(
                "p.csv: no articulation: the widest range of a joint at one point is 0.5000 mm \
                 (q1 at point `A`)"
            ),
            "{e}"
        );
        assert!(e.contains("at least 1°, 10 mm of a slide,"), "{e}");
        assert!(DataSet::from_poses(&rows(20.0), "p.csv").is_ok());
        // A revolute joint's 0.02° still counts as degrees.
        let e = DataSet::from_poses(&rows(0.0), "p.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("is 0.0200° (q3 at point `A`)"), "{e}");
    }

    /// The same readings approached from another side are two touches
    /// (the play puts the link elsewhere); from the same side, a repeat.
    #[test]
    fn a_row_approached_otherwise_is_no_repeat() {
        let t = "point,q1,approach\nA,1,+\nA,1,-\nA,1,-\n";
        let (p, _) = parse_poses(t, "p.csv", AngleUnit::Deg, Some(1)).unwrap();
        let r = Repeats::of(&p);
        assert_eq!((r.rows, r.of), (vec![2], vec![1]));
    }

    fn data(text: &str) -> Result<DataSet, InputError> {
        let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Deg, None).unwrap();
        DataSet::from_poses(&poses, "p.csv")
    }

    /// Each socket touched in one pose, read three times: refused, naming the
    /// problem (this once reached `identify` and panicked there).
    #[test]
    fn static_touches_are_refused() {
        let e = data("point,q1,q2\nA,10,20\nA,10,20\nA,10,20\nB,30,40\nB,30,40\nB,30,40\n")
            .unwrap_err();
        assert_eq!(e.file(), "p.csv");
        assert!(e.to_string().contains("no articulation"), "{e}");
        assert!(e.to_string().contains("identical readings"), "{e}");
    }

    /// Encoder noise alone is not articulation; the message says how far the
    /// widest joint moved, and where.
    #[test]
    fn jitter_is_not_articulation() {
        let e = data("point,q1,q2\nA,10,20\nA,10.01,20\nA,9.99,20.02\nB,30,40\nB,30,40\nB,30,40\n")
            .unwrap_err();
        assert!(e.to_string().contains("0.0200° (q2 at point `A`)"), "{e}");
        // One articulated point is enough (B's rows differ, or they would
        // count once).
        data("point,q1,q2\nA,10,20\nA,10.01,25\nA,9.99,20.02\nB,30,40\nB,30,40.01\nB,30,40\n")
            .unwrap();
    }

    fn length(a: u32, b: u32, distance_mm: f64, uncertainty_mm: Option<f64>) -> ArrayLength {
        ArrayLength {
            point_a: a,
            point_b: b,
            distance_mm,
            uncertainty_mm,
        }
    }

    /// Three points of three touches each, 6 joints.
    fn touch_arrays() -> (Vec<f64>, Vec<u32>) {
        let points = vec![7, 7, 7, 3, 3, 3, 9, 9, 9];
        let q = (0..points.len() * 6)
            .map(|i| (i as f64 * 0.3).sin())
            .collect();
        (q, points)
    }

    /// Arrays are checked as files are, and every refusal names the array
    /// and the 0-based index of what it refuses.
    #[test]
    fn arrays_are_checked_like_files() {
        let (q, points) = touch_arrays();
        let ok = DataSet::from_arrays(6, &q, &points, &[length(7, 9, 500.0, None)]).unwrap();
        assert_eq!(ok.points()[1].label, "3");
        assert_eq!(ok.points()[1].touches, 3..6);
        assert_eq!((ok.references()[0].a, ok.references()[0].b), (0, 2));
        assert_eq!(ok.references()[0].uncertainty, None);
        assert_eq!(ok.source().touch(4).to_string(), "points:5");
        assert_eq!(ok.source().reference(0).to_string(), "lengths:1");
        let cases = [
            (
                length(7, 7, 500.0, None),
                "lengths[0]: point_b = point_a = 7",
            ),
            (length(7, 4, 500.0, None), "lengths[0]: unknown point 4"),
            (length(7, 3, -1.0, None), "lengths[0]: distance_mm = -1"),
            (
                length(7, 3, f64::NAN, None),
                "lengths[0]: distance_mm = NaN",
            ),
            (
                length(7, 3, 1.0, Some(-0.1)),
                "lengths[0]: uncertainty_mm = -0.1",
            ),
            (
                length(7, 3, 1.0, Some(f64::INFINITY)),
                "lengths[0]: uncertainty_mm = inf",
            ),
        ];
        for (l, expected) in cases {
            let e = DataSet::from_arrays(6, &q, &points, &[l]).unwrap_err();
            assert!(e.to_string().starts_with(expected), "{e}");
            assert_eq!(e.file(), "lengths[0]");
        }
        let twice = [length(7, 3, 1.0, Some(0.0)), length(3, 7, 1.0, None)];
        let e = DataSet::from_arrays(6, &q, &points, &twice).unwrap_err();
        assert_eq!(e.to_string(), "lengths[1]: the pair 3–7 is given twice");
        let e = DataSet::from_arrays(6, &q[..48], &points[..8], &[]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "points[6]: point 9 has 2 touches; at least 3 are needed"
        );
        let mut nan = q.clone();
        nan[10] = f64::NAN;
        let e = DataSet::from_arrays(6, &nan, &points, &[]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "q[10]: NaN: readings must be finite (touch 1, joint 5)"
        );
        let e = DataSet::from_arrays(6, &q[..53], &points, &[]).unwrap_err();
        assert!(
            e.to_string().starts_with("q: 53 readings for 9 touches"),
            "{e}"
        );
        let e = DataSet::from_arrays(6, &[], &[], &[]).unwrap_err();
        assert_eq!(e.to_string(), "points: no touches");
        let still = vec![0.5; q.len()];
        let e = DataSet::from_arrays(6, &still, &points, &[]).unwrap_err();
        assert!(e.to_string().starts_with("points: no articulation"), "{e}");
    }
}
