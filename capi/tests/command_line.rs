//! The C API against the command line: on an arm file with a `[prior]`
//! table (`examples/mukca/kinova-1`, poses in radians) `aacmm_calibrate_files`
//! gives what `aacmm calibrate` writes — `calibration.json` byte for byte,
//! the calibrated parameters bit for bit, the verdict — and `successful` is
//! the library's verdict, not the solver's convergence; with a positions
//! file (`--positions`), alone or with touches, the same report too; with
//! a model beyond geometry (`--compliance`) too, its columns through
//! `aacmm_calibration_auxiliary`.

// Calling the C ABI from Rust takes raw pointers, as C does.
#![allow(unsafe_code)]

mod common;
use common::last_error;

use std::ffi::{CStr, CString, c_char};
use std::path::{Path, PathBuf};
use std::process::Command;

use aacmm_capi::{
    AACMM_ANGLE_DEG, AACMM_ANGLE_RAD, AACMM_METHOD_LM, AACMM_REASON_CHI_SQUARE, AACMM_ROBUST_HUBER,
    AacmmAuxiliary, AacmmCalibrateOptions, AacmmCalibration, AacmmCalibrationSummary,
    AacmmReasonKind, AacmmStatus, aacmm_arm_free, aacmm_arm_from_file,
    aacmm_arm_from_file_accepting_rejected, aacmm_arm_warnings, aacmm_calibrate_files,
    aacmm_calibrate_options_free, aacmm_calibrate_options_new,
    aacmm_calibrate_options_set_accept_poor_fit, aacmm_calibrate_options_set_compliance,
    aacmm_calibrate_options_set_encoder_noise_rad, aacmm_calibrate_options_set_method,
    aacmm_calibrate_options_set_position_noise_mm, aacmm_calibrate_options_set_positions_file,
    aacmm_calibrate_options_set_prior, aacmm_calibrate_options_set_probe_noise_mm,
    aacmm_calibrate_options_set_robust, aacmm_calibrate_options_set_thermal,
    aacmm_calibration_auxiliary, aacmm_calibration_auxiliary_count, aacmm_calibration_frame_count,
    aacmm_calibration_free, aacmm_calibration_params, aacmm_calibration_reason,
    aacmm_calibration_reason_count, aacmm_calibration_report, aacmm_calibration_summary,
    aacmm_calibration_verdict, aacmm_calibration_verdict_notes,
};
use aacmm_core::domain::Arm;
use aacmm_core::io::positions::write_positions;
use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml, read_arm, write_poses};
use aacmm_core::simulate::{
    CampaignSettings, ErrorModel, PositionSettings, simulate, simulate_positions,
};

/// The workspace root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("capi/ is in the workspace")
        .to_path_buf()
}

/// An example file by its path from the root, absolute: the C API and the
/// command line then name it alike in their reports.
fn example(path: &str) -> String {
    root().join(path).display().to_string()
}

/// The command line of this workspace: `$AACMM_CLI` if set, else built by
/// cargo now in this test's profile, so that the test never compares with
/// a binary left by an older tree. Built as `cargo test --workspace` builds
/// it (a no-op inside that command): `cargo build -p aacmm` would resolve
/// the dependencies without this crate's cbindgen, whose syn cargo shares
/// with the proc-macros', and so build the core and the CLI a second time
/// (2–5 minutes on two cores).
fn cli() -> PathBuf {
    if let Some(exe) = std::env::var_os("AACMM_CLI") {
        return exe.into();
    }
    let exe = std::env::current_exe().expect("the test's path");
    let profile = exe
        .parent()
        .and_then(Path::parent)
        .and_then(Path::file_name)
        .and_then(|n| n.to_str())
        .expect("target/PROFILE/deps/TEST")
        .to_string();
    let mut cargo = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cargo
        .args(["test", "--quiet", "--workspace", "--no-run"])
        .arg("--message-format=json")
        .current_dir(root());
    match profile.as_str() {
        "debug" => {}
        "release" => {
            cargo.arg("--release");
        }
        other => {
            cargo.args(["--profile", other]);
        }
    }
    let out = cargo.output().expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo test --workspace --no-run failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|m| m["target"]["name"] == "aacmm" && m["target"]["kind"][0] == "bin")
        .filter(|m| m["profile"]["test"] == false)
        .find_map(|m| m["executable"].as_str().map(PathBuf::from))
        .expect("cargo names the aacmm executable")
}

/// New options, changed by `set` (each setter must succeed).
fn options(set: impl FnOnce(*mut AacmmCalibrateOptions) -> Vec<AacmmStatus>) -> Options {
    let mut o = std::ptr::null_mut();
    // SAFETY: `o` is writable.
    let status = unsafe { aacmm_calibrate_options_new(&mut o) };
    assert_eq!(status, AacmmStatus::Ok);
    for status in set(o) {
        assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    }
    Options(o)
}

