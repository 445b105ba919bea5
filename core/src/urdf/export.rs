//! A D-H arm (a calibrated one) as URDF joint origins, and as a plain D-H
//! table.
//!
//! Link `i`'s frame is the frame just after joint `i`'s rotation (or
//! slide); joint `i + 1` sits in it at `Rz(θ_i)·Tz(d_i)·Tx(a_i)·Rx(α_i)` (a
//! Hayati joint: `Rz(θ_i)·Tx(a_i)·Rx(α_i)·Ry(β_i)`) and turns about (a
//! `prismatic` one: slides along) its z axis, so the URDF's readings are the
//! arm's `q` — a slide's in metres, the arm's in mm — (the zero offsets are
//! in the origins: `Tz(q)` commutes with `Rz(θ)·Tz(d)`).
//! The probe is a `fixed` joint at `B` after the last link's transform.
//! `xyz` in metres, `rpy` in radians (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`),
//! every number with the digits that read back to the same `f64`: the
//! toolkit's own URDF reader ([`super::parse_urdf`]) gives back the same
//! chain, the tip within 1 nm of the arm's probe for every reading.

use nalgebra::{Rotation3, Vector3};

use super::{JointKind, Urdf};
use crate::params::{DhJoint, DhParams, JointModel};

/// The names a URDF gives the arm: its robot, links and joints, and joint
/// limits; from a template URDF, or the defaults (`base_link`, `link1`…,
/// `joint1`…, `probe`).
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfNames {
    /// The robot's name.
    pub(crate) robot: String,
    /// `n + 1` links: the base, then the one after each joint.
    pub(crate) links: Vec<String>,
    /// `n` movable joints.
    pub joints: Vec<String>,
    /// Per joint, `[lower, upper]` in the arm's units (rad, mm for a
    /// prismatic joint), where known.
    pub limits: Vec<Option<[f64; 2]>>,
}

impl UrdfNames {
    /// The default names for an arm of `n` joints named `robot`, with
    /// `limits` (the arm's units: rad, mm for a prismatic joint; missing
    /// entries: none).
    pub fn defaults(robot: &str, n: usize, limits: &[Option<[f64; 2]>]) -> UrdfNames {
        UrdfNames {
            robot: robot.to_string(),
            links: std::iter::once("base_link".to_string())
                .chain((1..=n).map(|i| format!("link{i}")))
                .collect(),
            joints: (1..=n).map(|i| format!("joint{i}")).collect(),
            limits: (0..n).map(|i| limits.get(i).copied().flatten()).collect(),
        }
    }

    /// The names of the chain of a template URDF whose movable (revolute,
    /// continuous and prismatic) joints are, root to tip, of the kinds
    /// `kinds`: its joints, their links and limits (a slide's metres as
    /// mm). The chains tried are those from the top of the tree to each leaf
    /// link, in file order (a gripper's finger slides are another chain
    /// than the arm's); `None` when none fits.
    pub fn from_template(template: &Urdf, kinds: &[crate::params::JointKind]) -> Option<UrdfNames> {
        let movable = (template_chains(template).into_iter())
            .map(|(_, path)| path)
            .find(|path| {
                path.iter()
                    .map(|j| j.kind.movable())
                    .eq(kinds.iter().map(|k| Some(*k)))
            })?;
        if kinds.is_empty() {
            return None;
        }
        let mut links = vec![movable[0].parent.clone()];
        links.extend(movable.iter().map(|j| j.child.clone()));
        Some(UrdfNames {
            robot: template.name.clone(),
            links,
            joints: movable.iter().map(|j| j.name.clone()).collect(),
            limits: (movable.iter())
                .map(|j| match j.kind {
                    JointKind::Prismatic => j.limits.map(|l| l.map(|v| v * 1000.0)),
                    _ => j.limits,
                })
                .collect(),
        })
    }
}

