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
