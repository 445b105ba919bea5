//! `aacmm export`: an arm file as URDF (with a template's names) and as a
//! D-H table; read back by the toolkit's own URDF reader, the chain is the
//! arm within 1 nm.

use aacmm_core::kernel::ArmKernel;
use aacmm_core::urdf::{UrdfOptions, parse_urdf};

use crate::util::{aacmm, assert_clean_error, example, stderr, temp_dir};

/// The shipped Panda exported with its own URDF as the template: the
/// template's joint names and limits, and the tip where the arm puts its
/// probe for every reading; the D-H table has one row per joint and the
/// probe's.
#[test]
fn the_panda_exports_with_its_urdfs_names_and_reads_back() {
    let dir = temp_dir("export");
    let arm = example("mukca/panda-1/arm.toml");
    let template = example("mukca/urdf/panda.urdf");
    let (urdf_out, table) = (dir.join("panda.urdf"), dir.join("panda.csv"));
    let o = aacmm(&[
        "export",
        "--arm",
        arm.to_str().unwrap(),
        "--urdf",
        urdf_out.to_str().unwrap(),
        "--template",
        template.to_str().unwrap(),
        "--dh-table",
        table.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&urdf_out).unwrap();
    let urdf = parse_urdf(&text, "panda.urdf", UrdfOptions { snap_rad: 0.0 }).unwrap();
    let names: Vec<&str> = urdf.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names[..7],
        [
            "panda_joint1",
            "panda_joint2",
            "panda_joint3",
            "panda_joint4",
            "panda_joint5",
            "panda_joint6",
            "panda_joint7"
        ]
    );
    assert!(
        urdf.joints[3]
            .limits
            .is_some_and(|[lo, hi]| lo < -3.0 && hi < 0.0)
    );
    let chain = urdf.chain(None, "probe").unwrap();
    let params = aacmm_core::read_arm(&arm).unwrap().0.params;
    let k = ArmKernel::new(&params).unwrap();
    for i in 0..100 {
        let q: Vec<f64> = (0..7)
            .map(|j| ((i * 5 + j * 11) as f64 * 0.29).cos() * 2.0)
            .collect();
        let (tip, p) = (chain.position(&q), k.position(&q).unwrap());
        for c in 0..3 {
            assert!(
                (tip[c] * 1000.0 - p[c]).abs() < 1e-6,
                "{q:?}: {tip:?} m vs {p:?} mm"
            );
        }
    }
    let table = std::fs::read_to_string(&table).unwrap();
    assert_eq!(table.lines().count(), 1 + 7 + 1, "{table}");
    // A template of another robot is refused, naming the flag.
    let ur5 = example("ur5-tracker/arm.toml");
    let o = aacmm(&[
        "export",
        "--arm",
        ur5.to_str().unwrap(),
        "--urdf",
        urdf_out.to_str().unwrap(),
        "--template",
        template.to_str().unwrap(),
        "--force",
    ]);
    assert_clean_error(
        &o,
        &[
            "--template",
            "no chain of it has the arm's joints (RRRRRR: 6 joints",
            "RRRRRRR to `ball_link`",
            "RRRRRRRP to `panda_leftfinger`",
        ],
    );
}
