//! Tests of the whole simulator; the parts have their doc examples.

use std::path::PathBuf;

use super::files::{CAMPAIGN_FORMAT, campaign_to_toml};
use super::ik::IK_TOLERANCE_MM;
use super::settings::MAX_POSES_PER_SOCKET;
use super::sockets::round_nm;
use super::touches::separation;
use super::*;
use crate::io::{parse_poses, read_arm, read_lengths, read_points, read_poses};
use crate::kernel::ArmKernel;
use crate::params::{DhJoint, DhParams};

fn paper() -> Arm {
    Arm::without_limits("paper-table-1", DhParams::paper_nominal())
}

/// A 7-joint arm of similar size (twists ∓90°).
fn seven() -> Arm {
    let h = std::f64::consts::FRAC_PI_2;
    let rows = [
        (-h, 0.0, 350.0),
        (h, 0.0, 0.0),
        (-h, 30.0, 300.0),
        (h, -30.0, 0.0),
        (-h, 30.0, 250.0),
        (h, -30.0, 0.0),
        (-h, 0.0, 80.0),
    ];
    let joints = rows
        .iter()
        .map(|&(alpha, a, d)| DhJoint {
            a,
            d,
            alpha,
            theta: 0.0,
            ..DhJoint::default()
        })
        .collect();
    Arm::without_limits(
        "seven",
        DhParams {
            joints,
            probe: [0.0, 0.0, 60.0],
        },
    )
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("aacmm-sim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    crate::geometry::distance(&a, &b)
}

/// The true arm's probe centre at every recorded pose, against its socket.
fn max_socket_error(c: &Campaign) -> f64 {
    let p = ArmKernel::new(&c.true_arm.params)
        .unwrap()
        .positions_of(&c.poses.rows().collect::<Vec<_>>())
        .unwrap();
    p.iter()
        .zip(&c.touches)
        .map(|(p, t)| dist(*p, c.sockets[t.socket].1))
        .fold(0.0, f64::max)
}

#[test]
fn zero_noise_reproduces_sockets_6_and_7_joints() {
    for (nominal, errors) in [
        (paper(), ErrorModel::Paper),
        (paper(), ErrorModel::random(1.0, true)),
        (seven(), ErrorModel::random(1.0, false)),
    ] {
        let s = CampaignSettings::new(11, errors, 6, 8);
        let c = simulate(&nominal, &s).unwrap();
        assert_eq!(c.poses.len(), 48);
        assert_eq!(c.poses.joints(), nominal.params.joint_count());
        let e = max_socket_error(&c);
        assert!(e <= 1e-9, "{} joints: {e} mm", c.poses.joints());
        assert!(c.stats.max_residual_mm < IK_TOLERANCE_MM);
        // Labels follow the sockets, eight touches each.
        assert_eq!(c.poses.label(0), "S1");
        assert_eq!(c.poses.label(47), "S6");
    }
}

#[test]
fn touches_of_a_socket_are_distinct_articulations() {
    let mut s = CampaignSettings::new(3, ErrorModel::Paper, 5, 12);
    s.min_pose_separation_deg = 60.0;
    let c = simulate(&paper(), &s).unwrap();
    let min_sep = 60f64.to_radians();
    // The rule was exercised: some solutions were rejected as too close.
    assert!(c.stats.too_close > 0, "{:?}", c.stats);
    for a in 0..c.touches.len() {
        for b in a + 1..c.touches.len() {
            let (ta, tb) = (&c.touches[a], &c.touches[b]);
            if ta.socket == tb.socket {
                assert!(separation(&ta.q, &tb.q) >= min_sep, "touches {a} and {b}");
                // Noise-free readings are the true ones (to the degree rounding).
                assert!(separation(c.poses.reading(a), c.poses.reading(b)) >= min_sep - 1e-12);
            }
        }
    }
    // Not ten copies of one pose: every joint moves across the campaign.
    for j in 0..6 {
        let (lo, hi) = c
            .poses
            .rows()
            .map(|q| q[j])
            .fold((f64::MAX, f64::MIN), |(l, h), x| (l.min(x), h.max(x)));
        assert!(hi - lo > 1.0, "joint {} spans only {} rad", j + 1, hi - lo);
    }
}

#[test]
fn joint_limits_are_respected() {
    let mut nominal = paper();
    let lim = |lo: f64, hi: f64| Some([lo.to_radians(), hi.to_radians()]);
    nominal.limits = vec![
        lim(-170.0, 170.0),
        lim(-100.0, 100.0),
        None,
        lim(-150.0, 150.0),
        lim(-90.0, 120.0),
        lim(0.0, 300.0),
    ];
    let s = CampaignSettings::new(5, ErrorModel::Paper, 6, 10);
    let c = simulate(&nominal, &s).unwrap();
    assert_eq!(c.true_arm.limits, nominal.limits);
    for t in &c.touches {
        for (j, (&q, l)) in t.q.iter().zip(&nominal.limits).enumerate() {
            if let Some([lo, hi]) = l {
                assert!(
                    *lo <= q && q <= *hi,
                    "joint {}: {q} outside [{lo}, {hi}]",
                    j + 1
                );
            }
        }
    }
    for q in c.poses.rows() {
        for (j, (&q, l)) in q.iter().zip(&nominal.limits).enumerate() {
            if let Some([lo, hi]) = l {
                assert!(
                    *lo <= q && q <= *hi,
                    "reading {}: {q} outside [{lo}, {hi}]",
                    j + 1
                );
            }
        }
    }
    assert!(max_socket_error(&c) <= 1e-9);
    // Joint 6 reaches past 180° inside its limits: readings are shifted there.
    assert!(c.poses.rows().any(|q| q[5] > std::f64::consts::PI));
}

#[test]
fn paper_model_matches_table_2() {
    let c = simulate(&paper(), &CampaignSettings::new(1, ErrorModel::Paper, 2, 3)).unwrap();
    let t = &c.true_arm.params;
    let close = |x: f64, y: f64| (x - y).abs() < 1e-12;
    assert!(close(t.joints[0].theta.to_degrees(), 0.131));
    assert!(close(t.joints[1].theta.to_degrees(), 0.446));
    assert!(close(t.joints[2].alpha.to_degrees(), -90.0 - 0.021));
    assert!(close(t.joints[0].alpha.to_degrees(), -90.0 + 0.124));
    assert!(close(t.joints[1].a, -55.0 - 1.106));
    assert!(close(t.joints[3].a, -35.0 - 0.673));
    assert!(close(t.joints[0].d, 375.0 + 0.186));
    assert!(close(t.joints[5].d, 0.177));
    assert!(close(t.joints[5].a, -35.0 + 0.306));
    assert_eq!(t.joints[5].theta, 0.0); // no Δθ6
    assert_eq!(t.joints[5].alpha, std::f64::consts::FRAC_PI_2); // no Δβ6
    assert_eq!(t.probe[..2], [0.0, 0.0]);
    assert!(close(t.probe[2], 100.094));
    // Not for a 7-joint arm.
    let e = simulate(&seven(), &CampaignSettings::new(1, ErrorModel::Paper, 2, 3)).unwrap_err();
    assert!(matches!(e, SimError::Model(_)), "{e}");
    assert!(e.to_string().contains("6-joint"), "{e}");
}

#[test]
fn random_model_small_and_newly_assembled() {
    let nominal = paper();
    let mut uniform = Vec::new();
    let mut small = Vec::new();
    for seed in 0..30 {
        let mut r = rng(seed, streams::TRUE_ARM);
        let t = true_arm(&nominal, &ErrorModel::random(1.0, true), &mut r).unwrap();
        uniform.extend(t.params.joints.iter().map(|j| j.theta.to_degrees()));
        let mut r = rng(seed, streams::TRUE_ARM);
        let t = true_arm(&nominal, &ErrorModel::random(1.0, false), &mut r).unwrap();
        small.extend(t.params.joints.iter().map(|j| j.theta.to_degrees()));
        for (tj, nj) in t.params.joints.iter().zip(&nominal.params.joints) {
            assert!((tj.a - nj.a).abs() < 5.0 * DEFAULT_LENGTH_SIGMA_MM);
            assert!((tj.alpha - nj.alpha).to_degrees().abs() < 5.0 * DEFAULT_TWIST_SIGMA_DEG);
        }
    }
    // 180 zero offsets uniform in ±180°: every 60° sector is hit.
    assert!(uniform.iter().all(|z| (-180.0..180.0).contains(z)));
    for sector in 0..6 {
        let lo = -180.0 + 60.0 * sector as f64;
        let hits = uniform
            .iter()
            .filter(|&&z| lo <= z && z < lo + 60.0)
            .count();
        assert!(hits >= 10, "sector {lo}°: {hits} of 180");
    }
    // Gaussian ones stay small, with about the stated σ.
    assert!(small.iter().all(|z| z.abs() < 5.0 * DEFAULT_ZERO_SIGMA_DEG));
    let rms = (small.iter().map(|z| z * z).sum::<f64>() / small.len() as f64).sqrt();
    assert!(
        (rms / DEFAULT_ZERO_SIGMA_DEG - 1.0).abs() < 0.2,
        "rms {rms}"
    );
    // The scale multiplies the σ.
    let ErrorModel::Random {
        twist_sigma_deg, ..
    } = ErrorModel::random(0.5, false)
    else {
        unreachable!()
    };
    assert_eq!(twist_sigma_deg, DEFAULT_TWIST_SIGMA_DEG * 0.5);
}

#[test]
fn newly_assembled_arm_campaign_reproduces_sockets() {
    let s = CampaignSettings::new(8, ErrorModel::random(1.0, true), 4, 10);
    let c = simulate(&paper(), &s).unwrap();
    assert!(max_socket_error(&c) <= 1e-9);
    // The zero offsets are large, so the readings are far from the nominal's.
    let big = c
        .true_arm
        .params
        .joints
        .iter()
        .filter(|j| j.theta.abs() > 0.2)
        .count();
    assert!(big >= 3, "{:?}", c.true_arm.params.joints);
}

/// The poses are streamed into their file: the bytes of `write_poses` into
/// memory; a campaign without lengths written over one with them removes
/// the stale `lengths.csv`, and the paths written start with the poses.
#[test]
fn poses_stream_into_their_file_and_a_stale_lengths_file_goes() {
    let mut s = CampaignSettings::new(3, ErrorModel::Paper, 4, 6);
    s.reference_lengths = 2;
    let dir = temp_dir("stream");
    let c = simulate(&paper(), &s).unwrap();
    write_campaign(&dir, &c, &s).unwrap();
    let mut poses = Vec::new();
    crate::io::write_poses(&mut poses, &c.poses, AngleUnit::Deg).unwrap();
    assert_eq!(std::fs::read(dir.join(POSES_FILE)).unwrap(), poses);
    assert!(dir.join(LENGTHS_FILE).exists());
    s.reference_lengths = 0;
    let c = simulate(&paper(), &s).unwrap();
    let written = write_campaign(&dir, &c, &s).unwrap();
    assert!(!dir.join(LENGTHS_FILE).exists());
    let names: Vec<_> = (written.iter())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        [POSES_FILE, SOCKETS_FILE, TRUE_ARM_FILE, CAMPAIGN_FILE]
    );
    std::fs::remove_dir_all(dir).unwrap();
}

