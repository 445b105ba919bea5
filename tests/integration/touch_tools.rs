//! Touches made by several probes (a `tool` column in a poses file, issues
//! 40/41): each probe's offset fitted from its own touches — recovered
//! within 3σ —, the arm as from one probe's touches alone, the same bytes
//! on any thread count, and bad input refused by file, line and field.

use aacmm_core::calibrate::{Method, SolverSettings};
use aacmm_core::domain::{Arm, Poses, Spheres, Tool, arm_with_tool};
use aacmm_core::io::{AngleUnit, parse_lengths, parse_poses, write_poses};
use aacmm_core::params::{DhParams, ParamKind};
use aacmm_core::residuals::spheres::{SphereSize, SphereTerm};
use aacmm_core::simulate::{
    Campaign, CampaignSettings, ErrorModel, SphereSettings, simulate, simulate_spheres, true_arm,
};
use aacmm_core::{Calibration, DataSet, ModelOptions, Problem};
use rand::SeedableRng;

/// The second probe's nominal offset (mm, the last joint's frame).
const LONG: [f64; 3] = [20.0, -10.0, 180.0];
/// How far the true second probe is from its nominal offset, mm.
const LONG_ERROR: [f64; 3] = [0.12, -0.08, 0.15];
const ENCODER_DEG: f64 = 0.003;
const BALL: f64 = 6.0;
const LONG_BALL: f64 = 3.0;
const SPHERE: f64 = 25.4;
const PROBE_MM: f64 = 0.003;

/// The paper's arm with a 6 mm ball and a second probe, `long` (a 3 mm
/// ball).
fn nominal() -> Arm {
    Arm {
        ball_diameter_mm: Some(BALL),
        tools: vec![Tool {
            name: "long".into(),
            offset: LONG,
            ball_diameter_mm: Some(LONG_BALL),
        }],
        ..Arm::without_limits("paper", DhParams::paper_nominal())
    }
}

/// The true arm of `seed`: the paper's errors, `long` off its nominal.
fn truth(nominal: &Arm, seed: u64) -> Arm {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut t = true_arm(nominal, &ErrorModel::Paper, &mut rng).unwrap();
    t.tools[0].offset = std::array::from_fn(|k| LONG[k] + LONG_ERROR[k]);
    t
}

/// A campaign of `sockets` sockets touched `poses` times each by `tool` of
/// `truth`.
fn touched_by(
    nominal: &Arm,
    truth: &Arm,
    tool: &str,
    seed: u64,
    (sockets, poses): (usize, usize),
) -> Campaign {
    let settings = CampaignSettings {
        encoder_noise_deg: ENCODER_DEG,
        probe_noise_mm: PROBE_MM,
        reference_lengths: 6,
        ..CampaignSettings::new(
            seed,
            ErrorModel::File {
                arm: arm_with_tool(truth, tool).unwrap(),
            },
            sockets,
            poses,
        )
    };
    simulate(&arm_with_tool(nominal, tool).unwrap(), &settings).unwrap()
}

/// The rows of `parts` (a tool, its campaign, a prefix for its labels)
/// as one poses file's text, with a `tool` column when some part is not
/// the default probe's.
fn poses_text(parts: &[(&str, &Campaign, &str)]) -> String {
    let mut poses = Poses::new(parts[0].1.poses.joints());
    let mut line = 2;
    for (tool, c, prefix) in parts {
        for row in 0..c.poses.len() {
            poses.push(
                &format!("{prefix}{}", c.poses.label(row)),
                c.poses.reading(row),
                line,
            );
            if *tool != "probe" {
                poses.set_tool(tool);
            }
            line += 1;
        }
    }
    let mut out = Vec::new();
    write_poses(&mut out, &poses, AngleUnit::Rad).unwrap();
    String::from_utf8(out).unwrap()
}

/// The data set of `text` (a poses file), with `lengths` (of the default
/// probe's campaign) when given.
fn data_of(text: &str, lengths: Option<&Campaign>) -> DataSet {
    let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Rad, Some(6)).unwrap();
    let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    match lengths {
        Some(c) => data.with_lengths(&c.lengths, "l.csv").unwrap(),
        None => data,
    }
}

