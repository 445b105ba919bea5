use super::parse::snap;
use super::*;
use crate::reference_model::position;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A random serial chain in URDF: every joint origin random (xyz within
/// ±0.3 m, any rpy), random axes, fixed joints between, and a tool ball.
/// With `mixed`, joints are also `continuous` or `prismatic`, and some
/// follow the previous axis exactly (rpy 0, the same axis) or nearly
/// (a 0.002 rad pitch: a Hayati joint).
fn random_urdf(rng: &mut ChaCha8Rng, joints: usize, mixed: bool) -> String {
    let mut s = String::from("<robot name=\"random\">\n");
    let mut parent = "base".to_string();
    let num = |rng: &mut ChaCha8Rng, r: f64| rng.random_range(-r..r);
    let mut axis = [0.0, 0.0, 1.0];
    for j in 0..joints {
        let child = format!("l{j}");
        let xyz = [num(rng, 0.3), num(rng, 0.3), num(rng, 0.3)];
        let mut rpy = [num(rng, 3.2), num(rng, 1.5), num(rng, 3.2)];
        let follow = if mixed && j > 0 && parent.starts_with('l') {
            rng.random_range(0..3)
        } else {
            0
        };
        match follow {
            // Parallel to the previous axis (the same frame), or nearly.
            1 => rpy = [0.0; 3],
            2 => rpy = [0.0, 0.002, 0.0],
            _ => axis = [num(rng, 1.0), num(rng, 1.0), num(rng, 1.0)],
        }
        let kind = match (mixed, rng.random_range(0..4)) {
            (true, 0) => "prismatic",
            (true, 1) => "continuous",
            _ => "revolute",
        };
        s += &format!(
            "<joint name=\"j{j}\" type=\"{kind}\"><parent link=\"{parent}\"/>\
                 <child link=\"{child}\"/><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\
                 <axis xyz=\"{} {} {}\"/><limit lower=\"-3\" upper=\"3\"/></joint>\n",
            xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2], axis[0], axis[1], axis[2]
        );
        parent = child;
        if j % 3 == 1 {
            let f = format!("f{j}");
            s += &format!(
                "<joint name=\"fix{j}\" type=\"fixed\"><parent link=\"{parent}\"/>\
                     <child link=\"{f}\"/><origin xyz=\"0.01 0.02 0.05\" rpy=\"0.3 -0.2 1.0\"/>\
                     </joint>\n"
            );
            parent = f;
        }
    }
    s += &format!(
        "<joint name=\"ball\" type=\"fixed\"><parent link=\"{parent}\"/>\
             <child link=\"ball_link\"/><origin xyz=\"0.01 -0.02 0.17\" rpy=\"0.1 0.2 0.3\"/>\
             </joint>\n</robot>\n"
    );
    s
}

/// Random readings of `chain` in the URDF's units: ±π rad, ±0.5 m.
fn random_q(chain: &Chain, rng: &mut ChaCha8Rng) -> Vec<f64> {
    (chain.kinds.iter())
        .map(|k| match k {
            crate::params::JointKind::Revolute => {
                rng.random_range(-std::f64::consts::PI..std::f64::consts::PI)
            }
            crate::params::JointKind::Prismatic => rng.random_range(-0.5..0.5),
        })
        .collect()
}

/// The largest distance, mm, between the URDF tip and the D-H probe
/// mapped through the base, over `samples` random readings; the tool
/// frame's orientation, mapped through the base and the tool rotation,
/// must be the tip link's (within 1e-12 rad) at each.
pub(crate) fn worst_mm(
    chain: &Chain,
    dh: &DhConversion,
    rng: &mut ChaCha8Rng,
    samples: usize,
) -> f64 {
    let kernel = crate::kernel::ArmKernel::new(&dh.params).unwrap();
    (0..samples)
        .map(|_| {
            let q = random_q(chain, rng);
            let urdf = chain.transform(&q);
            // The arm reads a slide in mm.
            let q_arm: Vec<f64> = (q.iter().zip(&chain.kinds))
                .map(|(v, k)| match k {
                    crate::params::JointKind::Revolute => *v,
                    crate::params::JointKind::Prismatic => v * 1000.0,
                })
                .collect();
            let pose = kernel.pose(&q_arm).unwrap();
            let p = pose.position;
            let in_root = dh.base * Point3::new(p[0] / 1000.0, p[1] / 1000.0, p[2] / 1000.0);
            let r = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::from_fn(|i, j| {
                pose.rotation[i][j]
            }));
            let tool = dh.base.rotation * UnitQuaternion::from_rotation_matrix(&r) * dh.tool;
            // The matrices' difference: about the angle between them,
            // without acos's loss of digits near 0.
            let turn = (tool.to_rotation_matrix().matrix()
                - urdf.rotation.to_rotation_matrix().matrix())
            .norm();
            assert!(turn < 1e-12, "orientation off by {turn} rad at {q:?}");
            (in_root.coords - urdf.translation.vector).norm() * 1000.0
        })
        .fold(0.0, f64::max)
}

