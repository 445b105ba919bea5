//! `aacmm identify` and `aacmm calibrate` on the shipped example campaign.

use crate::util::{
    aacmm, assert_clean_error, calibrate_shipped, shipped as campaign, shipped_arm as arm,
    simulate_held_out, stdout, temp_dir,
};

#[test]
fn identify_reports_rank_rules_and_the_fixed_set() {
    let dir = temp_dir("identify");
    let json = dir.join("id.json");
    let (arm, poses, lengths) = (arm(), campaign("poses.csv"), campaign("lengths.csv"));
    let noise = ["--encoder-noise", "0.005", "--probe-noise", "0.01"];
    let mut args = vec![
        "identify",
        "--arm",
        &arm,
        "--data",
        &poses,
        "--lengths",
        &lengths,
    ];
    args.extend(noise);
    args.extend(["--json", json.to_str().unwrap()]);
    let o = aacmm(&args);
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("Rank: 21 identifiable"), "{text}");
    assert!(
        text.contains("--fix auto): d1,alpha6,theta1,theta6,Bx,By"),
        "{text}"
    );
    assert!(
        text.contains("∂p/∂theta6 = +100.0000 mm/rad ∂p/∂a6"),
        "{text}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["identification"]["rank"], 21);
    assert_eq!(
        report["identification"]["free"].as_array().unwrap().len(),
        21
    );

    let mut bare = vec!["identify", "--arm", &arm, "--data", &poses];
    bare.extend(noise);
    let text = stdout(&aacmm(&bare));
    assert!(text.contains("Rank: 20 identifiable"), "{text}");
    assert!(text.contains("scale: no reference length"), "{text}");
}

