//! The positions an instrument saw: per row, the readings, the position
//! (and orientation) seen, its frame and tool. Its file is
//! [`crate::io::positions`].

use std::collections::HashMap;

use super::labels::Labels;
use crate::memory::{OutOfMemory, try_grow};

/// The frame of rows that name none (a file without a `frame` column).
pub const DEFAULT_FRAME: &str = "instrument";

/// How far from 1 the length of an orientation's quaternion may be: a
/// tracker writes unit quaternions to about 1e-9; a larger departure is a
/// column mix-up or a hand-typed row, refused rather than normalised.
pub const UNIT_QUATERNION_TOLERANCE: f64 = 1e-6;

/// The fewest positions a frame's registration (six unknowns) can rest on.
pub const MIN_FRAME_POSITIONS: usize = 3;

/// The positions an instrument saw, row by row, with the readings they
/// were seen at — what a reference-position file
/// ([`crate::io::positions`]) is read into, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct Positions {
    pub(crate) joints: usize,
    /// The prismatic joints (bit `j` for joint `j`): readings in mm.
    pub(crate) prismatic: u16,
    /// The point labels, each once.
    labels: Labels,
    /// Per row, its point label (an index into `labels`).
    label_of: Vec<u32>,
    /// The frames, in order of first appearance.
    frames: Vec<String>,
    /// Each frame's index in `frames` (a file may hold many stations).
    frame_index: HashMap<String, usize>,
    /// Per row, its frame (index into `frames`).
    frame_of: Vec<usize>,
    /// Readings, rad, row-major.
    q: Vec<f64>,
    /// Per row, the position seen, mm.
    xyz: Vec<[f64; 3]>,
    /// Per row, the tool's orientation seen (`[w, x, y, z]`, unit, as
    /// read), when the row gives one.
    orientation: Vec<Option<[f64; 4]>>,
    /// The tools rows name, in order of first appearance after the
    /// default tool (always first, [`super::DEFAULT_TOOL`]).
    pub(crate) tools: Vec<String>,
    /// Per tool, its nominal offset (mm, the last joint's frame) once the
    /// arm's tools are known (`resolve_tools`, in [`crate::io::positions`]);
    /// `None` for the default tool (the arm's probe).
    pub(crate) tool_offsets: Vec<Option<[f64; 3]>>,
    /// Per row, its tool (index into `tools`).
    tool_of: Vec<u32>,
    /// Per row, its stated standard uncertainty per coordinate, mm.
    pub(crate) uncertainty: Vec<Option<f64>>,
    /// Per row, its 1-based line.
    pub(crate) lines: Vec<usize>,
    /// Per row, the temperature (°C) and time (s), when recorded.
    temperature: Option<Vec<f64>>,
    time: Option<Vec<f64>>,
    /// Per row and joint (row after row), the direction of approach (`+1`,
    /// `−1`, `0` not known), when recorded ([`crate::io::approach`]).
    pub(crate) approach: Option<Vec<i8>>,
}

impl Positions {
    /// No rows, for `joints` joints.
    pub fn new(joints: usize) -> Positions {
        Positions {
            joints,
            prismatic: 0,
            labels: Labels::default(),
            label_of: Vec::new(),
            frames: Vec::new(),
            frame_index: HashMap::new(),
            frame_of: Vec::new(),
            q: Vec::new(),
            xyz: Vec::new(),
            orientation: Vec::new(),
            tools: vec![super::DEFAULT_TOOL.to_string()],
            tool_offsets: vec![None],
            tool_of: Vec::new(),
            uncertainty: Vec::new(),
            lines: Vec::new(),
            temperature: None,
            time: None,
            approach: None,
        }
    }