#[test]
fn random_chains_agree_to_a_nanometre() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    for trial in 0..50 {
        let joints = if trial % 2 == 0 { 6 } else { 7 };
        let text = random_urdf(&mut rng, joints, false);
        let urdf = parse_urdf(&text, "random.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
        let chain = urdf.chain(None, "ball_link").unwrap();
        assert_eq!(chain.joints.len(), joints);
        let dh = chain.to_dh().unwrap();
        let worst = worst_mm(&chain, &dh, &mut rng, 200);
        // 1e-9 m = 1e-6 mm.
        assert!(worst < 1e-6, "trial {trial}: {worst} mm\n{text}");
    }
}

/// Any chain of 1 to 12 joints — revolute, continuous and prismatic,
/// fixed joints between, consecutive axes parallel and nearly parallel
/// — converts exactly: the tip within 1 nm and the tool frame's
/// orientation the tip link's at random readings; nearly parallel axes
/// make Hayati joints, slides prismatic ones.
#[test]
fn any_chain_agrees_in_position_and_orientation() {
    let mut rng = ChaCha8Rng::seed_from_u64(39);
    let (mut hayati, mut prismatic) = (0, 0);
    for trial in 0..120 {
        let joints = 1 + trial % 12;
        let text = random_urdf(&mut rng, joints, true);
        let urdf = parse_urdf(&text, "random.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
        let chain = urdf.chain(Some("base"), "ball_link").unwrap();
        assert_eq!(chain.joints.len(), joints);
        let dh = chain.to_dh().unwrap();
        for (j, kind) in dh.params.joints.iter().zip(&chain.kinds) {
            assert_eq!(j.kind, *kind);
            hayati += usize::from(j.model == JointModel::Hayati);
            prismatic += usize::from(*kind == crate::params::JointKind::Prismatic);
        }
        let worst = worst_mm(&chain, &dh, &mut rng, 50);
        assert!(worst < 1e-6, "trial {trial}: {worst} mm\n{text}");
    }
    assert!(
        hayati > 20 && prismatic > 100,
        "{hayati} Hayati, {prismatic} prismatic"
    );
}

/// The robots of examples/mukca, with the right angles snapped (as the
/// arm files are made); as written, the Kinova's axes 2 and 3 (1.5708,
/// -3.1416) meet 38 km away: joint 2 becomes a Hayati joint, exact too.
#[test]
fn shipped_urdfs_agree_to_a_nanometre() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/mukca/urdf");
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (file, joints) in [("gen3lite.urdf", 6), ("panda.urdf", 7)] {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let urdf = parse_urdf(&text, file, UrdfOptions::default()).unwrap();
        let chain = urdf.chain(None, "ball_link").unwrap();
        assert_eq!(chain.joints.len(), joints);
        let dh = chain.to_dh().unwrap();
        let worst = worst_mm(&chain, &dh, &mut rng, 1000);
        assert!(worst < 1e-6, "{file}: {worst} mm");
        let as_written = parse_urdf(&text, file, UrdfOptions { snap_rad: 0.0 }).unwrap();
        let written = as_written.chain(None, "ball_link").unwrap();
        let dh = written.to_dh();
        if file == "gen3lite.urdf" {
            let dh = dh.unwrap();
            let models: Vec<JointModel> = dh.params.joints.iter().map(|j| j.model).collect();
            let mut want = vec![JointModel::Dh; 6];
            want[1] = JointModel::Hayati;
            assert_eq!(models, want);
            assert!((dh.params.joints[1].beta.abs() - 7.3e-6).abs() < 1e-7);
            let worst = worst_mm(&written, &dh, &mut rng, 1000);
            assert!(worst < 1e-6, "{file} as written: {worst} mm");
        } else {
            // The Panda's URDF writes π/2 to full precision: nothing to snap.
            assert_eq!(dh.unwrap().params, chain.to_dh().unwrap().params);
        }
    }
}

