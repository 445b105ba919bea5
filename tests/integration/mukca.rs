//! The MUKCa real data shipped in examples/mukca: files complete, arm files
//! equal to their URDFs' conversion, and the leave-one-placement-out
//! evaluation scoring the nominal arm as an independent computation does and
//! improving on it.

use std::path::PathBuf;

use aacmm_core::calibrate::validate::placements::{
    PlacementSummary, leave_one_placement_out, placement_of,
};
use aacmm_core::calibrate::{Method, ModelOptions, SolverSettings};
use aacmm_core::dataset::DataSet;
use aacmm_core::io::{AngleUnit, read_arm, read_lengths, read_poses};
use aacmm_core::reference_model;
use aacmm_core::urdf::{UrdfOptions, parse_urdf};

use crate::util::example;

/// A shipped MUKCa folder: its arm file and its touches with lengths.
pub(crate) fn load(name: &str) -> (aacmm_core::domain::Arm, DataSet) {
    let dir = example("mukca").join(name);
    let (arm, _) = read_arm(&dir.join("arm.toml")).unwrap();
    let (poses, _) = read_poses(
        &dir.join("poses.csv"),
        AngleUnit::Rad,
        Some(arm.params.joint_count()),
    )
    .unwrap();
    let lengths = read_lengths(&dir.join("lengths.csv")).unwrap();
    let data = DataSet::from_poses(&poses, "poses.csv")
        .unwrap()
        .with_lengths(&lengths, "lengths.csv")
        .unwrap();
    (arm, data)
}

/// A data folder, its labels with their touch counts, and its lengths.
type Expected = (&'static str, &'static [(&'static str, usize)], usize);

/// Every MUKCa row is there: the touch counts of the source files
/// (examples/mukca/README.md), label by label.
#[test]
fn shipped_data_is_complete() {
    let expect: [Expected; 3] = [
        (
            "kinova-1",
            &[
                ("front-h0", 20),
                ("front-h1", 20),
                ("kinova_left-h0", 20),
                ("kinova_left-h1", 20),
                ("kinova_behind_raised-h0", 10),
                ("kinova_left_on_dingo-h0", 20),
            ],
            2,
        ),
        (
            "kinova-2",
            &[
                ("front_rotated-h0", 20),
                ("front_rotated-h1", 20),
                ("left-h0", 20),
                ("left-h1", 21),
                ("right-high-h0", 22),
                ("right-high-h1", 21),
                ("gen3lite-h1", 24),
            ],
            3,
        ),
        (
            "panda-1",
            &[
                ("front-h0", 30),
                ("front-h1", 32),
                ("side_right-h0", 30),
                ("side_right-h1", 30),
                ("window-h0", 30),
                ("window-h1", 30),
            ],
            3,
        ),
    ];
    for (name, points, lengths) in expect {
        let (_, data) = load(name);
        let got: Vec<(&str, usize)> = data
            .points()
            .iter()
            .map(|p| (p.label.as_str(), p.touches.len()))
            .collect();
        assert_eq!(got, points, "{name}");
        assert_eq!(data.references().len(), lengths, "{name}");
        for r in data.references() {
            // Lengths join the two sockets of one placement.
            let (a, b) = (&data.points()[r.a].label, &data.points()[r.b].label);
            assert_eq!(placement_of(a), placement_of(b));
            assert_eq!(r.distance, 50.0);
        }
    }
}

/// The shipped arm files are the conversion of the shipped URDFs (so that
/// neither drifts from the other): geometry, and the links' and the tool's
/// masses with their centres of mass.
#[test]
fn arm_files_are_the_urdf_conversion() {
    for (urdf, arms) in [
        ("gen3lite.urdf", &["kinova-1", "kinova-2"][..]),
        ("panda.urdf", &["panda-1"][..]),
    ] {
        let path: PathBuf = example("mukca").join("urdf").join(urdf);
        let text = std::fs::read_to_string(&path).unwrap();
        let parsed = parse_urdf(&text, urdf, UrdfOptions::default()).unwrap();
        let dh = parsed.chain(None, "ball_link").unwrap().to_dh().unwrap();
        for arm in arms {
            let (file, _) = read_arm(&example("mukca").join(arm).join("arm.toml")).unwrap();
            let (a, b) = (file.params.to_vec(), dh.params.to_vec());
            assert_eq!(a.len(), b.len());
            for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                // The files are rounded to 1e-9 mm / 1e-9 deg.
                assert!(
                    (x - y).abs() < 1e-8,
                    "{arm} parameter {i}: file {x}, URDF {y}"
                );
            }
            // Masses and centres as the files round them (1e-12 kg, 1e-9 mm);
            // gravity the base's −z (not stated).
            let (p, m) = (&file.physics, &dh.masses);
            assert_eq!(p.gravity, m.gravity, "{arm}");
            assert_eq!(p.link_masses.len(), m.links.len(), "{arm}");
            let stated = p.link_masses.iter().chain([&p.probe_mass]);
            let converted = m.links.iter().chain([&m.tool]);
            for (i, (x, y)) in stated.zip(converted).enumerate() {
                let (x, y) = (x.unwrap(), y.unwrap());
                let c = x.com_mm.unwrap();
                assert!(
                    (x.kg - y.kg).abs() < 1e-12
                        && (0..3).all(|k| (c[k] - y.com_mm[k]).abs() < 1e-8),
                    "{arm} mass {i}: file {x:?}, URDF {y:?}"
                );
            }
        }
    }
}

/// Mean distance of touches to their centroid, and the centroids, from the
/// reference (nalgebra) model — independent of the kernel and the metrics.
fn by_hand(params: &[f64], data: &DataSet, points: &[usize]) -> (f64, Vec<[f64; 3]>) {
    let mut es = Vec::new();
    let mut centroids = Vec::new();
    for &p in points {
        let xyz: Vec<[f64; 3]> = data.points()[p]
            .touches
            .clone()
            .map(|i| reference_model::position(params, data.reading(i)))
            .collect();
        let n = xyz.len() as f64;
        let c = [0, 1, 2].map(|k| xyz.iter().map(|x| x[k]).sum::<f64>() / n);
        let e = xyz
            .iter()
            .map(|x| ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2) + (x[2] - c[2]).powi(2)).sqrt())
            .sum::<f64>()
            / n;
        es.push(e);
        centroids.push(c);
    }
    (es.iter().sum::<f64>() / es.len() as f64, centroids)
}