    /// Records the last row's temperature (°C) and time (s); a column is
    /// kept only when every row has it (the reader's rule).
    pub(crate) fn record(&mut self, temperature: Option<f64>, time: Option<f64>) {
        let n = self.len();
        for (column, v) in [(&mut self.temperature, temperature), (&mut self.time, time)] {
            match v {
                Some(v) if n == 1 => *column = Some(vec![v]),
                Some(v) => {
                    if let Some(c) = column.as_mut().filter(|c| c.len() + 1 == n) {
                        c.push(v);
                    }
                }
                None => *column = None,
            }
        }
    }

    /// Records the last row's directions of approach (one per joint: `+1`,
    /// `−1`, `0` not known); kept only when every row has them, as
    /// [`Positions::record`].
    ///
    /// # Panics
    /// If `signs` has another joint count than the rows.
    pub(crate) fn record_approach(&mut self, signs: Option<&[i8]>) {
        let n = self.len();
        match signs {
            Some(s) if n == 1 => self.approach = Some(s.to_vec()),
            Some(s) => {
                assert_eq!(s.len(), self.joints, "one direction per joint");
                if let Some(a) =
                    (self.approach.as_mut()).filter(|a| a.len() + s.len() == n * s.len())
                {
                    a.extend_from_slice(s);
                }
            }
            None => self.approach = None,
        }
    }

    /// These rows with the directions of approach `approach` (per row and
    /// joint, row after row: `+1`, `−1`, `0` not known), or without any.
    ///
    /// # Panics
    /// If `approach` does not hold one direction per row and joint.
    pub fn with_approach(mut self, approach: Option<Vec<i8>>) -> Positions {
        if let Some(a) = &approach {
            assert_eq!(a.len(), self.q.len(), "one direction per reading");
        }
        self.approach = approach;
        self
    }

    /// Per row and joint (row after row), the direction of approach, when
    /// recorded ([`crate::io::approach`]).
    pub fn approaches(&self) -> Option<&[i8]> {
        self.approach.as_deref()
    }

    /// Per row, the temperature (°C), when recorded.
    pub fn temperatures(&self) -> Option<&[f64]> {
        self.temperature.as_deref()
    }

    /// Per row, the time (s), when recorded.
    pub fn times(&self) -> Option<&[f64]> {
        self.time.as_deref()
    }

    /// Appends a row: readings `q` (rad), the position (mm) in frame
    /// `frame`, its uncertainty (mm) if stated, and its line.
    ///
    /// # Panics
    ///
    /// When `q` has another joint count than the set's, or memory for the
    /// row cannot be had (as `Vec::push`; the readers return an error).
    pub fn push(
        &mut self,
        label: &str,
        frame: &str,
        q: &[f64],
        xyz: [f64; 3],
        uncertainty: Option<f64>,
        line: usize,
    ) {
        if let Err(e) = self.try_push(label, frame, q, xyz, uncertainty, line) {
            panic!("{e}");
        }
    }

    /// [`Positions::push`], or an [`OutOfMemory`] (and nothing added) when
    /// the row's room cannot be had.
    ///
    /// # Panics
    ///
    /// When `q` has another joint count than the set's.
    pub fn try_push(
        &mut self,
        label: &str,
        frame: &str,
        q: &[f64],
        xyz: [f64; 3],
        uncertainty: Option<f64>,
        line: usize,
    ) -> Result<(), OutOfMemory> {
        assert_eq!(q.len(), self.joints, "one reading per joint");
        self.room_for_row()?;
        let label = self.labels.intern(label, "the positions' labels")?;
        // Rows of one frame usually follow each other: the last row's first.
        let f = match self.frame_of.last() {
            Some(&last) if self.frames[last] == frame => last,
            _ => match self.frame_index.get(frame) {
                Some(&f) => f,
                None => {
                    self.frames.push(frame.to_string());
                    (self.frame_index).insert(frame.to_string(), self.frames.len() - 1);
                    self.frames.len() - 1
                }
            },
        };
        self.label_of.push(label);
        self.frame_of.push(f);
        self.q.extend_from_slice(q);
        self.xyz.push(xyz);
        self.orientation.push(None);
        self.tool_of.push(0);
        self.uncertainty.push(uncertainty);
        self.lines.push(line);
        Ok(())
    }

