//! The reports of `calibrate --out` and `evaluate --report`: every file
//! there, every SVG is XML, the page holds nothing from outside, and every
//! number it shares with the JSON is the same number.

use std::path::Path;

use aacmm_core::report::{CALIBRATION_FILES, EVALUATION_FILES, HTML_FILE, UNCERTAINTY_MAP_SVG};
use roxmltree::{Document, ParsingOptions};

use crate::util::{
    aacmm, assert_clean_error, calibrate_shipped, shipped, shipped_arm as arm, simulate_held_out,
    stderr, temp_dir,
};

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Parses the page as XML (it is written so that it is).
fn page(html: &str) -> Document<'_> {
    let options = ParsingOptions {
        allow_dtd: true,
        ..ParsingOptions::default()
    };
    Document::parse_with_options(html, options).expect("report.html is well-formed XML")
}

/// Nothing the page refers to is outside it.
#[track_caller]
fn assert_self_contained(html: &str) {
    let lower = html.to_lowercase();
    for bad in [
        "<script", "src=", "<link", "@import", "url(", "<iframe", "<img", "<object",
    ] {
        assert!(!lower.contains(bad), "report.html holds `{bad}`");
    }
    for n in page(html).descendants() {
        if let Some(href) = n.attribute("href") {
            assert!(href.starts_with('#'), "a link out of the page: {href}");
        }
    }
}

/// Every `data-json` cell against the JSON: the same number, shown
/// rounded from it. Returns how many cells were checked.
#[track_caller]
pub(crate) fn assert_agrees_with_json(html: &str, json: &serde_json::Value) -> usize {
    let doc = page(html);
    let mut checked = 0;
    for n in doc.descendants().filter(|n| n.has_attribute("data-json")) {
        let pointer = n.attribute("data-json").unwrap();
        // A yes/no (the verdict) is said as `true`/`false`.
        if let Some(b) = json.pointer(pointer).and_then(serde_json::Value::as_bool) {
            assert_eq!(
                n.attribute("data-value"),
                Some(b.to_string().as_str()),
                "{pointer}"
            );
            checked += 1;
            continue;
        }
        let in_json = json
            .pointer(pointer)
            .and_then(serde_json::Value::as_f64)
            .unwrap_or_else(|| panic!("{pointer}: not a number in the JSON"));
        let value: f64 = n.attribute("data-value").unwrap().parse().unwrap();
        assert_eq!(value, in_json, "{pointer}");
        let shown = n.text().unwrap().trim();
        let decimals = shown.split_once('.').map_or(0, |(_, d)| {
            d.split_once('e').map_or(d.len(), |(m, _)| m.len())
        });
        let shown: f64 = shown.parse().unwrap();
        let tolerance = if n.text().unwrap().contains('e') {
            // d.dddddde±k: relative.
            value.abs() * 10f64.powi(-(decimals as i32)) * 0.51
        } else {
            10f64.powi(-(decimals as i32)) * 0.51
        };
        assert!(
            (shown - value).abs() <= tolerance + 1e-12,
            "{pointer}: shows {shown}, is {value}"
        );
        checked += 1;
    }
    checked
}

#[test]
fn calibrate_report_is_self_contained_and_says_what_calibration_json_says() {
    let dir = temp_dir("report-calibrate");
    let fresh = dir.join("fresh");
    simulate_held_out(&fresh, "4", "5", "2");
    let run = |name: &str| {
        let out = dir.join(name);
        let o = calibrate_shipped(
            &out,
            &[
                "--method",
                "lm",
                "--validate",
                fresh.join("poses.csv").to_str().unwrap(),
                "--validate-lengths",
                fresh.join("lengths.csv").to_str().unwrap(),
                "--cross-validate",
                "2",
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            crate::util::stdout(&o).contains(&format!("wrote {}", out.join(HTML_FILE).display())),
            "{}",
            crate::util::stdout(&o)
        );
        out
    };
    let out = run("a");
    // Every calibration of the shipped campaign has an uncertainty map (its
    // covariance is finite): its figure is written with the others.
    let files: Vec<&str> = CALIBRATION_FILES
        .into_iter()
        .chain([UNCERTAINTY_MAP_SVG])
        .collect();
    for &file in &files {
        let text = read(&out.join(file));
        if file.ends_with(".svg") {
            let doc = Document::parse(&text).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert!(doc.root_element().has_tag_name("svg"), "{file}");
            // The page holds the same figure.
            assert!(read(&out.join(HTML_FILE)).contains(text.trim()), "{file}");
        }
    }
    let html = read(&out.join(HTML_FILE));
    assert_self_contained(&html);
    let json: serde_json::Value =
        serde_json::from_str(&read(&out.join("calibration.json"))).unwrap();
    let checked = assert_agrees_with_json(&html, &json);
    // 27 parameters × nominal, calibrated, correction + 21 σ; 4 validation
    // data sets (fitted, held out, 2 folds) × before and after × 6 to 8
    // figures; the solver and identifiability figures.
    assert!(checked >= 27 * 3 + 21 + 4 * 2 * 6 + 10, "{checked} cells");
    for pointer in [
        "/calibration/parameters/26/correction",
        "/calibration/dof/sigma0",
        "/calibration/solver/final_cost",
        "/calibration/identification/rank",
        "/validation/held_out/figures/after/length_rms",
        "/validation/cross_validation/folds/1/figures/after/e_mean",
        "/uncertainty_map/rms_mm",
        "/uncertainty_map/regions/4/max_mm",
    ] {
        assert!(
            html.contains(&format!("data-json=\"{pointer}\"")),
            "{pointer}"
        );
    }
    // The held-out points are in the figures: the single-point figure has
    // a series per data set and arm.
    let fig = read(&out.join("single-point-errors.svg"));
    let doc = Document::parse(&fig).unwrap();
    let series: Vec<(&str, &str)> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("series"))
        .map(|n| {
            (
                n.attribute("data-name").unwrap(),
                n.attribute("data-points").unwrap(),
            )
        })
        .collect();
    assert_eq!(
        series,
        [
            ("nominal, fitted", "10"),
            ("calibrated, fitted", "10"),
            ("nominal, held out", "4"),
            ("calibrated, held out", "4")
        ]
    );
    // Same input, same bytes.
    let again = run("b");
    for &file in &files {
        assert_eq!(
            read(&out.join(file)),
            read(&again.join(file)),
            "{file} differs"
        );
    }
}

