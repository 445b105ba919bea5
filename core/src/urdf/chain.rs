//! The serial chain between two links of a URDF, and the masses that move
//! with it.

use super::*;

/// One step of a chain, root to tip.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Step {
    /// A rigid transform (a fixed joint's origin, or a revolute joint's
    /// origin before its rotation).
    Rigid(Isometry3<f64>),
    /// A rotation by the next reading about this unit axis.
    Turn(Vector3<f64>),
    /// A translation by the next reading (m) along this unit axis.
    Slide(Vector3<f64>),
}

/// The serial chain from a root link to a tip link.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    /// The movable joints, root to tip: the columns `q1..qn` of a poses file.
    pub joints: Vec<String>,
    /// Whether each turns or slides.
    pub kinds: Vec<crate::params::JointKind>,
    /// Each one's `type` as written (`revolute`, `continuous`, `prismatic`).
    pub types: Vec<String>,
    /// Each one's line in the file.
    pub lines: Vec<usize>,
    /// Their `[lower, upper]` limits, rad or m, where the URDF states them.
    pub limits: Vec<Option<[f64; 2]>>,
    /// The `fixed` joints folded into the arm: entry `k < n` those just
    /// before movable joint `k` (entry 0: into the base, the others: into
    /// the link of joint `k − 1`), entry `n` those after the last one (into
    /// the tool).
    pub folded: Vec<Vec<String>>,
    pub(super) steps: Vec<Step>,
    /// The URDF file's name, for messages.
    pub(super) file: String,
    /// The masses of the links that move with the chain (or sit on its
    /// root side), in the file's order of `<link>` elements.
    pub masses: Vec<ChainMass>,
}

/// The part of a chain a link moves with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Carrier {
    /// The root side, before the first joint: it loads no joint.
    Base,
    /// The link after joint `j` (0-based): that joint's child link and
    /// every link fixed to it (for the last joint, its child link only).
    Link(usize),
    /// The tool: what is fixed after the last joint, but for that joint's
    /// child link.
    Tool,
}

/// A link's mass as a chain carries it.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainMass {
    /// The link.
    pub link: String,
    /// What it moves with.
    pub carrier: Carrier,
    /// Its mass, kg.
    pub kg: f64,
    /// Its centre of mass in the root frame with every reading zero, m.
    pub com: Point3<f64>,
    /// The joints off the chain between it and the chain that are not
    /// `fixed` (each taken at its zero), nearest the link first.
    pub moving: Vec<String>,
}

impl Urdf {
    /// Whether a joint names `link` as its parent or child.
    fn joins(&self, link: &str) -> bool {
        self.joints
            .iter()
            .any(|j| j.child == link || j.parent == link)
    }

    /// The chain from `root` (or, without one, the link that is no joint's
    /// child above `tip`) down to `tip`.
    ///
    /// # Errors
    /// An unknown tip or root link; a root not above the tip (both named,
    /// and where going up from the tip ends); a joint on the way that is
    /// neither revolute, continuous, prismatic nor fixed (named, with its
    /// line).
    pub fn chain(&self, root: Option<&str>, tip: &str) -> Result<Chain, InputError> {
        for (link, what) in [(Some(tip), "tip"), (root, "base")] {
            match link {
                Some(link) if !self.joins(link) => {
                    return Err(InputError::file_error(
                        &self.file,
                        format!(
                            "no link {} is joined to the robot (the {what} must be a link's name)",
                            quoted(link)
                        ),
                    ));
                }
                _ => {}
            }
        }
        let path = self.path_up(root, tip)?;
        let mut chain = Chain {
            joints: Vec::new(),
            kinds: Vec::new(),
            types: Vec::new(),
            lines: Vec::new(),
            limits: Vec::new(),
            folded: vec![Vec::new()],
            steps: Vec::new(),
            file: self.file.clone(),
            masses: self.masses_along(&path),
        };
        for j in path {
            chain.steps.push(Step::Rigid(j.origin));
            let Some(kind) = j.kind.movable() else {
                if j.kind == JointKind::Fixed {
                    chain
                        .folded
                        .last_mut()
                        .expect("one entry")
                        .push(j.name.clone());
                    continue;
                }
                return Err(InputError::field(
                    &self.file,
                    j.line,
                    "type",
                    format!(
                        "joint {} on the way to {} is {}; a serial chain has revolute, \
                         continuous, prismatic and fixed joints only",
                        quoted(&j.name),
                        quoted(tip),
                        quoted(&j.type_name)
                    ),
                ));
            };
            chain.steps.push(match kind {
                crate::params::JointKind::Revolute => Step::Turn(j.axis),
                crate::params::JointKind::Prismatic => Step::Slide(j.axis),
            });
            chain.joints.push(j.name.clone());
            chain.kinds.push(kind);
            chain.types.push(j.type_name.clone());
            chain.lines.push(j.line);
            chain.limits.push(j.limits);
            chain.folded.push(Vec::new());
        }
        Ok(chain)
    }