/// Each leaf link of `template` (in file order) and the movable joints from
/// the top of its tree down to it (a loop of joints: left out).
pub fn template_chains(template: &Urdf) -> Vec<(String, Vec<&super::UrdfJoint>)> {
    let parents: std::collections::HashSet<&str> =
        template.joints.iter().map(|j| j.parent.as_str()).collect();
    (template.joints.iter())
        .filter(|j| !parents.contains(j.child.as_str()))
        .filter_map(|leaf| {
            let path = template.path_up(None, &leaf.child).ok()?;
            let movable = path.into_iter().filter(|j| j.kind.movable().is_some());
            Some((leaf.child.clone(), movable.collect()))
        })
        .collect()
}

/// The rigid transform of link `j` before the next joint turns:
/// translation (mm) and rotation.
fn link_transform(j: &DhJoint) -> (Vector3<f64>, Rotation3<f64>) {
    let (s, c) = j.theta.sin_cos();
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), j.theta);
    let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), j.alpha);
    match j.model {
        JointModel::Hayati => {
            let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), j.beta);
            (Vector3::new(j.a * c, j.a * s, 0.0), rz * rx * ry)
        }
        _ => (Vector3::new(j.a * c, j.a * s, j.d), rz * rx),
    }
}

/// `<origin xyz="…" rpy="…"/>` of a transform (translation in mm).
fn origin(t: Vector3<f64>, r: Rotation3<f64>) -> String {
    let (roll, pitch, yaw) = r.euler_angles();
    let m = t / 1000.0;
    format!(
        "<origin xyz=\"{:?} {:?} {:?}\" rpy=\"{:?} {:?} {:?}\"/>",
        m.x, m.y, m.z, roll, pitch, yaw
    )
}

/// The arm `params` as a URDF with `names`: one joint per joint (axis z; a
/// revolute one `revolute` with its limits where known, `continuous` where
/// not; a prismatic one `prismatic`, its limits in metres where known and
/// no `<limit>` where not), then a fixed joint to the probe link `probe`.
///
/// ```
/// use aacmm_core::params::DhParams;
/// use aacmm_core::urdf::{UrdfOptions, parse_urdf, export::{UrdfNames, to_urdf}};
/// let arm = DhParams::paper_nominal();
/// let text = to_urdf(&arm, &UrdfNames::defaults("paper", 6, &[]));
/// let back = parse_urdf(&text, "out.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
/// let chain = back.chain(None, "probe").unwrap();
/// let tip = chain.position(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]);
/// let k = aacmm_core::kernel::ArmKernel::new(&arm).unwrap();
/// let p = k.position(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]).unwrap();
/// assert!((0..3).all(|i| (tip[i] * 1000.0 - p[i]).abs() < 1e-6));
/// ```
pub fn to_urdf(params: &DhParams, names: &UrdfNames) -> String {
    let n = params.joint_count();
    let mut s = format!(
        "<?xml version=\"1.0\"?>\n<!-- written by aacmm export: the D-H arm's joint origins; \
         readings are the arm's q -->\n<robot name=\"{}\">\n",
        xml_escape(&names.robot)
    );
    for link in names
        .links
        .iter()
        .chain(std::iter::once(&"probe".to_string()))
    {
        s += &format!("  <link name=\"{}\"/>\n", xml_escape(link));
    }
    let mut previous = (Vector3::zeros(), Rotation3::identity());
    for i in 0..n {
        let limit = names.limits.get(i).copied().flatten();
        let slides = params.joints[i].kind == crate::params::JointKind::Prismatic;
        let (kind, limit) = match (slides, limit) {
            (true, limit) => ("prismatic", limit.map(|l| l.map(|v| v / 1000.0))),
            (false, Some(limit)) => ("revolute", Some(limit)),
            (false, None) => ("continuous", None),
        };
        s += &format!(
            "  <joint name=\"{}\" type=\"{kind}\">\n    <parent link=\"{}\"/>\n    <child \
             link=\"{}\"/>\n    {}\n    <axis xyz=\"0 0 1\"/>\n",
            xml_escape(&names.joints[i]),
            xml_escape(&names.links[i]),
            xml_escape(&names.links[i + 1]),
            origin(previous.0, previous.1)
        );
        if let Some([lo, hi]) = limit {
            s += &format!(
                "    <limit lower=\"{lo:?}\" upper=\"{hi:?}\" effort=\"0\" velocity=\"0\"/>\n"
            );
        }
        s += "  </joint>\n";
        previous = link_transform(&params.joints[i]);
    }
    let b = Vector3::from(params.probe);
    let (t, r) = previous;
    s += &format!(
        "  <joint name=\"probe\" type=\"fixed\">\n    <parent link=\"{}\"/>\n    <child \
         link=\"probe\"/>\n    {}\n  </joint>\n</robot>\n",
        xml_escape(&names.links[n]),
        origin(t + r * b, r)
    );
    s
}

