//! The report on a small simulated campaign: every SVG is XML with the
//! series and points it should hold, the page holds nothing from outside,
//! the same input gives the same bytes, and bad input is an error.

use std::sync::OnceLock;

use roxmltree::{Document, Node};

use super::*;
use crate::calibrate::Calibration;
use crate::calibrate::validate::before_after;
use crate::calibrate::{FixSpec, Method, ModelOptions, SolverSettings, calibrate};
use crate::dataset::DataSet;
use crate::domain::Arm;
use crate::params::DhParams;
use crate::residuals::Noise;
use crate::simulate::{CampaignSettings, ErrorModel, simulate};

/// A fitted campaign (6 sockets × 5 touches, 2 lengths), a held-out one
/// (4 sockets × 4 touches, 1 length) of the same true arm, and the LM fit.
struct Case {
    nominal: DhParams,
    truth: DhParams,
    data: DataSet,
    held: DataSet,
    cal: Calibration,
}

fn case() -> &'static Case {
    static CASE: OnceLock<Case> = OnceLock::new();
    CASE.get_or_init(|| {
        let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
        let mut s = CampaignSettings::new(5, ErrorModel::Paper, 6, 5);
        s.reference_lengths = 2;
        s.encoder_noise_deg = 0.005;
        s.probe_noise_mm = 0.01;
        let fitted = simulate(&nominal, &s).unwrap();
        let mut h = CampaignSettings::new(
            6,
            ErrorModel::File {
                arm: fitted.true_arm.clone(),
            },
            4,
            4,
        );
        h.reference_lengths = 1;
        h.encoder_noise_deg = 0.005;
        h.probe_noise_mm = 0.01;
        let held = simulate(&nominal, &h).unwrap();
        let data = fitted.data_set().unwrap();
        let model = ModelOptions {
            noise: Noise {
                encoder_rad: Some(0.005f64.to_radians()),
                probe_mm: Some(0.01),
                ..Noise::default()
            },
            ..ModelOptions::default()
        };
        let lm = SolverSettings::default().with_method(Method::Lm);
        let cal = calibrate(&nominal.params, &data, &model, &lm).unwrap();
        Case {
            nominal: nominal.params,
            truth: fitted.true_arm.params,
            data,
            held: held.data_set().unwrap(),
            cal,
        }
    })
}

/// The calibration report of `cal` on the case's data (with held-out data
/// when `held`).
fn report_of(c: &Case, cal: &Calibration, held: bool) -> Result<Report, ReportError> {
    report_with(c, cal, held, None)
}

/// [`report_of`] with an uncertainty map.
fn report_with(
    c: &Case,
    cal: &Calibration,
    held: bool,
    map: Option<&crate::plan::UncertaintyMap>,
) -> Result<Report, ReportError> {
    let fb = positions(&c.nominal, &c.data)?;
    let fa = positions(&cal.params, &c.data)?;
    let hb = positions(&c.nominal, &c.held)?;
    let ha = positions(&cal.params, &c.held)?;
    let fitted = before_after(&c.nominal, &cal.params, &c.data).unwrap();
    let held_figures = before_after(&c.nominal, &cal.params, &c.held).unwrap();
    let mut measured = vec![Measured {
        data: &c.data,
        held_out: false,
        before: Some(&fb),
        after: &fa,
    }];
    let mut validation = vec![ValidationRow {
        name: "fitted".into(),
        held_out: false,
        figures: &fitted,
        json: Some("/validation/fitted".into()),
    }];
    if held {
        measured.push(Measured {
            data: &c.held,
            held_out: true,
            before: Some(&hb),
            after: &ha,
        });
        validation.push(ValidationRow {
            name: "held out".into(),
            held_out: true,
            figures: &held_figures,
            json: None,
        });
    }
    calibration_report(&CalibrationInput {
        title: "Calibration <of> `test` & co".into(),
        inputs: vec![("poses".into(), "p.csv".into())],
        calibration: cal,
        calibration_json: Some("/calibration".into()),
        measured,
        arms: Arms {
            before: "nominal".into(),
            after: "calibrated".into(),
        },
        validation,
        truth: Some(&c.truth),
        positions: Vec::new(),
        beyond: Vec::new(),
        uncertainty_map: map,
        uncertainty_map_json: map.map(|_| "/uncertainty_map".into()),
        spheres: None,
        folds: &[],
        held_out_spheres: None,
        tools: None,
        touch_tools: None,
        uncertainty_maps_in_frames: &[],
        uncertainty_maps_at_tools: &[],
        verdict: None,
        seed: 0,
    })
}