    /// Room for one more row ([`Positions::push`] then grows nothing
    /// large), or an [`OutOfMemory`]: a reader's growth that cannot be had
    /// is an error, not an abort.
    fn room_for_row(&mut self) -> Result<(), OutOfMemory> {
        let what = "the positions' rows";
        try_grow(&mut self.label_of, what, 1)?;
        try_grow(&mut self.frame_of, what, 1)?;
        try_grow(&mut self.q, what, self.joints)?;
        try_grow(&mut self.xyz, what, 1)?;
        try_grow(&mut self.orientation, what, 1)?;
        try_grow(&mut self.tool_of, what, 1)?;
        try_grow(&mut self.uncertainty, what, 1)?;
        try_grow(&mut self.lines, what, 1)?;
        for c in [&mut self.temperature, &mut self.time]
            .into_iter()
            .flatten()
        {
            try_grow(c, what, 1)?;
        }
        Ok(())
    }

    /// Rows.
    pub fn len(&self) -> usize {
        self.xyz.len()
    }

    /// Whether there is no row.
    pub fn is_empty(&self) -> bool {
        self.xyz.is_empty()
    }

    /// Joints per reading.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// The prismatic joints, bit `j` for joint `j` (none unless read for
    /// such an arm or set by [`Positions::with_shape`]): readings in mm.
    pub fn prismatic_mask(&self) -> u16 {
        self.prismatic
    }

    /// These rows as readings of a chain of `shape` (of their joint
    /// count): its prismatic joints' readings are mm, written as they are.
    ///
    /// # Panics
    /// If `shape` has another joint count than the rows.
    pub fn with_shape(mut self, shape: crate::params::ChainShape) -> Positions {
        assert_eq!(shape.joints(), self.joints, "joints of the shape");
        self.prismatic = shape.prismatic_mask();
        self
    }

    /// The frames, in order of first appearance.
    pub fn frames(&self) -> &[String] {
        &self.frames
    }

    /// Row `i`'s frame (an index into [`Positions::frames`]).
    pub fn frame(&self, i: usize) -> usize {
        self.frame_of[i]
    }

    /// Row `i`'s point label.
    pub fn label(&self, i: usize) -> &str {
        self.labels.get(self.label_of[i] as usize)
    }

    /// Row `i`'s readings, rad.
    pub fn reading(&self, i: usize) -> &[f64] {
        &self.q[i * self.joints..(i + 1) * self.joints]
    }

    /// Every reading, rad, row-major.
    pub fn readings(&self) -> &[f64] {
        &self.q
    }

    /// Row `i`'s position, mm.
    pub fn position(&self, i: usize) -> [f64; 3] {
        self.xyz[i]
    }

    /// Sets the last row's orientation seen: the tool frame in the row's
    /// frame as a quaternion `[w, x, y, z]` (unit: the reader refuses one
    /// that is not, [`UNIT_QUATERNION_TOLERANCE`]), or none.
    ///
    /// # Panics
    /// If there is no row.
    pub(crate) fn set_orientation(&mut self, q: Option<[f64; 4]>) {
        *self.orientation.last_mut().expect("a row to orient") = q;
    }

    /// These rows with the orientations `orientation` (per row, `[w, x, y,
    /// z]` or none): a simulation's, or a file's rows re-oriented.
    ///
    /// # Panics
    /// If `orientation` does not hold one entry per row.
    pub fn with_orientations(mut self, orientation: Vec<Option<[f64; 4]>>) -> Positions {
        assert_eq!(orientation.len(), self.len(), "one orientation per row");
        self.orientation = orientation;
        self
    }

    /// Row `i`'s orientation seen (`[w, x, y, z]`, the tool frame in the
    /// row's frame), when the row gives one.
    pub fn orientation(&self, i: usize) -> Option<[f64; 4]> {
        self.orientation[i]
    }

