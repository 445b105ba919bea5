//! The touches of points: per row, the point touched, the encoder readings
//! and what was recorded beside them. Its file is [`crate::io::poses`].

use super::labels::Labels;
use crate::memory::{OutOfMemory, try_grow, try_vec};

/// The touches of points, row by row — what a poses file
/// ([`crate::io::poses`]) is read into — stored compactly: each point label
/// once (rows name their point by index), the readings in one row-major
/// array.
///
/// ```
/// use aacmm_core::domain::Poses;
/// let mut poses = Poses::new(2);
/// poses.push("S1", &[0.5, 1.0], 2);
/// poses.push("S2", &[0.0, -1.0], 3);
/// poses.push("S1", &[0.25, 2.0], 4);
/// assert_eq!(poses.len(), 3);
/// assert_eq!(poses.points().collect::<Vec<_>>(), ["S1", "S2"]);
/// assert_eq!((poses.point(2), poses.label(2)), (0, "S1"));
/// assert_eq!(poses.reading(1), [0.0, -1.0]);
/// assert_eq!(poses.line(2), 4);
/// assert_eq!(poses.labels().collect::<Vec<_>>(), ["S1", "S2", "S1"]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Poses {
    /// Number of joints (reading columns).
    pub(crate) joints: usize,
    /// The prismatic joints (bit `j` for joint `j`): their readings are
    /// mm, written as they are whatever the angle unit.
    pub(crate) prismatic: u16,
    /// The labels of the points touched, each once, in order of first
    /// appearance.
    points: Labels,
    /// Per row, the index of its point in `points`.
    pub(crate) point_of: Vec<u32>,
    /// Per row, the `joints` encoder readings, rad, row after row.
    pub(crate) q: Vec<f64>,
    /// Per row, its 1-based line in the source file (for messages); 0 for
    /// a row made in memory.
    pub(crate) lines: Vec<usize>,
    /// Per row, the temperature (°C) and time (s), when the file has the
    /// columns ([`crate::corrections`]).
    temperature: Option<Vec<f64>>,
    time: Option<Vec<f64>>,
    /// Per row, the direction each joint approached its reading from
    /// (`+1`, `−1`, `0` not known), row after row, when the file has the
    /// column ([`crate::io::approach`]).
    pub(crate) approach: Option<Vec<i8>>,
    /// Per row, the tool that touched (an index into `tools`; `0` the
    /// default tool), when the file has a `tool` column.
    pub(crate) tool_of: Option<Vec<u32>>,
    /// The tools the rows name, the default ([`super::DEFAULT_TOOL`])
    /// first, then in order of first appearance; resolved against the
    /// arm's `[[tool]]` later ([`crate::DataSet::with_tools`]).
    pub(crate) tools: Vec<String>,
}

impl Poses {
    /// No rows, readings of `joints` joints.
    pub fn new(joints: usize) -> Poses {
        Poses::with_capacity(joints, 0)
    }

