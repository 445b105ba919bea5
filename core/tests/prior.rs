//! Prior knowledge of the arm (stated tolerances, a MAP fit): it must not
//! bias well-determined parameters, it must hold what the data cannot see
//! at nominal with the prior's σ, it counts in the dof, bad tolerances are
//! refused where they are written, and identify shows the rank it adds.

use std::path::PathBuf;

use aacmm_core::calibrate::prior::conditioning;
use aacmm_core::calibrate::{
    Calibration, CalibrationError, FixSpec, ModelOptions, SolverSettings, calibrate,
};
use aacmm_core::dataset::DataSet;
use aacmm_core::identify::identify;
use aacmm_core::io::{parse_prior, read_arm, read_lengths};
use aacmm_core::params::DhParams;
use aacmm_core::residuals::Noise;
use aacmm_core::tolerances::Tolerances;

fn root(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(file)
}

/// The shipped campaign and arm, and the README's noise.
fn shipped() -> (DhParams, DataSet, ModelOptions) {
    let (arm, _) = read_arm(&root("paper-table-1.toml")).unwrap();
    let poses = root("paper-campaign/poses.csv");
    let (p, _) =
        aacmm_core::io::read_poses(&poses, aacmm_core::io::AngleUnit::Deg, Some(6)).unwrap();
    let lengths = read_lengths(&root("paper-campaign/lengths.csv")).unwrap();
    let data = DataSet::from_poses(&p, "poses.csv")
        .unwrap()
        .with_lengths(&lengths, "lengths.csv")
        .unwrap();
    let options = ModelOptions {
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        },
        ..ModelOptions::default()
    };
    (arm.params, data, options)
}

fn with_prior(options: &ModelOptions, spec: &str) -> ModelOptions {
    ModelOptions {
        prior: Tolerances::parse(spec, 6).unwrap(),
        ..options.clone()
    }
}

/// (a) + (c): on the shipped campaign, a prior as loose as the arm's own
/// errors (its corrections reach 1.1 mm and 0.74°, so 1 mm / 0.5° is what a
/// maker of it could state) moves no parameter by 0.1 σ of today's result;
/// the fixed set is the data's; the dof gain one row per free parameter.
#[test]
fn a_realistic_prior_does_not_bias_well_determined_parameters() {
    let (start, data, options) = shipped();
    let plain = calibrate(&start, &data, &options, &SolverSettings::default()).unwrap();
    let map = calibrate(
        &start,
        &data,
        &with_prior(&options, "length=1mm,angle=0.5deg"),
        &SolverSettings::default(),
    )
    .unwrap();
    assert!(plain.solver.is_solution_usable() && map.solver.is_solution_usable());
    assert!(plain.prior.is_none() && plain.dof.prior_rows == 0);
    let free = |c: &Calibration| -> Vec<String> {
        c.parameters
            .iter()
            .filter(|p| p.fixed.is_none())
            .map(|p| p.id.to_string())
            .collect()
    };
    assert_eq!(free(&plain), free(&map), "fix = auto is the data's own");
    let mut worst = (0.0f64, String::new());
    for (a, b) in plain.parameters.iter().zip(&map.parameters) {
        let Some(sigma) = a.sigma else { continue };
        let shift = (a.calibrated - b.calibrated).abs() / sigma;
        if shift > worst.0 {
            worst = (shift, a.id.to_string());
        }
    }
    assert!(worst.0 < 0.1, "{} moved by {:.3} σ", worst.1, worst.0);
    // (c) one pseudo-observation per free parameter, in the dof.
    let free_count = plain.dof.free_parameters;
    assert_eq!(map.dof.prior_rows, free_count);
    assert_eq!(
        map.dof.degrees_of_freedom,
        plain.dof.degrees_of_freedom + free_count
    );
    let report = map.prior.as_ref().unwrap();
    assert_eq!(report.rows, free_count);
    assert_eq!(report.parameters.len(), free_count);
    // Well determined: the data carry (nearly) all the information.
    assert!(report.parameters.iter().all(|p| p.data_share > 0.99));
    // σ0 is over the augmented rows: the cost includes the prior's.
    let expected = (map.solver.final_cost / map.dof.degrees_of_freedom as f64).sqrt();
    assert!((map.dof.sigma0 - expected).abs() < 1e-12);
}