#[test]
fn calibrate_writes_an_arm_every_command_loads_and_the_same_bytes_twice() {
    let dir = temp_dir("calibrate");
    let poses = campaign("poses.csv");
    let run = |out: &str| {
        let out = dir.join(out);
        let o = calibrate_shipped(&out, &["--cross-validate", "3", "--seed", "2"]);
        assert!(o.status.success(), "{}", crate::util::stderr(&o));
        (stdout(&o), out)
    };
    let (text, first) = run("a");
    let (_, second) = run("b");
    for f in ["calibrated.toml", "calibration.json"] {
        assert_eq!(
            std::fs::read(first.join(f)).unwrap(),
            std::fs::read(second.join(f)).unwrap(),
            "{f} differs between runs"
        );
    }
    assert!(text.contains("degrees of freedom"), "{text}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(first.join("calibration.json")).unwrap())
            .unwrap();
    let cal = &report["calibration"];
    assert_eq!(cal["solver"]["successful"], true);
    let dof = &cal["dof"];
    // m − p: 300 touch rows + 5 lengths − (21 parameters + 30 centre coordinates)
    assert_eq!(dof["degrees_of_freedom"], 254);
    let sigma0 = dof["sigma0"].as_f64().unwrap();
    assert!((0.8..1.25).contains(&sigma0), "{sigma0}");
    // The fit beats the nominal arm by far on the fitted and held-out points.
    let v = &report["validation"];
    let after = v["fitted"]["after"]["e_mean"].as_f64().unwrap();
    let before = v["fitted"]["before"]["e_mean"].as_f64().unwrap();
    assert!(after < before / 30.0, "{before} -> {after}");
    for fold in v["cross_validation"]["folds"].as_array().unwrap() {
        assert!(
            fold["figures"]["after"]["e_mean"].as_f64().unwrap() < 0.1,
            "{fold}"
        );
    }
    // The calibrated arm is an ordinary arm file, and evaluate agrees with
    // the report on the fitted data.
    let calibrated = first.join("calibrated.toml");
    let json = dir.join("ev.json");
    let o = aacmm(&[
        "evaluate",
        "--arm",
        calibrated.to_str().unwrap(),
        "--data",
        &poses,
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    let ev: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let e = ev["evaluation"]["single_point_e"]["mean"].as_f64().unwrap();
    assert!((e - after).abs() < 1e-9, "{e} vs {after}");
}

#[test]
fn calibrate_validates_on_held_out_files() {
    let dir = temp_dir("calibrate-validate");
    let fresh = dir.join("fresh");
    simulate_held_out(&fresh, "6", "8", "3");
    let out = dir.join("out");
    let (held, held_lengths) = (fresh.join("poses.csv"), fresh.join("lengths.csv"));
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm(),
        "--data",
        &campaign("poses.csv"),
        "--lengths",
        &campaign("lengths.csv"),
        "--validate",
        held.to_str().unwrap(),
        "--validate-lengths",
        held_lengths.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    assert!(stdout(&o).contains("held out, after"));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
            .unwrap();
    let h = &report["validation"]["held_out"]["figures"];
    assert!(h["after"]["e_mean"].as_f64().unwrap() < 0.1, "{h}");
    assert!(h["after"]["length_rms"].as_f64().unwrap() < 0.05, "{h}");
}

#[test]
fn calibrate_errors_are_clear() {
    let dir = temp_dir("calibrate-bad");
    let out = dir.join("out");
    let (arm, poses) = (arm(), campaign("poses.csv"));
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm,
        "--data",
        &poses,
        "--fix",
        "theta1,gamma2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--fix", "unknown parameter `gamma2`"]);
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm,
        "--data",
        &poses,
        "--cross-validate",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--cross-validate 50"]);
    let o = aacmm(&["calibrate", "--arm", &arm, "--data", &poses, "--out", &arm]);
    assert_clean_error(&o, &["--out"]);
}

#[test]
fn every_method_says_what_ran_and_how_long_each_phase_took() {
    let dir = temp_dir("calibrate-methods");
    let run = |method: &str, extra: &[&str]| {
        let out = dir.join(method);
        let mut args = vec!["--method", method];
        args.extend(extra);
        let o = calibrate_shipped(&out, &args);
        assert!(o.status.success(), "{method}: {}", crate::util::stderr(&o));
        // Not a terminal: no progress bar on stderr.
        let err = crate::util::stderr(&o);
        assert!(!err.contains('\r') && !err.contains("=>"), "{err}");
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
                .unwrap();
        let timing: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("timing.json")).unwrap())
                .unwrap();
        (stdout(&o), report, timing)
    };
    // The paper's annealing alone stops far above the noise floor: usable
    // only on request, and the χ² verdict says why.
    let refused = calibrate_shipped(
        &dir.join("sa-refused"),
        &["--method", "sa", "--sa-chain", "20", "--sa-t0", "0.5"],
    );
    assert_eq!(refused.status.code(), Some(1));
    assert!(
        crate::util::stderr(&refused).contains("residuals larger than the stated noise explains"),
        "{}",
        crate::util::stderr(&refused)
    );
    let (text, report, timing) = run(
        "sa",
        &["--sa-chain", "20", "--sa-t0", "0.5", "--accept-poor-fit"],
    );
    assert_eq!(report["verdict"]["usable"], true);
    assert!(
        report["verdict"]["notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().starts_with("accepted on request: χ²")),
        "{}",
        report["verdict"]
    );
    let solver = &report["calibration"]["solver"];
    assert_eq!(solver["method"], "sa");
    assert_eq!(solver["stop"]["anneal"], "cooled");
    assert_eq!(solver["anneal"]["options"]["chain"], 20);
    assert_eq!(solver["anneal"]["options"]["t0"], 0.5);
    assert!(
        text.contains("Annealing: T0 0.5 mm, alpha 0.9, L 20"),
        "{text}"
    );
    assert_eq!(timing["phases"][0]["name"], "identify");
    assert_eq!(timing["phases"][1]["name"], "anneal");
    assert!(timing["phases"][1]["ms"].as_f64().unwrap() > 0.0);
    // calibration.json holds no times (same bytes for the same seed).
    assert!(solver["phases"][0].get("seconds").is_none());

    let (text, report, _) = run("hybrid", &[]);
    let solver = &report["calibration"]["solver"];
    assert_eq!(solver["anneal"]["stop"], "switched");
    assert!(
        text.contains("Switch (s0 5, epsilon1 0.0001): at T = "),
        "{text}"
    );
    assert_eq!(solver["phases"][2]["name"], "lm");

    let (text, report, _) = run("global", &[]);
    let solver = &report["calibration"]["solver"];
    assert_eq!(solver["global"]["stop"], "noise_floor");
    assert!(
        text.contains(
            "Global: 1 minimum (the start arm, 0 grid cell(s), 0 random start(s)) on the circles \
             of theta2, theta3, theta4, theta5"
        ),
        "{text}"
    );
}

#[test]
fn bad_solver_settings_are_clean_errors() {
    let dir = temp_dir("calibrate-bad-solver");
    let (arm, poses) = (arm(), campaign("poses.csv"));
    let out = dir.join("out");
    let base = [
        "calibrate",
        "--arm",
        &arm,
        "--data",
        &poses,
        "--out",
        out.to_str().unwrap(),
    ];
    for (extra, expect) in [
        (
            "--sa-cooling=1.5",
            "--sa-cooling 1.5: must lie strictly between 0 and 1",
        ),
        ("--sa-t0=0", "--sa-t0 0: must be a finite number > 0"),
        ("--global-starts=0", "--global-starts 0: at least 1"),
        (
            "--global-confirmations=500",
            "--global-confirmations 500: more than the 109 starts there can be",
        ),
        (
            "--probe-noise=-1",
            "--probe-noise -1: must be a finite number ≥ 0",
        ),
        (
            "--encoder-noise=nan",
            "--encoder-noise NaN: must be a finite number ≥ 0",
        ),
        ("--fix=d1,d1", "--fix d1,d1: `d1` is listed twice"),
        ("--method=ceres", "invalid value 'ceres' for '--method"),
    ] {
        let mut args = base.to_vec();
        args.push(extra);
        assert_clean_error(&aacmm(&args), &[expect]);
    }
}