/// Options that free themselves.
struct Options(*mut AacmmCalibrateOptions);

impl Drop for Options {
    fn drop(&mut self) {
        // SAFETY: a live handle, not used after.
        unsafe { aacmm_calibrate_options_free(self.0) };
    }
}

/// A calibration result that frees itself.
struct Calibration(*mut AacmmCalibration);

impl Drop for Calibration {
    fn drop(&mut self) {
        // SAFETY: a live handle, not used after.
        unsafe { aacmm_calibration_free(self.0) };
    }
}

impl Calibration {
    /// `aacmm_calibrate_files` on files named from the root.
    fn of_files(arm: &str, poses: &str, lengths: Option<&str>, unit: u32, o: &Options) -> Self {
        Calibration::of_paths(
            &example(arm),
            Some(&example(poses)),
            lengths.map(example).as_deref(),
            unit,
            o,
        )
    }

    /// `aacmm_calibrate_files` on these paths (no poses: `NULL`).
    fn of_paths(
        arm: &str,
        poses: Option<&str>,
        lengths: Option<&str>,
        unit: u32,
        o: &Options,
    ) -> Self {
        let c = Calibration::try_paths(arm, poses, lengths, unit, o);
        c.unwrap_or_else(|status| panic!("{status:?}: {}", last_error()))
    }

    /// `aacmm_calibrate_files` on these paths, or its refusal.
    fn try_paths(
        arm: &str,
        poses: Option<&str>,
        lengths: Option<&str>,
        unit: u32,
        o: &Options,
    ) -> Result<Self, AacmmStatus> {
        let c = |p: &str| CString::new(p).unwrap();
        let (arm, poses, lengths) = (c(arm), poses.map(c), lengths.map(c));
        let path = |p: &Option<CString>| p.as_ref().map_or(std::ptr::null(), |p| p.as_ptr());
        let mut out = std::ptr::null_mut();
        // SAFETY: NUL-terminated paths (NULL when absent), live options, a
        // writable output slot.
        let status = unsafe {
            aacmm_calibrate_files(
                arm.as_ptr(),
                path(&poses),
                path(&lengths),
                unit,
                o.0,
                &mut out,
            )
        };
        match status {
            AacmmStatus::Ok => Ok(Calibration(out)),
            s => {
                assert!(out.is_null(), "a refused calibration gave a result");
                Err(s)
            }
        }
    }

    /// Every auxiliary column: name and values.
    fn auxiliary(&self) -> Vec<(String, AacmmAuxiliary)> {
        let mut count = usize::MAX;
        // SAFETY: a live result; `count` is writable.
        let status = unsafe { aacmm_calibration_auxiliary_count(self.0, &mut count) };
        assert_eq!(status, AacmmStatus::Ok);
        (0..count)
            .map(|i| {
                let mut column = std::mem::MaybeUninit::uninit();
                // SAFETY: a live result; room for the struct; the name's
                // buffers as stated.
                let name = self.text(|b, n, len| unsafe {
                    aacmm_calibration_auxiliary(self.0, i, column.as_mut_ptr(), b, n, len)
                });
                // SAFETY: written by the calls above (with the name).
                (name, unsafe { column.assume_init() })
            })
            .collect()
    }

    fn frame_count(&self) -> usize {
        let mut n = usize::MAX;
        // SAFETY: a live result; `n` is writable.
        let status = unsafe { aacmm_calibration_frame_count(self.0, &mut n) };
        assert_eq!(status, AacmmStatus::Ok);
        n
    }

    fn params(&self) -> Vec<f64> {
        let mut p = vec![0.0; 27];
        // SAFETY: a live result of a 6-joint arm; 27 writable doubles.
        let status = unsafe { aacmm_calibration_params(self.0, p.as_mut_ptr(), p.len()) };
        assert_eq!(status, AacmmStatus::Ok);
        p
    }

    fn summary(&self) -> AacmmCalibrationSummary {
        let mut s = std::mem::MaybeUninit::uninit();
        // SAFETY: a live result; room for the struct, written on success.
        unsafe {
            assert_eq!(
                aacmm_calibration_summary(self.0, s.as_mut_ptr()),
                AacmmStatus::Ok
            );
            s.assume_init()
        }
    }

    /// A string output: sized first, then copied.
    fn text(&self, mut get: impl FnMut(*mut c_char, usize, *mut usize) -> AacmmStatus) -> String {
        let mut len = 0;
        assert_eq!(
            get(std::ptr::null_mut(), 0, &mut len),
            AacmmStatus::BufferTooSmall
        );
        let mut buf = vec![0u8; len + 1];
        assert_eq!(
            get(buf.as_mut_ptr().cast(), buf.len(), &mut len),
            AacmmStatus::Ok
        );
        assert_eq!(buf[len], 0);
        String::from_utf8(buf[..len].to_vec()).unwrap()
    }

    fn report(&self) -> String {
        // SAFETY: a live result; the buffers are as stated.
        self.text(|b, n, len| unsafe { aacmm_calibration_report(self.0, b, n, len) })
    }

