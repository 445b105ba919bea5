//! `aacmm simulate` end to end: the built binary writes a paper-like
//! campaign whose files read back with the io readers, byte-identical for
//! the same seed.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::util::{aacmm, example, temp_dir};
use aacmm_core::io::{AngleUnit, read_arm, read_lengths, read_points, read_poses};
use aacmm_core::kernel::ArmKernel;

const FILES: [&str; 5] = [
    "poses.csv",
    "lengths.csv",
    "sockets.csv",
    "true_arm.toml",
    "campaign.toml",
];

fn nominal() -> PathBuf {
    example("paper-table-1.toml")
}

/// Runs `aacmm simulate` on the paper's nominal arm into `out`.
pub fn simulate(extra: &[&str], out: &Path) -> Output {
    let arm = nominal();
    let mut args = vec!["simulate", "--arm", arm.to_str().unwrap()];
    args.extend(extra);
    args.extend(["--out", out.to_str().unwrap()]);
    aacmm(&args)
}

/// The paper-like campaign of the README: Table 1 arm, Table 2 errors,
/// 10 sockets × 10 poses, with noise.
pub fn paper_like(seed: &str, out: &Path) -> Output {
    let args = [
        "--errors",
        "paper",
        "--sockets",
        "10",
        "--poses",
        "10",
        "--seed",
        seed,
        "--encoder-noise",
        "0.005",
        "--probe-noise",
        "0.01",
    ];
    simulate(&args, out)
}

fn bytes(dir: &Path) -> Vec<Vec<u8>> {
    FILES
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect()
}

#[test]
fn paper_like_campaign_is_complete_and_reproducible() {
    let (a, b, c) = (temp_dir("sim-a"), temp_dir("sim-b"), temp_dir("sim-c"));
    let run = paper_like("7", &a);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("true arm: paper Table 2 errors"),
        "{stderr}"
    );
    assert!(stderr.contains("100 poses"), "{stderr}");

    // The five files exist and read back.
    let (arm, _) = read_arm(&a.join("true_arm.toml")).unwrap();
    assert_eq!(arm.params.joint_count(), 6);
    assert!((arm.params.probe[2] - 100.094).abs() < 1e-12);
    let (poses, warnings) = read_poses(&a.join("poses.csv"), AngleUnit::Deg, Some(6)).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(poses.len(), 100);
    let sockets = read_points(&a.join("sockets.csv")).unwrap();
    assert_eq!(sockets.len(), 10);
    assert_eq!(sockets[9].0, "S10");
    let lengths = read_lengths(&a.join("lengths.csv")).unwrap();
    assert_eq!(lengths.len(), 3);
    let campaign = std::fs::read_to_string(a.join("campaign.toml")).unwrap();
    assert!(campaign.contains("seed = 7\n"), "{campaign}");
    assert!(campaign.contains("model = \"paper\""), "{campaign}");
    // Noise as asked: the true arm's points scatter about their sockets by
    // roughly the noise (0.005° at up to ~1 m is ~0.09 mm; seating 0.01 mm).
    let p = ArmKernel::new(&arm.params)
        .unwrap()
        .positions_of(&poses.rows().collect::<Vec<_>>())
        .unwrap();
    let centre = |l: &str| sockets.iter().find(|s| s.0 == l).unwrap().1;
    let worst = p
        .iter()
        .zip(poses.labels())
        .map(|(p, l)| {
            (0..3)
                .map(|i| (p[i] - centre(l)[i]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    assert!(worst > 0.01 && worst < 1.0, "worst {worst} mm");

    // Same seed, same bytes; another seed, other bytes.
    assert!(paper_like("7", &b).status.success());
    assert_eq!(bytes(&a), bytes(&b));
    assert!(paper_like("8", &c).status.success());
    for ((x, y), name) in bytes(&a).iter().zip(bytes(&c)).zip(FILES) {
        if name != "true_arm.toml" {
            assert_ne!(*x, y, "{name}");
        }
    }
    assert_eq!(
        bytes(&a)[3],
        bytes(&c)[3],
        "the paper's true arm does not depend on the seed"
    );
    for d in [a, b, c] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

#[test]
fn zero_noise_campaign_reproduces_sockets() {
    let dir = temp_dir("sim-exact");
    let args = [
        "--errors",
        "assembled",
        "--sockets",
        "4",
        "--poses",
        "5",
        "--seed",
        "3",
    ];
    let run = simulate(&args, &dir);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (arm, _) = read_arm(&dir.join("true_arm.toml")).unwrap();
    let (poses, _) = read_poses(&dir.join("poses.csv"), AngleUnit::Deg, Some(6)).unwrap();
    let sockets = read_points(&dir.join("sockets.csv")).unwrap();
    let p = ArmKernel::new(&arm.params)
        .unwrap()
        .positions_of(&poses.rows().collect::<Vec<_>>())
        .unwrap();
    for (p, l) in p.iter().zip(poses.labels()) {
        let c = sockets.iter().find(|s| s.0 == l).unwrap().1;
        let e = (0..3).map(|i| (p[i] - c[i]).powi(2)).sum::<f64>().sqrt();
        assert!(e <= 1e-9, "{l}: {e} mm");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_input_is_a_clear_error() {
    let dir = temp_dir("sim-bad");
    let fail = |args: &[&str]| {
        let run = simulate(args, &dir);
        assert!(!run.status.success());
        String::from_utf8_lossy(&run.stderr).into_owned()
    };
    let e = fail(&[
        "--errors",
        "paper",
        "--sockets",
        "3",
        "--poses",
        "2",
        "--seed",
        "1",
    ]);
    assert!(e.contains("--poses: at least 3"), "{e}");
    let e = fail(&[
        "--errors",
        "paper",
        "--sockets",
        "3",
        "--poses",
        "5",
        "--seed",
        "1",
        "--reference-lengths",
        "4",
    ]);
    assert!(
        e.contains("--reference-lengths: 4 reference lengths"),
        "{e}"
    );
    let e = fail(&[
        "--errors",
        "random",
        "--sockets",
        "3",
        "--poses",
        "5",
        "--seed",
        "1",
        "--encoder-noise",
        "-1",
    ]);
    assert!(
        e.contains("--encoder-noise: must be finite and not negative"),
        "{e}"
    );
    let e = fail(&[
        "--errors",
        "random",
        "--error-scale",
        "1e308",
        "--sockets",
        "3",
        "--poses",
        "5",
        "--seed",
        "1",
    ]);
    assert!(
        e.contains("--error-scale: at most 1000 (a length σ of 400 mm; beyond, no arm), got 1e308"),
        "{e}"
    );
    let e = fail(&[
        "--errors",
        "paper",
        "--true",
        "x.toml",
        "--sockets",
        "3",
        "--poses",
        "5",
        "--seed",
        "1",
    ]);
    assert!(e.contains("cannot be used with"), "{e}");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("my-sockets.csv");
    std::fs::write(&file, "point,x,y,z\nA,1,2,oops\n").unwrap();
    let f = file.to_str().unwrap();
    let e = fail(&[
        "--errors",
        "paper",
        "--sockets-file",
        f,
        "--poses",
        "5",
        "--seed",
        "1",
    ]);
    assert!(e.contains(&format!("{f}:2: field `z`")), "{e}");
    // Nothing was written.
    assert!(!dir.join("poses.csv").exists());
    std::fs::remove_dir_all(dir).unwrap();
}
