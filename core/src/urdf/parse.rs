//! Reading a URDF: its `<joint>` and `<link>` elements, every number
//! checked and placed at its line, `rpy` components near a multiple of π/2
//! snapped to it.

use super::*;

/// Parses the joints and links of a URDF; `file` names it in messages.
///
/// # Errors
/// Malformed XML (at its line); a root element other than `<robot>`; a joint
/// without a name, type, parent or child; an `xyz`, `rpy` or `axis` that is
/// not three finite numbers; a zero axis; a link that is the child of two
/// joints; a `<link>` without a name or defined twice; an `<inertial>`
/// without `<mass>`, or whose `value` is not a finite number ≥ 0.
///
/// ```
/// use aacmm_core::urdf::{parse_urdf, UrdfOptions};
/// let text = r#"<robot name="r">
///   <joint name="j1" type="revolute">
///     <parent link="base"/><child link="l1"/>
///     <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>
///   </joint>
///   <joint name="j2" type="revolute">
///     <parent link="l1"/><child link="l2"/>
///     <origin xyz="0 0 0.2" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
///   </joint>
/// </robot>"#;
/// let urdf = parse_urdf(text, "r.urdf", UrdfOptions::default()).unwrap();
/// assert_eq!(urdf.joints.len(), 2);
/// assert_eq!(urdf.snapped.len(), 1); // 1.5708 → π/2
/// let bad = text.replace("0 0 0.2", "0 0 x");
/// let e = parse_urdf(&bad, "r.urdf", UrdfOptions::default()).unwrap_err();
/// assert!(e.to_string().starts_with("r.urdf:8: field `xyz`"), "{e}");
/// ```
pub fn parse_urdf(text: &str, file: &str, options: UrdfOptions) -> Result<Urdf, InputError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        InputError::line_error(
            file,
            e.pos().row as usize,
            // The parser's message quotes names from the file: bounded.
            format!("not well-formed XML: {}", shown(&e.to_string())),
        )
    })?;
    let root = robot_element(&doc, file)?;
    let mut urdf = Urdf {
        file: file.to_string(),
        name: root.attribute("name").unwrap_or_default().to_string(),
        joints: Vec::new(),
        links: Vec::new(),
        snapped: Vec::new(),
    };
    for node in root.children().filter(|n| n.has_tag_name("link")) {
        let link = read_link(&doc, node, file)?;
        if let Some(other) = urdf.links.iter().find(|l| l.name == link.name) {
            return Err(InputError::field(
                file,
                link.line,
                "name",
                format!(
                    "link {} is already defined (line {}); a URDF names each link once",
                    quoted(&link.name),
                    other.line
                ),
            ));
        }
        urdf.links.push(link);
    }
    let mut child_of: HashMap<String, usize> = HashMap::new();
    for node in root.children().filter(|n| n.has_tag_name("joint")) {
        let element = JointElement {
            doc: &doc,
            node,
            file,
            at: line(&doc, node),
        };
        let joint = element.read(options, &mut urdf.snapped)?;
        if let Some(&other) = child_of.get(&joint.child) {
            return Err(InputError::field(
                file,
                joint.line,
                "child",
                format!(
                    "link {} is already the child of joint {} (line {}); a URDF is a tree",
                    quoted(&joint.child),
                    quoted(&urdf.joints[other].name),
                    urdf.joints[other].line
                ),
            ));
        }
        child_of.insert(joint.child.clone(), urdf.joints.len());
        urdf.joints.push(joint);
    }
    Ok(urdf)
}

/// The document's root element, which must be `<robot>`.
fn robot_element<'a, 'input>(
    doc: &'a roxmltree::Document<'input>,
    file: &str,
) -> Result<roxmltree::Node<'a, 'input>, InputError> {
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(InputError::line_error(
            file,
            line(doc, root),
            format!(
                "the root element is <{}>; a URDF has <robot>",
                shown(root.tag_name().name())
            ),
        ));
    }
    Ok(root)
}