fn figure<'a>(r: &'a Report, file: &str) -> &'a str {
    &r.figures.iter().find(|f| f.file == file).unwrap().svg
}

/// Every group of `class` as (name, data-points, node).
fn groups<'a, 'i>(doc: &'a Document<'i>, class: &str) -> Vec<(String, usize, Node<'a, 'i>)> {
    doc.descendants()
        .filter(|n| n.has_tag_name("g") && n.attribute("class") == Some(class))
        .map(|n| {
            (
                n.attribute("data-name").unwrap().to_string(),
                n.attribute("data-points").unwrap().parse().unwrap(),
                n,
            )
        })
        .collect()
}

/// Children of `g` named `tag`.
fn count(g: Node, tag: &str) -> usize {
    g.children().filter(|c| c.has_tag_name(tag)).count()
}

/// Markers of a group: one circle, polygon or rect each.
fn markers(g: Node) -> usize {
    count(g, "circle") + count(g, "polygon") + count(g, "rect")
}

#[test]
fn every_figure_is_xml_with_its_series_and_points() {
    let c = case();
    let r = report_of(c, &c.cal, true).unwrap();
    let files: Vec<&str> = r.files().map(|(f, _)| f).collect();
    assert_eq!(files, CALIBRATION_FILES);
    for f in &r.figures {
        let doc = Document::parse(&f.svg).unwrap_or_else(|e| panic!("{}: {e}", f.file));
        assert!(doc.root_element().has_tag_name("svg"), "{}", f.file);
        let title = doc.root_element().first_element_child().unwrap();
        assert!(title.has_tag_name("title"), "{}", f.file);
        assert_eq!(title.text(), Some(f.title.as_str()));
    }

    // 1: a series per data set and arm, one marker per point.
    let doc = Document::parse(figure(&r, SINGLE_POINT_SVG)).unwrap();
    let s = groups(&doc, "series");
    let names: Vec<&str> = s.iter().map(|g| g.0.as_str()).collect();
    assert_eq!(
        names,
        [
            "nominal, fitted",
            "calibrated, fitted",
            "nominal, held out",
            "calibrated, held out"
        ]
    );
    for (name, n, g) in &s {
        let points = if name.ends_with("fitted") { 6 } else { 4 };
        assert_eq!((*n, markers(*g)), (points, points), "{name}");
    }
    assert_eq!(groups(&doc, "guide").len(), 4, "a mean line per series");

    // 2: every pair (15 fitted, 6 held out) and every reference length.
    let doc = Document::parse(figure(&r, LENGTHS_SVG)).unwrap();
    for (name, n, g) in groups(&doc, "series") {
        let expected = match (name.contains("reference"), name.contains("fitted")) {
            (false, true) => 15,
            (false, false) => 6,
            (true, true) => 2,
            (true, false) => 1,
        };
        assert_eq!((n, markers(g)), (expected, expected), "{name}");
    }
    assert_eq!(groups(&doc, "series").len(), 8);

    // 3: 21 free corrections, 6 fixed, 27 true errors.
    let doc = Document::parse(figure(&r, PARAMETERS_SVG)).unwrap();
    let s = groups(&doc, "series");
    let total = |name: &str, f: fn(Node) -> usize| -> (usize, usize) {
        s.iter()
            .filter(|g| g.0 == name)
            .fold((0, 0), |(a, b), g| (a + g.1, b + f(g.2)))
    };
    assert_eq!(total("free corrections", |g| count(g, "circle")), (21, 21));
    assert_eq!(total("fixed parameters", |g| count(g, "polyline")), (6, 6));
    assert_eq!(total("true errors", |g| count(g, "circle")), (27, 27));

    // 4: singular values of all 27 columns; a 21 × 21 heat map.
    let doc = Document::parse(figure(&r, IDENTIFIABILITY_SVG)).unwrap();
    let s = groups(&doc, "series");
    let id = c.cal.identification.as_ref().unwrap();
    let by = |name: &str| s.iter().find(|g| g.0 == name).unwrap();
    assert_eq!(by("all columns").1, 27);
    assert_eq!(markers(by("all columns").2), 27);
    assert_eq!(by("analysed").1, id.analysed_singular_values.len());
    assert_eq!(
        (
            by("correlation cells").1,
            count(by("correlation cells").2, "rect")
        ),
        (441, 441)
    );

    // 5: a histogram per data set and arm.
    let doc = Document::parse(figure(&r, RESIDUALS_SVG)).unwrap();
    let s = groups(&doc, "series");
    assert_eq!(s.len(), 4);
    assert!(s.iter().all(|g| g.1 == figures::residuals::BINS));

    // 6: the start and each accepted step; the rejected ones.
    let doc = Document::parse(figure(&r, SOLVER_SVG)).unwrap();
    let s = groups(&doc, "series");
    let h = &c.cal.solver.history;
    let accepted = h.iter().filter(|i| i.accepted).count();
    let by = |name: &str| s.iter().find(|g| g.0 == name).unwrap();
    assert_eq!(
        (by("accepted").1, markers(by("accepted").2)),
        (accepted + 1, accepted + 1)
    );
    assert_eq!(by("rejected").1, h.len() - accepted);
}