fn files(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

#[test]
fn same_settings_same_bytes_and_campaign_toml_regenerates() {
    let mut s = CampaignSettings::new(2024, ErrorModel::random(1.0, false), 5, 6);
    s.encoder_noise_deg = 0.002;
    s.probe_noise_mm = 0.005;
    s.reference_lengths = 4;
    s.length_uncertainty_mm = Some(0.001);
    s.nominal_file = Some("examples/paper-table-1.toml".into());
    let (d1, d2, d3, d4) = (
        temp_dir("det1"),
        temp_dir("det2"),
        temp_dir("det3"),
        temp_dir("det4"),
    );
    let c1 = simulate(&paper(), &s).unwrap();
    let written = write_campaign(&d1, &c1, &s).unwrap();
    assert_eq!(written.len(), 5);
    let c2 = simulate(&paper(), &s).unwrap();
    assert_eq!(c1, c2);
    write_campaign(&d2, &c2, &s).unwrap();
    let f1 = files(&d1);
    assert_eq!(
        f1.iter().map(|f| f.0.as_str()).collect::<Vec<_>>(),
        [
            CAMPAIGN_FILE,
            LENGTHS_FILE,
            POSES_FILE,
            SOCKETS_FILE,
            TRUE_ARM_FILE
        ]
    );
    assert_eq!(f1, files(&d2));

    // campaign.toml alone regenerates the identical files.
    let (nominal, settings) = read_campaign(&d1.join(CAMPAIGN_FILE)).unwrap();
    assert_eq!((&nominal, &settings), (&paper(), &s));
    let c3 = simulate(&nominal, &settings).unwrap();
    write_campaign(&d3, &c3, &settings).unwrap();
    assert_eq!(f1, files(&d3));

    // Another seed, other bytes in every data file.
    s.seed = 2025;
    write_campaign(&d4, &simulate(&paper(), &s).unwrap(), &s).unwrap();
    for (a, b) in f1.iter().zip(files(&d4)) {
        assert_ne!(a.1, b.1, "{}", a.0);
    }
    for d in [d1, d2, d3, d4] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

#[test]
fn written_files_read_back_exactly() {
    let mut s = CampaignSettings::new(9, ErrorModel::random(1.0, true), 4, 5);
    s.encoder_noise_deg = 0.01;
    s.length_uncertainty_mm = Some(0.002);
    let c = simulate(&paper(), &s).unwrap();
    let dir = temp_dir("readback");
    write_campaign(&dir, &c, &s).unwrap();
    let (poses, warnings) = read_poses(&dir.join(POSES_FILE), AngleUnit::Deg, Some(6)).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(poses, c.poses); // bit-exact, lines included
    assert_eq!(read_arm(&dir.join(TRUE_ARM_FILE)).unwrap().0, c.true_arm);
    assert_eq!(read_points(&dir.join(SOCKETS_FILE)).unwrap(), c.sockets);
    let lengths = read_lengths(&dir.join(LENGTHS_FILE)).unwrap();
    assert_eq!(lengths, c.lengths);
    assert!(lengths.iter().all(|l| l.uncertainty == Some(0.002)));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn noise_has_the_stated_size() {
    let mut s = CampaignSettings::new(4, ErrorModel::Paper, 6, 10);
    let quiet = simulate(&paper(), &s).unwrap();
    s.encoder_noise_deg = 0.01;
    let enc = simulate(&paper(), &s).unwrap();
    // Same seed: same true arm, sockets and true readings; only the readings differ.
    assert_eq!(
        (&enc.true_arm, &enc.sockets, &enc.touches),
        (&quiet.true_arm, &quiet.sockets, &quiet.touches)
    );
    let d: Vec<f64> = enc
        .poses
        .rows()
        .zip(&enc.touches)
        .flat_map(|(r, t)| r.iter().zip(&t.q).map(|(a, b)| wrap(a - b).to_degrees()))
        .collect();
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    assert!((rms / 0.01 - 1.0).abs() < 0.15, "encoder noise rms {rms}°");
    assert!(max_socket_error(&enc) > 1e-3);

    s.encoder_noise_deg = 0.0;
    s.probe_noise_mm = 0.02;
    let seat = simulate(&paper(), &s).unwrap();
    assert_eq!(seat.sockets, quiet.sockets);
    let e: Vec<f64> = seat
        .touches
        .iter()
        .flat_map(|t| {
            let c = seat.sockets[t.socket].1;
            (0..3).map(move |i| t.point[i] - c[i])
        })
        .collect();
    let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt();
    assert!((rms / 0.02 - 1.0).abs() < 0.2, "seating rms {rms} mm");
    // The true arm still reaches each seated point exactly.
    let p = ArmKernel::new(&seat.true_arm.params)
        .unwrap()
        .positions_of(&seat.poses.rows().collect::<Vec<_>>())
        .unwrap();
    for (p, t) in p.iter().zip(&seat.touches) {
        assert!(dist(*p, t.point) <= 1e-9);
    }
}

#[test]
fn reference_lengths_are_true_distances_of_distinct_long_pairs() {
    let mut s = CampaignSettings::new(6, ErrorModel::Paper, 8, 3);
    s.reference_lengths = 10;
    let c = simulate(&paper(), &s).unwrap();
    assert_eq!(c.lengths.len(), 10);
    let at = |l: &str| c.sockets.iter().find(|s| s.0 == l).unwrap().1;
    let mut pairs = std::collections::HashSet::new();
    for l in &c.lengths {
        assert_eq!(l.distance, dist(at(&l.a), at(&l.b)));
        assert_eq!(l.uncertainty, None);
        let key = if l.a < l.b {
            (&l.a, &l.b)
        } else {
            (&l.b, &l.a)
        };
        assert!(pairs.insert(key), "pair {key:?} twice");
    }
    // From the longer half of the 28 pairs, longest first.
    let mut all: Vec<f64> = Vec::new();
    for i in 0..8 {
        for j in i + 1..8 {
            all.push(dist(c.sockets[i].1, c.sockets[j].1));
        }
    }
    all.sort_by(|a, b| b.total_cmp(a));
    assert!(c.lengths.iter().all(|l| l.distance >= all[13]));
    assert!(c.lengths.windows(2).all(|w| w[0].distance >= w[1].distance));
    // Coinciding sockets are the sockets' fault, not the uncertainty's.
    let twins = vec![
        ("A".to_string(), [1.0, 2.0, 3.0]),
        ("B".into(), [1.0, 2.0, 3.0]),
    ];
    let e = reference_lengths(&twins, 1, None, &mut rng(1, streams::LENGTHS)).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("setting `sockets.points`: sockets `A` and `B` are at the same place"),
        "{e}"
    );
}

#[test]
fn given_sockets_keep_their_labels() {
    let dir = temp_dir("given");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("sockets.csv");
    std::fs::write(
        &path,
        "point,x,y,z\nA,300,100,400\nB,-200,350,250.1234567\nC,0,-400,600\n",
    )
    .unwrap();
    let mut s = CampaignSettings::new(1, ErrorModel::Paper, 1, 5);
    s.sockets = SocketPlan::from_file(&path).unwrap();
    s.reference_lengths = 3;
    let c = simulate(&paper(), &s).unwrap();
    assert_eq!(c.sockets[1], ("B".to_string(), [-200.0, 350.0, 250.123457]));
    assert_eq!(c.poses.label(5), "B");
    assert!(max_socket_error(&c) <= 1e-9);
    // An unknown format names the file, line and field.
    std::fs::write(&path, "label,x,y,z\nA,1,2,3\n").unwrap();
    let e = SocketPlan::from_file(&path).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("{}:1: field `label`", path.display())),
        "{e}"
    );
    std::fs::write(&path, "point,x,y,z\nA,1,2\n").unwrap();
    let e = SocketPlan::from_file(&path).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}:2", path.display())), "{e}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn impossible_settings_are_errors() {
    let n = paper();
    let err = |f: &dyn Fn(&mut CampaignSettings)| {
        let mut s = CampaignSettings::new(1, ErrorModel::Paper, 4, 5);
        f(&mut s);
        simulate(&n, &s).unwrap_err().to_string()
    };
    assert_eq!(
        err(&|s| s.sockets = SocketPlan::Spread { count: 0 }),
        "setting `sockets`: at least one socket is needed"
    );
    assert!(err(&|s| s.poses_per_socket = 2).starts_with("setting `poses_per_socket`: at least 3"));
    assert!(err(&|s| s.reference_lengths = 7).starts_with(
        "setting `reference_lengths`: 7 reference lengths asked for, but 4 sockets make only 6"
    ));
    assert!(err(&|s| s.encoder_noise_deg = -1.0).starts_with("setting `encoder_noise_deg`"));
    assert!(err(&|s| s.probe_noise_mm = f64::NAN).starts_with("setting `probe_noise_mm`"));
    assert!(
        err(&|s| s.length_uncertainty_mm = Some(-0.1))
            .starts_with("setting `length_uncertainty_mm`")
    );
    assert!(
        err(&|s| s.min_pose_separation_deg = 200.0)
            .starts_with("setting `min_pose_separation_deg`")
    );
    assert!(err(&|s| s.seed = u64::MAX).starts_with("setting `seed`"));
    assert!(err(&|s| s.starts_per_pose = 0).starts_with("setting `starts_per_pose`"));
    assert!(
        err(&|s| s.sockets = SocketPlan::Spread { count: usize::MAX })
            .starts_with("setting `sockets`: at most")
    );
    assert!(
        err(&|s| s.poses_per_socket = usize::MAX)
            .starts_with("setting `poses_per_socket`: at most")
    );
    // More touches than separated articulations exist: refused up front,
    // with the reason.
    let many = err(&|s| s.poses_per_socket = MAX_POSES_PER_SOCKET + 1);
    assert!(
        many.starts_with(&format!(
            "setting `poses_per_socket`: at most {MAX_POSES_PER_SOCKET} touches per socket"
        )) && many.contains("at least 20° in some joint"),
        "{many}"
    );
    // Two sockets at the same place, named by their labels.
    let same = |s: &mut CampaignSettings| {
        let p = |label: &str, x: f64| SocketPoint {
            label: label.into(),
            x,
            y: 100.0,
            z: 400.0,
        };
        s.sockets = SocketPlan::Given {
            file: None,
            points: vec![p("A", 300.0), p("B", 200.0), p("C", 300.0000000001)],
        };
        s.reference_lengths = 0;
    };
    assert_eq!(
        err(&same),
        "setting `sockets.points`: sockets `A` and `C` are at the same place \
         (300.0000000001, 100, 400 mm): every socket must be a different point"
    );
    assert!(
        err(&|s| s.errors = ErrorModel::random(-1.0, false))
            .starts_with("setting `errors.length_sigma_mm`")
    );
    assert!(
        err(&|s| s.errors = ErrorModel::File { arm: seven() })
            .contains("has 7 joints, the nominal arm 6")
    );
    // Joints that barely move reach no comfortable volume.
    let mut stiff = paper();
    stiff.limits = vec![Some([0.0, 0.01]); 6];
    let e = simulate(&stiff, &CampaignSettings::new(1, ErrorModel::Paper, 4, 5)).unwrap_err();
    assert!(
        matches!(
            e,
            SimError::SocketsNotPlaced {
                placed: 0,
                wanted: 4,
                ..
            }
        ),
        "{e}"
    );
    // A socket out of reach.
    let far = |s: &mut CampaignSettings| {
        s.sockets = SocketPlan::Given {
            file: None,
            points: vec![SocketPoint {
                label: "F".into(),
                x: 5000.0,
                y: 0.0,
                z: 0.0,
            }],
        };
        s.reference_lengths = 0;
        s.starts_per_pose = 2;
    };
    assert!(
        err(&far).starts_with("socket `F`: found 0 of 5 distinct poses"),
        "{}",
        err(&far)
    );
    // Unsupported joint counts and bad limits.
    let mut long = paper();
    for _ in 0..7 {
        long.params.joints.push(long.params.joints[5]);
        long.limits.push(None);
    }
    let e = simulate(
        &long,
        &CampaignSettings::new(1, ErrorModel::random(1.0, false), 2, 3),
    );
    let e = e.unwrap_err().to_string();
    assert!(e.contains("13 joints"), "{e}");
    let mut bad = paper();
    bad.limits[1] = Some([1.0, -1.0]);
    let e = simulate(&bad, &CampaignSettings::new(1, ErrorModel::Paper, 2, 3)).unwrap_err();
    assert!(e.to_string().contains("joint 2: limits"), "{e}");
}