/// A prior that covers only some parameters adds rows only for them.
#[test]
fn only_free_parameters_with_a_tolerance_are_rows() {
    let (start, data, options) = shipped();
    let map = calibrate(
        &start,
        &data,
        &with_prior(&options, "theta2=0.5deg,a1=1mm,d1=1mm"),
        &SolverSettings::default(),
    )
    .unwrap();
    // d1 is fixed (base motion): no row for it.
    assert_eq!(map.dof.prior_rows, 2);
    let names: Vec<&str> = map
        .prior
        .as_ref()
        .unwrap()
        .parameters
        .iter()
        .map(|p| p.name.as_str())
        .collect();
    assert_eq!(names, ["a1", "theta2"]);
}

/// (b): d1 (a slide of the whole measurement along the base axis) is
/// invisible to the data. Left free without a prior it is refused; with a
/// tolerance it is determined by the prior alone: nominal value, posterior
/// σ = the tolerance, no data share.
#[test]
fn a_direction_without_data_stays_at_nominal_with_the_prior_sigma() {
    let (start, data, options) = shipped();
    let fix = FixSpec::parse("theta1,theta6,alpha6,Bx,By", 6).unwrap();
    let free_d1 = ModelOptions {
        fix,
        ..options.clone()
    };
    let refused = calibrate(&start, &data, &free_d1, &SolverSettings::default()).unwrap_err();
    assert!(
        matches!(refused, CalibrationError::Unidentifiable { .. }),
        "{refused}"
    );
    let map = calibrate(
        &start,
        &data,
        &with_prior(&free_d1, "length=0.5mm,angle=0.1deg"),
        &SolverSettings::default(),
    )
    .unwrap();
    assert!(map.solver.is_solution_usable(), "{:?}", map.solver.stop);
    let d1 = map.estimate("d1".parse().unwrap()).unwrap();
    assert!(d1.fixed.is_none());
    assert!(
        d1.correction.abs() < 1e-6,
        "d1 moved by {} mm",
        d1.correction
    );
    let entry = map.prior.as_ref().unwrap().of("d1").unwrap().clone();
    assert!(
        (entry.posterior_sigma - 0.5).abs() < 0.005,
        "posterior σ {} mm, tolerance 0.5 mm",
        entry.posterior_sigma
    );
    assert!(entry.data_share < 0.01, "data share {}", entry.data_share);
    // The reported σ is the posterior's: σ̂ rescales the data's
    // information, not the stated tolerance, so a direction the data do not
    // see keeps the tolerance whatever σ̂ (here far enough from 1 to tell).
    let sigma = d1.sigma.unwrap();
    assert!((map.dof.sigma0 - 1.0).abs() > 0.02, "σ̂ {}", map.dof.sigma0);
    assert!((sigma / 0.5 - 1.0).abs() < 0.001, "σ {sigma}");
    assert!((entry.posterior_sigma - sigma).abs() < 1e-12);
}

fn arm_text(prior: &str) -> String {
    let text = std::fs::read_to_string(root("paper-table-1.toml")).unwrap();
    format!("{text}\n{prior}")
}