#[test]
fn evaluate_report_writes_three_figures_and_agrees_with_its_json() {
    let dir = temp_dir("report-evaluate");
    let (out, json) = (dir.join("report"), dir.join("ev.json"));
    let o = aacmm(&[
        "evaluate",
        "--arm",
        &arm(),
        "--data",
        &shipped("poses.csv"),
        "--lengths",
        &shipped("lengths.csv"),
        "--json",
        json.to_str().unwrap(),
        "--report",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    written.sort();
    let mut expected: Vec<String> = EVALUATION_FILES.iter().map(|s| s.to_string()).collect();
    expected.sort();
    assert_eq!(written, expected);
    let html = read(&out.join(HTML_FILE));
    assert_self_contained(&html);
    let json: serde_json::Value = serde_json::from_str(&read(&json)).unwrap();
    // 10 points × 6 figures, 5 summaries × 5, 5 references × 3.
    assert_eq!(assert_agrees_with_json(&html, &json), 60 + 25 + 15);
}

#[test]
fn report_paths_are_checked_before_any_work() {
    let dir = temp_dir("report-paths");
    let out = dir.join("out");
    std::fs::create_dir_all(out.join(HTML_FILE)).unwrap();
    let o = aacmm(&[
        "evaluate",
        "--arm",
        &arm(),
        "--data",
        &shipped("poses.csv"),
        "--report",
        out.to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--report", "report.html is a directory"]);
    assert!(
        crate::util::stdout(&o).is_empty(),
        "no work before the check"
    );
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm(),
        "--data",
        &shipped("poses.csv"),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_clean_error(&o, &["--out", "report.html is a directory"]);
}

/// A tracker campaign of two stations, a quarter of its rows held out:
/// (fitted file, held-out file) in `dir`.
fn tracker_campaign(dir: &Path) -> (String, String) {
    let sim = dir.join("sim");
    let o = aacmm(&[
        "simulate",
        "--arm",
        &arm(),
        "--errors",
        "random",
        "--positions",
        "120",
        "--frames",
        "2",
        "--seed",
        "4",
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = read(&sim.join("positions.csv"));
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string() + "\n";
    let (mut fitted, mut held) = (header.clone(), header);
    for (i, l) in lines.enumerate() {
        let to = if i % 4 == 3 { &mut held } else { &mut fitted };
        *to += l;
        to.push('\n');
    }
    (
        crate::util::write(dir, "fitted.csv", &fitted),
        crate::util::write(dir, "held.csv", &held),
    )
}

/// The report of a calibration from tracker positions alone leads with the
/// 3-D errors before and after (table per data set and per frame, and the
/// figure on the page), states the position noise that was used, and has
/// no touch section, figure or JSON field: a section per kind of evidence
/// present.
#[test]
fn the_tracker_report_leads_with_the_3d_errors_and_has_no_touch_section() {
    let dir = temp_dir("report-tracker");
    let (fitted, held) = tracker_campaign(&dir);
    let out = dir.join("out");
    let o = aacmm(&[
        "calibrate",
        "--arm",
        &arm(),
        "--positions",
        &fitted,
        "--validate-positions",
        &held,
        "--position-noise",
        "0.015+0.006/m",
        "--method",
        "lm",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let html = read(&out.join(HTML_FILE));
    assert_self_contained(&html);
    let json: serde_json::Value =
        serde_json::from_str(&read(&out.join("calibration.json"))).unwrap();
    // Every number shared with the JSON is the same (the 3-D errors' too).
    assert!(assert_agrees_with_json(&html, &json) > 0);
    for pointer in [
        "/validation/fitted/after/positions/p95",
        "/validation/held_out/figures/before/positions/rms",
    ] {
        assert!(
            html.contains(&format!("data-json=\"{pointer}\"")),
            "{pointer} not on the page"
        );
    }
    // No touch: no touch section, figure or field, and no "0 touches".
    for absent in [
        "id=\"single-point\"",
        "id=\"lengths\"",
        "id=\"residuals\"",
        "0 touches",
        "At a glance",
        "touch σ",
        "noise</th><td>not stated",
    ] {
        assert!(
            !html.contains(absent),
            "`{absent}` on the page of positions alone"
        );
    }
    for file in [
        "single-point-errors.svg",
        "length-errors.svg",
        "residuals.svg",
    ] {
        assert!(!out.join(file).exists(), "{file} written without touches");
    }
    for set in [
        "/validation/fitted/before",
        "/validation/held_out/figures/after",
    ] {
        let figures = json.pointer(set).unwrap().as_object().unwrap();
        let keys: Vec<&String> = figures.keys().collect();
        assert_eq!(keys, ["positions"], "{set}");
    }
    // The first numbered section is the 3-D errors, with its figure and a
    // row per frame of each data set.
    let first = html
        .find("<section id=\"positions\"")
        .expect("a section of the 3-D errors");
    for later in [
        "id=\"parameters\"",
        "id=\"identifiability\"",
        "id=\"solver\"",
    ] {
        assert!(
            html.find(later).unwrap() > first,
            "{later} before the 3-D errors"
        );
    }
    assert!(
        html.contains("<h2>1. 3-D errors at the reference positions"),
        "not numbered first"
    );
    let section = &html[first..first + html[first..].find("</section>").unwrap()];
    let figure = read(&out.join("position-errors.svg"));
    assert!(
        section.contains(
            figure
                .trim_start_matches("<?xml version=\"1.0\" encoding=\"UTF-8\"?>")
                .trim()
        )
    );
    for frame in ["<td>station1</td>", "<td>station2</td>"] {
        // Fitted and held out, each before and after.
        assert_eq!(section.matches(frame).count(), 4, "{frame}");
    }
    // The noise used, as stated.
    assert!(
        html.contains("σ = 0.015 mm + 0.006 mm per metre from the instrument"),
        "the stated position noise is not on the page"
    );
    // The text summary's table has the 95th percentile.
    let text = crate::util::stdout(&o);
    assert!(
        text.contains("poses     mean      RMS      p95      max"),
        "{text}"
    );
}

/// Held-out positions in a frame the fit does not have: refused by file,
/// line and field with the fitted frames' names (registered on themselves
/// they would score optimistically); with --register-held-out they are,
/// and the summary, calibration.json and the page each say so.
#[test]
fn held_out_positions_in_an_unfitted_frame_are_refused_unless_asked_and_then_said() {
    let dir = temp_dir("report-held-frame");
    let (fitted, same) = tracker_campaign(&dir);
    let text = read(Path::new(&same)).replace(",station2\n", ",station3\n");
    let renamed = crate::util::write(&dir, "held3.csv", &text);
    let line = 1 + text.lines().position(|l| l.ends_with(",station3")).unwrap();
    let run = |held: &str, out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec![
            "calibrate",
            "--arm",
            &*arm(),
            "--positions",
            &fitted,
            "--validate-positions",
            held,
            "--method",
            "lm",
            "--out",
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
        args.push(out.display().to_string());
        args.extend(extra.iter().map(|s| s.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        (aacmm(&args), out)
    };
    let (o, out) = run(&renamed, "refused", &[]);
    assert_clean_error(
        &o,
        &[
            &format!("held3.csv:{line}: field `frame`"),
            "`station3` was not fitted",
            "the fitted frames are `station1`, `station2`",
            "--register-held-out",
        ],
    );
    assert!(!out.join("calibration.json").exists());
    let (o, out) = run(&renamed, "asked", &["--register-held-out"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        crate::util::stdout(&o).contains(
            "held out: frame `station3` not fitted, registered on its own positions as asked"
        ),
        "{}",
        crate::util::stdout(&o)
    );
    let json: serde_json::Value =
        serde_json::from_str(&read(&out.join("calibration.json"))).unwrap();
    assert_eq!(
        json.pointer("/validation/held_out/registered_on_itself"),
        Some(&serde_json::json!(["station3"]))
    );
    let html = read(&out.join(HTML_FILE));
    assert!(
        html.contains("frame `station3` not fitted, registered on its own positions (--register-held-out): optimistic"),
        "the page does not say the held-out frame was registered on itself"
    );
    // Held-out frames that were fitted are scored in them, without a word.
    let (o, out) = run(&same, "fitted-frames", &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!crate::util::stdout(&o).contains("registered on its own"));
    assert!(!read(&out.join("calibration.json")).contains("registered_on_itself"));
}
