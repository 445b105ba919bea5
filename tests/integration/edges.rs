//! Edges found by trying the CLI as a new user would: inputs that once
//! panicked, and messages that once blamed the wrong thing.

use crate::util::{aacmm, assert_clean_error, shipped, shipped_arm, temp_dir, write};

/// The shipped campaign reduced to the first row of each socket, repeated
/// ten times (`jitter`: with ±0.01° added, as encoder noise would).
fn static_campaign(jitter: bool) -> String {
    let text = std::fs::read_to_string(shipped("poses.csv")).unwrap();
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    let mut seen: Vec<&str> = Vec::new();
    for line in lines {
        let label = line.split(',').next().unwrap();
        if seen.contains(&label) {
            continue;
        }
        seen.push(label);
        for k in 0..10 {
            if jitter {
                let d = [-0.01, -0.005, 0.0, 0.005, 0.01][k % 5];
                let q: Vec<String> = line
                    .split(',')
                    .skip(1)
                    .map(|v| (v.parse::<f64>().unwrap() + d).to_string())
                    .collect();
                out.push_str(&format!("{label},{}\n", q.join(",")));
            } else {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    out
}

/// `identify` and `calibrate` on a campaign without articulation panicked
/// in the pivoted Cholesky (`rank ≤ columns`); now an error names the file
/// and the problem.
#[test]
fn static_data_is_an_error_not_a_panic() {
    let dir = temp_dir("edges-static");
    for jitter in [false, true] {
        let data = write(&dir, "static.csv", &static_campaign(jitter));
        let o = aacmm(&["identify", "--arm", &shipped_arm(), "--data", &data]);
        assert_clean_error(&o, &[&data, "no articulation"]);
        let out = dir.join("out").display().to_string();
        let o = aacmm(&[
            "calibrate",
            "--arm",
            &shipped_arm(),
            "--data",
            &data,
            "--out",
            &out,
        ]);
        assert_clean_error(&o, &[&data, "no articulation"]);
    }
}