#[test]
fn the_page_is_self_contained_xml_and_the_same_bytes_twice() {
    let c = case();
    let r = report_of(c, &c.cal, true).unwrap();
    let html = &r.html;
    assert!(html.starts_with("<!DOCTYPE html>"));
    let lower = html.to_lowercase();
    for bad in [
        "<script", "src=", "<link", "@import", "url(", "<iframe", "<img",
    ] {
        assert!(!lower.contains(bad), "the page holds `{bad}`");
    }
    let doc = Document::parse_with_options(
        html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    for n in doc.descendants().filter(|n| n.has_attribute("href")) {
        assert!(n.attribute("href").unwrap().starts_with('#'), "{n:?}");
    }
    // Every figure inline, and the title escaped.
    assert_eq!(
        doc.descendants().filter(|n| n.has_tag_name("svg")).count(),
        6
    );
    assert!(html.contains("Calibration &lt;of&gt; `test` &amp; co"));
    // Numbers carry their place in the JSON, in full.
    let cell = doc
        .descendants()
        .find(|n| n.attribute("data-json") == Some("/calibration/parameters/1/correction"))
        .unwrap();
    let v: f64 = cell.attribute("data-value").unwrap().parse().unwrap();
    assert_eq!(v, c.cal.parameters[1].correction);
    assert_eq!(cell.text().unwrap(), format!("{v:.6}"));

    let again = report_of(c, &c.cal, true).unwrap();
    assert_eq!(again, r);
}

#[test]
fn solver_and_identifiability_branches_draw_notes_instead_of_data() {
    let c = case();
    let mut cal = c.cal.clone();
    cal.identification = None;
    cal.solver.history.clear();
    cal.solver.method = Method::Sa;
    cal.solver.anneal = Some(crate::calibrate::AnnealTrace {
        options: Default::default(),
        switch_rule: None,
        stop: crate::calibrate::AnnealStop::Cooled,
        start_energy: 8.0,
        best_energy: 6.0,
        evaluations: 300,
        temperatures: (0..3)
            .map(|k| crate::calibrate::AnnealStep {
                temperature: 0.9f64.powi(k),
                energy: 8.0 - k as f64,
                best: 8.0 - k as f64,
                acceptance: 0.1,
            })
            .collect(),
    });
    let r = report_of(c, &cal, false).unwrap();
    let id = Document::parse(figure(&r, IDENTIFIABILITY_SVG)).unwrap();
    assert!(
        id.descendants()
            .any(|n| n.text().map(str::trim) == Some("no identifiability analysis ran."))
    );
    let solver = Document::parse(figure(&r, SOLVER_SVG)).unwrap();
    let s = groups(&solver, "series");
    let names: Vec<&str> = s.iter().map(|g| g.0.as_str()).collect();
    assert_eq!(names, ["energy", "best energy", "acceptance"]);
    assert!(s.iter().all(|g| g.1 == 3));
    assert!(r.html.contains("No held-out data were given"));
}

#[test]
fn evaluation_report_has_three_figures_of_one_arm() {
    let c = case();
    let xyz = positions(&c.truth, &c.data).unwrap();
    let r = evaluation_report(&EvaluationInput {
        title: "Evaluation".into(),
        inputs: vec![],
        measured: Measured {
            data: &c.data,
            held_out: false,
            before: None,
            after: &xyz,
        },
        arm: "true".into(),
        evaluation_json: Some("/evaluation".into()),
    })
    .unwrap();
    let files: Vec<&str> = r.files().map(|(f, _)| f).collect();
    assert_eq!(files, EVALUATION_FILES);
    let doc = Document::parse(figure(&r, SINGLE_POINT_SVG)).unwrap();
    let s = groups(&doc, "series");
    assert_eq!(s.len(), 1);
    assert_eq!((s[0].0.as_str(), s[0].1), ("true, measured", 6));
    let page = Document::parse_with_options(
        &r.html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        page.descendants()
            .any(|n| n.attribute("data-json") == Some("/evaluation/points/5/two_s"))
    );
}

#[test]
fn bad_positions_are_errors_not_panics() {
    let c = case();
    let xyz = positions(&c.nominal, &c.data).unwrap();
    let input = |after: &'static [[f64; 3]]| EvaluationInput {
        title: String::new(),
        inputs: vec![],
        measured: Measured {
            data: &c.data,
            held_out: false,
            before: None,
            after,
        },
        arm: "a".into(),
        evaluation_json: None,
    };
    let short: &'static [[f64; 3]] = Box::leak(xyz[1..].to_vec().into_boxed_slice());
    let e = evaluation_report(&input(short)).unwrap_err();
    assert!(
        matches!(
            e,
            ReportError::Positions {
                got: 29,
                expected: 30,
                ..
            }
        ),
        "{e}"
    );
    let mut nan = xyz.clone();
    nan[3][1] = f64::NAN;
    let nan: &'static [[f64; 3]] = Box::leak(nan.into_boxed_slice());
    let e = evaluation_report(&input(nan)).unwrap_err();
    assert!(e.to_string().contains("not a finite number"), "{e}");
    // Exact data: every e is 0 and the log axes still draw.
    let exact: Vec<[f64; 3]> = c
        .data
        .points()
        .iter()
        .flat_map(|p| {
            p.touches
                .clone()
                .map(move |_| [p.touches.start as f64, 0.0, 0.0])
        })
        .collect();
    let exact: &'static [[f64; 3]] = Box::leak(exact.into_boxed_slice());
    let r = evaluation_report(&input(exact)).unwrap();
    for f in &r.figures {
        Document::parse(&f.svg).unwrap();
    }
}