fn model() -> ModelOptions {
    let mut m = ModelOptions::default();
    m.noise.encoder_rad = Some(ENCODER_DEG.to_radians());
    m.noise.probe_mm = Some(PROBE_MM);
    m
}

fn calibrate(nominal: &Arm, data: DataSet, threads: usize) -> Calibration {
    calibrate_with(nominal, data, None, threads)
}

/// The fit of `data` and, when given, of `spheres`' points (the diameter
/// stated) from `nominal`.
fn calibrate_with(
    nominal: &Arm,
    data: DataSet,
    spheres: Option<&Spheres>,
    threads: usize,
) -> Calibration {
    let mut settings = SolverSettings::default().with_method(Method::Lm);
    settings.threads = threads;
    let mut p = Problem::new(nominal.clone(), data, model()).unwrap();
    if let Some(rows) = spheres {
        let term = SphereTerm::new(
            rows.clone(),
            "spheres.csv",
            &nominal.params,
            SphereSize::Known(SPHERE),
            nominal.ball_diameter_mm,
            &model().noise,
            |b| p.add_boxed_block(b),
        )
        .unwrap();
        p = p.with_spheres(term);
    }
    let report = p.run(&settings).unwrap();
    assert!(report.verdict.usable, "{:?}", report.verdict);
    report.calibration
}

/// `truth`'s points on spheres: `placements` by its probe (`S1`, …) and
/// as many by its `long` stylus (`L1`, …, the rows naming it).
fn sphere_points(truth: &Arm, placements: usize, seed: u64) -> Spheres {
    let settings = |ball: f64, seed: u64| SphereSettings {
        placements,
        diameter_mm: SPHERE,
        ball_diameter_mm: ball,
        encoder_rad: ENCODER_DEG.to_radians(),
        probe_mm: PROBE_MM,
        seed,
    };
    let by_probe = simulate_spheres(truth, &settings(BALL, seed)).unwrap();
    let stylus = arm_with_tool(truth, "long").unwrap();
    let by_long = simulate_spheres(&stylus, &settings(LONG_BALL, seed + 1)).unwrap();
    let mut out = by_probe.spheres.clone();
    let b = &by_long.spheres;
    for i in 0..b.len() {
        let name = b.spheres()[b.sphere(i)].replacen('S', "L", 1);
        out.push(&name, b.reading(i), out.len() + 2, None);
        out.set_tool(&truth.tools[0]);
    }
    out
}

/// `(combined − alone)/σ_alone` of every parameter free in both fits.
fn against(combined: &Calibration, alone: &Calibration) -> Vec<(String, f64)> {
    let mut z = Vec::new();
    for (e, one) in combined.parameters.iter().zip(&alone.parameters) {
        assert_eq!(e.id, one.id);
        let (Some(s), None, None) = (one.sigma, one.fixed.as_ref(), e.fixed.as_ref()) else {
            continue;
        };
        z.push((format!("{:?}", e.id), (e.calibrated - one.calibrated) / s));
    }
    z
}

fn rms(z: &[(String, f64)]) -> f64 {
    (z.iter().map(|(_, z)| z * z).sum::<f64>() / z.len().max(1) as f64).sqrt()
}

/// Per axis, `(estimate − truth)/σ` of the default probe's `B` and of
/// `long`'s offset.
fn probe_errors(cal: &Calibration, truth: &Arm) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    for e in (cal.parameters.iter()).filter(|e| e.id.kind == ParamKind::Probe) {
        // A column the data cannot tell from another (`Bx` from `a6`) is
        // held at its nominal.
        let Some(sigma) = e.sigma.filter(|_| e.fixed.is_none()) else {
            continue;
        };
        let want = truth.params.probe[e.id.index];
        out.push((format!("B{}", e.id.index), (e.calibrated - want) / sigma));
    }
    let (name, x, sigma) = (cal.tool_estimates().into_iter())
        .find(|(n, _, _)| n == "long")
        .expect("long fitted");
    let sigma = sigma.expect("long's σ");
    for k in 0..3 {
        out.push((
            format!("{name}.{k}"),
            (x[k] - truth.tools[0].offset[k]) / sigma[k],
        ));
    }
    out
}