/// `s` as an XML attribute value: markup escaped, tab and line breaks as
/// character references (read back as written, not normalised to spaces),
/// and the characters XML 1.0 cannot hold at all (the other C0 controls,
/// U+FFFE, U+FFFF) as U+FFFD, so that a name from an arm file never makes a
/// file that no URDF reader accepts.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            '\u{0}'..='\u{1f}' | '\u{fffe}' | '\u{ffff}' => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
    out
}

/// The arm as a plain D-H table, CSV: one row per joint (`theta_deg`,
/// `d_mm`, `a_mm`, `alpha_deg`, and `beta_deg` for a Hayati joint, whose
/// `d_mm` is empty), then a `probe` row with the probe's `x_mm,y_mm,z_mm`
/// in the last frame; the last column, `type`, says whether the joint turns
/// (`revolute`: the reading is added to θ) or slides (`prismatic`: the
/// reading, mm, is added to `d`, or stands where `d` would for a Hayati
/// joint). Standard D-H: `A_i = Rz(θ_i + q_i)·Tz(d_i)·Tx(a_i)·Rx(α_i)`;
/// Hayati: `Rz(θ_i + q_i)·Tx(a_i)·Rx(α_i)·Ry(β_i)`; a slide's `q_i` moves
/// from `Rz` into `Tz`.
///
/// ```
/// use aacmm_core::params::{DhParams, JointKind};
/// use aacmm_core::urdf::export::dh_table;
/// let t = dh_table(&DhParams::paper_nominal());
/// assert!(t.starts_with("link,model,theta_deg,d_mm,a_mm,alpha_deg,beta_deg,x_mm,y_mm,z_mm,type\n1,dh,0.0,"));
/// assert!(t.lines().nth(1).unwrap().ends_with(",revolute"));
/// assert!(t.ends_with("probe,point,,,,,,0.0,0.0,100.0,\n"));
/// let mut track = DhParams::paper_nominal();
/// track.joints[0] = track.joints[0].with_kind(JointKind::Prismatic);
/// assert!(dh_table(&track).lines().nth(1).unwrap().ends_with(",prismatic"));
/// ```
pub fn dh_table(params: &DhParams) -> String {
    let mut s =
        String::from("link,model,theta_deg,d_mm,a_mm,alpha_deg,beta_deg,x_mm,y_mm,z_mm,type\n");
    for (i, j) in params.joints.iter().enumerate() {
        let (model, d, beta) = match j.model {
            JointModel::Hayati => (
                "hayati",
                String::new(),
                format!("{:?}", j.beta.to_degrees()),
            ),
            _ => ("dh", format!("{:?}", j.d), String::new()),
        };
        s += &format!(
            "{},{model},{:?},{d},{:?},{:?},{beta},,,,{}\n",
            i + 1,
            j.theta.to_degrees(),
            j.a,
            j.alpha.to_degrees(),
            j.kind.name()
        );
    }
    let b = params.probe;
    s += &format!("probe,point,,,,,,{:?},{:?},{:?},\n", b[0], b[1], b[2]);
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::ArmKernel;
    use crate::params::JointKind as ArmKind;
    use crate::urdf::{UrdfOptions, parse_urdf};

    /// Exported and read back by the toolkit's own URDF reader, the chain's
    /// tip is the arm's probe within 1 nm — D-H and Hayati joints, 6, 7 and
    /// 7 joints with two slides (one Hayati), zero offsets and twists off
    /// their nominal values; a slide's limits in metres — and the D-H
    /// conversion of the read-back chain is the same arm up to its base.
    #[test]
    fn exported_urdf_reads_back_within_a_nanometre() {
        let mut hayati = DhParams::paper_nominal();
        hayati.joints[1] = DhJoint {
            a: hayati.joints[1].a,
            alpha: 0.001,
            theta: 0.05,
            beta: 0.003,
            model: JointModel::Hayati,
            ..DhJoint::default()
        };
        hayati.joints[2].theta = -0.2;
        let mut seven = DhParams::paper_nominal();
        seven.joints.push(DhJoint {
            a: 12.0,
            d: 40.0,
            alpha: 0.4,
            theta: 0.1,
            ..DhJoint::default()
        });
        // A track (a slide before the arm) and a Hayati slide.
        let mut track = DhParams::paper_nominal();
        track.joints.insert(
            0,
            DhJoint::dh(150.0, 30.0, 1.2, 0.3).with_kind(ArmKind::Prismatic),
        );
        track.joints[3] =
            DhJoint::hayati(track.joints[3].a, 0.002, 0.1, -0.004).with_kind(ArmKind::Prismatic);
        for (name, arm) in [
            ("paper", DhParams::paper_nominal()),
            ("hayati", hayati),
            ("seven", seven),
            ("track", track),
        ] {
            let n = arm.joint_count();
            let kinds: Vec<ArmKind> = arm.joints.iter().map(|j| j.kind).collect();
            let limits = vec![Some([-3.0, 3.0]); n];
            let text = to_urdf(&arm, &UrdfNames::defaults(name, n, &limits));
            let urdf = parse_urdf(&text, "x.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
            for j in urdf.joints.iter().filter(|j| j.name != "probe") {
                let slides = j.kind == JointKind::Prismatic;
                let m = if slides { 1e-3 } else { 1.0 };
                assert_eq!(j.limits, Some([-3.0 * m, 3.0 * m]), "{name}");
            }
            let chain = urdf.chain(None, "probe").unwrap();
            assert_eq!(chain.kinds, kinds);
            // The reader's own conversion of the exported chain.
            let dh = chain.to_dh().unwrap();
            let k = ArmKernel::new(&arm).unwrap();
            for i in 0..50 {
                let q: Vec<f64> = (0..n)
                    .map(|j| ((i * 7 + j * 3) as f64 * 0.37).sin() * 2.5)
                    .collect();
                // A slide's reading: mm for the arm, m for the URDF.
                let q: Vec<f64> = (q.iter().zip(&kinds))
                    .map(|(v, k)| {
                        if *k == ArmKind::Prismatic {
                            v * 100.0
                        } else {
                            *v
                        }
                    })
                    .collect();
                let q_urdf: Vec<f64> = (q.iter().zip(&kinds))
                    .map(|(v, k)| {
                        if *k == ArmKind::Prismatic {
                            v / 1000.0
                        } else {
                            *v
                        }
                    })
                    .collect();
                let p = k.position(&q).unwrap();
                let tip = chain.position(&q_urdf);
                for c in 0..3 {
                    assert!(
                        (tip[c] * 1000.0 - p[c]).abs() < 1e-6,
                        "{name} {q:?}: {tip:?} vs {p:?}"
                    );
                }
                let other = ArmKernel::new(&dh.params).unwrap().position(&q).unwrap();
                let at = dh.base * nalgebra::Point3::from(Vector3::from(other) / 1000.0);
                for c in 0..3 {
                    assert!((at[c] - tip[c]).abs() < 1e-9, "{name}: {at:?} vs {tip:?}");
                }
            }
        }
    }

    /// A hostile name from an arm file (markup, line breaks, NUL) makes a
    /// well-formed URDF: markup and line breaks read back as written, a
    /// character XML cannot hold reads back as U+FFFD.
    #[test]
    fn hostile_names_export_as_well_formed_xml() {
        let arm = DhParams::paper_nominal();
        let mut names = UrdfNames::defaults("a\r\nb<&\"\0>\t", 6, &[]);
        names.joints[0] = "j\u{1b}1".to_string();
        let text = to_urdf(&arm, &names);
        let urdf = parse_urdf(&text, "x.urdf", UrdfOptions::default()).unwrap();
        assert_eq!(urdf.name, "a\r\nb<&\"\u{fffd}>\t");
        assert_eq!(urdf.joints[0].name, "j\u{fffd}1");
        assert!(urdf.chain(None, "probe").is_ok());
    }
}