    /// `(usable, reasons, notes)`.
    fn verdict(&self) -> (bool, String, String) {
        let mut usable = !self.summary().successful;
        // SAFETY: a live result; the buffers are as stated.
        let reasons = self
            .text(|b, n, len| unsafe { aacmm_calibration_verdict(self.0, &mut usable, b, n, len) });
        // SAFETY: as above.
        let notes =
            self.text(|b, n, len| unsafe { aacmm_calibration_verdict_notes(self.0, b, n, len) });
        (usable, reasons, notes)
    }

    /// Each reason's kind and text, through the reason accessors.
    fn reasons(&self) -> Vec<(AacmmReasonKind, String)> {
        let mut count = usize::MAX;
        // SAFETY: a live result; `count` writable.
        let status = unsafe { aacmm_calibration_reason_count(self.0, &mut count) };
        assert_eq!(status, AacmmStatus::Ok);
        let reasons: Vec<(AacmmReasonKind, String)> = (0..count)
            .map(|i| {
                let mut kind = u32::MAX;
                // SAFETY: a live result; the buffers are as stated.
                let text = self.text(|b, n, len| unsafe {
                    aacmm_calibration_reason(self.0, i, &mut kind, b, n, len)
                });
                (kind, text)
            })
            .collect();
        // One past the last: refused, naming the count.
        let (mut kind, mut len) = (0, 0);
        // SAFETY: as above.
        let status = unsafe {
            aacmm_calibration_reason(self.0, count, &mut kind, std::ptr::null_mut(), 0, &mut len)
        };
        assert_eq!(status, AacmmStatus::InvalidArgument);
        reasons
    }
}

/// Bitwise equality with the index of the first difference.
fn assert_bits(what: &str, a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    if let Some(i) = (0..a.len()).find(|&i| a[i].to_bits() != b[i].to_bits()) {
        panic!("{what}[{i}]: {:e} vs {:e}", a[i], b[i]);
    }
}

const KINOVA: [&str; 3] = [
    "examples/mukca/kinova-1/arm.toml",
    "examples/mukca/kinova-1/poses.csv",
    "examples/mukca/kinova-1/lengths.csv",
];

/// Runs `aacmm calibrate` on kinova-1 with `extra` flags; its output
/// directory.
fn command_line(name: &str, extra: &[&str]) -> (PathBuf, bool) {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&out);
    let [arm, poses, lengths] = KINOVA.map(example);
    let mut flags = vec!["--angle-unit", "rad"];
    flags.extend(extra);
    let usable = calibrate_cli(&out, [&arm, &poses, &lengths], &flags);
    (out, usable)
}