/// The probe's and long's campaigns of `seed`, the long's sockets others
/// (labels `L…`) than the probe's.
fn campaigns(nominal: &Arm, seed: u64) -> (Arm, Campaign, Campaign) {
    let truth = truth(nominal, seed);
    let a = touched_by(nominal, &truth, "probe", seed + 100, (12, 10));
    let b = touched_by(nominal, &truth, "long", seed + 200, (12, 10));
    (truth, a, b)
}

#[test]
fn each_probes_offset_is_recovered_within_three_sigma() {
    let nominal = nominal();
    for seed in 1..=4 {
        let (truth, a, b) = campaigns(&nominal, seed);
        let data = data_of(
            &poses_text(&[("probe", &a, ""), ("long", &b, "L")]),
            Some(&a),
        );
        assert_eq!(data.touch_tools().unwrap().names(), ["probe", "long"]);
        let cal = calibrate(&nominal, data, 1);
        for (name, z) in probe_errors(&cal, &truth) {
            assert!(z.abs() < 3.0, "seed {seed}: {name} off by {z:.2} σ");
        }
        // Its offset moved from the nominal towards the truth (0.2 mm off).
        let long = cal.tool_offsets()[0].1;
        let miss = |x: [f64; 3]| {
            (0..3)
                .map(|k| (x[k] - truth.tools[0].offset[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        assert!(miss(long) < 0.3 * miss(LONG), "seed {seed}: {long:?}");
    }
}

#[test]
fn the_arm_agrees_with_one_probes_touches_alone() {
    let nominal = nominal();
    let (_, a, b) = campaigns(&nominal, 7);
    let both = calibrate(
        &nominal,
        data_of(
            &poses_text(&[("probe", &a, ""), ("long", &b, "L")]),
            Some(&a),
        ),
        1,
    );
    let alone = calibrate(
        &nominal,
        data_of(&poses_text(&[("probe", &a, "")]), Some(&a)),
        1,
    );
    for (e, one) in both.parameters.iter().zip(&alone.parameters) {
        // The second probe's touches say more about the arm: every σ
        // smaller.
        if let (Some(b), Some(s), None) = (e.sigma, one.sigma, one.fixed.as_ref()) {
            assert!(b < s, "{:?}: σ {b} with both, {s} alone", e.id);
        }
    }
    let z = against(&both, &alone);
    assert!(
        rms(&z) < 1.0 && rms(&z) > 0.0,
        "RMS {:.2} σ: {z:?}",
        rms(&z)
    );
    for (id, z) in &z {
        assert!(z.abs() < 3.0, "{id}: {z:.2} σ of the one-probe fit");
    }
}

/// Issue 41's combined calibration: two probes' touches, both probes'
/// points on spheres (their `tool` column) and lengths in one fit — each
/// probe's offset recovered within 3σ (one `tool.long` block, shared by
/// the touches and the sphere points), the arm within σ of the touches
/// alone and of the spheres alone.
#[test]
fn touches_spheres_and_lengths_of_two_probes_in_one_fit() {
    let nominal = nominal();
    let (truth, a, b) = campaigns(&nominal, 21);
    let text = poses_text(&[("probe", &a, ""), ("long", &b, "L")]);
    let spheres = sphere_points(&truth, 4, 2100);
    let combined = calibrate_with(&nominal, data_of(&text, Some(&a)), Some(&spheres), 1);
    for (name, z) in probe_errors(&combined, &truth) {
        assert!(z.abs() < 3.0, "{name} off by {z:.2} σ");
    }
    let long: Vec<_> = (combined.auxiliary.iter())
        .filter(|c| c.name.starts_with("tool.long."))
        .collect();
    assert_eq!(long.len(), 3, "one block for the stylus");
    let touches = calibrate(&nominal, data_of(&text, Some(&a)), 1);
    let alone = calibrate_with(&nominal, DataSet::without_touches(6, 0), Some(&spheres), 1);
    for (kind, one) in [("touches", &touches), ("spheres", &alone)] {
        let z = against(&combined, one);
        assert!(z.len() > 10, "{kind}: {z:?}");
        assert!(rms(&z) < 1.0, "{kind}: RMS {:.2} σ: {z:?}", rms(&z));
        for (id, z) in &z {
            assert!(z.abs() < 3.0, "{kind}: {id} {z:.2} σ");
        }
    }
}

#[test]
fn a_file_without_tools_reads_as_before_and_keeps_its_bytes() {
    let nominal = nominal();
    let (_, a, _) = campaigns(&nominal, 3);
    let text = poses_text(&[("probe", &a, "")]);
    assert!(!text.lines().next().unwrap().contains("tool"));
    let plain = DataSet::from_poses(&a.poses, "p.csv").unwrap();
    let read = data_of(&text, None);
    assert!(read.touch_tools().is_none());
    assert_eq!(read.points(), plain.points());
    // An empty tool column is the default probe's: the same fit, bit for bit.
    let with_empty = text.replacen("q6\n", "q6,tool\n", 1).replace('\n', ",\n");
    let with_empty = with_empty.replacen("q6,tool,\n", "q6,tool\n", 1);
    let empty = data_of(&with_empty, None);
    assert!(empty.touch_tools().is_none());
    let (x, y) = (calibrate(&nominal, read, 1), calibrate(&nominal, empty, 1));
    assert_eq!(x.calibrated_vector(), y.calibrated_vector());
}

#[test]
fn two_probes_give_the_same_bytes_on_one_and_two_threads() {
    let nominal = nominal();
    let truth = truth(&nominal, 11);
    // Enough points that the touch term's chunks split between threads.
    let a = touched_by(&nominal, &truth, "probe", 1100, (260, 3));
    let b = touched_by(&nominal, &truth, "long", 1200, (260, 3));
    // The long probe's rows first in the file: the probe's points first all
    // the same, each tool's contiguous.
    let text = poses_text(&[("long", &b, "L"), ("probe", &a, "")]);
    let data = data_of(&text, Some(&a));
    let runs = data.touch_tools().unwrap().runs();
    assert_eq!(runs, [(0, 0..260), (1, 260..520)]);
    assert!(
        aacmm_core::parallel::threads_for(
            aacmm_core::residuals::point_chunks(data.points().len()),
            2
        ) == 2
    );
    let one = calibrate(&nominal, data.clone(), 1);
    let two = calibrate(&nominal, data, 2);
    let bits = |c: &Calibration| -> Vec<u64> {
        (c.calibrated_vector().iter())
            .chain(c.auxiliary.iter().map(|a| &a.calibrated))
            .map(|v| v.to_bits())
            .collect()
    };
    assert_eq!(bits(&one), bits(&two));
}

#[test]
fn bad_tools_are_refused_by_file_line_and_field() {
    let nominal = nominal();
    let (_, a, b) = campaigns(&nominal, 5);
    // A tool the arm does not know: its first row named.
    let text = poses_text(&[("probe", &a, ""), ("short", &b, "L")]);
    let (poses, _) = parse_poses(&text, "p.csv", AngleUnit::Rad, Some(6)).unwrap();
    let first = poses.lines()[a.poses.len()];
    let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    let e = Problem::new(nominal.clone(), data, model())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("p.csv:{first}")) && e.contains("`tool`") && e.contains("`short`"),
        "{e}"
    );
    assert!(e.contains("`probe`, `long`"), "{e}");
    // A length naming a label both probes touched: ambiguous.
    let text = poses_text(&[("probe", &a, ""), ("long", &b, "")]);
    let (poses, _) = parse_poses(&text, "p.csv", AngleUnit::Rad, Some(6)).unwrap();
    let data = DataSet::from_poses(&poses, "p.csv").unwrap();
    let l = parse_lengths("point_a,point_b,distance\nS1,S2,500\n", "l.csv").unwrap();
    let e = data.with_lengths(&l, "l.csv").unwrap_err().to_string();
    assert!(
        e.starts_with("l.csv:2: field `point_a`: point `S1` was touched by several tools"),
        "{e}"
    );
    // The annealer sees every touch through the probe: refused by name.
    let data = data_of(&poses_text(&[("probe", &a, ""), ("long", &b, "L")]), None);
    let e = Problem::new(nominal.clone(), data, model())
        .unwrap()
        .run(&SolverSettings::default().with_method(Method::Sa))
        .unwrap_err()
        .to_string();
    assert!(e.contains("method") && e.contains("tool"), "{e}");
    // A one-probe stage refuses the rows of another, at the first one.
    let e = poses
        .refuse_tools("p.csv", "points")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&format!("p.csv:{first}: field `tool`")),
        "{e}"
    );
}