    /// The joints from `root` (or the top) down to `tip`, root first.
    pub(super) fn path_up(
        &self,
        root: Option<&str>,
        tip: &str,
    ) -> Result<Vec<&UrdfJoint>, InputError> {
        let by_child: HashMap<&str, &UrdfJoint> =
            self.joints.iter().map(|j| (j.child.as_str(), j)).collect();
        let mut path: Vec<&UrdfJoint> = Vec::new();
        let mut link = tip;
        while Some(link) != root {
            match by_child.get(link) {
                Some(j) if path.len() == self.joints.len() => {
                    return Err(InputError::field(
                        &self.file,
                        j.line,
                        "parent",
                        format!(
                            "going up from {} never ends: joint {} is on a loop of \
                             joints; a URDF is a tree",
                            quoted(tip),
                            quoted(&j.name)
                        ),
                    ));
                }
                Some(j) => {
                    path.push(j);
                    link = &j.parent;
                }
                None if root.is_none() => break,
                None => return Err(self.not_connected(root.unwrap_or_default(), tip, &path)),
            }
        }
        path.reverse();
        Ok(path)
    }

    /// The error of a `root` that is not above `tip`, after going up from
    /// the tip through `path` (tip first) to the top.
    fn not_connected(&self, root: &str, tip: &str, path: &[&UrdfJoint]) -> InputError {
        let top = path.last().map_or(tip, |j| j.parent.as_str());
        let through: Vec<String> = path.iter().map(|j| quoted(&j.name)).collect();
        let message = format!(
            "the chain does not connect base link {} to tip link {}: going up from {} \
             {}ends at {}, the top of its tree, without meeting {}",
            quoted(root),
            quoted(tip),
            quoted(tip),
            if through.is_empty() {
                String::new()
            } else {
                format!("through joints {} ", shown(&through.join(", ")))
            },
            quoted(top),
            quoted(root)
        );
        match path.last() {
            Some(j) => InputError::field(&self.file, j.line, "parent", message),
            None => InputError::file_error(&self.file, message),
        }
    }
}

impl Urdf {
    /// The links with a mass that move with the chain `path` (joints, root
    /// to tip), each with its carrier and its centre at `q = 0`.
    fn masses_along(&self, path: &[&UrdfJoint]) -> Vec<ChainMass> {
        let Some(first) = path.first() else {
            return Vec::new();
        };
        let turning = path.iter().filter(|j| j.kind.movable().is_some()).count();
        // Each link of the chain: its carrier and its frame at q = 0.
        let mut on_chain: HashMap<&str, (Carrier, Isometry3<f64>)> = HashMap::new();
        let (mut carrier, mut t, mut turned) = (Carrier::Base, Isometry3::identity(), 0);
        on_chain.insert(first.parent.as_str(), (carrier, t));
        for j in path {
            t *= j.origin;
            if j.kind.movable().is_some() {
                carrier = Carrier::Link(turned);
                turned += 1;
            } else if turned == turning && turned > 0 {
                carrier = Carrier::Tool;
            }
            on_chain.insert(j.child.as_str(), (carrier, t));
        }
        let by_child: HashMap<&str, &UrdfJoint> =
            self.joints.iter().map(|j| (j.child.as_str(), j)).collect();
        let mut out = Vec::new();
        for link in &self.links {
            let Some(inertial) = link.inertial else {
                continue;
            };
            // Up from the link to the chain; a link that never reaches it
            // (above the root, another tree) does not move with it.
            let mut up: Vec<&UrdfJoint> = Vec::new();
            let mut at = link.name.as_str();
            let attached = loop {
                if let Some(&found) = on_chain.get(at) {
                    break Some(found);
                }
                match by_child.get(at) {
                    Some(j) if up.len() < self.joints.len() => {
                        up.push(j);
                        at = &j.parent;
                    }
                    // No parent, or a loop of joints (which `chain` refuses
                    // on the way to the tip; off it, the link is left out).
                    _ => break None,
                }
            };
            let Some((mut carrier, mut t)) = attached else {
                continue;
            };
            if !up.is_empty() && turning > 0 && carrier == Carrier::Link(turning - 1) {
                carrier = Carrier::Tool;
            }
            for j in up.iter().rev() {
                t *= j.origin;
            }
            out.push(ChainMass {
                link: link.name.clone(),
                carrier,
                kg: inertial.kg,
                com: t * Point3::from(inertial.com),
                moving: up
                    .iter()
                    .filter(|j| j.kind != JointKind::Fixed)
                    .map(|j| j.name.clone())
                    .collect(),
            });
        }
        out
    }
}