#[test]
fn a_user_fixed_set_reads_as_the_users_choice() {
    let c = case();
    let model = ModelOptions {
        fix: FixSpec::parse("theta1,d1,theta6,alpha6,Bx,By", 6).unwrap(),
        ..ModelOptions::default()
    };
    let lm = SolverSettings::default().with_method(Method::Lm);
    let cal = calibrate(&c.nominal, &c.data, &model, &lm).unwrap();
    let r = report_of(c, &cal, false).unwrap();
    let svg = figure(&r, PARAMETERS_SVG);
    assert_eq!(svg.matches("user&apos;s choice").count(), 6, "{svg}");
}

#[test]
fn one_point_without_lengths_says_what_cannot_be_drawn() {
    let c = case();
    let one = c.data.subset(&[2]);
    let xyz = positions(&c.nominal, &one).unwrap();
    let r = evaluation_report(&EvaluationInput {
        title: "one point".into(),
        inputs: vec![],
        measured: Measured {
            data: &one,
            held_out: false,
            before: None,
            after: &xyz,
        },
        arm: "nominal".into(),
        evaluation_json: None,
    })
    .unwrap();
    let lengths = figure(&r, LENGTHS_SVG);
    assert!(
        lengths.contains("A single point has no pairs."),
        "{lengths}"
    );
    assert!(
        lengths.contains("No reference lengths were given:"),
        "{lengths}"
    );
    assert!(r.html.contains("No pairs of points"));
    for f in &r.figures {
        Document::parse(&f.svg).unwrap();
    }
}

