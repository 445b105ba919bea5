//! Points probed on the surface of reference spheres. Its file is
//! [`crate::io::spheres`].

use super::{DEFAULT_TOOL, Tool};

/// The fewest points that can fix a sphere of unknown centre and diameter.
pub const MIN_SPHERE_POINTS: usize = 4;

/// Points probed on reference spheres, row by row: per row, the sphere
/// and the readings — what a sphere-surface file ([`crate::io::spheres`])
/// is read into, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct Spheres {
    joints: usize,
    /// The prismatic joints (bit `j` for joint `j`): readings in mm.
    prismatic: u16,
    /// The sphere labels, in order of first appearance.
    names: Vec<String>,
    /// Per row, its sphere (an index into `names`).
    sphere_of: Vec<usize>,
    /// Per sphere, its index's inverse: the sphere of a label (so that
    /// reading a file is linear in its rows whatever the spheres).
    index: std::collections::HashMap<String, usize>,
    /// Per sphere, its rows in file order.
    rows: Vec<Vec<usize>>,
    /// Readings, rad (mm for a slide), row-major.
    q: Vec<f64>,
    /// Per row, its 1-based line.
    lines: Vec<usize>,
    /// Per row, its articulation, when the file has the column.
    articulation: Option<Vec<u32>>,
    /// The tools rows name: the default tool (the arm's `[probe]`) first,
    /// then in order of first appearance.
    tools: Vec<Tool>,
    /// Per row, its tool (an index into `tools`).
    tool_of: Vec<u32>,
}

impl Spheres {
    /// No rows, for `joints` joints (`prismatic`: bit `j` for a slide).
    pub fn new(joints: usize, prismatic: u16) -> Spheres {
        Spheres {
            joints,
            prismatic,
            names: Vec::new(),
            sphere_of: Vec::new(),
            index: std::collections::HashMap::new(),
            rows: Vec::new(),
            q: Vec::new(),
            lines: Vec::new(),
            articulation: None,
            tools: vec![default_tool()],
            tool_of: Vec::new(),
        }
    }

    /// Adds a row: a point on sphere `sphere` at readings `q` (rad; mm for
    /// a slide), from `line`, of articulation `articulation` (kept only
    /// when every row gives one).
    ///
    /// # Panics
    /// If `q` has another joint count than the rows.
    pub fn push(&mut self, sphere: &str, q: &[f64], line: usize, articulation: Option<u32>) {
        assert_eq!(q.len(), self.joints, "a row of {} joints", self.joints);
        let s = match self.index.get(sphere) {
            Some(&s) => s,
            None => {
                self.names.push(sphere.to_string());
                self.index.insert(sphere.to_string(), self.names.len() - 1);
                self.rows.push(Vec::new());
                self.names.len() - 1
            }
        };
        let first = self.sphere_of.is_empty();
        self.rows[s].push(self.sphere_of.len());
        self.sphere_of.push(s);
        self.tool_of.push(0);
        self.q.extend_from_slice(q);
        self.lines.push(line);
        match (articulation, &mut self.articulation) {
            (Some(a), Some(column)) => column.push(a),
            (Some(a), None) if first => self.articulation = Some(vec![a]),
            _ => self.articulation = None,
        }
    }

    /// Sets the last row's tool: `tool` (one of the arm's `[[tool]]`, its
    /// offset and ball); a row not set is the default tool's.
    ///
    /// # Panics
    /// Without a row.
    pub fn set_tool(&mut self, tool: &Tool) {
        let k = match self.tools.iter().position(|t| t.name == tool.name) {
            Some(k) => k,
            None => {
                self.tools.push(tool.clone());
                self.tools.len() - 1
            }
        };
        *self.tool_of.last_mut().expect("a row to name a tool of") = k as u32;
    }