/// Consecutive parallel and intersecting axes: the special cases of the
/// common normal.
#[test]
fn parallel_and_intersecting_axes_agree() {
    let text = r#"<robot name="p">
          <joint name="j1" type="revolute"><parent link="b"/><child link="l1"/>
            <origin xyz="0.1 0.2 0.3" rpy="0 0 0.4"/><axis xyz="0 0 1"/></joint>
          <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
            <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/></joint>
          <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
            <origin xyz="0.25 0 0" rpy="3.141592653589793 0 0"/><axis xyz="0 0 1"/></joint>
          <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
            <origin xyz="0 0 0.1" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 1"/></joint>
          <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>
            <origin xyz="0 0 0" rpy="0 1.5707963267948966 0"/><axis xyz="0 0 -1"/></joint>
          <joint name="j6" type="continuous"><parent link="l5"/><child link="l6"/>
            <origin xyz="0.05 0 0.1"/><axis xyz="1 0 0"/></joint>
          <joint name="tool" type="fixed"><parent link="l6"/><child link="ball"/>
            <origin xyz="0 0 0.15"/></joint>
        </robot>"#;
    let urdf = parse_urdf(text, "p.urdf", UrdfOptions::default()).unwrap();
    let chain = urdf.chain(Some("b"), "ball").unwrap();
    let dh = chain.to_dh().unwrap();
    // j1 ∥ j2 on one line: a1 = 0; j2 ∥ j3 (antiparallel), 250 mm apart.
    assert!(dh.params.joints[0].a.abs() < 1e-12);
    assert!((dh.params.joints[1].a.abs() - 250.0).abs() < 1e-9);
    assert!((dh.params.joints[1].alpha.abs() - std::f64::consts::PI).abs() < 1e-12);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    assert!(worst_mm(&chain, &dh, &mut rng, 500) < 1e-6);
}

#[test]
// 1.5708 and 3.1416 are what published URDFs write; that is the point.
#[allow(clippy::approx_constant)]
fn snapping_rounds_right_angles_only() {
    let mut notes = Vec::new();
    let v = snap([1.5708, -3.1416, 0.001], 1e-4, |i, _, to, _| {
        notes.push((i, to))
    });
    assert_eq!(
        v,
        [std::f64::consts::FRAC_PI_2, -std::f64::consts::PI, 0.001]
    );
    assert_eq!(notes, [(0, "π/2".to_string()), (1, "-π".to_string())]);
}

#[test]
fn bad_input_is_located() {
    let e = parse_urdf(
        "<robot><joint name=\"a\"/></robot>",
        "x.urdf",
        UrdfOptions::default(),
    )
    .unwrap_err();
    assert_eq!(e.to_string(), "x.urdf:1: field `type`: missing on <joint>");
    let e = parse_urdf(
        "<robot>\n<joint type=></robot>",
        "x.urdf",
        UrdfOptions::default(),
    )
    .unwrap_err();
    assert!(
        e.to_string().starts_with("x.urdf:2: not well-formed XML"),
        "{e}"
    );
    for kind in ["floating", "planar"] {
        let text = format!(
            "<robot>\n<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/>\
                 <child link=\"b\"/></joint>\n<joint name=\"s\" type=\"{kind}\">\
                 <parent link=\"b\"/><child link=\"c\"/></joint></robot>"
        );
        let urdf = parse_urdf(&text, "s.urdf", UrdfOptions::default()).unwrap();
        let e = urdf.chain(None, "c").unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "s.urdf:3: field `type`: joint `s` on the way to `c` is `{kind}`; a serial \
                     chain has revolute, continuous, prismatic and fixed joints only"
            )
        );
        // Beside the chain, it is no matter.
        assert!(urdf.chain(None, "b").is_ok());
    }
    let slider = r#"<robot><joint name="s" type="prismatic"><parent link="a"/>
            <child link="b"/></joint></robot>"#;
    let urdf = parse_urdf(slider, "s.urdf", UrdfOptions::default()).unwrap();
    let chain = urdf.chain(None, "b").unwrap();
    assert_eq!(chain.kinds, [crate::params::JointKind::Prismatic]);
    let e = urdf.chain(None, "nowhere").unwrap_err();
    assert!(e.to_string().contains("no link `nowhere`"), "{e}");
    let e = urdf.chain(Some("nowhere"), "b").unwrap_err();
    assert_eq!(
        e.to_string(),
        "s.urdf: no link `nowhere` is joined to the robot (the base must be a link's name)"
    );
}