#[test]
fn the_uncertainty_map_has_its_figure_section_and_table() {
    use crate::plan::{sample_poses, uncertainty_map};
    let c = case();
    let (free, cov) = c.cal.geometry_covariance().unwrap();
    let poses = sample_poses(&[None; 6], 0, 400, 7);
    let map = uncertainty_map(&c.cal.params, &poses, &free, &cov, "the test's full turns").unwrap();
    let r = report_with(c, &c.cal, false, Some(&map)).unwrap();
    let files: Vec<&str> = r.files().map(|(f, _)| f).collect();
    assert_eq!(files[..CALIBRATION_FILES.len()], CALIBRATION_FILES);
    assert_eq!(files[CALIBRATION_FILES.len()..], [UNCERTAINTY_MAP_SVG]);

    // A marker per point, in the bands of height; a step per band of reach.
    let doc = Document::parse(figure(&r, UNCERTAINTY_MAP_SVG)).unwrap();
    let s = groups(&doc, "series");
    assert!(!s.is_empty() && s.len() <= 3, "{}", s.len());
    assert!(
        s.iter()
            .all(|g| g.0.starts_with("height above the shoulder"))
    );
    let total: (usize, usize) = s
        .iter()
        .fold((0, 0), |(a, b), g| (a + g.1, b + markers(g.2)));
    assert_eq!(total, (map.points.len(), map.points.len()));
    let bands = map.regions.iter().filter(|b| b.poses > 0).count();
    let guides = groups(&doc, "guide");
    assert_eq!(guides.len(), 1);
    assert_eq!((guides[0].0.as_str(), guides[0].1), ("RMS per band", bands));

    // The section, numbered after the six, in the navigation; the sentence
    // with the map's own numbers; every number of the table in full.
    let html = &r.html;
    assert!(html.contains("<a href=\"#uncertainty-map\">7 Uncertainty map</a>"));
    assert!(html.contains("<h2>7. Predicted position uncertainty over the workspace</h2>"));
    assert!(
        html.contains(
            "holds the calibrated probe position's error with 95 % probability (2.80 σ for \
             an isotropic 3-D error, not 2 σ), over 400 poses sampled within the test&#39;s \
             full turns"
        ),
        "{html}"
    );
    let page = Document::parse_with_options(
        html,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    let cell = |pointer: &str| -> f64 {
        let n = page
            .descendants()
            .find(|n| n.attribute("data-json") == Some(pointer))
            .unwrap_or_else(|| panic!("{pointer}"));
        n.attribute("data-value").unwrap().parse().unwrap()
    };
    for (i, b) in map.regions.iter().enumerate() {
        let at = |f: &str| format!("/uncertainty_map/regions/{i}/{f}");
        assert_eq!(cell(&at("reach_from_mm")), b.reach_from_mm);
        assert_eq!(cell(&at("reach_to_mm")), b.reach_to_mm);
        assert_eq!(cell(&at("poses")), b.poses as f64);
        assert_eq!(cell(&at("rms_mm")), b.rms_mm);
        assert_eq!(cell(&at("max_mm")), b.max_mm);
    }
    assert_eq!(cell("/uncertainty_map/median_mm"), map.median_mm);
    assert_eq!(cell("/uncertainty_map/poses"), 400.0);

    // Without a map: neither section nor figure.
    let without = report_of(c, &c.cal, false).unwrap();
    assert!(!without.html.contains("uncertainty-map"));
    assert!(
        without
            .figures
            .iter()
            .all(|f| f.file != UNCERTAINTY_MAP_SVG)
    );
}