/// A `<link>` element: its name and its `<inertial>`'s mass and centre
/// (the inertia tensor is not needed and not read).
fn read_link(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    file: &str,
) -> Result<UrdfLink, InputError> {
    let at = line(doc, node);
    let name = node
        .attribute("name")
        .map(str::to_string)
        .ok_or_else(|| InputError::field(file, at, "name", "missing on <link>"))?;
    let Some(el) = node.children().find(|c| c.has_tag_name("inertial")) else {
        return Ok(UrdfLink {
            name,
            inertial: None,
            line: at,
        });
    };
    let inertial_at = line(doc, el);
    let com = match el.children().find(|c| c.has_tag_name("origin")) {
        Some(o) => {
            let l = line(doc, o);
            // The rpy turns the inertia tensor only; read to refuse a
            // malformed one.
            triple(o.attribute("rpy"), [0.0; 3], file, l, "rpy")?;
            triple(o.attribute("xyz"), [0.0; 3], file, l, "xyz")?
        }
        None => [0.0; 3],
    };
    let mass = el
        .children()
        .find(|c| c.has_tag_name("mass"))
        .ok_or_else(|| {
            InputError::field(
                file,
                inertial_at,
                "mass",
                format!("link {}: <inertial> without <mass>", quoted(&name)),
            )
        })?;
    let mass_at = line(doc, mass);
    let text = mass.attribute("value").ok_or_else(|| {
        InputError::field(
            file,
            mass_at,
            "mass",
            format!("link {}: <mass> without `value`", quoted(&name)),
        )
    })?;
    let kg = match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => v,
        _ => {
            return Err(InputError::field(
                file,
                mass_at,
                "mass",
                format!(
                    "link {}: {} is not a mass (a finite number of kg, ≥ 0)",
                    quoted(&name),
                    quoted(text)
                ),
            ));
        }
    };
    Ok(UrdfLink {
        name,
        inertial: Some(Inertial {
            kg,
            com: Vector3::from(com),
        }),
        line: at,
    })
}

/// A `<joint>` element being read, and where it is, for messages.
struct JointElement<'a, 'input> {
    doc: &'a roxmltree::Document<'input>,
    node: roxmltree::Node<'a, 'input>,
    file: &'a str,
    /// The line of `<joint>`.
    at: usize,
}

impl<'a, 'input> JointElement<'a, 'input> {
    /// The joint, its `rpy` snapped by `options` (each rounding noted in
    /// `snapped`).
    fn read(
        &self,
        options: UrdfOptions,
        snapped: &mut Vec<String>,
    ) -> Result<UrdfJoint, InputError> {
        let name = self.attribute("name")?;
        let type_name = self.attribute("type")?;
        let kind = match type_name.as_str() {
            "revolute" | "continuous" => JointKind::Revolute,
            "prismatic" => JointKind::Prismatic,
            "fixed" => JointKind::Fixed,
            _ => JointKind::Other,
        };
        let parent = self.link(&name, "parent")?;
        let child = self.link(&name, "child")?;
        let origin = self.origin(&name, options.snap_rad, snapped)?;
        let axis = self.axis(&name, kind)?;
        Ok(UrdfJoint {
            limits: self.limits(&name, &type_name)?,
            name,
            type_name,
            kind,
            parent,
            child,
            origin,
            axis,
            line: self.at,
        })
    }

    fn attribute(&self, attribute: &str) -> Result<String, InputError> {
        self.node
            .attribute(attribute)
            .map(str::to_string)
            .ok_or_else(|| InputError::field(self.file, self.at, attribute, "missing on <joint>"))
    }

    fn child(&self, tag: &str) -> Option<roxmltree::Node<'a, 'input>> {
        self.node.children().find(|c| c.has_tag_name(tag))
    }

    /// The `link` of the `<parent>` or `<child>` element (`tag`) of the
    /// joint `name`.
    fn link(&self, name: &str, tag: &str) -> Result<String, InputError> {
        let el = self.child(tag).ok_or_else(|| {
            InputError::field(
                self.file,
                self.at,
                tag,
                format!("joint {} has no <{tag}>", quoted(name)),
            )
        })?;
        el.attribute("link").map(str::to_string).ok_or_else(|| {
            InputError::field(
                self.file,
                line(self.doc, el),
                "link",
                format!("<{tag}> without `link`"),
            )
        })
    }

    /// The child frame in the parent frame, its `rpy` within `snap_rad`
    /// of a multiple of π/2 set to it (each rounding noted in `snapped`).
    fn origin(
        &self,
        name: &str,
        snap_rad: f64,
        snapped: &mut Vec<String>,
    ) -> Result<Isometry3<f64>, InputError> {
        let origin_el = self.child("origin");
        let (xyz, rpy) = match origin_el {
            Some(el) => {
                let l = line(self.doc, el);
                (
                    triple(el.attribute("xyz"), [0.0; 3], self.file, l, "xyz")?,
                    triple(el.attribute("rpy"), [0.0; 3], self.file, l, "rpy")?,
                )
            }
            None => ([0.0; 3], [0.0; 3]),
        };
        let rpy = snap(rpy, snap_rad, |i, from, to, by| {
            snapped.push(format!(
                "line {}: {} {} {from} → {to} ({by:.1e} rad)",
                origin_el.map_or(self.at, |el| line(self.doc, el)),
                shown(name),
                ["roll", "pitch", "yaw"][i]
            ));
        });
        Ok(Isometry3::from_parts(
            Translation3::from(Vector3::from(xyz)),
            UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
        ))
    }