    /// The tools rows name, the default tool first (named
    /// [`DEFAULT_TOOL`]: the arm's `[probe]`, its offset and ball the
    /// arm's — the `Tool`'s own fields unused).
    pub fn tools(&self) -> &[Tool] {
        &self.tools
    }

    /// Row `i`'s tool (an index into [`Spheres::tools`]; 0 the default).
    pub fn tool(&self, i: usize) -> usize {
        self.tool_of[i] as usize
    }

    /// Sphere `s`'s tool (the tool of its rows: one per placement).
    pub(crate) fn tool_of_sphere(&self, s: usize) -> usize {
        self.rows[s].first().map_or(0, |&i| self.tool(i))
    }

    /// These rows, each probed by `tool` (one of an arm's `[[tool]]`):
    /// what a file without a `tool` column holds when every point was
    /// touched with that probe.
    pub(crate) fn as_tool(&self, tool: &Tool) -> Spheres {
        let mut out = Spheres::new(self.joints, self.prismatic);
        for i in 0..self.len() {
            out.push(
                &self.names[self.sphere_of[i]],
                self.reading(i),
                self.line(i),
                self.articulation(i),
            );
            out.set_tool(tool);
        }
        out
    }

    /// Whether some row names a tool other than the default.
    pub(crate) fn has_tools(&self) -> bool {
        self.tool_of.iter().any(|&k| k != 0)
    }

    /// Rows.
    pub fn len(&self) -> usize {
        self.sphere_of.len()
    }

    /// Whether there is no row.
    pub fn is_empty(&self) -> bool {
        self.sphere_of.is_empty()
    }

    /// Joints per row.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// The prismatic joints, bit `j` for joint `j`.
    pub fn prismatic_mask(&self) -> u16 {
        self.prismatic
    }

    /// The spheres' labels, in order of first appearance.
    pub fn spheres(&self) -> &[String] {
        &self.names
    }

    /// Row `i`'s sphere (an index into [`Spheres::spheres`]).
    pub fn sphere(&self, i: usize) -> usize {
        self.sphere_of[i]
    }

    /// Row `i`'s readings (rad; mm for a slide).
    pub fn reading(&self, i: usize) -> &[f64] {
        &self.q[i * self.joints..(i + 1) * self.joints]
    }

    /// Every reading, row-major.
    pub fn readings(&self) -> &[f64] {
        &self.q
    }

    /// Row `i`'s 1-based line in its file (0: made in memory).
    pub fn line(&self, i: usize) -> usize {
        self.lines[i]
    }

    /// Whether the rows carry an articulation (the file's column).
    pub(crate) fn has_articulation(&self) -> bool {
        self.articulation.is_some()
    }

    /// Row `i`'s articulation, when the file has the column.
    pub fn articulation(&self, i: usize) -> Option<u32> {
        self.articulation.as_ref().map(|a| a[i])
    }

    /// The rows of sphere `s`, in file order.
    pub fn rows_of(&self, s: usize) -> Vec<usize> {
        self.rows[s].clone()
    }

    /// The rows `keep` (in that order; the spheres renumbered in order of
    /// first appearance among them): a fold's share.
    pub fn subset(&self, keep: &[usize]) -> Spheres {
        let mut out = Spheres::new(self.joints, self.prismatic);
        for &i in keep {
            out.push(
                &self.names[self.sphere_of[i]],
                self.reading(i),
                self.lines[i],
                self.articulation(i),
            );
            if self.tool(i) != 0 {
                out.set_tool(&self.tools[self.tool(i)]);
            }
        }
        out
    }

    /// The same rows with the slides of `shape` (their readings in mm).
    pub fn with_shape(mut self, shape: crate::params::ChainShape) -> Spheres {
        self.prismatic = shape.prismatic_mask();
        self
    }
}

/// The default tool as [`Spheres::tools`] lists it.
fn default_tool() -> Tool {
    Tool {
        name: DEFAULT_TOOL.to_string(),
        offset: [0.0; 3],
        ball_diameter_mm: None,
    }
}