    /// No rows, with room for `rows` rows.
    ///
    /// # Panics
    /// If the room cannot be allocated (see [`Poses::try_with_capacity`]).
    pub fn with_capacity(joints: usize, rows: usize) -> Poses {
        match Poses::try_with_capacity(joints, rows) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        }
    }

    /// No rows, with room for `rows` rows, or an [`OutOfMemory`] when
    /// that cannot be allocated.
    pub fn try_with_capacity(joints: usize, rows: usize) -> Result<Poses, OutOfMemory> {
        let what = "the rows' readings";
        Ok(Poses {
            joints,
            prismatic: 0,
            points: Labels::default(),
            point_of: try_vec(what, rows)?,
            q: try_vec(what, rows.saturating_mul(joints))?,
            lines: try_vec(what, rows)?,
            temperature: None,
            time: None,
            approach: None,
            tool_of: None,
            tools: vec![super::DEFAULT_TOOL.to_string()],
        })
    }

    /// The column of a condition (`temperature` or `time`).
    pub(crate) fn condition_mut(&mut self, name: &str) -> &mut Option<Vec<f64>> {
        if name == "temperature" {
            &mut self.temperature
        } else {
            &mut self.time
        }
    }

    /// Per row, the temperature (°C), when recorded.
    pub fn temperatures(&self) -> Option<&[f64]> {
        self.temperature.as_deref()
    }

    /// Per row, the time (s), when recorded.
    pub(crate) fn times(&self) -> Option<&[f64]> {
        self.time.as_deref()
    }

    /// Per row and joint (row after row), the direction of approach (`+1`,
    /// `−1`, `0` not known), when recorded ([`crate::io::approach`]).
    pub fn approaches(&self) -> Option<&[i8]> {
        self.approach.as_deref()
    }

    /// These poses with the directions of approach `approach` (per row and
    /// joint, row after row: `+1`, `−1`, `0` not known), or without any.
    ///
    /// # Panics
    /// If `approach` does not hold one direction per row and joint.
    pub fn with_approach(mut self, approach: Option<Vec<i8>>) -> Poses {
        if let Some(a) = &approach {
            assert_eq!(a.len(), self.q.len(), "one direction per reading");
        }
        self.approach = approach;
        self
    }

    /// Adds a row: a touch of the point `label` with readings `q` (rad),
    /// read from `line` of its file (or numbered by the caller).
    ///
    /// # Panics
    /// If `q` does not hold [`Poses::joints`] readings, past 2³² distinct
    /// labels, or when the row's memory cannot be had (as `Vec::push`;
    /// [`Poses::try_push`] returns an error instead).
    pub fn push(&mut self, label: &str, q: &[f64], line: usize) {
        if let Err(e) = self.try_push(label, q, line) {
            panic!("{e}");
        }
    }

    /// [`Poses::push`], or an [`OutOfMemory`] (and nothing added) when the
    /// row's memory cannot be had or past 2³² distinct labels.
    ///
    /// # Panics
    /// If `q` does not hold [`Poses::joints`] readings.
    pub fn try_push(&mut self, label: &str, q: &[f64], line: usize) -> Result<(), OutOfMemory> {
        assert_eq!(q.len(), self.joints, "readings of one row");
        let what = "the rows' readings";
        try_grow(&mut self.point_of, what, 1)?;
        try_grow(&mut self.q, what, q.len())?;
        try_grow(&mut self.lines, what, 1)?;
        let id = self.intern(label)?;
        self.point_of.push(id);
        self.q.extend_from_slice(q);
        self.lines.push(line);
        if let Some(a) = &mut self.approach {
            // A row pushed without directions: not known.
            a.extend(std::iter::repeat_n(0, q.len()));
        }
        if let Some(t) = &mut self.tool_of {
            // A row pushed without a tool: the default tool's.
            t.push(0);
        }
        Ok(())
    }

    /// Sets the last row's tool by name (empty or [`super::DEFAULT_TOOL`]:
    /// the default tool); the poses gain a `tool` column if they had none.
    ///
    /// ```
    /// use aacmm_core::domain::Poses;
    /// let mut poses = Poses::new(1);
    /// poses.push("A", &[0.0], 2);
    /// poses.push("A", &[1.0], 3);
    /// poses.set_tool("long");
    /// assert_eq!((poses.tool(0), poses.tool(1)), (0, 1));
    /// assert_eq!(poses.tools(), ["probe", "long"]);
    /// ```
    ///
    /// # Panics
    /// If there is no row.
    pub fn set_tool(&mut self, name: &str) {
        let rows = self.len();
        assert!(rows > 0, "a row to name a tool of");
        let k = self.tool_index(name);
        let of = self.tool_of.get_or_insert_with(|| vec![0; rows]);
        of[rows - 1] = k;
    }

    /// Appends a row's tool by name (the reader's `tool` cell).
    pub(crate) fn push_tool(&mut self, name: &str) {
        let k = self.tool_index(name);
        if let Some(of) = &mut self.tool_of {
            of.push(k);
        }
    }

    /// The index of the tool named `name` among [`Poses::tools`], added if
    /// new (empty or [`super::DEFAULT_TOOL`]: `0`).
    fn tool_index(&mut self, name: &str) -> u32 {
        if name.is_empty() || name == super::DEFAULT_TOOL {
            return 0;
        }
        match self.tools.iter().position(|t| t == name) {
            Some(k) => k as u32,
            None => {
                self.tools.push(name.to_string());
                (self.tools.len() - 1) as u32
            }
        }
    }

    /// The tools the rows name, the default tool first, then in order of
    /// first appearance.
    pub fn tools(&self) -> &[String] {
        &self.tools
    }

    /// Row `row`'s tool (an index into [`Poses::tools`]; `0` the default).
    pub fn tool(&self, row: usize) -> usize {
        self.tool_of.as_ref().map_or(0, |t| t[row] as usize)
    }

    /// Whether some row names a tool other than the default.
    pub(crate) fn has_tools(&self) -> bool {
        self.tool_of
            .as_ref()
            .is_some_and(|t| t.iter().any(|&k| k != 0))
    }

    /// These poses with each point touched by another tool made a point of
    /// its own — a ball's centre in a socket depends on the ball, so the
    /// touches of two probes do not share a centre —, the points ordered by
    /// tool (the default first, then in order of first appearance) and in
    /// order of first appearance within a tool; and per point its tool.
    /// `None` when no row names a tool other than the default (the poses
    /// as they are).
    pub(crate) fn keyed_by_tool(&self) -> Result<Option<(Poses, Vec<u32>)>, OutOfMemory> {
        let Some(of) = self.tool_of.as_ref().filter(|_| self.has_tools()) else {
            return Ok(None);
        };
        let mut id: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
        let mut keys: Vec<(u32, u32)> = Vec::new();
        for (row, &p) in self.point_of.iter().enumerate() {
            let key = (of[row], p);
            id.entry(key).or_insert_with(|| {
                keys.push(key);
                0
            });
        }
        // Stable: first appearance kept within a tool.
        keys.sort_by_key(|&(tool, _)| tool);
        let mut points = Labels::default();
        for (n, key) in keys.iter().enumerate() {
            id.insert(*key, n as u32);
            points.push_new(self.points.get(key.1 as usize), "the point labels")?;
        }
        let point_of = (self.point_of.iter().zip(of))
            .map(|(&p, &t)| id[&(t, p)])
            .collect();
        let tools = keys.iter().map(|&(t, _)| t).collect();
        Ok(Some((
            Poses {
                points,
                point_of,
                ..self.clone()
            },
            tools,
        )))
    }

    /// Appends the rows of `rows` (of the same columns): their points and
    /// tools are these poses' if the labels are (a new one is added, in
    /// order of first appearance), so reading a file in pieces and
    /// appending them gives the poses read whole.
    pub(crate) fn append(&mut self, rows: Poses) -> Result<(), OutOfMemory> {
        let what = "the rows' readings";
        try_grow(&mut self.point_of, what, rows.len())?;
        try_grow(&mut self.q, what, rows.q.len())?;
        try_grow(&mut self.lines, what, rows.len())?;
        let mut point = Vec::with_capacity(rows.points.len());
        for label in rows.points.iter() {
            point.push(self.points.intern(label, "the point labels")?);
        }
        let tool: Vec<u32> = rows.tools.iter().map(|t| self.tool_index(t)).collect();
        self.point_of
            .extend(rows.point_of.iter().map(|&p| point[p as usize]));
        self.q.extend_from_slice(&rows.q);
        self.lines.extend_from_slice(&rows.lines);
        let pairs = [
            (&mut self.temperature, &rows.temperature),
            (&mut self.time, &rows.time),
        ];
        for (into, from) in pairs {
            if let (Some(into), Some(from)) = (into, from) {
                try_grow(into, what, from.len())?;
                into.extend_from_slice(from);
            }
        }
        if let (Some(into), Some(from)) = (&mut self.approach, &rows.approach) {
            try_grow(into, what, from.len())?;
            into.extend_from_slice(from);
        }
        if let (Some(into), Some(from)) = (&mut self.tool_of, &rows.tool_of) {
            try_grow(into, what, from.len())?;
            into.extend(from.iter().map(|&k| tool[k as usize]));
        }
        Ok(())
    }

    /// The index of `label` in `points`, added if new. Rows of one point
    /// usually follow each other: the previous row's point is tried first.
    #[inline]
    pub(crate) fn intern(&mut self, label: &str) -> Result<u32, OutOfMemory> {
        if let Some(&last) = self.point_of.last()
            && self.points.get(last as usize) == label
        {
            return Ok(last);
        }
        self.points.intern(label, "the point labels")
    }

    /// Number of rows (touches).
    pub fn len(&self) -> usize {
        self.point_of.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.point_of.is_empty()
    }

    /// Number of joints (readings per row).
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// The prismatic joints, bit `j` for joint `j` (none unless read for
    /// such an arm or set by [`Poses::with_shape`]): their readings are mm.
    pub fn prismatic_mask(&self) -> u16 {
        self.prismatic
    }

    /// The readings of reference positions, a touch per row of its point
    /// label, with its line (the positions themselves, the frames and the
    /// conditions left out).
    ///
    /// # Errors
    ///
    /// When the rows' memory cannot be had.
    pub(crate) fn from_positions(p: &super::Positions) -> Result<Poses, OutOfMemory> {
        let mut out = Poses {
            prismatic: p.prismatic_mask(),
            ..Poses::try_with_capacity(p.joints(), p.len())?
        };
        for i in 0..p.len() {
            out.try_push(p.label(i), p.reading(i), p.line(i))?;
        }
        Ok(out)
    }

    /// No rows, of the joints (and prismatic joints) of `self`, with room
    /// for `rows` rows.
    ///
    /// # Panics
    /// As [`Poses::with_capacity`].
    pub fn empty_like(&self, rows: usize) -> Poses {
        Poses {
            prismatic: self.prismatic,
            ..Poses::with_capacity(self.joints, rows)
        }
    }

    /// These poses as readings of a chain of `shape` (of their joint
    /// count): its prismatic joints' readings are mm, and
    /// [`crate::io::write_poses`] writes them as they are.
    ///
    /// # Panics
    /// If `shape` has another joint count than the poses.
    pub fn with_shape(mut self, shape: crate::params::ChainShape) -> Poses {
        assert_eq!(shape.joints(), self.joints, "joints of the shape");
        self.prismatic = shape.prismatic_mask();
        self
    }

    /// The labels of the points touched, each once, in order of first
    /// appearance.
    pub fn points(&self) -> impl ExactSizeIterator<Item = &str> + '_ {
        self.points.iter()
    }

    /// The label of point `p` (an index into [`Poses::points`]).
    pub(crate) fn point_label(&self, p: usize) -> &str {
        self.points.get(p)
    }

    /// The index in [`Poses::points`] of the point row `row` touches.
    pub fn point(&self, row: usize) -> usize {
        self.point_of[row] as usize
    }

    /// The label of the point row `row` touches.
    pub fn label(&self, row: usize) -> &str {
        self.points.get(self.point(row))
    }

    /// The label of every row, in row order.
    pub fn labels(&self) -> impl ExactSizeIterator<Item = &str> + '_ {
        self.point_of.iter().map(|&p| self.points.get(p as usize))
    }

    /// Every row's readings, row after row, the rest of the poses freed
    /// (a data set keeps a file's readings this way when its rows are in
    /// touch order already).
    pub(crate) fn into_readings(self) -> Vec<f64> {
        self.q
    }

    /// The readings (rad) of row `row`.
    pub fn reading(&self, row: usize) -> &[f64] {
        &self.q[row * self.joints..(row + 1) * self.joints]
    }

    /// The readings (rad) of every row, row after row.
    pub fn readings(&self) -> &[f64] {
        &self.q
    }

    /// The readings of every row, in row order.
    pub fn rows(&self) -> impl ExactSizeIterator<Item = &[f64]> + '_ {
        (0..self.len()).map(|row| self.reading(row))
    }

    /// The 1-based line of row `row` in its file (0: made in memory).
    pub fn line(&self, row: usize) -> usize {
        self.lines[row]
    }

    /// The line of every row.
    pub fn lines(&self) -> &[usize] {
        &self.lines
    }
}
