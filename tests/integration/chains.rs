//! Chains other than 6R and 7R through the command line: `simulate
//! --chain` draws a nominal arm of any shape, and the campaign it simulates
//! is calibrated with the true arm recovered within its σ.

use std::path::Path;

use aacmm_core::io::{AngleUnit, LengthUnit, read_arm, write_arm};
use serde_json::Value;

use crate::util::{aacmm, temp_dir};

fn run(args: &[&str]) -> String {
    let out = aacmm(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{args:?}: {stderr}");
    stderr
}

/// A campaign of `sockets` sockets touched `poses` times each into `out`.
fn simulate(out: &Path, arm: &[&str], (sockets, poses): (&str, &str), truth: &[&str], seed: &str) {
    let mut args = vec!["simulate"];
    args.extend(arm);
    args.extend(truth);
    let out = out.to_str().unwrap();
    args.extend([
        "--sockets",
        sockets,
        "--poses",
        poses,
        "--reference-lengths",
        "6",
        "--encoder-noise",
        "0.001",
        "--probe-noise",
        "0.002",
        "--seed",
        seed,
        "--out",
        out,
    ]);
    run(&args);
}

fn calibrate(dir: &Path, arm: &Path) -> Value {
    let out = dir.join("cal");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    run(&[
        "calibrate",
        "--arm",
        &s(arm),
        "--data",
        &s(&dir.join("poses.csv")),
        "--lengths",
        &s(&dir.join("lengths.csv")),
        "--encoder-noise",
        "0.001",
        "--probe-noise",
        "0.002",
        "--out",
        &s(&out),
    ]);
    let text = std::fs::read_to_string(out.join("calibration.json")).unwrap();
    check_joint_types(&text, arm);
    serde_json::from_str(&text).unwrap()
}

/// `calibration.json` names each joint's type when the chain has a slide
/// (and not for a revolute one: its JSON is what it was), the chain read
/// back from it is the arm's, and the summary lists the joints with their
/// reading units (a slide's mm).
fn check_joint_types(json: &str, arm: &Path) {
    let (arm, _) = read_arm(arm).unwrap();
    let shape = arm.params.shape().unwrap();
    let value: Value = serde_json::from_str(json).unwrap();
    let types = &value["calibration"]["joint_types"];
    let r = aacmm_core::CalibrationReport::from_json(json).unwrap();
    assert_eq!(r.calibration.params.shape().unwrap(), shape);
    if shape.prismatic_mask() == 0 {
        assert_eq!(*types, Value::Null);
        assert!(!r.summary().contains("Joints:"));
        return;
    }
    let written: String = (types.as_array().unwrap().iter())
        .map(|t| match t.as_str().unwrap() {
            "revolute" => 'R',
            "prismatic" => 'P',
            other => panic!("joint type {other}"),
        })
        .collect();
    assert_eq!(written, shape.to_string());
    let summary = r.summary();
    let line = summary.lines().find(|l| l.starts_with("Joints: ")).unwrap();
    for (j, letter) in written.chars().enumerate() {
        let want = match letter {
            'P' => format!("{} prismatic (reading mm)", j + 1),
            _ => format!("{} revolute (reading deg)", j + 1),
        };
        assert!(line.contains(&want), "{line}");
    }
}

/// A campaign of a random nominal arm of `shape`, simulated and calibrated
/// by the command line: the true arm (its parameters the data cannot
/// determine kept at the nominal's, as the fit keeps them) within 4σ on
/// every free parameter, and the normalised errors' RMS plausible.
fn recovered(shape: &str, campaign: (&str, &str), seed: u64) {
    let dir = temp_dir(&format!("chain-{shape}"));
    let first = dir.join("first");
    let seed_text = seed.to_string();
    let chain: &[&str] = &["--chain", shape];
    simulate(&first, chain, campaign, &["--errors", "random"], &seed_text);
    let nominal_path = first.join("nominal.toml");
    let (nominal, _) = read_arm(&nominal_path).unwrap();
    assert_eq!(nominal.params.shape().unwrap().to_string(), shape);
    let fit = calibrate(&first, &nominal_path);
    assert_eq!(
        fit["verdict"]["usable"], true,
        "{shape}: {}",
        fit["verdict"]
    );
    // The truth the fit can see: the fixed parameters at the nominal's.
    let (mut truth, _) = read_arm(&first.join("true_arm.toml")).unwrap();
    let parameters = fit["calibration"]["parameters"].as_array().unwrap();
    for p in parameters.iter().filter(|p| p["fixed"] != Value::Null) {
        let id = nominal
            .params
            .parse_param(p["name"].as_str().unwrap())
            .unwrap();
        *truth.params.get_mut(id) = nominal.params.get(id);
    }
    let truth_path = dir.join("truth.toml");
    write_arm(&truth_path, &truth, LengthUnit::Mm, AngleUnit::Deg).unwrap();
    let second = dir.join("second");
    let nominal_arg = nominal_path.to_str().unwrap();
    let truth_arg = truth_path.to_str().unwrap();
    let seed2 = (seed + 100).to_string();
    let arm: &[&str] = &["--arm", nominal_arg];
    simulate(&second, arm, campaign, &["--true", truth_arg], &seed2);
    let fit = calibrate(&second, &nominal_path);
    assert_eq!(
        fit["verdict"]["usable"], true,
        "{shape}: {}",
        fit["verdict"]
    );
    let mut squares = Vec::new();
    for p in fit["calibration"]["parameters"].as_array().unwrap() {
        let Some(sigma) = p["sigma"].as_f64() else {
            continue;
        };
        let name = p["name"].as_str().unwrap();
        let id = nominal.params.parse_param(name).unwrap();
        let unit = p["unit"].as_str().unwrap();
        let true_value = if unit == "deg" {
            truth.params.get(id).to_degrees()
        } else {
            truth.params.get(id)
        };
        let z = (p["calibrated"].as_f64().unwrap() - true_value) / sigma;
        assert!(z.abs() < 4.0, "{shape}: {name} is {z:.2}σ from the truth");
        squares.push(z * z);
    }
    assert!(
        squares.len() > 10,
        "{shape}: {} free parameters",
        squares.len()
    );
    let rms = (squares.iter().sum::<f64>() / squares.len() as f64).sqrt();
    assert!((0.3..2.0).contains(&rms), "{shape}: normalised RMS {rms}");
}

#[test]
fn a_robot_on_a_track_is_recovered() {
    recovered("PRRRRRR", ("12", "10"), 3);
}

#[test]
fn a_scara_like_rrpr_is_recovered() {
    // Four joints for three coordinates: a socket's poses lie on a curve,
    // few of them far apart: more sockets, fewer poses each.
    recovered("RRPR", ("16", "4"), 1);
}

/// Same seed, same bytes; the nominal arm too.
#[test]
fn simulate_chain_is_deterministic() {
    let dir = temp_dir("chain-same-bytes");
    let (a, b) = (dir.join("a"), dir.join("b"));
    for out in [&a, &b] {
        let chain: &[&str] = &["--chain", "RPRRPR"];
        simulate(out, chain, ("12", "5"), &["--errors", "random"], "2");
    }
    for file in [
        "nominal.toml",
        "true_arm.toml",
        "poses.csv",
        "lengths.csv",
        "sockets.csv",
    ] {
        let read = |d: &Path| std::fs::read(d.join(file)).unwrap();
        assert_eq!(read(&a), read(&b), "{file}");
    }
    let poses = std::fs::read_to_string(a.join("poses.csv")).unwrap();
    assert!(poses.starts_with("point,q1,q2,q3,q4,q5,q6\n"), "{poses}");
    // A bad chain is refused by the flag.
    let out = aacmm(&[
        "simulate",
        "--chain",
        "RRXR",
        "--errors",
        "random",
        "--sockets",
        "3",
    ]);
    assert!(!out.status.success());
}