    /// The unit axis (URDF's default is x); a movable joint's must not be
    /// zero.
    fn axis(&self, name: &str, kind: JointKind) -> Result<Vector3<f64>, InputError> {
        let axis_el = self.child("axis");
        let axis = match axis_el {
            Some(el) => triple(
                el.attribute("xyz"),
                [1.0, 0.0, 0.0],
                self.file,
                line(self.doc, el),
                "axis",
            )?,
            None => [1.0, 0.0, 0.0],
        };
        let axis = Vector3::from(axis);
        if kind.movable().is_some() && axis.norm() == 0.0 {
            let moves = match kind {
                JointKind::Prismatic => "slides along",
                _ => "turns about",
            };
            return Err(InputError::field(
                self.file,
                axis_el.map_or(self.at, |el| line(self.doc, el)),
                "axis",
                format!("joint {} {moves} a zero axis", quoted(name)),
            ));
        }
        Ok(if axis.norm() > 0.0 {
            axis.normalize()
        } else {
            axis
        })
    }

    /// `[lower, upper]` of a `revolute` or `prismatic` joint, when both are
    /// stated and `lower < upper` (URDF's default for either is 0, so a
    /// `<limit>` without them, or with both 0, states no range).
    ///
    /// # Errors
    /// A stated `lower` or `upper` that is not a finite number, or a
    /// `lower` above `upper`.
    fn limits(&self, name: &str, type_name: &str) -> Result<Option<[f64; 2]>, InputError> {
        let Some(el) = self.child("limit") else {
            return Ok(None);
        };
        let at = line(self.doc, el);
        let bound = |field: &str| -> Result<Option<f64>, InputError> {
            let Some(text) = el.attribute(field) else {
                return Ok(None);
            };
            match text.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(Some(v)),
                _ => Err(InputError::field(
                    self.file,
                    at,
                    field,
                    format!(
                        "joint {}: {} is not a limit (a finite number, {})",
                        quoted(name),
                        quoted(text),
                        if type_name == "prismatic" { "m" } else { "rad" }
                    ),
                )),
            }
        };
        let (lo, hi) = (bound("lower")?, bound("upper")?);
        if !matches!(type_name, "revolute" | "prismatic") {
            return Ok(None);
        }
        match (lo, hi) {
            (Some(lo), Some(hi)) if lo > hi => Err(InputError::field(
                self.file,
                at,
                "upper",
                format!("joint {}: upper {hi} is below lower {lo}", quoted(name)),
            )),
            (Some(lo), Some(hi)) if lo < hi => Ok(Some([lo, hi])),
            _ => Ok(None),
        }
    }
}

fn line(doc: &roxmltree::Document, node: roxmltree::Node) -> usize {
    doc.text_pos_at(node.range().start).row as usize
}

/// Three whitespace-separated finite numbers, or `default` when absent.
fn triple(
    value: Option<&str>,
    default: [f64; 3],
    file: &str,
    line: usize,
    field: &str,
) -> Result<[f64; 3], InputError> {
    let Some(text) = value else {
        return Ok(default);
    };
    let parsed: Vec<Option<f64>> = text
        .split_whitespace()
        .map(|t| t.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect();
    match parsed.as_slice() {
        [Some(a), Some(b), Some(c)] => Ok([*a, *b, *c]),
        _ => Err(InputError::field(
            file,
            line,
            field,
            format!("{} is not three finite numbers", quoted(text)),
        )),
    }
}

/// Rounds components within `tol` of a multiple of π/2; `note(i, from, to,
/// by)` for each one changed.
pub(super) fn snap(
    v: [f64; 3],
    tol: f64,
    mut note: impl FnMut(usize, f64, String, f64),
) -> [f64; 3] {
    let h = std::f64::consts::FRAC_PI_2;
    let mut out = v;
    for (i, x) in v.iter().enumerate() {
        let k = (x / h).round();
        let to = k * h;
        let by = (x - to).abs();
        if by > 0.0 && by <= tol {
            out[i] = to;
            let name = match k as i64 {
                0 => "0".to_string(),
                1 => "π/2".to_string(),
                -1 => "-π/2".to_string(),
                2 => "π".to_string(),
                -2 => "-π".to_string(),
                k if k % 2 == 0 => format!("{}π", k / 2),
                k => format!("{k}π/2"),
            };
            note(i, *x, name, by);
        }
    }
    out
}