#[test]
fn campaign_toml_errors_are_located() {
    let text =
        campaign_to_toml(&paper(), &CampaignSettings::new(1, ErrorModel::Paper, 3, 4)).unwrap();
    let e =
        parse_campaign(&text.replace("probe_noise_mm", "probe_nosie_mm"), "c.toml").unwrap_err();
    let line = 1 + text[..text.find("probe_noise_mm").unwrap()]
        .matches('\n')
        .count();
    assert!(
        e.to_string().starts_with(&format!("c.toml:{line}: ")),
        "{e}"
    );
    let e = parse_campaign(
        &text.replace("poses_per_socket = 4", "poses_per_socket = 1"),
        "c.toml",
    );
    assert!(
        e.unwrap_err()
            .to_string()
            .starts_with("setting `poses_per_socket`")
    );
    let e = parse_campaign(&text.replace(CAMPAIGN_FORMAT, "other"), "c.toml").unwrap_err();
    assert!(e.to_string().starts_with("c.toml: field `format`"), "{e}");
}

#[test]
fn true_arm_is_canonical() {
    for seed in 0..20 {
        let t = true_arm(&paper(), &ErrorModel::random(1.0, true), &mut rng(seed, 1)).unwrap();
        let text = crate::io::arm_to_toml(&t, crate::io::LengthUnit::Mm, AngleUnit::Deg);
        assert_eq!(crate::io::parse_arm(&text, "t").unwrap().0, t);
    }
    // Readings written in degrees read back bit-exactly.
    let s = CampaignSettings::new(3, ErrorModel::random(1.0, true), 3, 4);
    let c = simulate(&paper(), &s).unwrap();
    let mut out = Vec::new();
    crate::io::write_poses(&mut out, &c.poses, AngleUnit::Deg).unwrap();
    let (back, _) = parse_poses(
        std::str::from_utf8(&out).unwrap(),
        "p",
        AngleUnit::Deg,
        Some(6),
    )
    .unwrap();
    assert_eq!(back.readings(), c.poses.readings());
}