#[test]
fn leave_one_placement_out_on_the_kinova() {
    let (arm, data) = load("kinova-2");
    let lm = SolverSettings::default().with_method(Method::Lm);
    let folds = leave_one_placement_out(&arm.params, &data, &ModelOptions::default(), &lm).unwrap();
    let names: Vec<&str> = folds.iter().map(|f| f.placement.as_str()).collect();
    assert_eq!(names, ["front_rotated", "left", "right-high", "gen3lite"]);
    let nominal = arm.params.to_vec();
    for f in &folds {
        assert!(f.successful, "{}", f.placement);
        assert_eq!(f.trained_touches + f.touches, data.len());
        let points: Vec<usize> = f
            .sockets
            .iter()
            .map(|s| data.points().iter().position(|p| &p.label == s).unwrap())
            .collect();
        let (e, c) = by_hand(&nominal, &data, &points);
        assert!(
            (f.nominal.e_mean - e).abs() < 1e-9,
            "{}: {} vs {e}",
            f.placement,
            f.nominal.e_mean
        );
        match c.as_slice() {
            [a, b] => {
                let d =
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
                let got = f.nominal.length_max.unwrap();
                assert!((got - (d - 50.0).abs()).abs() < 1e-9, "{}", f.placement);
                assert_eq!(f.trained_lengths, 2);
            }
            _ => {
                assert_eq!(f.nominal.length_max, None);
                assert_eq!(f.trained_lengths, 3);
            }
        }
        // Calibrated without this placement, the arm is more consistent on it.
        assert!(f.calibrated.e_mean < f.nominal.e_mean, "{}", f.placement);
    }
    let s = PlacementSummary::of(&folds);
    // Measured: 10.3 → 2.9 mm (−72 %), |d − 50| 3.0 → 0.5 mm (−83 %).
    assert!(s.consistency_change_percent() < -50.0, "{s:?}");
    assert!(s.distance_change_percent().unwrap() < -50.0, "{s:?}");
}

#[test]
fn one_placement_is_refused() {
    let (arm, data) = load("kinova-1");
    let front: Vec<usize> = (0..2).collect();
    let one = data.subset(&front);
    let (model, settings) = (ModelOptions::default(), SolverSettings::default());
    let e = leave_one_placement_out(&arm.params, &one, &model, &settings).unwrap_err();
    assert!(e.to_string().contains("two placements or more"), "{e}");
}