/// `aacmm calibrate --arm --data --lengths` into `out` with `extra` flags;
/// whether it exited 0 (it must have written its files either way).
fn calibrate_cli(out: &Path, [arm, poses, lengths]: [&str; 3], extra: &[&str]) -> bool {
    let run = Command::new(cli())
        .args([
            "calibrate",
            "--arm",
            arm,
            "--data",
            poses,
            "--lengths",
            lengths,
        ])
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .expect("aacmm runs");
    assert!(
        out.join("calibration.json").is_file(),
        "aacmm calibrate wrote nothing:\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    run.status.success()
}

/// The arm file's `[prior]` reaches the fit: the C API writes the command
/// line's report byte for byte and its calibrated parameters bit for bit,
/// with the same verdict; `prior = "none"` is `--prior none`, and differs.
#[test]
fn an_arm_files_prior_gives_the_command_lines_result() {
    let [arm, poses, lengths] = KINOVA;
    let defaults = options(|_| Vec::new());
    let c = Calibration::of_files(arm, poses, Some(lengths), AACMM_ANGLE_RAD, &defaults);
    let (dir, exit_ok) = command_line("kinova-1-cli", &[]);
    let json = std::fs::read_to_string(dir.join("calibration.json")).unwrap();
    let report = c.report();
    assert_eq!(report, json, "the C API's report is not the command line's");
    // The command line writes no radians: its calibrated parameters are
    // those of `calibrated.toml` (mm, and deg converted so that they read
    // back to the same radians where a decimal can). The C API's
    // parameters, written the same way, give the same bytes.
    let params = c.params();
    let (start, _) = read_arm(&root().join(arm)).unwrap();
    let from_c = Arm {
        name: format!("{}-calibrated", start.name),
        params: start.params.with_values(&params).unwrap(),
        limits: start.limits.clone(),
        prior: None,
        physics: start.physics.clone(),
        ball_diameter_mm: start.ball_diameter_mm,
        tools: start.tools.clone(),
    };
    assert_eq!(
        arm_to_toml(&from_c, LengthUnit::Mm, AngleUnit::Deg),
        // The file ends with the verdict, which the arm does not carry.
        std::fs::read_to_string(dir.join("calibrated.toml"))
            .unwrap()
            .split("\n[verdict]\n")
            .next()
            .unwrap(),
        "the C API's calibrated parameters are not the command line's"
    );
    // And in the report's units (deg by `to_degrees`, another conversion),
    // parameter by parameter: the numbers of the command line's JSON, as
    // written (parsed, they could be off by an ulp).
    let mut rest = &json[json.find("\"parameters\": [").unwrap()..];
    for (id, &v) in start.params.param_ids().zip(&params) {
        let key = "\"calibrated\": ";
        let at = rest.find(key).unwrap() + key.len();
        let written = &rest[at..at + rest[at..].find([',', '\n']).unwrap()];
        assert_eq!(
            serde_json::to_string(&id.to_user(v)).unwrap(),
            written,
            "{id}"
        );
        rest = &rest[at..];
    }

    // The verdict, as the report and the exit status have it.
    let expected: serde_json::Value = serde_json::from_str(&json).unwrap();
    let v = &expected["verdict"];
    let strings = |key: &str| -> String {
        let items: Vec<&str> = v[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap())
            .collect();
        items.join("\n")
    };
    let (usable, reasons, notes) = c.verdict();
    assert_eq!(usable, v["usable"].as_bool().unwrap());
    assert_eq!((usable, c.summary().successful), (exit_ok, exit_ok));
    // The same reasons and notes, in C's words: the same sentence where it
    // names no option, no flag anywhere.
    for (c_text, cli_text) in [(reasons, strings("reasons")), (notes, strings("notes"))] {
        assert_eq!(c_text.lines().count(), cli_text.lines().count());
        assert!(!c_text.contains("--"), "{c_text}");
        for (a, b) in c_text.lines().zip(cli_text.lines()) {
            if !b.contains("--") {
                assert_eq!(a, b);
            }
        }
    }
    assert!(
        !expected["calibration"]["prior"].is_null(),
        "the fit had a prior"
    );

    // Without the prior: the command line's `--prior none`, another fit.
    let none = options(|o| {
        // SAFETY: live options; a NUL-terminated literal.
        vec![unsafe { aacmm_calibrate_options_set_prior(o, c"none".as_ptr()) }]
    });
    let bare = Calibration::of_files(arm, poses, Some(lengths), AACMM_ANGLE_RAD, &none);
    let (dir, _) = command_line("kinova-1-cli-no-prior", &["--prior", "none"]);
    let json = std::fs::read_to_string(dir.join("calibration.json")).unwrap();
    assert_eq!(bare.report(), json);
    assert!(
        params
            .iter()
            .zip(bare.params())
            .any(|(a, b)| a.to_bits() != b.to_bits()),
        "the prior changed nothing: is it used at all?"
    );
}

/// Far overstated noise on the shipped campaign: the solver converges, the
/// verdict refuses (`successful` false, `converged` true, the reason given);
/// accepting a poor fit makes it usable, with a note saying so.
#[test]
fn successful_is_the_verdict_not_the_solver() {
    let loud = |accept: bool| {
        options(|o| {
            // SAFETY: live options.
            unsafe {
                vec![
                    aacmm_calibrate_options_set_encoder_noise_rad(o, 30f64.to_radians()),
                    aacmm_calibrate_options_set_probe_noise_mm(o, 100.0),
                    aacmm_calibrate_options_set_accept_poor_fit(o, accept),
                ]
            }
        })
    };
    let files = [
        "examples/paper-table-1.toml",
        "examples/paper-campaign/poses.csv",
        "examples/paper-campaign/lengths.csv",
    ];
    let refused = Calibration::of_files(
        files[0],
        files[1],
        Some(files[2]),
        AACMM_ANGLE_DEG,
        &loud(false),
    );
    let s = refused.summary();
    assert!(s.converged, "the solver converged");
    assert!(!s.successful, "but the verdict refuses the fit");
    let (usable, reasons, _) = refused.verdict();
    assert!(!usable);
    assert!(
        reasons.lines().next().unwrap().contains("overstated"),
        "{reasons}"
    );
    // Typed: the χ² test, said as the Birge ratio with C's remedies.
    let typed = refused.reasons();
    assert_eq!(typed.len(), reasons.lines().count());
    let (kind, text) = &typed[0];
    assert_eq!(*kind, AACMM_REASON_CHI_SQUARE, "{text}");
    assert_eq!(text, reasons.lines().next().unwrap());
    for want in [
        "the Birge ratio σ̂₀ = √(χ²/dof) = ",
        "times less than the stated noise (aacmm_calibrate_options_set_encoder_noise_rad(o, ",
        "0 in aacmm_calibrate_options_set_encoder_noise_rad, \
         aacmm_calibrate_options_set_probe_noise_mm: not stated",
        "with aacmm_calibrate_options_set_accept_poor_fit.",
    ] {
        assert!(text.contains(want), "`{want}` missing: {text}");
    }
    assert!(!text.contains("--"), "{text}");
    let report: serde_json::Value = serde_json::from_str(&refused.report()).unwrap();
    assert_eq!(report["verdict"]["usable"], false);

    let accepted = Calibration::of_files(
        files[0],
        files[1],
        Some(files[2]),
        AACMM_ANGLE_DEG,
        &loud(true),
    );
    assert!(accepted.summary().successful);
    let (usable, reasons, notes) = accepted.verdict();
    assert!(usable);
    assert_eq!(reasons, "");
    assert!(notes.starts_with("accepted on request: "), "{notes}");
    assert_bits("params", &accepted.params(), &refused.params());
}

/// A positions file (`--positions`), alone and with touches and lengths:
/// the C API's report is the command line's, byte for byte, and the frames
/// are counted. The shipped UR5 tracker rows alone; a simulated campaign's
/// touches, lengths and tracker positions (written to files) together.
#[test]
fn a_positions_file_gives_the_command_lines_result() {
    let flags = ["--method", "lm", "--position-noise", "0.015+0.006/m"];
    let tracked = options(|o| {
        // SAFETY: live options.
        unsafe {
            vec![
                aacmm_calibrate_options_set_method(o, AACMM_METHOD_LM),
                aacmm_calibrate_options_set_position_noise_mm(o, 0.015, 0.006),
            ]
        }
    });
    let set_file = |path: &str| {
        let path = CString::new(path).unwrap();
        // SAFETY: live options; a NUL-terminated path.
        let status =
            unsafe { aacmm_calibrate_options_set_positions_file(tracked.0, path.as_ptr()) };
        assert_eq!(status, AacmmStatus::Ok);
    };
    let cli = |name: &str, args: &[&str]| -> String {
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
        let _ = std::fs::remove_dir_all(&out);
        let run = Command::new(cli())
            .arg("calibrate")
            .args(args)
            .args(flags)
            .arg("--out")
            .arg(&out)
            .output()
            .expect("aacmm runs");
        std::fs::read_to_string(out.join("calibration.json")).unwrap_or_else(|_| {
            panic!(
                "aacmm calibrate wrote nothing:\n{}",
                String::from_utf8_lossy(&run.stderr)
            )
        })
    };

    // The UR5's 20 random poses seen by a tracker, alone.
    let (arm, positions) = (
        example("examples/ur5-tracker/arm.toml"),
        example("examples/ur5-tracker/positions-random.csv"),
    );
    set_file(&positions);
    let c = Calibration::of_paths(&arm, None, None, AACMM_ANGLE_DEG, &tracked);
    let json = cli(
        "ur5-positions-cli",
        &["--arm", &arm, "--positions", &positions],
    );
    assert_eq!(c.report(), json, "positions alone");
    assert_eq!(c.frame_count(), 1);

    // Touches, lengths and positions of one simulated arm, in files.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("touches-and-positions");
    std::fs::create_dir_all(&dir).unwrap();
    let arm = example("examples/paper-table-1.toml");
    let (nominal, _) = read_arm(Path::new(&arm)).unwrap();
    let mut settings = CampaignSettings::new(5, ErrorModel::Paper, 6, 8);
    settings.encoder_noise_deg = 0.005;
    settings.probe_noise_mm = 0.01;
    let campaign = simulate(&nominal, &settings).unwrap();
    let seen = simulate_positions(
        &campaign.true_arm,
        &PositionSettings {
            poses: 30,
            frames: 2,
            noise: aacmm_core::residuals::Noise {
                position_mm: Some(0.015),
                position_mm_per_m: Some(0.006),
                ..Default::default()
            },
            seed: 6,
        },
    )
    .unwrap();
    let file = |name: &str| dir.join(name).display().to_string();
    let (poses, lengths, positions) = (
        file("poses.csv"),
        file("lengths.csv"),
        file("positions.csv"),
    );
    let mut text = Vec::new();
    write_poses(&mut text, &campaign.poses, AngleUnit::Deg).unwrap();
    std::fs::write(&poses, &text).unwrap();
    let mut text = Vec::new();
    aacmm_core::io::write_lengths(&mut text, &campaign.lengths).unwrap();
    std::fs::write(&lengths, &text).unwrap();
    let mut text = Vec::new();
    write_positions(&mut text, &seen.positions, AngleUnit::Deg).unwrap();
    std::fs::write(&positions, &text).unwrap();
    set_file(&positions);
    // SAFETY: live options.
    unsafe {
        aacmm_calibrate_options_set_encoder_noise_rad(tracked.0, 0.005f64.to_radians());
        aacmm_calibrate_options_set_probe_noise_mm(tracked.0, 0.01);
    }
    let c = Calibration::of_paths(
        &arm,
        Some(&poses),
        Some(&lengths),
        AACMM_ANGLE_DEG,
        &tracked,
    );
    let json = cli(
        "touches-and-positions-cli",
        &[
            "--arm",
            &arm,
            "--data",
            &poses,
            "--lengths",
            &lengths,
            "--positions",
            &positions,
            "--encoder-noise",
            "0.005",
            "--probe-noise",
            "0.01",
        ],
    );
    assert_eq!(c.report(), json, "touches, lengths and positions");
    assert_eq!(c.frame_count(), 2);
}

/// `aacmm calibrate` with `args`, written to a fresh directory `name`: its
/// `calibration.json`.
fn command_line_report(name: &str, args: &[&str]) -> String {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(cli())
        .arg("calibrate")
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("aacmm runs");
    std::fs::read_to_string(out.join("calibration.json")).unwrap_or_else(|_| {
        panic!(
            "aacmm calibrate wrote nothing:\n{}",
            String::from_utf8_lossy(&run.stderr)
        )
    })
}

/// The number `key` of the auxiliary column `name` as `json` writes it.
fn written<'a>(json: &'a str, name: &str, key: &str) -> &'a str {
    let column = &json[json
        .find(&format!("\"name\": \"{name}\""))
        .unwrap_or_else(|| panic!("no column {name}"))..];
    let key = format!("\"{key}\": ");
    let at = column.find(&key).unwrap() + key.len();
    &column[at..at + column[at..].find([',', '\n']).unwrap()]
}