#[test]
fn given_true_arm_and_sockets_survive_campaign_toml() {
    let mut given = paper();
    given.name = "measured".into();
    given.params.joints[2].alpha = -1.5 + 1e-13; // no short degree form
    given.params.joints[4].theta = 0.1 + f64::EPSILON;
    given.limits[1] = Some([-2.0, 2.0]);
    let mut s = CampaignSettings::new(12, ErrorModel::File { arm: given.clone() }, 1, 4);
    s.sockets = SocketPlan::Given {
        file: Some("mine.csv".into()),
        points: vec![
            SocketPoint {
                label: "P1".into(),
                x: 300.0,
                y: 100.0,
                z: 400.0,
            },
            SocketPoint {
                label: "P 2".into(),
                x: -250.5,
                y: 300.25,
                z: 200.125,
            },
        ],
    };
    s.reference_lengths = 1;
    let c = simulate(&paper(), &s).unwrap();
    assert_eq!(c.true_arm.params, given.params);
    assert_eq!(c.true_arm.limits[1], Some([-2.0, 2.0]));
    assert!(max_socket_error(&c) <= 1e-9);
    let text = campaign_to_toml(&paper(), &s).unwrap();
    let (nominal, back) = parse_campaign(&text, "c.toml").unwrap();
    assert_eq!((nominal, &back), (paper(), &s));
    assert_eq!(simulate(&paper(), &back).unwrap(), c);
}

