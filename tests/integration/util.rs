//! What the CLI tests share: running the binary, scratch folders, the
//! shipped example files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the built `aacmm` binary with `args`.
pub fn aacmm(args: &[&str]) -> Output {
    command(args).output().expect("the aacmm binary runs")
}

/// The built `aacmm` binary with `args`, to be given its streams and run.
pub fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_aacmm"));
    c.args(args);
    c
}

/// A fresh, empty folder for one test, under cargo's `target/tmp` so runs do
/// not pile up in the system's temporary directory.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("aacmm-test-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A file in the repository's `examples/`.
pub fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name)
}

/// The shipped nominal arm, `examples/paper-table-1.toml`.
pub fn shipped_arm() -> String {
    example("paper-table-1.toml").display().to_string()
}

/// A file of the shipped campaign, `examples/paper-campaign/`.
pub fn shipped(file: &str) -> String {
    example("paper-campaign").join(file).display().to_string()
}

/// `aacmm calibrate` on the shipped campaign with its lengths and noise,
/// into `out`, with `extra` flags.
pub fn calibrate_shipped(out: &Path, extra: &[&str]) -> Output {
    calibrate_files(&shipped_arm(), &shipped("poses.csv"), out, extra)
}

/// `aacmm calibrate` of `arm` on `poses` with the shipped campaign's
/// lengths and noise, into `out`, with `extra` flags.
pub fn calibrate_files(arm: &str, poses: &str, out: &Path, extra: &[&str]) -> Output {
    let lengths = shipped("lengths.csv");
    let mut args = vec![
        "calibrate",
        "--arm",
        arm,
        "--data",
        poses,
        "--lengths",
        &lengths,
        "--encoder-noise",
        "0.005",
        "--probe-noise",
        "0.01",
        "--out",
        out.to_str().expect("UTF-8 path"),
    ];
    args.extend(extra);
    aacmm(&args)
}

/// Fresh sockets of the shipped campaign's true arm (`aacmm simulate
/// --true`, seed 9, the shipped noise) into `out`, for held-out data.
pub fn simulate_held_out(out: &Path, sockets: &str, poses: &str, lengths: &str) {
    let o = aacmm(&[
        "simulate",
        "--arm",
        &shipped_arm(),
        "--true",
        &shipped("true_arm.toml"),
        "--sockets",
        sockets,
        "--poses",
        poses,
        "--seed",
        "9",
        "--encoder-noise",
        "0.005",
        "--probe-noise",
        "0.01",
        "--reference-lengths",
        lengths,
        "--out",
        out.to_str().expect("UTF-8 path"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Writes `text` to `dir/name` and returns the path as a string.
pub fn write(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write test file");
    path.display().to_string()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A failed run with a one-line explanation and no panic.
#[track_caller]
pub fn assert_clean_error(o: &Output, expect: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure, got success: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    for e in expect {
        assert!(err.contains(e), "stderr lacks `{e}`: {err}");
    }
}

/// The shipped campaign with one touch mislabelled: touch 17 (file line
/// 18, a touch of S2) labelled S1 — the gross error a refused calibration
/// is tested with. Written into `dir`; returns the path.
pub fn mislabelled_poses(dir: &Path) -> String {
    let text = std::fs::read_to_string(shipped("poses.csv")).expect("shipped poses");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    assert!(lines[17].starts_with("S2,"), "{}", lines[17]);
    lines[17] = lines[17].replacen("S2,", "S1,", 1);
    write(dir, "poses.csv", &(lines.join("\n") + "\n"))
}

/// A standard normal draw (Box–Muller).
pub fn normal(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    use rand::RngExt;
    let (u, v): (f64, f64) = (rng.random_range(f64::EPSILON..1.0), rng.random());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// Per pose, the empirical 95 % radius of `predicted` (per campaign, a
/// position per pose, mm) about the campaigns' mean position; and the RMS
/// of those radii over the poses: what an uncertainty map predicts.
pub fn spread_95(predicted: &[Vec<[f64; 3]>]) -> (Vec<f64>, f64) {
    let n = predicted.len() as f64;
    let poses = predicted.first().map_or(0, Vec::len);
    let q95: Vec<f64> = (0..poses)
        .map(|j| {
            let mean: [f64; 3] =
                std::array::from_fn(|k| predicted.iter().map(|p| p[j][k]).sum::<f64>() / n);
            let mut d: Vec<f64> = (predicted.iter())
                .map(|p| {
                    (0..3)
                        .map(|k| (p[j][k] - mean[k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            d.sort_by(f64::total_cmp);
            d[(0.95 * n) as usize]
        })
        .collect();
    let rms = (q95.iter().map(|x| x * x).sum::<f64>() / q95.len().max(1) as f64).sqrt();
    (q95, rms)
}
