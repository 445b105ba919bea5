//! `aacmm plan`: pools drawn (positions, touches) and read, the chosen rows
//! written back as rows of the pool, a plan that adds to a calibration, and
//! bad input refused by flag, file and line. Small pools (200 candidates,
//! K = 20) keep the tests fast in debug builds.

use std::path::Path;

use aacmm_core::domain::Poses;
use aacmm_core::io::{AngleUnit, read_poses};

use crate::util::{
    aacmm, assert_clean_error, calibrate_shipped, shipped, shipped_arm, stderr, stdout, temp_dir,
    write,
};

/// `aacmm plan --arm <shipped> ARGS`, which must succeed; its stdout.
fn plan_ok(args: &[&str]) -> String {
    let arm = shipped_arm();
    let o = aacmm(&[&["plan", "--arm", &arm][..], args].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    stdout(&o)
}

fn poses(path: &Path, unit: AngleUnit) -> Poses {
    read_poses(path, unit, Some(6)).expect("a poses file").0
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).expect("JSON")
}

/// The 95 % radius RMS at `pointer` (a spread) of the plan.
fn rms(plan: &serde_json::Value, pointer: &str) -> f64 {
    plan.pointer(&format!("{pointer}/rms_mm"))
        .and_then(|v| v.as_f64())
        .unwrap_or_else(|| panic!("{pointer}: {plan}"))
}

#[test]
fn positions_drawn_within_the_limits_beat_random_ones() {
    let dir = temp_dir("plan-positions");
    let (out, js) = (dir.join("chosen.csv"), dir.join("plan.json"));
    let text = plan_ok(&[
        "--sample",
        "200",
        "--count",
        "20",
        "--measure",
        "positions",
        "--out",
        out.to_str().unwrap(),
        "--json",
        js.to_str().unwrap(),
    ]);
    for want in [
        "Plan: 20 of 200 candidate positions, drawn uniformly within ±180° on every joint",
        "the 20 chosen",
        "all 200 candidates",
        "20 at random (median of 10)",
        "RMS radius as rows are added",
        "← chosen",
        "instrument frame's 6",
    ] {
        assert!(text.contains(want), "lacks `{want}`:\n{text}");
    }
    let chosen = poses(&out, AngleUnit::Deg);
    assert_eq!(chosen.len(), 20);
    let plan = json(&js);
    assert_eq!(plan["count"], 20);
    assert_eq!(plan["candidates"], 200);
    // The labels are the drawn pool's, P1…P200, in the order chosen.
    for (i, step) in plan["steps"].as_array().unwrap()[..20].iter().enumerate() {
        let row = step["row"].as_u64().unwrap();
        assert_eq!(chosen.label(i), format!("P{}", row + 1));
    }
    let (planned, all) = (rms(&plan, "/planned"), rms(&plan, "/all"));
    let random = rms(&plan, "/random/median");
    assert!(
        all < planned && planned < random,
        "{all} {planned} {random}"
    );
}