/// A base that is not above the tip, a slide along a zero axis, limits
/// that are not numbers or not in order: each named, at its line.
#[test]
fn bad_chains_and_limits_are_located() {
    let text = r#"<robot>
          <joint name="j1" type="revolute"><parent link="a"/><child link="b"/></joint>
          <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/></joint>
          <joint name="side" type="revolute"><parent link="a"/><child link="d"/></joint>
        </robot>"#;
    let urdf = parse_urdf(text, "t.urdf", UrdfOptions::default()).unwrap();
    let e = urdf.chain(Some("d"), "c").unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.urdf:2: field `parent`: the chain does not connect base link `d` to tip link \
             `c`: going up from `c` through joints `j2`, `j1` ends at `a`, the top of its tree, \
             without meeting `d`"
    );
    let joint = |kind: &str, body: &str| {
        format!(
            "<robot>\n<joint name=\"s\" type=\"{kind}\"><parent link=\"a\"/>\
                 <child link=\"b\"/>\n{body}</joint></robot>"
        )
    };
    let cases = [
        (
            joint("prismatic", "<axis xyz=\"0 0 0\"/>"),
            "z.urdf:3: field `axis`: joint `s` slides along a zero axis",
        ),
        (
            joint("prismatic", "<limit lower=\"-0.1\" upper=\"1,5\"/>"),
            "z.urdf:3: field `upper`: joint `s`: `1,5` is not a limit (a finite number, m)",
        ),
        (
            joint("revolute", "<limit lower=\"nan\" upper=\"1\"/>"),
            "z.urdf:3: field `lower`: joint `s`: `nan` is not a limit (a finite number, rad)",
        ),
        (
            joint("revolute", "<limit lower=\"1\" upper=\"-1\"/>"),
            "z.urdf:3: field `upper`: joint `s`: upper -1 is below lower 1",
        ),
    ];
    for (text, message) in cases {
        let e = parse_urdf(&text, "z.urdf", UrdfOptions::default()).unwrap_err();
        assert_eq!(e.to_string(), message);
    }
    // Thirteen movable joints, or none, are no arm.
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let long = random_urdf(&mut rng, 13, true);
    let urdf = parse_urdf(&long, "long.urdf", UrdfOptions::default()).unwrap();
    let e = urdf.chain(None, "ball_link").unwrap().to_dh().unwrap_err();
    assert_eq!(
        e.to_string(),
        "long.urdf: the chain has 13 movable (revolute, continuous or prismatic) joints; \
             an arm has 1 to 12"
    );
    let e = urdf
        .chain(Some("l12"), "ball_link")
        .unwrap()
        .to_dh()
        .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("long.urdf: the chain has 0 movable"),
        "{e}"
    );
    // Limits are kept in the URDF's units: a slide's in metres.
    let text = joint("prismatic", "<limit lower=\"-0.1\" upper=\"0.5\"/>");
    let urdf = parse_urdf(&text, "z.urdf", UrdfOptions::default()).unwrap();
    assert_eq!(urdf.chain(None, "b").unwrap().limits, [Some([-0.1, 0.5])]);
}