/// Joint compliance (`--compliance 2,3`, the arm file's masses loading the
/// joints) on the shipped UR5 tracker grid: the C API writes the command
/// line's report byte for byte; the compliances are the first auxiliary
/// columns, fitted, the values the report writes, in its physics too.
#[test]
fn a_compliance_gives_the_command_lines_result() {
    let (arm, positions) = (
        example("examples/ur5-tracker/arm.toml"),
        example("examples/ur5-tracker/positions-grid.csv"),
    );
    let path = CString::new(positions.as_str()).unwrap();
    let o = options(|o| {
        // SAFETY: live options; NUL-terminated strings.
        unsafe {
            vec![
                aacmm_calibrate_options_set_method(o, AACMM_METHOD_LM),
                aacmm_calibrate_options_set_positions_file(o, path.as_ptr()),
                aacmm_calibrate_options_set_compliance(o, c"2,3".as_ptr()),
            ]
        }
    });
    let c = Calibration::of_paths(&arm, None, None, AACMM_ANGLE_DEG, &o);
    let json = command_line_report(
        "ur5-compliance-cli",
        &[
            "--arm",
            &arm,
            "--positions",
            &positions,
            "--compliance",
            "2,3",
            "--method",
            "lm",
        ],
    );
    assert_eq!(
        c.report(),
        json,
        "the C API's report is not the command line's"
    );

    let columns = c.auxiliary();
    let names: Vec<&str> = columns.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "compliance2",
            "compliance3",
            "instrument.rx",
            "instrument.ry",
            "instrument.rz",
            "instrument.tx",
            "instrument.ty",
            "instrument.tz"
        ]
    );
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    for (k, (name, a)) in columns.iter().enumerate() {
        for (key, v) in [("start", a.start), ("calibrated", a.calibrated)] {
            assert_eq!(
                serde_json::to_string(&v).unwrap(),
                written(&json, name, key),
                "{name}.{key}"
            );
        }
        assert_eq!(
            serde_json::to_string(&a.sigma).unwrap(),
            written(&json, name, "sigma"),
            "{name}.sigma"
        );
        assert!(!a.fixed, "{name}: held");
        assert_eq!(report["calibration"]["auxiliary"][k]["name"], *name);
    }
    // The data see both compliances (each many σ from 0), and the report's
    // physics holds them in rad/(N·m).
    let physics = &report["calibration"]["physics"]["compliance"];
    for (j, (name, a)) in columns[..2].iter().enumerate() {
        assert!(a.calibrated.abs() > 5.0 * a.sigma, "{name}: {a:?}");
        let si = physics[j + 1].as_f64().unwrap();
        assert!(
            (si - a.calibrated * 1e-6).abs() <= 1e-12 * si.abs(),
            "{name}: {si} rad/(N·m) vs {} µrad/(N·m)",
            a.calibrated
        );
    }
}