/// (d): every bad tolerance in an arm file is refused with its file, line
/// and key; on the command line's syntax, by the field `prior`.
#[test]
fn bad_tolerances_are_refused_where_they_are_written() {
    let base_lines = arm_text("").lines().count();
    let cases: [(&str, &str, &str); 11] = [
        ("length_mm = 0", "length_mm", "must be a finite number > 0"),
        (
            "angle_deg = -0.1",
            "angle_deg",
            "must be a finite number > 0",
        ),
        ("a1_mm = nan", "a1_mm", "must be a finite number > 0"),
        (
            "theta5_deg = inf",
            "theta5_deg",
            "must be a finite number > 0",
        ),
        ("theta9_deg = 0.1", "theta9_deg", "unknown target `theta9`"),
        // Pseudo-observations that overflow, or that constrain nothing.
        (
            "a2_mm = 1e-300",
            "a2_mm",
            "should be fixed, not given a tolerance",
        ),
        ("angle_deg = 1e300", "angle_deg", "that constrains nothing"),
        ("theta5_mm = 0.1", "theta5_mm", "theta5 is an angle"),
        ("length = 0.5", "length", "has no unit"),
        ("Bz_mm = \"0.5\"", "Bz_mm", "is not a number"),
        (
            "length_in = 0.5",
            "length_in",
            "length is a length: give its tolerance in mm or m",
        ),
    ];
    for (line, key, needle) in cases {
        let text = arm_text(&format!("[prior]\nd_mm = 0.5\n{line}\n"));
        let e = parse_prior(&text, "arm.toml", 6).unwrap_err().to_string();
        let at = format!("arm.toml:{}: field `{key}`: [prior]: ", base_lines + 3);
        assert!(e.starts_with(&at), "{line}: {e}");
        assert!(e.contains(needle), "{line}: {e}");
    }
    let top = format!("prior = 3\n{}", arm_text(""));
    let e = parse_prior(&top, "arm.toml", 6).unwrap_err().to_string();
    assert!(
        e.contains("field `prior`") && e.contains("expected a [prior] table"),
        "{e}"
    );
    // Every reader of arm files refuses a bad table the same way.
    let bad = arm_text("[prior]\ntheta5_mm = 0.1\n");
    let e = aacmm_core::io::parse_arm(&bad, "arm.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("field `theta5_mm`: [prior]: theta5 is an angle"),
        "{e}"
    );
    // A good table reads back.
    let good =
        arm_text("[prior]\nlength_mm = 0.5\nangle_deg = 0.1\ntheta5_deg = 0.05\nprobe_mm = 2\n");
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("aacmm-prior-arm");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("arm.toml");
    std::fs::write(&path, &good).unwrap();
    let (arm, _) = read_arm(&path).unwrap();
    let prior = arm.prior.clone();
    assert_eq!(
        arm.params,
        read_arm(&root("paper-table-1.toml")).unwrap().0.params
    );
    let s = prior.unwrap().sigmas(6);
    assert_eq!(s[0], Some(0.5)); // a1: length
    assert_eq!(s[24], Some(2.0)); // Bx: probe beats length
    assert!((s[22].unwrap() - 0.05f64.to_radians()).abs() < 1e-18); // theta5
    assert!((s[12].unwrap() - 0.1f64.to_radians()).abs() < 1e-18); // alpha1
    // The command line's syntax.
    for (spec, needle) in [
        ("length=0mm", "must be a finite number > 0"),
        ("length=0.5", "no unit"),
        ("theta5=0.05mm", "theta5 is an angle"),
        ("wrist=1deg", "unknown target `wrist`"),
        ("length:0.5mm", "expected TARGET=VALUEUNIT"),
        ("", "no tolerance given"),
        ("length=abcmm", "is not a number"),
        ("length=1e-13mm", "below 1e-12"),
        ("theta5=1e13rad", "above 1e12"),
    ] {
        let e = Tolerances::parse(spec, 6).unwrap_err();
        assert_eq!(e.field(), "prior");
        assert!(e.reason.contains(needle), "{spec}: {e}");
    }
    // A later entry overrides; the command line overrides the file.
    let file = Tolerances::parse("length=0.5mm,theta5=0.05deg", 6)
        .unwrap()
        .unwrap();
    let flag = Tolerances::parse("theta5=0.2deg", 6).unwrap().unwrap();
    let s = file.overridden_by(&flag).sigmas(6);
    assert!((s[22].unwrap() - 0.2f64.to_radians()).abs() < 1e-18);
    assert_eq!(s[0], Some(0.5));
}

/// (e): identify with a prior: every parameter with a tolerance is
/// determined (rank 27 of 27, from 21 after the rules), and the free
/// parameters are better conditioned.
#[test]
fn identify_shows_the_rank_the_prior_adds() {
    let (start, data, options) = shipped();
    let id = identify(&start, &data, &options.noise, 1).unwrap();
    let t = Tolerances::parse("length=0.5mm,angle=0.1deg", 6)
        .unwrap()
        .unwrap();
    let c = conditioning(&start, &data, &options.noise, &t, &id, 1).unwrap();
    assert_eq!(c.rank_without, 21);
    assert_eq!(c.rank_with, 27);
    assert_eq!(c.parameters_with_tolerance, 27);
    assert!(c.condition_with <= c.condition_without, "{c:?}");
    // A prior on one parameter only adds its rank only.
    let one = Tolerances::parse("Bx=1mm", 6).unwrap().unwrap();
    let c = conditioning(&start, &data, &options.noise, &one, &id, 1).unwrap();
    assert_eq!(c.parameters_with_tolerance, 1);
    assert!(c.rank_with < 27, "{c:?}");
}