/// A random chain whose links have masses: a base mass before the
/// first joint (on a mounting link above it), each joint's child link,
/// links fixed to them beside the chain and on it, a link behind a
/// prismatic joint beside the chain, the tool's links after the last
/// joint (beside the chain and beyond the tip), a zero mass and a link
/// without one. Returns the URDF and each massive link's carrier, in
/// file order.
fn random_massive_urdf(rng: &mut ChaCha8Rng, joints: usize) -> (String, Vec<(String, Carrier)>) {
    /// Adds a link of random mass and centre carried by `carrier`.
    fn massive(
        out: &mut (String, Vec<(String, Carrier)>),
        rng: &mut ChaCha8Rng,
        name: &str,
        carrier: Carrier,
    ) {
        let kg = rng.random_range(0.05..3.0);
        let c: [f64; 3] = std::array::from_fn(|_| rng.random_range(-0.2..0.2));
        out.0 += &format!(
            "<link name=\"{name}\"><inertial><origin xyz=\"{} {} {}\" rpy=\"0.3 -0.1 2\"/>\
                 <mass value=\"{kg}\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" \
                 iyz=\"0\" izz=\"1\"/></inertial></link>\n",
            c[0], c[1], c[2]
        );
        out.1.push((name.to_string(), carrier));
    }
    /// Adds a joint of kind `kind` at a random origin, about a random
    /// axis.
    fn joint(out: &mut String, rng: &mut ChaCha8Rng, [name, kind, parent, child]: [&str; 4]) {
        let xyz: [f64; 3] = std::array::from_fn(|_| rng.random_range(-0.3..0.3));
        let rpy = [
            rng.random_range(-3.2..3.2),
            rng.random_range(-1.5..1.5),
            rng.random_range(-3.2..3.2),
        ];
        let axis: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
        *out += &format!(
            "<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/>\
                 <child link=\"{child}\"/><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\
                 <axis xyz=\"{} {} {}\"/></joint>\n",
            xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2], axis[0], axis[1], axis[2]
        );
    }
    let mut out = ("<link name=\"world\"/>\n".to_string(), Vec::new());
    let mut js = String::new();
    joint(&mut js, rng, ["mount", "fixed", "world", "base"]);
    massive(&mut out, rng, "base", Carrier::Base);
    let mut parent = "base".to_string();
    for j in 0..joints {
        let last = j + 1 == joints;
        let child = format!("l{j}");
        joint(
            &mut js,
            rng,
            [&format!("j{j}"), "revolute", &parent, &child],
        );
        massive(&mut out, rng, &child, Carrier::Link(j));
        let beside = if last {
            Carrier::Tool
        } else {
            Carrier::Link(j)
        };
        if j % 2 == 0 || last {
            let side = format!("side{j}");
            joint(
                &mut js,
                rng,
                [&format!("fix_side{j}"), "fixed", &child, &side],
            );
            massive(&mut out, rng, &side, beside);
        }
        if j == 1 {
            joint(&mut js, rng, ["slide", "prismatic", &child, "slider"]);
            massive(&mut out, rng, "slider", beside);
        }
        parent = child;
        if j % 3 == 1 && !last {
            let f = format!("f{j}");
            joint(&mut js, rng, [&format!("fix{j}"), "fixed", &parent, &f]);
            massive(&mut out, rng, &f, Carrier::Link(j));
            parent = f;
        }
    }
    joint(&mut js, rng, ["ball", "fixed", &parent, "ball_link"]);
    massive(&mut out, rng, "ball_link", Carrier::Tool);
    joint(
        &mut js,
        rng,
        ["beyond_joint", "fixed", "ball_link", "beyond"],
    );
    massive(&mut out, rng, "beyond", Carrier::Tool);
    out.0 += "<link name=\"nothing\"><inertial><mass value=\"0\"/></inertial></link>\n";
    joint(&mut js, rng, ["nothing_joint", "fixed", "l0", "nothing"]);
    out.1.push(("nothing".into(), Carrier::Link(0)));
    (
        format!("<robot name=\"massive\">\n{}{js}</robot>\n", out.0),
        out.1,
    )
}

/// Each link's pose in the root frame at readings `q` of the chain's
/// joints (by name), every other joint at its zero: the URDF tree walked
/// directly, independently of [`Chain`].
fn link_pose(urdf: &Urdf, chain: &Chain, q: &[f64], link: &str) -> Isometry3<f64> {
    match urdf.joints.iter().find(|j| j.child == link) {
        None => Isometry3::identity(),
        Some(j) => {
            let turn = (chain.joints.iter().position(|n| *n == j.name)).map_or(0.0, |i| q[i]);
            link_pose(urdf, chain, q, &j.parent)
                * j.origin
                * Isometry3::from_parts(
                    Translation3::identity(),
                    UnitQuaternion::from_scaled_axis(j.axis * turn),
                )
        }
    }
}

/// The centre of mass of the links carried by `carrier` in the root
/// frame at `q` through the URDF, m, and their mass.
fn urdf_com(urdf: &Urdf, chain: &Chain, q: &[f64], carrier: Carrier) -> (f64, Vector3<f64>) {
    let (mut kg, mut moment) = (0.0, Vector3::zeros());
    for m in chain.masses.iter().filter(|m| m.carrier == carrier) {
        let link = urdf.links.iter().find(|l| l.name == m.link).unwrap();
        let inertial = link.inertial.unwrap();
        let r = link_pose(urdf, chain, q, &link.name) * Point3::from(inertial.com);
        kg += inertial.kg;
        moment += r.coords * inertial.kg;
    }
    (kg, moment / kg)
}

/// The mass `m` of the link after joint `k` (the tool: `k = n`) in the
/// root frame at `q` through the D-H arm (its frame `k + 1`, the tool's
/// the last), m: the arm cut after that frame with `com_mm` as its probe.
fn dh_com(dh: &DhConversion, q: &[f64], k: usize, m: &DhMass) -> Vector3<f64> {
    let n = dh.params.joints.len();
    let frames = (k + 1).min(n);
    let mut arm = dh.params.clone();
    arm.joints.truncate(frames);
    arm.probe = m.com_mm;
    let p = position(&arm.to_vec(), &q[..frames]);
    (dh.base * Point3::new(p[0] / 1000.0, p[1] / 1000.0, p[2] / 1000.0)).coords
}