#[test]
fn campaign_arms_are_tables_and_old_files_are_named() {
    let mut given = paper();
    given.name = "measured".into();
    let s = CampaignSettings::new(1, ErrorModel::File { arm: given }, 3, 4);
    let text = campaign_to_toml(&paper(), &s).unwrap();
    assert!(
        text.contains("\n[nominal]\nname = \"paper-table-1\"\n"),
        "{text}"
    );
    assert!(
        text.contains("\n[[nominal.joint]]\ntheta = 0.0\nalpha = -90.0\n"),
        "{text}"
    );
    assert!(
        text.contains("\n[settings.errors.arm]\nname = \"measured\"\n"),
        "{text}"
    );
    // A bad embedded arm is reported like an arm file, at its table.
    let bad = text.replacen("length_unit = \"mm\"", "length_unit = \"inch\"", 1);
    let e = parse_campaign(&bad, "c.toml").unwrap_err().to_string();
    assert!(
        e.contains("field `length_unit`: unknown length unit `inch`"),
        "{e}"
    );
    // A version-1 file (arms as strings) is named as such, not as a type error.
    let old = text.replace(CAMPAIGN_FORMAT, "aacmm-campaign-1");
    let e = parse_campaign(&old, "c.toml").unwrap_err().to_string();
    assert_eq!(
        e,
        "c.toml: field `format`: expected \"aacmm-campaign-2\", found \"aacmm-campaign-1\""
    );
}