/// The session's report has a table of the probes the touches name: per
/// probe its touches, its fitted offset (the stylus's the fit's own, with
/// σ) and its touches' spread about their points' centres — far smaller
/// after than before, and after of the noise's size (0.003° per encoder
/// at a 0.6–1 m reach, 0.003 mm of probe: ≈ 0.04 mm in 3-D); the summary
/// and the page show it, and a file naming no probe has none.
#[test]
fn the_report_has_a_row_per_probe_of_the_touches() {
    use aacmm_core::session::Request;
    let nominal = nominal();
    let (_, a, b) = campaigns(&nominal, 5);
    let text = poses_text(&[("probe", &a, ""), ("long", &b, "L")]);
    let run = |text: &str| {
        let request = Request::new(nominal.clone(), data_of(text, Some(&a)));
        (request.noise(model().noise).method("lm").threads(Some(1)))
            .run()
            .unwrap()
    };
    let (problem, report) = run(&text);
    let t = report.touch_tools.as_ref().expect("a table of the probes");
    assert_eq!(t.file, "p.csv");
    let names: Vec<&str> = t.tools.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(names, ["probe", "long"]);
    assert_eq!(
        (t.tools[0].rows, t.tools[1].rows),
        (a.poses.len(), b.poses.len())
    );
    let long = &report.calibration.tool_estimates()[0];
    assert_eq!((t.tools[1].offset, t.tools[1].sigma), (long.1, long.2));
    assert_eq!(t.tools[1].nominal, LONG);
    for r in &t.tools {
        assert!(
            r.rms_after < 0.05 * r.rms_before && r.rms_after < 0.08,
            "{}: {} → {} mm",
            r.name,
            r.rms_before,
            r.rms_after
        );
    }
    assert!(report.tools.is_none(), "no positions");
    let summary = report.summary();
    assert!(summary.contains("Tool points (p.csv)"), "{summary}");
    assert!(report.to_json().contains("\"touch_tools\""));
    // The page has the section, and its sections are numbered 1, 2, … in
    // order (the touches' were numbered as if no section came before).
    let page = aacmm_core::report::session_report(&report, &problem)
        .unwrap()
        .html;
    assert!(page.contains("<th>RMS from the centre, nominal</th>"));
    let numbers: Vec<usize> = (page.split("<h2>").skip(1))
        .filter_map(|h| h.split_once(". ")?.0.parse().ok())
        .collect();
    assert!(numbers.len() > 5, "{numbers:?}");
    assert_eq!(numbers, (1..=numbers.len()).collect::<Vec<_>>());
    let plain = run(&poses_text(&[("probe", &a, "")])).1;
    assert!(plain.touch_tools.is_none());
    assert!(!plain.summary().contains("Tool points"));
    assert!(!plain.to_json().contains("touch_tools"));
}