/// The largest distance, mm, between each carried centre of mass
/// through the URDF and through the D-H arm, over `samples` random
/// readings in ±π; and the masses must be the same.
fn worst_com_mm(
    urdf: &Urdf,
    chain: &Chain,
    dh: &DhConversion,
    rng: &mut ChaCha8Rng,
    samples: usize,
) -> f64 {
    let n = chain.joints.len();
    let mut worst: f64 = 0.0;
    for _ in 0..samples {
        let q: Vec<f64> = (0..n)
            .map(|_| rng.random_range(-std::f64::consts::PI..std::f64::consts::PI))
            .collect();
        let stated = (dh.masses.links.iter().enumerate())
            .filter_map(|(k, m)| Some((Carrier::Link(k), k, (*m)?)))
            .chain(dh.masses.tool.map(|m| (Carrier::Tool, n, m)));
        for (carrier, k, m) in stated {
            let (kg, urdf_com) = urdf_com(urdf, chain, &q, carrier);
            assert!((kg - m.kg).abs() < 1e-12, "{carrier:?}: {kg} vs {}", m.kg);
            worst = worst.max((dh_com(dh, &q, k, &m) - urdf_com).norm() * 1000.0);
        }
    }
    worst
}

/// The masses as the corrections' [`crate::corrections::Physics`] (what
/// an arm file with them reads as).
fn physics_of(m: &DhMasses) -> crate::corrections::Physics {
    let mass = |d: &DhMass| crate::corrections::Mass {
        kg: d.kg,
        com_mm: Some(d.com_mm),
    };
    crate::corrections::Physics {
        link_masses: m.links.iter().map(|l| l.as_ref().map(mass)).collect(),
        probe_mass: m.tool.as_ref().map(mass),
        gravity: m.gravity,
        ..Default::default()
    }
}

/// Gravity (the root's −z) about each joint axis, N·m, from the URDF
/// directly: the masses outboard of the joint, about a point on its
/// axis.
fn urdf_torques(urdf: &Urdf, chain: &Chain, q: &[f64]) -> Vec<f64> {
    let g = Vector3::new(0.0, 0.0, -crate::corrections::gravity::STANDARD_GRAVITY);
    (0..chain.joints.len())
        .map(|j| {
            let joint = urdf
                .joints
                .iter()
                .find(|u| u.name == chain.joints[j])
                .unwrap();
            let at = link_pose(urdf, chain, q, &joint.parent) * joint.origin;
            let (axis, point) = (at.rotation * joint.axis, at.translation.vector);
            let outboard = chain.masses.iter().filter(|m| match m.carrier {
                Carrier::Link(k) => k >= j,
                Carrier::Tool => true,
                Carrier::Base => false,
            });
            outboard
                .map(|m| {
                    let inertial = urdf
                        .links
                        .iter()
                        .find(|l| l.name == m.link)
                        .unwrap()
                        .inertial
                        .unwrap();
                    let r = link_pose(urdf, chain, q, &m.link) * Point3::from(inertial.com);
                    axis.dot(&(r.coords - point).cross(&(g * inertial.kg)))
                })
                .sum()
        })
        .collect()
}