/// Without stated noise the touch σ is estimated from the fit, and the
/// prior's weight depends on it: it is re-estimated until it settles, so a
/// loose prior still leaves a simulated campaign's result where the data
/// put it, with lengths or without.
#[test]
fn with_unstated_noise_the_prior_weighs_against_the_estimated_touch_sigma() {
    use aacmm_core::domain::Arm;
    use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};
    let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
    for lengths in [3, 0] {
        let mut s = CampaignSettings::new(5, ErrorModel::Paper, 10, 10);
        s.reference_lengths = lengths;
        s.encoder_noise_deg = 0.005;
        s.probe_noise_mm = 0.01;
        let c = simulate(&nominal, &s).unwrap();
        let data = c.data_set().unwrap();
        let options = ModelOptions::default();
        let plain =
            calibrate(&nominal.params, &data, &options, &SolverSettings::default()).unwrap();
        let map = calibrate(
            &nominal.params,
            &data,
            &with_prior(&options, "length=2mm,angle=1deg"),
            &SolverSettings::default(),
        )
        .unwrap();
        assert!(
            map.solver.is_solution_usable(),
            "{lengths}: {:?}",
            map.solver.stop
        );
        assert!(map.dof.touch_sigma_estimated);
        let ratio = map.dof.touch_sigma_mm / plain.dof.touch_sigma_mm;
        assert!(
            (ratio - 1.0).abs() < 0.05,
            "{lengths}: touch σ ratio {ratio}"
        );
        assert!(
            (0.8..1.25).contains(&map.dof.sigma0),
            "{lengths}: σ0 {}",
            map.dof.sigma0
        );
        for (a, b) in plain.parameters.iter().zip(&map.parameters) {
            let Some(sigma) = a.sigma else { continue };
            let shift = (a.calibrated - b.calibrated).abs() / sigma;
            assert!(
                shift < 0.1,
                "{lengths} lengths: {} moved by {shift:.3} σ",
                a.id
            );
        }
        // A prior far tighter than the arm's errors binds: the first fit
        // (touches weighed as 1 mm) is held near nominal and overstates
        // the touch σ. The σ the result is weighed with must be the one its
        // own touch residuals give (within the 5 % that stops the refits).
        let tight = calibrate(
            &nominal.params,
            &data,
            &with_prior(&options, "length=0.05mm,angle=0.01deg"),
            &SolverSettings::default(),
        )
        .unwrap();
        let d = &tight.dof;
        let data_cost = tight.solver.final_cost - tight.prior.as_ref().unwrap().cost;
        let touch_dof = (d.touch_rows - d.centre_coordinates - d.free_parameters) as f64;
        // Lengths add their own rows to the data cost.
        let own = (data_cost / (touch_dof + d.length_rows as f64)).sqrt();
        assert!(
            (own - 1.0).abs() < 0.06,
            "{lengths} lengths: residuals give {own} × the weights' σ"
        );
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(3000))]
    /// `--prior` strings built from the spec's own pieces and odd ones never
    /// panic: a parse is `none`, tolerances that pass their own check and
    /// describe themselves, or an error naming the field `prior`.
    #[test]
    fn any_prior_spec_parses_or_is_refused_by_its_field(
        pieces in proptest::collection::vec(
            proptest::sample::select(vec![
                "length", "angle", "theta", "theta5", "theta7", "theta0", "a1", "d6", "alpha2",
                "hbeta2", "probe", "Bz", "=", "==", ",", " ", "0.5", "-1", "0", "1e308", "1e309",
                "nan", "inf", "-inf", "1e", "e5", ".5", "mm", "m", "deg", "rad", "um", "é", "°",
                "none", "\u{0}", "\u{202e}", "99999999999999999999",
            ]),
            0..12,
        ),
        joints in 1usize..=8,
    ) {
        let spec: String = pieces.concat();
        match Tolerances::parse(&spec, joints) {
            Ok(None) => proptest::prop_assert_eq!(spec.trim(), "none"),
            Ok(Some(t)) => {
                proptest::prop_assert!(!t.is_empty());
                let _ = t.check(joints);
                let _ = t.describe(joints);
                proptest::prop_assert_eq!(t.sigmas(joints).len(), 4 * joints + 3);
            }
            Err(e) => {
                proptest::prop_assert_eq!(e.field(), "prior");
                proptest::prop_assert!(!e.reason.is_empty());
            }
        }
    }
}