/// The uncertainty map at the stylus (`long`, its fitted offset in place
/// of the probe, its offset's uncertainty and correlation with the arm
/// counted in) against 120 campaigns of one design (the same poses, new
/// encoder noise and new length errors each time): at 40 workspace poses
/// the spread of the calibrated stylus positions about their mean is what
/// the first campaign's map predicts — the RMS over the poses of the
/// empirical 95 % radius within 12 % of the map's (measured: 1.03 times;
/// the geometry's covariance alone at the stylus, its offset's left out,
/// predicts 0.76 of the spread and fails). The session's report carries
/// the map, named by its tool.
#[test]
fn the_map_at_a_stylus_matches_monte_carlo() {
    use aacmm_core::plan::uncertainty_map_at_tool;
    use aacmm_core::session::Request;
    let nominal = nominal();
    let truth = truth(&nominal, 31);
    let exact = |tool: &str, seed: u64, (sockets, touches): (usize, usize)| {
        let settings = CampaignSettings {
            encoder_noise_deg: 0.0,
            probe_noise_mm: 0.0,
            reference_lengths: sockets.min(6),
            ..CampaignSettings::new(
                seed,
                ErrorModel::File {
                    arm: arm_with_tool(&truth, tool).unwrap(),
                },
                sockets,
                touches,
            )
        };
        simulate(&arm_with_tool(&nominal, tool).unwrap(), &settings).unwrap()
    };
    // The stylus touches few sockets: its offset's own uncertainty is a
    // large share of the map's at the stylus.
    let (a, b) = (exact("probe", 3100, (12, 10)), exact("long", 3200, (3, 6)));
    let workspace = exact("long", 3300, (4, 10)).poses;
    let rows: Vec<&[f64]> = (0..40).map(|i| workspace.reading(i)).collect();
    let poses = aacmm_core::kernel::PreparedPoses::new(6, &rows).unwrap();
    let mut noise = model().noise;
    noise.probe_mm = None;
    let sigma = ENCODER_DEG.to_radians();
    let length_sigma = noise.length_default_mm;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(77);
    let mut draw = |s: f64| s * crate::util::normal(&mut rng);
    let (mut predicted, mut map) = (Vec::new(), None);
    for run in 0..120 {
        let mut poses_of = Poses::new(6);
        for (tool, c, prefix) in [("probe", &a, ""), ("long", &b, "L")] {
            for i in 0..c.poses.len() {
                let q: Vec<f64> = (c.poses.reading(i).iter())
                    .map(|v| v + draw(sigma))
                    .collect();
                poses_of.push(&format!("{prefix}{}", c.poses.label(i)), &q, i + 2);
                if tool != "probe" {
                    poses_of.set_tool(tool);
                }
            }
        }
        let mut lengths = a.lengths.clone();
        lengths
            .iter_mut()
            .for_each(|l| l.distance += draw(length_sigma));
        let data = (DataSet::from_poses(&poses_of, "p.csv").unwrap())
            .with_lengths(&lengths, "l.csv")
            .unwrap();
        let mut settings = SolverSettings::default().with_method(Method::Lm);
        settings.threads = 1;
        let report = (Problem::new(
            nominal.clone(),
            data.clone(),
            ModelOptions {
                noise,
                ..ModelOptions::default()
            },
        ))
        .unwrap()
        .run(&settings)
        .unwrap();
        let c = &report.calibration;
        let (_, x, _) = c.tool_estimates().remove(0);
        if run == 0 {
            // The reported covariance is scaled by this campaign's σ̂₀²;
            // the spread over campaigns is the stated noise's.
            let (free, at, cov) = c.tool_covariance("long").unwrap();
            assert_eq!(at, x);
            let cov = cov / c.dof.sigma0.powi(2);
            let m = uncertainty_map_at_tool(&c.params, &poses, &free, &cov, ("long", x), "test");
            map = Some(m.unwrap());
            // The session's report has the map at the stylus, by name.
            let session = Request::new(nominal.clone(), data)
                .noise(noise)
                .method("lm")
                .threads(Some(1))
                .run()
                .unwrap()
                .1;
            let at_tools = &session.uncertainty_maps_at_tools;
            assert_eq!(at_tools.len(), 1);
            assert_eq!(at_tools[0].tool.as_deref(), Some("long"));
            assert!(session.summary().contains("at tool point `long`"));
        }
        let mut arm = c.params.clone();
        arm.probe = x;
        let k = aacmm_core::kernel::ArmKernel::new(&arm).unwrap();
        predicted.push(
            rows.iter()
                .map(|q| k.position(q).unwrap())
                .collect::<Vec<_>>(),
        );
    }
    let map = map.unwrap();
    let (_, empirical) = crate::util::spread_95(&predicted);
    let ratio = empirical / map.rms_mm;
    eprintln!(
        "stylus map: Monte Carlo 95 % radius RMS {empirical:.5} mm, map {:.5} mm",
        map.rms_mm
    );
    assert!(
        (0.88..=1.12).contains(&ratio),
        "empirical 95 % radius RMS {empirical:.5} mm, the map's {:.5} mm",
        map.rms_mm
    );
    assert_eq!(map.tool.as_deref(), Some("long"));
}