/// What the arm or the data cannot support is refused when calibrating,
/// naming the setting: a compliance without masses (the paper's arm file
/// states none), a thermal expansion without temperatures (the UR5 grid has
/// no `temperature` column).
#[test]
fn beyond_geometry_without_its_inputs_is_refused() {
    let compliant = options(|o| {
        // SAFETY: live options; a NUL-terminated literal.
        vec![unsafe { aacmm_calibrate_options_set_compliance(o, c"2,3".as_ptr()) }]
    });
    let refused = Calibration::try_paths(
        &example("examples/paper-table-1.toml"),
        Some(&example("examples/paper-campaign/poses.csv")),
        None,
        AACMM_ANGLE_DEG,
        &compliant,
    );
    assert_eq!(refused.err(), Some(AacmmStatus::InvalidArgument));
    let m = last_error();
    assert!(
        m.starts_with("compliance = 2,3: no mass loads the joints"),
        "{m}"
    );

    let positions = CString::new(example("examples/ur5-tracker/positions-grid.csv")).unwrap();
    let thermal = options(|o| {
        // SAFETY: live options; a NUL-terminated path.
        unsafe {
            vec![
                aacmm_calibrate_options_set_positions_file(o, positions.as_ptr()),
                aacmm_calibrate_options_set_thermal(o, true),
            ]
        }
    });
    let refused = Calibration::try_paths(
        &example("examples/ur5-tracker/arm.toml"),
        None,
        None,
        AACMM_ANGLE_DEG,
        &thermal,
    );
    assert_eq!(refused.err(), Some(AacmmStatus::InvalidArgument));
    let m = last_error();
    assert!(
        m.starts_with("thermal = on: thermal expansion needs the temperature of every pose"),
        "{m}"
    );
}