/// Masses carried to the D-H frames: every link where it belongs, each
/// carried centre of mass where the URDF puts it at any reading (within
/// 1e-6 mm), and the gravity torques the toolkit computes from the
/// converted arm those of the URDF (gravity its root's −z, stated in
/// the D-H base, which the random first axis turns).
#[test]
fn random_chains_carry_their_masses() {
    let mut rng = ChaCha8Rng::seed_from_u64(29);
    for trial in 0..30 {
        let joints = if trial % 2 == 0 { 6 } else { 7 };
        let (text, expect) = random_massive_urdf(&mut rng, joints);
        let urdf = parse_urdf(&text, "massive.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
        let chain = urdf.chain(None, "ball_link").unwrap();
        let carried: Vec<(String, Carrier)> = chain
            .masses
            .iter()
            .map(|m| (m.link.clone(), m.carrier))
            .collect();
        assert_eq!(carried, expect, "trial {trial}");
        let moving: Vec<&ChainMass> = chain
            .masses
            .iter()
            .filter(|m| !m.moving.is_empty())
            .collect();
        assert_eq!(moving.len(), 1);
        assert_eq!(
            (moving[0].link.as_str(), moving[0].moving.as_slice()),
            ("slider", &["slide".to_string()][..])
        );
        let dh = chain.to_dh().unwrap();
        assert_eq!(dh.masses.links.len(), joints);
        assert!(dh.masses.links.iter().all(Option::is_some));
        assert!(dh.masses.tool.is_some());
        let worst = worst_com_mm(&urdf, &chain, &dh, &mut rng, 50);
        assert!(worst < 1e-6, "trial {trial}: {worst} mm\n{text}");
        assert!(dh.masses.gravity.is_some(), "the base is turned");
        let physics = physics_of(&dh.masses);
        for _ in 0..20 {
            let q: Vec<f64> = (0..joints).map(|_| rng.random_range(-3.0..3.0)).collect();
            let mut tau = vec![0.0; joints];
            crate::corrections::gravity::torques(&dh.params, &physics, &q, &mut tau);
            let want = urdf_torques(&urdf, &chain, &q);
            for (j, (a, b)) in tau.iter().zip(&want).enumerate() {
                assert!(
                    (a - b).abs() < 1e-9 * (1.0 + b.abs()),
                    "trial {trial} joint {j}: {a} vs {b}"
                );
            }
        }
    }
}

/// The shipped URDFs' masses: the link after each joint, the gripper
/// (and fingers) as the probe's, the base left out, gravity the base's
/// −z; their centres where the URDF puts them at any reading.
#[test]
fn shipped_urdfs_carry_their_masses() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/mukca/urdf");
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    // Link after joint 2, the tool's mass, the base's.
    for (file, after_2, tool, base) in [
        (
            "gen3lite.urdf",
            1.17756164,
            0.1395 + 2.0 * (0.018385 + 0.010748),
            1.14608471,
        ),
        ("panda.urdf", 0.646926, 0.73 + 2.0 * 0.015, 0.629769),
    ] {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let urdf = parse_urdf(&text, file, UrdfOptions::default()).unwrap();
        let chain = urdf.chain(None, "ball_link").unwrap();
        let dh = chain.to_dh().unwrap();
        let p = &dh.masses;
        assert!((p.links[1].unwrap().kg - after_2).abs() < 1e-12, "{file}");
        assert!((p.tool.unwrap().kg - tool).abs() < 1e-12, "{file}");
        let left_out: Vec<f64> = (chain.masses.iter())
            .filter(|m| m.carrier == Carrier::Base)
            .map(|m| m.kg)
            .collect();
        assert_eq!(left_out, [base], "{file}");
        assert_eq!(p.gravity, None, "{file}: the D-H base is the URDF root");
        let worst = worst_com_mm(&urdf, &chain, &dh, &mut rng, 500);
        assert!(worst < 1e-6, "{file}: {worst} mm");
    }
}