/// A campaign of 540 sockets, 4 touches each, simulated into `dir`: the
/// shipped campaign's 10 sockets, each with its 3 × 3 × 6 neighbours 10 mm
/// apart (none lower than the socket: two are near the table). Returns the
/// poses and lengths files.
fn many_points(dir: &std::path::Path) -> (String, String) {
    let shipped = std::fs::read_to_string(campaign("sockets.csv")).unwrap();
    let mut sockets = String::from("point,x,y,z\n");
    for line in shipped.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let c: Vec<f64> = f[1..].iter().map(|v| v.parse().unwrap()).collect();
        for (k, (dx, dy, dz)) in (0..54).map(|k| (k % 3, k / 3 % 3, k / 9)).enumerate() {
            let at = |v: f64, d: usize, low: f64| v + 10.0 * (d as f64 - low);
            let (x, y, z) = (at(c[0], dx, 1.0), at(c[1], dy, 1.0), at(c[2], dz, 0.0));
            sockets.push_str(&format!("{}-{k},{x},{y},{z}\n", f[0]));
        }
    }
    let sockets = crate::util::write(dir, "sockets.csv", &sockets);
    let out = dir.join("campaign");
    #[rustfmt::skip]
    let o = aacmm(&[
        "simulate", "--arm", &arm(), "--true", &campaign("true_arm.toml"),
        "--sockets-file", &sockets, "--poses", "4", "--seed", "9",
        "--encoder-noise", "0.005", "--probe-noise", "0.01",
        "--out", out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::util::stderr(&o));
    let file = |f: &str| out.join(f).display().to_string();
    (file("poses.csv"), file("lengths.csv"))
}

/// On enough points that the normal equations run in chunks on both
/// threads: the shipped campaign's 10 points are one chunk, on one thread
/// whatever `--threads`, so this test could not fail on them.
#[test]
fn same_seed_same_files_whatever_the_thread_count() {
    use aacmm_core::io::{AngleUnit, read_poses};
    use aacmm_core::parallel::threads_for;
    use aacmm_core::residuals::point_chunks;
    let dir = temp_dir("calibrate-threads");
    let (poses, lengths) = many_points(&dir);
    let (read, _) = read_poses(poses.as_ref(), AngleUnit::Deg, Some(6)).unwrap();
    let n = read.points().len();
    assert_eq!(
        threads_for(point_chunks(n), 2),
        2,
        "{n} points make {} chunk(s) of work: on one thread",
        point_chunks(n)
    );
    let run = |threads: &str| {
        let out = dir.join(threads);
        #[rustfmt::skip]
        let o = aacmm(&[
            "calibrate", "--arm", &arm(), "--data", &poses, "--lengths", &lengths,
            "--encoder-noise", "0.005", "--probe-noise", "0.01",
            "--threads", threads, "--seed", "3", "--out", out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", crate::util::stderr(&o));
        out
    };
    let (one, two) = (run("1"), run("2"));
    for f in ["calibrated.toml", "calibration.json", "report.html"] {
        // Not assert_eq!: a report's bytes would flood the message.
        assert!(
            std::fs::read(one.join(f)).unwrap() == std::fs::read(two.join(f)).unwrap(),
            "{f} differs between 1 and 2 threads"
        );
    }
    let o = calibrate_shipped(&dir.join("zero"), &["--threads", "0"]);
    assert_clean_error(&o, &["--threads"]);
}

/// A hostile `--threads` is refused by name with the library's bound (the
/// one Python's `threads` and C's setter have), never attempted: 2^62 and a
/// number beyond any integer type alike, in every command that has it.
#[test]
fn hostile_thread_counts_are_refused_by_name() {
    let dir = temp_dir("calibrate-hostile-threads");
    let bound = "'--threads <N>': at most 1024 worker threads";
    for n in ["1025", "4611686018427387904", "18446744073709551616"] {
        let o = calibrate_shipped(&dir.join(n), &["--threads", n]);
        assert_clean_error(&o, &[bound]);
        assert!(!dir.join(n).join("calibration.json").exists());
        for command in ["identify", "evaluate"] {
            let (arm, poses) = (arm(), campaign("poses.csv"));
            #[rustfmt::skip]
            let o = aacmm(&[command, "--arm", &arm, "--data", &poses, "--threads", n]);
            assert_clean_error(&o, &[bound]);
        }
    }
    let o = calibrate_shipped(&dir.join("word"), &["--threads", "many"]);
    assert_clean_error(&o, &["`many` is not a whole number of threads (1 to 1024)"]);
}