    /// How many rows give an orientation.
    pub fn oriented_rows(&self) -> usize {
        self.orientation.iter().filter(|o| o.is_some()).count()
    }

    /// Sets the last row's tool by name: empty or [`super::DEFAULT_TOOL`]
    /// is the default tool.
    ///
    /// # Panics
    /// If there is no row.
    pub fn set_tool(&mut self, name: &str) {
        let last = self.tool_of.len().checked_sub(1);
        self.set_tool_of(last.expect("a row to name a tool of"), name);
    }

    /// Sets row `i`'s tool by name, as [`Positions::set_tool`] the last
    /// row's (rows set in order keep the tools in order of first
    /// appearance, as a file's reader has them).
    ///
    /// # Panics
    /// If there is no row `i`.
    pub fn set_tool_of(&mut self, i: usize, name: &str) {
        let k = if name.is_empty() {
            0
        } else {
            match self.tools.iter().position(|t| t == name) {
                Some(k) => k,
                None => {
                    self.tools.push(name.to_string());
                    self.tool_offsets.push(None);
                    self.tools.len() - 1
                }
            }
        };
        self.tool_of[i] = k as u32;
    }

    /// These rows with every row the default tool's (the tools named
    /// forgotten): what [`Positions::set_tool_of`] names them from again.
    pub fn without_tools(mut self) -> Positions {
        self.tools.truncate(1);
        self.tool_offsets.truncate(1);
        self.tool_of.iter_mut().for_each(|k| *k = 0);
        self
    }

    /// The tools named, the default tool ([`super::DEFAULT_TOOL`]) first,
    /// the others in order of first appearance.
    pub fn tools(&self) -> &[String] {
        &self.tools
    }

    /// Row `i`'s tool (an index into [`Positions::tools`]; 0 the default).
    pub fn tool(&self, i: usize) -> usize {
        self.tool_of[i] as usize
    }

    /// Whether some row names a tool other than the default.
    pub(crate) fn has_tools(&self) -> bool {
        self.tool_of.iter().any(|&k| k != 0)
    }

    /// Tool `k`'s nominal offset (mm, the last joint's frame), once known
    /// (`resolve_tools`, in [`crate::io::positions`]); `None` for the
    /// default tool.
    pub(crate) fn tool_offset(&self, k: usize) -> Option<[f64; 3]> {
        self.tool_offsets[k]
    }

    /// Row `i`'s stated uncertainty, mm.
    pub fn uncertainty(&self, i: usize) -> Option<f64> {
        self.uncertainty[i]
    }

    /// Row `i`'s line.
    pub fn line(&self, i: usize) -> usize {
        self.lines[i]
    }

    /// These rows with every revolute joint's reading multiplied by `k`
    /// (a prismatic joint's, mm, as it is): with `k = 180/π`, the numbers
    /// as typed taken as radians — what `--angle-unit rad` would have read
    /// from a file read in degrees.
    pub(crate) fn revolute_scaled(&self, k: f64) -> Positions {
        let mut out = self.clone();
        let joints = self.joints.max(1);
        let slides = |j: usize| j < 16 && self.prismatic & (1 << j) != 0;
        for (i, q) in out.q.iter_mut().enumerate() {
            if !slides(i % joints) {
                *q *= k;
            }
        }
        out
    }

    /// The rows `keep`, in that order (frames renumbered in order of first
    /// appearance among them).
    pub fn subset(&self, keep: &[usize]) -> Positions {
        let mut out = Positions::new(self.joints);
        out.prismatic = self.prismatic;
        for &i in keep {
            out.push(
                self.label(i),
                &self.frames[self.frame_of[i]],
                self.reading(i),
                self.xyz[i],
                self.uncertainty[i],
                self.lines[i],
            );
            out.set_orientation(self.orientation[i]);
            out.set_tool(&self.tools[self.tool(i)]);
            let k = out.tool_of[out.len() - 1] as usize;
            out.tool_offsets[k] = self.tool_offsets[self.tool(i)];
            out.record(
                self.temperature.as_ref().map(|t| t[i]),
                self.time.as_ref().map(|t| t[i]),
            );
            let n = self.joints;
            out.record_approach(self.approach.as_ref().map(|a| &a[i * n..(i + 1) * n]));
        }
        out
    }
}