/// A refused calibration through the C API: one mislabelled touch gives
/// `successful` false and the reasons; its `calibrated.toml` (written by
/// the command line) is refused by `aacmm_arm_from_file`, naming the
/// verdict, and read with a warning by
/// `aacmm_arm_from_file_accepting_rejected`.
#[test]
fn a_refused_calibration_says_so_and_its_arm_file_is_refused_unless_asked() {
    let dir = std::env::temp_dir().join(format!("aacmm-capi-verdict-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let poses = mislabelled(&dir);
    let (arm, lengths) = (
        example("examples/paper-table-1.toml"),
        example("examples/paper-campaign/lengths.csv"),
    );
    let c = Calibration::of_paths(
        &arm,
        Some(&poses),
        Some(&lengths),
        AACMM_ANGLE_DEG,
        &options(|_| vec![]),
    );
    let (usable, reasons, _) = c.verdict();
    assert!(!usable && !c.summary().successful);
    assert!(reasons.contains("worse than the nominal"), "{reasons}");

    let out = dir.join("out");
    assert!(!calibrate_cli(&out, [&arm, &poses, &lengths], &[]));
    let file = CString::new(out.join("calibrated.toml").display().to_string()).unwrap();
    let mut handle = std::ptr::null_mut();
    // SAFETY: a NUL-terminated path and a writable slot.
    let status = unsafe { aacmm_arm_from_file(file.as_ptr(), &mut handle) };
    assert_eq!(status, AacmmStatus::Input);
    assert!(handle.is_null());
    let message = last_error();
    assert!(
        message.contains("field `verdict`") && message.contains("NOT usable"),
        "{message}"
    );
    assert!(
        message.contains("aacmm_arm_from_file_accepting_rejected"),
        "{message}"
    );
    // SAFETY: as above.
    let status = unsafe { aacmm_arm_from_file_accepting_rejected(file.as_ptr(), &mut handle) };
    assert_eq!(status, AacmmStatus::Ok, "{}", last_error());
    let mut buf = vec![0 as c_char; 4096];
    let mut len = 0;
    // SAFETY: a live handle, a buffer of the length given.
    let status = unsafe { aacmm_arm_warnings(handle, buf.as_mut_ptr(), buf.len(), &mut len) };
    assert_eq!(status, AacmmStatus::Ok);
    // SAFETY: NUL-terminated by the call.
    let warnings = unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    assert!(warnings.contains("NOT usable"), "{warnings}");
    // SAFETY: a live handle, not used after.
    unsafe { aacmm_arm_free(handle) };
    let _ = std::fs::remove_dir_all(&dir);
}

/// Poses in radians read as degrees (the paper campaign written in rad,
/// given with `AACMM_ANGLE_DEG`): the refusal names the angle unit and its
/// C setting, not the lengths file — through the C API the reader's
/// warning is not shown, so the error alone must say it.
#[test]
fn radians_read_as_degrees_name_the_angle_unit() {
    let (poses, _) = aacmm_core::io::read_poses(
        Path::new(&example("examples/paper-campaign/poses.csv")),
        AngleUnit::Deg,
        None,
    )
    .unwrap();
    let mut text = Vec::new();
    write_poses(&mut text, &poses, AngleUnit::Rad).unwrap();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capi-radians");
    std::fs::create_dir_all(&dir).unwrap();
    let rad = dir.join("rad.csv");
    std::fs::write(&rad, text).unwrap();
    let defaults = options(|_| Vec::new());
    let refused = Calibration::try_paths(
        &example("examples/paper-table-1.toml"),
        Some(rad.to_str().unwrap()),
        Some(&example("examples/paper-campaign/lengths.csv")),
        AACMM_ANGLE_DEG,
        &defaults,
    );
    assert_eq!(refused.err(), Some(AacmmStatus::Calibration));
    let m = last_error();
    assert!(m.contains("look like radians read as degrees"), "{m}");
    assert!(m.contains("AACMM_ANGLE_RAD"), "{m}");
    assert!(m.contains("the lengths file is not the cause"), "{m}");
    assert!(!m.contains("different units"), "{m}");
}

/// The shipped campaign with touch 17 (file line 18, a touch of S2)
/// labelled S1, written into `dir`; its path.
fn mislabelled(dir: &Path) -> String {
    let shipped = std::fs::read_to_string(example("examples/paper-campaign/poses.csv")).unwrap();
    let mut lines: Vec<String> = shipped.lines().map(str::to_string).collect();
    assert!(lines[17].starts_with("S2,"));
    lines[17] = lines[17].replacen("S2,", "S1,", 1);
    let poses = dir.join("poses.csv");
    std::fs::write(&poses, lines.join("\n") + "\n").unwrap();
    poses.display().to_string()
}

/// Issue 43 through the C API. Case 1: the Kinova's touches with the
/// paper's arm — the first reason is that the data and the arm disagree,
/// not the solver's start budget. Case 2: one mislabelled touch with a
/// robust loss under the default (global) method is usable, as with LM.
#[test]
fn the_first_reason_is_the_true_cause() {
    let defaults = options(|_| Vec::new());
    let kinova = Calibration::of_files(
        "examples/paper-table-1.toml",
        "examples/mukca/kinova-1/poses.csv",
        None,
        AACMM_ANGLE_RAD,
        &defaults,
    );
    let (usable, reasons, _) = kinova.verdict();
    assert!(!usable && !kinova.summary().successful);
    assert!(
        reasons.starts_with("the data and the arm disagree: none of the "),
        "{reasons}"
    );
    assert!(!reasons.contains("more starts"), "{reasons}");

    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capi-first-cause");
    std::fs::create_dir_all(&dir).unwrap();
    let poses = mislabelled(&dir);
    let robust = options(|o| {
        // SAFETY: a live options handle.
        unsafe {
            vec![
                aacmm_calibrate_options_set_encoder_noise_rad(o, 0.005f64.to_radians()),
                aacmm_calibrate_options_set_probe_noise_mm(o, 0.01),
                aacmm_calibrate_options_set_robust(o, AACMM_ROBUST_HUBER, 0.0),
            ]
        }
    });
    let c = Calibration::of_paths(
        &example("examples/paper-table-1.toml"),
        Some(&poses),
        Some(&example("examples/paper-campaign/lengths.csv")),
        AACMM_ANGLE_DEG,
        &robust,
    );
    let (usable, reasons, _) = c.verdict();
    assert!(usable && c.summary().successful, "{reasons}");
    let report: serde_json::Value = serde_json::from_str(&c.report()).unwrap();
    assert_eq!(
        report["calibration"]["solver"]["stop"]["global"]["search"],
        "robust_floor"
    );
}

/// Issue 43, cases 3 and 4, through the C API: lengths in metres name the
/// lengths file; an arm file in the wrong unit (its millimetres declared
/// as metres) names the arm file — each first in the message.
#[test]
fn a_unit_mistake_names_the_file_at_fault() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capi-units");
    std::fs::create_dir_all(&dir).unwrap();
    let arm = example("examples/paper-table-1.toml");
    let text = std::fs::read_to_string(&arm).unwrap();
    let arm_m = dir.join("arm-m.toml");
    std::fs::write(
        &arm_m,
        text.replace("length_unit = \"mm\"", "length_unit = \"m\""),
    )
    .unwrap();
    let lengths = std::fs::read_to_string(example("examples/paper-campaign/lengths.csv")).unwrap();
    let metres: Vec<String> = (lengths.lines().enumerate())
        .map(|(i, l)| {
            let mut f: Vec<String> = l.split(',').map(str::to_string).collect();
            if i > 0 {
                f[2] = format!("{}", f[2].parse::<f64>().unwrap() / 1000.0);
            }
            f.join(",")
        })
        .collect();
    let lengths_m = dir.join("lengths-m.csv");
    std::fs::write(&lengths_m, metres.join("\n") + "\n").unwrap();
    let (poses, shipped_lengths) = (
        example("examples/paper-campaign/poses.csv"),
        example("examples/paper-campaign/lengths.csv"),
    );
    let defaults = options(|_| Vec::new());
    let cases = [
        (
            arm_m.display().to_string(),
            shipped_lengths,
            "the arm file's lengths",
        ),
        (
            arm,
            lengths_m.display().to_string(),
            "the reference lengths are 1.000e-3",
        ),
    ];
    for (arm, lengths, cause) in cases {
        let refused = Calibration::try_paths(
            &arm,
            Some(&poses),
            Some(&lengths),
            AACMM_ANGLE_DEG,
            &defaults,
        );
        assert_eq!(refused.err(), Some(AacmmStatus::Calibration));
        let m = last_error();
        let at_fault = if cause.starts_with("the arm") {
            &arm
        } else {
            &lengths
        };
        assert!(m.starts_with(&format!("{at_fault}: {cause}")), "{m}");
    }
}