/// The paper's Table 2 errs in `d` on every joint; a Hayati joint has no
/// `d` (its d-slot is β), so the paper model is refused for such an arm
/// rather than leaving that error out silently.
#[test]
fn paper_errors_are_refused_for_a_hayati_arm() {
    let mut arm = paper();
    arm.params.joints[1].model = crate::params::JointModel::Hayati;
    let s = CampaignSettings::new(1, ErrorModel::Paper, 4, 5);
    let e = simulate(&arm, &s).unwrap_err().to_string();
    assert!(e.contains("joint 2 of the nominal arm is Hayati"), "{e}");
    let random = CampaignSettings::new(1, ErrorModel::random(1.0, false), 4, 5);
    assert!(simulate(&arm, &random).is_ok());
}

/// Formerly the doc examples of these crate-private helpers.
#[test]
fn the_helpers_round_wrap_and_write_the_campaign() {
    assert_eq!(round_nm(1.0 / 3.0), 0.333333);
    let pi = std::f64::consts::PI;
    let d = separation(&[pi - 0.1, 0.0], &[-pi + 0.1, 0.05]);
    assert!((d - 0.2).abs() < 1e-12);
    let nominal = Arm::without_limits("n", DhParams::paper_nominal());
    let text =
        campaign_to_toml(&nominal, &CampaignSettings::new(5, ErrorModel::Paper, 4, 5)).unwrap();
    assert!(text.contains("\n[settings]\nseed = 5\n"));
    let (arm, settings) = parse_campaign(&text, "campaign.toml").unwrap();
    assert_eq!((arm, settings.seed), (nominal, 5));
}