impl Positions {
    /// The first frame whose rows cannot determine its registration (six
    /// unknowns) — fewer than [`MIN_FRAME_POSITIONS`] distinct positions
    /// (a sphere touched in several poses counts once), or all on one line
    /// — with its first row and why; `None` when every frame can be
    /// registered. Linear in the rows.
    ///
    /// ```
    /// let mut p = aacmm_core::domain::Positions::new(1);
    /// for (i, x) in [0.0, 1.0, 2.0].into_iter().enumerate() {
    ///     p.push("P", "f", &[i as f64], [x, x, x], None, i + 2);
    /// }
    /// assert!(p.unregistrable_frame().unwrap().1.contains("lie on one line"));
    /// ```
    pub fn unregistrable_frame(&self) -> Option<(usize, String)> {
        let mut by_frame: Vec<Vec<usize>> = vec![Vec::new(); self.frames.len()];
        for i in 0..self.len() {
            by_frame[self.frame(i)].push(i);
        }
        for (name, rows) in self.frames.iter().zip(&by_frame) {
            let first = rows[0];
            let distinct = self.distinct_up_to(rows, MIN_FRAME_POSITIONS);
            if distinct < MIN_FRAME_POSITIONS {
                return Some((
                    first,
                    format!(
                        "frame {} has {distinct} distinct position(s); its registration (3 \
                         rotations, 3 translations) needs at least {MIN_FRAME_POSITIONS} not on \
                         one line — give each station or placement several rows, or leave the \
                         `frame` column out if every row is in one frame",
                        crate::error::quoted(name)
                    ),
                ));
            }
            let (length, off) = self.spread_off_line(rows);
            if off <= 1e-6 * length.max(1.0) {
                return Some((
                    first,
                    format!(
                        "the positions of frame {} lie on one line: a rotation about it is \
                         not determined; measure points off that line",
                        crate::error::quoted(name)
                    ),
                ));
            }
        }
        None
    }

    /// How many distinct positions `rows` hold, counting no further than
    /// `enough`.
    fn distinct_up_to(&self, rows: &[usize], enough: usize) -> usize {
        let mut seen: Vec<[f64; 3]> = Vec::with_capacity(enough);
        for &i in rows {
            let x = self.position(i);
            if !seen.contains(&x) {
                seen.push(x);
                if seen.len() == enough {
                    break;
                }
            }
        }
        seen.len()
    }

    /// The largest distance of a position of `rows` from the first, and
    /// the largest distance of one from the line through the first and
    /// that one, mm.
    fn spread_off_line(&self, rows: &[usize]) -> (f64, f64) {
        let o = self.position(rows[0]);
        let d = |i: usize| {
            let x = self.position(i);
            [x[0] - o[0], x[1] - o[1], x[2] - o[2]]
        };
        let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let far = rows
            .iter()
            .map(|&i| d(i))
            .max_by(|a, b| norm(*a).total_cmp(&norm(*b)))
            .unwrap_or([0.0; 3]);
        let length = norm(far);
        if length == 0.0 {
            return (0.0, 0.0);
        }
        let u = far.map(|v| v / length);
        let off = rows
            .iter()
            .map(|&i| {
                let v = d(i);
                let along = v[0] * u[0] + v[1] * u[1] + v[2] * u[2];
                norm(std::array::from_fn(|k| v[k] - along * u[k]))
            })
            .fold(0.0, f64::max);
        (length, off)
    }
}
