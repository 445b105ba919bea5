//! `aacmm evaluate`: figures on stdout and in JSON, and located errors.

use crate::util::{aacmm, assert_clean_error, example, stdout, temp_dir, write};

const POSES: &str = "point,q1,q2,q3,q4,q5,q6\n\
    A,0,0,0,0,0,0\nA,0,0,0,0,0,1\nA,0,0,0,0,1,0\n\
    B,10,20,30,40,50,60\nB,10,20,30,40,50,61\nB,10,20,30,40,51,61\n";

#[test]
fn reports_table_and_json() {
    let dir = temp_dir("evaluate-ok");
    let data = write(&dir, "poses.csv", POSES);
    let lengths = write(&dir, "lengths.csv", "point_a,point_b,distance\nA,B,500\n");
    let json = dir.join("report.json");
    let arm = example("paper-table-1.toml");
    let o = aacmm(&[
        "evaluate",
        "--arm",
        arm.to_str().unwrap(),
        "--data",
        &data,
        "--lengths",
        &lengths,
        "--json",
        json.to_str().unwrap(),
        "--pairs",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = stdout(&o);
    for needle in ["e+3sigma [mm]", "delta_max", "2s", "eq. 19", "E_Uni"] {
        assert!(table.contains(needle), "table lacks {needle}:\n{table}");
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    assert_eq!(report["length_unit"], "mm");
    let ev = &report["evaluation"];
    assert_eq!(ev["points"].as_array().unwrap().len(), 2);
    assert_eq!(report["pair_length"].as_array().unwrap().len(), 1);
    // Reference error = centroid distance − 500 mm.
    let measured = ev["reference"][0]["measured"].as_f64().unwrap();
    let error = ev["reference"][0]["error"].as_f64().unwrap();
    assert!((error - (measured - 500.0)).abs() < 1e-12);
    let centroid_distance = report["pair_length"][0]["centroid_distance"]
        .as_f64()
        .unwrap();
    assert_eq!(measured, centroid_distance);
}

#[test]
fn errors_point_at_file_and_line() {
    let dir = temp_dir("evaluate-bad");
    let arm = example("paper-table-1.toml");
    let arm = arm.to_str().unwrap();
    let few = write(
        &dir,
        "few.csv",
        "point,q1,q2,q3,q4,q5,q6\nA,0,0,0,0,0,0\nA,0,0,0,0,0,1\nA,0,0,0,0,1,0\nB,1,2,3,4,5,6\nB,1,2,3,4,5,7\n",
    );
    let o = aacmm(&["evaluate", "--arm", arm, "--data", &few]);
    assert_clean_error(&o, &["few.csv:5", "point", "`B` has 2"]);

    let data = write(&dir, "poses.csv", POSES);
    let unknown = write(
        &dir,
        "lengths.csv",
        "point_a,point_b,distance\nA,B,500\nA,C,300\n",
    );
    let o = aacmm(&[
        "evaluate",
        "--arm",
        arm,
        "--data",
        &data,
        "--lengths",
        &unknown,
    ]);
    assert_clean_error(&o, &["lengths.csv:3", "point_b", "`C`"]);

    let negative = write(&dir, "neg.csv", "point_a,point_b,distance\nA,B,-5\n");
    let o = aacmm(&[
        "evaluate",
        "--arm",
        arm,
        "--data",
        &data,
        "--lengths",
        &negative,
    ]);
    assert_clean_error(&o, &["neg.csv:2", "distance"]);
}

/// 1000 points of 3 touches with reference lengths (the pairs of points split
/// into 16 chunks, so 2 and 4 threads share the work): the JSON is the same
/// bytes on 1, 2 and 4 threads; `--threads 0` is refused.
#[test]
fn json_is_the_same_bytes_on_any_thread_count() {
    let dir = temp_dir("evaluate-threads");
    let mut poses = String::from("point,q1,q2,q3,q4,q5,q6\n");
    for p in 0..1000 {
        for k in 0..3 {
            let q: Vec<String> = (0..6)
                .map(|j| {
                    let base = ((p * 7 + j * 13) as f64 * 0.37).sin() * 120.0;
                    format!("{:.4}", base + (k * 20 + j) as f64 * 0.5)
                })
                .collect();
            poses.push_str(&format!("P{p},{}\n", q.join(",")));
        }
    }
    let data = write(&dir, "poses.csv", &poses);
    let mut lengths = String::from("point_a,point_b,distance\n");
    for i in 0..20 {
        lengths.push_str(&format!("P{i},P{},{}\n", 999 - i, 500 + i));
    }
    let lengths = write(&dir, "lengths.csv", &lengths);
    let arm = example("paper-table-1.toml");
    let run = |threads: &str| {
        let json = dir.join(format!("t{threads}.json"));
        let o = aacmm(&[
            "evaluate",
            "--arm",
            arm.to_str().unwrap(),
            "--data",
            &data,
            "--lengths",
            &lengths,
            "--json",
            json.to_str().unwrap(),
            "--threads",
            threads,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (std::fs::read(json).unwrap(), stdout(&o))
    };
    let (one, table) = run("1");
    let report: serde_json::Value = serde_json::from_slice(&one).unwrap();
    let ev = &report["evaluation"];
    assert_eq!(ev["points"].as_array().unwrap().len(), 1000);
    assert_eq!(ev["pair_length_summary"]["count"], 1000 * 999 / 2);
    assert_eq!(ev["reference"].as_array().unwrap().len(), 20);
    for threads in ["2", "4"] {
        let (bytes, text) = run(threads);
        assert!(bytes == one, "JSON differs between 1 and {threads} threads");
        assert_eq!(text, table, "table differs between 1 and {threads} threads");
    }
    let o = aacmm(&[
        "evaluate",
        "--arm",
        arm.to_str().unwrap(),
        "--data",
        &data,
        "--threads",
        "0",
    ]);
    assert_clean_error(&o, &["--threads"]);
}