/// A message that echoes a hostile label, arm name or socket: bounded (the
/// label cut to 80 characters, its length said) and free of raw control
/// characters.
fn assert_bounded(message: &str, long: bool) {
    assert!(
        message.chars().count() < 600,
        "{} characters: {message:.700}",
        message.len()
    );
    assert!(!message.contains(char::is_control), "{message:?}");
    assert!(!long || message.contains("(10000 characters)"), "{message}");
}

#[test]
fn hostile_labels_give_bounded_messages() {
    let n = paper();
    let hostile = ["S\r\n\0".to_string(), format!("S{}", "x".repeat(9_999))];
    for label in &hostile {
        let long = label.len() == 10_000;
        let err = |f: &dyn Fn(&mut CampaignSettings)| {
            let mut s = CampaignSettings::new(1, ErrorModel::Paper, 4, 5);
            s.reference_lengths = 0;
            f(&mut s);
            simulate(&n, &s).unwrap_err().to_string()
        };
        let p = |label: &str, x: f64| SocketPoint {
            label: label.into(),
            x,
            y: 100.0,
            z: 400.0,
        };
        let given = |points| SocketPlan::Given { file: None, points };
        // Twice, at one place, not finite, out of reach.
        let twice = err(&|s| s.sockets = given(vec![p(label, 300.0), p(label, 200.0)]));
        assert!(
            twice.starts_with("setting `sockets.points`: socket labels must be"),
            "{twice}"
        );
        let same = err(&|s| s.sockets = given(vec![p(label, 300.0), p("B", 300.0)]));
        assert!(same.contains("are at the same place"), "{same}");
        let nan = err(&|s| s.sockets = given(vec![p(label, f64::NAN)]));
        assert!(nan.contains("has a non-finite coordinate"), "{nan}");
        let far = err(&|s| {
            s.sockets = given(vec![p(label, 5000.0)]);
            s.starts_per_pose = 1;
        });
        assert!(far.starts_with("socket `S"), "{far}");
        // A true arm or a nominal arm named so.
        let mut other = seven();
        other.name = label.clone();
        let joints = err(&|s| s.errors = ErrorModel::File { arm: other.clone() });
        assert!(joints.contains("has 7 joints"), "{joints}");
        let mut limits = paper();
        limits.name = label.clone();
        limits.limits[1] = Some([1.0, -1.0]);
        let e = simulate(&limits, &CampaignSettings::new(1, ErrorModel::Paper, 2, 3));
        let bad = e.unwrap_err().to_string();
        assert!(bad.contains("joint 2: limits"), "{bad}");
        for message in [twice, same, nan, far, joints, bad] {
            assert_bounded(&message, long);
        }
    }
}