#[test]
fn bad_masses_are_located() {
    let parse = |links: &str| {
        let text = format!("<robot>\n{links}\n</robot>");
        parse_urdf(&text, "m.urdf", UrdfOptions::default())
    };
    let cases = [
        ("<link/>", "m.urdf:2: field `name`: missing on <link>"),
        (
            "<link name=\"a\">\n<inertial><origin xyz=\"0 0 0\"/></inertial></link>",
            "m.urdf:3: field `mass`: link `a`: <inertial> without <mass>",
        ),
        (
            "<link name=\"a\"><inertial>\n<mass/></inertial></link>",
            "m.urdf:3: field `mass`: link `a`: <mass> without `value`",
        ),
        (
            "<link name=\"a\"><inertial><mass value=\"-1\"/></inertial></link>",
            "m.urdf:2: field `mass`: link `a`: `-1` is not a mass (a finite number of kg, ≥ 0)",
        ),
        (
            "<link name=\"a\"><inertial><mass value=\"heavy\"/></inertial></link>",
            "m.urdf:2: field `mass`: link `a`: `heavy` is not a mass (a finite number of kg, ≥ 0)",
        ),
        (
            "<link name=\"a\"><inertial><mass value=\"inf\"/></inertial></link>",
            "m.urdf:2: field `mass`: link `a`: `inf` is not a mass (a finite number of kg, ≥ 0)",
        ),
        (
            "<link name=\"a\"><inertial>\n<origin xyz=\"0 0\"/><mass value=\"1\"/></inertial></link>",
            "m.urdf:3: field `xyz`: `0 0` is not three finite numbers",
        ),
        (
            "<link name=\"a\"><inertial>\n<origin rpy=\"0 x 0\"/><mass value=\"1\"/></inertial></link>",
            "m.urdf:3: field `rpy`: `0 x 0` is not three finite numbers",
        ),
        (
            "<link name=\"a\"/>\n<link name=\"a\"/>",
            "m.urdf:3: field `name`: link `a` is already defined (line 2); a URDF names each \
                 link once",
        ),
    ];
    for (links, message) in cases {
        let e = parse(links).unwrap_err();
        assert_eq!(e.to_string(), message);
        assert!(matches!(e, InputError::Field { .. }), "{e:?}");
    }
    // A link without <inertial> has no mass; a mass of 0 is a mass.
    let urdf =
        parse("<link name=\"a\"/><link name=\"b\"><inertial><mass value=\"0\"/></inertial></link>")
            .unwrap();
    assert_eq!(urdf.links[0].inertial, None);
    assert_eq!(urdf.links[1].inertial.map(|i| i.kg), Some(0.0));
    // Joints in a loop are refused, not followed forever.
    let text = r#"<robot>
            <joint name="j1" type="revolute"><parent link="a"/><child link="b"/></joint>
            <joint name="j2" type="revolute"><parent link="b"/><child link="a"/></joint>
            </robot>"#;
    let urdf = parse_urdf(text, "loop.urdf", UrdfOptions::default()).unwrap();
    let e = urdf.chain(None, "b").unwrap_err();
    assert!(e.to_string().contains("is on a loop of joints"), "{e}");
    // A chain without masses converts to an arm without any.
    let text = r#"<robot><link name="base"><inertial><mass value="2"/></inertial></link>
            <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
            <axis xyz="0 0 1"/></joint></robot>"#;
    let urdf = parse_urdf(text, "base.urdf", UrdfOptions::default()).unwrap();
    let chain = urdf.chain(None, "l1").unwrap();
    assert_eq!(chain.masses.len(), 1);
    assert_eq!(chain.to_dh().unwrap().masses, DhMasses::default());
}

/// Names, values and tips echoed in a message are bounded (cut to 80
/// characters, their length said) and their control characters escaped,
/// however long or garbled the file or the tip asked for.
#[test]
fn hostile_names_give_bounded_messages() {
    let long = "n".repeat(10_000);
    // A name with line breaks (as XML character references, the only
    // way an attribute keeps them) and a very long one.
    for name in ["a&#13;&#10;b", long.as_str()] {
        let link = |extra: &str| format!("<robot>\n<link name=\"{name}\">{extra}</link>\n</robot>");
        let joint = |kind: &str, body: &str| {
            format!("<robot>\n<joint name=\"{name}\" type=\"{kind}\">{body}</joint>\n</robot>")
        };
        let parts = "<parent link=\"base\"/><child link=\"tip\"/>";
        let texts = [
            format!("<robot>\n<link name=\"{name}\"/><link name=\"{name}\"/>\n</robot>"),
            link("<inertial><mass value=\"x\"/></inertial>"),
            link(&format!("<inertial><mass value=\"{name}\"/></inertial>")),
            link("<inertial/>"),
            link(&format!(
                "<inertial><origin xyz=\"{name}\"/><mass value=\"1\"/></inertial>"
            )),
            joint("revolute", ""),
            joint("revolute", &format!("{parts}<axis xyz=\"0 0 0\"/>")),
            format!("<{}/>", name.replace("&#13;&#10;", "_")),
            format!(
                "<robot><{0}></{0}x></robot>",
                name.replace("&#13;&#10;", "_")
            ),
        ];
        let mut messages: Vec<String> = texts
            .iter()
            .map(|t| {
                parse_urdf(t, "h.urdf", UrdfOptions::default())
                    .unwrap_err()
                    .to_string()
            })
            .collect();
        let urdf = parse_urdf(
            &joint(&format!("prismatic{name}"), parts),
            "h.urdf",
            UrdfOptions::default(),
        )
        .unwrap();
        messages.push(urdf.chain(None, "tip").unwrap_err().to_string());
        messages.push(urdf.chain(None, "t\r\n\0").unwrap_err().to_string());
        messages.push(urdf.chain(Some(&long), "tip").unwrap_err().to_string());
        for m in &messages {
            assert!(m.chars().count() < 600, "{} characters: {m:.700}", m.len());
            assert!(!m.contains(char::is_control), "{m:?}");
        }
        if name == long {
            let cut = messages.iter().filter(|m| m.contains("(10000 characters)"));
            assert!(cut.count() >= 8, "{messages:#?}");
        } else {
            assert!(
                messages[0].contains("link `a\\r\\nb` is already defined"),
                "{}",
                messages[0]
            );
        }
    }
}