#[test]
fn touches_drawn_on_the_arm_seed_three_per_socket() {
    let dir = temp_dir("plan-touches");
    let out = dir.join("chosen.csv");
    let text = plan_ok(&[
        "--sample",
        "200",
        "--count",
        "20",
        "--measure",
        "touches",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        text.contains("5 sockets spread over the reachable volume, 40 touches each"),
        "{text}"
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("Touches per socket: "))
        .unwrap_or_else(|| panic!("{text}"));
    let counts: Vec<usize> = line["Touches per socket: ".len()..]
        .split(", ")
        .map(|s| s.rsplit(' ').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(counts.iter().sum::<usize>(), 20, "{line}");
    assert!(counts.iter().all(|&n| n >= 3), "{line}");
    let chosen = poses(&out, AngleUnit::Deg);
    assert_eq!(chosen.len(), 20);
    assert!(chosen.labels().all(|l| l.starts_with('S')));
}

/// The chosen rows are rows of the candidates, labels kept, each once, in
/// the candidates' own angle unit.
#[test]
fn chosen_rows_are_rows_of_the_candidates() {
    let dir = temp_dir("plan-round-trip");
    // The shipped campaign in radians, so that the unit is honoured both ways.
    let pool = poses(Path::new(&shipped("poses.csv")), AngleUnit::Deg);
    let mut rad = Vec::new();
    aacmm_core::io::write_poses(&mut rad, &pool, AngleUnit::Rad).unwrap();
    let candidates = write(&dir, "pool.csv", &String::from_utf8(rad).unwrap());
    let out = dir.join("chosen.csv");
    let text = plan_ok(&[
        "--candidates",
        &candidates,
        "--angle-unit",
        "rad",
        "--count",
        "20",
        "--measure",
        "touches",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(text.contains("  line  criterion"), "{text}");
    let chosen = poses(&out, AngleUnit::Rad);
    assert_eq!(chosen.len(), 20);
    let mut seen = Vec::new();
    for i in 0..chosen.len() {
        let row = (0..pool.len())
            .find(|&r| pool.reading(r) == chosen.reading(i))
            .unwrap_or_else(|| panic!("chosen row {i} is no row of the candidates"));
        assert_eq!(pool.label(row), chosen.label(i));
        assert!(!seen.contains(&row), "row {row} chosen twice");
        seen.push(row);
    }
    // Again: --out exists now, and is kept without --force.
    let arm = shipped_arm();
    let again = [
        "plan",
        "--arm",
        &arm,
        "--candidates",
        &candidates,
        "--angle-unit",
        "rad",
        "--count",
        "20",
        "--measure",
        "touches",
        "--out",
        out.to_str().unwrap(),
    ];
    assert_clean_error(&aacmm(&again), &["--out", "already exists", "--force"]);
    let forced = aacmm(&[&again[..], &["--force"]].concat());
    assert!(forced.status.success(), "{}", stderr(&forced));
}

#[test]
fn a_plan_adds_to_a_calibration() {
    let dir = temp_dir("plan-given");
    let cal = dir.join("calibration");
    let o = calibrate_shipped(&cal, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = plan_ok(&[
        "--given",
        cal.to_str().unwrap(),
        "--candidates",
        &shipped("poses.csv"),
        "--measure",
        "touches",
    ]);
    assert!(text.contains("Adding to the calibration in"), "{text}");
    assert!(
        text.contains("Measure these 10 next, in this order"),
        "{text}"
    );
    assert!(text.contains("(the calibration's)"), "{text}");
    let ranked = text
        .lines()
        .skip_while(|l| !l.starts_with("Measure these"))
        .skip(2)
        .take_while(|l| l.starts_with("  "))
        .count();
    assert_eq!(ranked, 10, "{text}");
    // --noise is the calibration's with --given: the two are refused together.
    let arm = shipped_arm();
    let data = shipped("poses.csv");
    let o = aacmm(&[
        "plan",
        "--arm",
        &arm,
        "--given",
        cal.to_str().unwrap(),
        "--candidates",
        &data,
        "--measure",
        "touches",
        "--noise",
        "0.02",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn bad_input_is_refused_by_flag_file_and_line() {
    let dir = temp_dir("plan-bad");
    let arm = shipped_arm();
    let data = shipped("poses.csv");
    let run = |extra: &[&str]| {
        let base = ["plan", "--arm", &arm, "--measure", "positions"];
        aacmm(&[&base[..], extra].concat())
    };
    let o = run(&["--candidates", &data, "--count", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert_clean_error(&o, &["--count 0: choose between 1 and the 100 candidates"]);
    let o = run(&["--candidates", &data, "--count", "101"]);
    assert_eq!(o.status.code(), Some(1));
    assert_clean_error(
        &o,
        &["--count 101: choose between 1 and the 100 candidates"],
    );
    let five = write(&dir, "five.csv", "point,q1,q2,q3,q4,q5\nA,1,2,3,4,5\n");
    let o = run(&["--candidates", &five, "--count", "1"]);
    assert_eq!(o.status.code(), Some(1));
    assert_clean_error(&o, &["five.csv:1: field `q6`", "the arm has 6 joints"]);
    let bad = write(&dir, "bad.csv", "point,q1,q2,q3,q4,q5,q6\nA,1,2,3,x,5,6\n");
    let o = run(&["--candidates", &bad, "--count", "1"]);
    assert_clean_error(&o, &["bad.csv:2: field `q4`"]);
    let o = run(&["--given", dir.to_str().unwrap(), "--candidates", &data]);
    assert_clean_error(&o, &["--given", "calibration.json"]);
    // A command line that cannot be parsed: exit 2.
    assert_eq!(run(&["--candidates", &data]).status.code(), Some(2));
    assert_eq!(
        run(&["--candidates", &data, "--sample", "10", "--count", "5"])
            .status
            .code(),
        Some(2)
    );
}

/// The README's `plan` block is the real output, line for line (its
/// `--out` written to a scratch folder instead).
#[test]
fn the_readme_block_is_real_output() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md"))
        .expect("README.md");
    let at = readme
        .find("$ aacmm plan ")
        .expect("the README shows aacmm plan");
    let end = at + readme[at..].find("\n```").expect("the block ends");
    let block = &readme[at..end];
    // The command spans two lines, joined by `\`.
    let (command, shown) = block.split_once("\n      ").expect("a continued command");
    let (rest, shown) = shown.split_once('\n').expect("output after the command");
    let command = format!("{} {rest}", command.trim_end_matches('\\'));
    let root = env!("CARGO_MANIFEST_DIR");
    let out = temp_dir("plan-readme").join("chosen.csv");
    let args: Vec<String> = (command.split_whitespace().skip(2))
        .map(|a| match a {
            "/tmp/chosen.csv" => out.display().to_string(),
            a if a.starts_with("examples/") => format!("{root}/{a}"),
            a => a.to_string(),
        })
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = aacmm(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let real = stdout(&o).replace(&out.display().to_string(), "/tmp/chosen.csv");
    assert_eq!(shown.trim_end(), real.trim_end());
}

/// Issue 43, case 9: a workspace larger than the criterion uses is sampled,
/// and the summary says so — how many of how many, why, and the flag that
/// changes it — instead of a bare "(500 poses used)"; all of a small one is
/// said to be used.
#[test]
fn a_sampled_workspace_is_said_with_why_and_how_to_change_it() {
    let base = ["--sample", "200", "--count", "20", "--measure", "positions"];
    let text = plan_ok(&[&base[..], &["--workspace-poses", "50"]].concat());
    assert!(
        text.contains(
            "workspace: the candidates, an even sample of 50 of its 200 poses (each workspace \
             pose adds to every step's work; --workspace-poses N uses up to N)"
        ),
        "{text}"
    );
    let all = plan_ok(&base);
    assert!(
        all.contains("workspace: the candidates (200 poses);"),
        "{all}"
    );
    let arm = shipped_arm();
    let o = aacmm(
        &[
            &["plan", "--arm", &arm][..],
            &base,
            &["--workspace-poses", "0"],
        ]
        .concat(),
    );
    assert_clean_error(&o, &["--workspace-poses 0: at least 1"]);
}

/// `--tool NAME` plans for one of the arm's `[[tool]]` styli: the rows it
/// chooses are those of an arm file whose probe is that stylus; a tool
/// the arm does not have is refused by the flag, with the arm's tools.
#[test]
fn a_plan_for_a_stylus_is_the_plan_of_its_offset() {
    let dir = temp_dir("plan-tool");
    let text = std::fs::read_to_string(shipped_arm()).unwrap();
    let (arm, _) = aacmm_core::io::parse_arm(&text, "arm.toml").unwrap();
    let p = arm.params.probe;
    let long = [p[0] + 15.0, p[1] - 5.0, p[2] + 60.0];
    let tooled = aacmm_core::domain::Arm {
        tools: vec![aacmm_core::domain::Tool {
            name: "long".into(),
            offset: long,
            ball_diameter_mm: None,
        }],
        ..arm.clone()
    };
    let mut moved = arm.clone();
    moved.params.probe = long;
    let toml = |a: &aacmm_core::domain::Arm| {
        aacmm_core::io::arm_to_toml(a, aacmm_core::io::LengthUnit::Mm, AngleUnit::Deg)
    };
    let tooled = write(&dir, "tooled.toml", &toml(&tooled));
    let moved = write(&dir, "moved.toml", &toml(&moved));
    let chosen = |arm: &str, tool: &[&str], out: &str| {
        let out = dir.join(out);
        let args = [
            &["plan", "--arm", arm, "--sample", "200", "--count", "12"][..],
            &["--measure", "touches", "--out", out.to_str().unwrap()][..],
            tool,
        ]
        .concat();
        let o = aacmm(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read_to_string(out).unwrap()
    };
    let by_tool = chosen(&tooled, &["--tool", "long"], "tool.csv");
    assert_eq!(by_tool, chosen(&moved, &[], "moved.csv"));
    assert_ne!(
        by_tool,
        chosen(&tooled, &[], "probe.csv"),
        "the probe's plan is another"
    );
    let o = aacmm(&[
        "plan",
        "--arm",
        &tooled,
        "--sample",
        "50",
        "--count",
        "5",
        "--measure",
        "touches",
        "--tool",
        "short",
    ]);
    assert_clean_error(&o, &["--tool short", "`probe`, `long`"]);
}
