//! The one request path (`session::Request`): every bad intent — a setting
//! as a user writes it — is refused by the library's own field before any
//! work; the arm file's prior is used, dropped or overridden entry by entry
//! as asked; and every warning about the inputs (a reader's, readings
//! outside the arm's joint limits, the held-out data's) is kept, in the
//! request and in the report.

use std::path::{Path, PathBuf};

use aacmm_core::calibrate::{
    AnnealOptions, CalibrationError, GlobalOptions, LmOptions, SwitchRule,
};
use aacmm_core::io::AngleUnit;
use aacmm_core::session::{Request, user_noise};

/// A file of the repository.
fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
}

const ARM: &str = "examples/paper-table-1.toml";
const POSES: &str = "examples/paper-campaign/poses.csv";
const LENGTHS: &str = "examples/paper-campaign/lengths.csv";

/// The shipped campaign, with its lengths and noise.
fn shipped() -> Request {
    Request::read(repo(ARM), repo(POSES), AngleUnit::Deg)
        .unwrap()
        .read_lengths(repo(LENGTHS))
        .unwrap()
        .noise(user_noise(Some(0.005), Some(0.01), 0.0005, None))
}

/// A change to a request: what a user asks for.
type Intent = Box<dyn Fn(Request) -> Request>;

/// The field a refusal names (never a command-line flag).
fn field_of<T>(result: Result<T, CalibrationError>) -> &'static str {
    match result {
        Err(CalibrationError::Option(e)) => {
            assert!(!e.to_string().contains("--"), "names a flag: {e}");
            e.field()
        }
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(_) => panic!("accepted"),
    }
}

#[test]
fn each_bad_intent_is_refused_by_its_field() {
    let cases: Vec<(&str, Intent)> = vec![
        ("fix", Box::new(|r| r.fix("theta9"))),
        ("fix", Box::new(|r| r.fix("auto,theta1"))),
        ("robust.loss", Box::new(|r| r.robust(Some("bogus"), None))),
        (
            "robust.scale_k",
            Box::new(|r| r.robust(Some("huber"), Some(-1.0))),
        ),
        ("robust.scale_k", Box::new(|r| r.robust(None, Some(2.0)))),
        ("prior", Box::new(|r| r.prior(Some("theta5=1mm")))),
        ("prior", Box::new(|r| r.prior(Some("q9=1mm")))),
        ("prior", Box::new(|r| r.prior(Some("length=0.5")))),
        ("prior", Box::new(|r| r.prior(Some("")))),
        ("threads", Box::new(|r| r.threads(Some(0)))),
        ("method", Box::new(|r| r.method("newton"))),
        (
            "noise.probe_mm",
            Box::new(|r| r.noise(user_noise(None, Some(-1.0), 0.0005, None))),
        ),
        (
            "noise.encoder_rad",
            Box::new(|r| r.noise(user_noise(Some(f64::NAN), None, 0.0005, None))),
        ),
        (
            "noise.length_weight",
            Box::new(|r| r.noise(user_noise(None, None, 0.0005, Some(-2.0)))),
        ),
        ("cross_validate", Box::new(|r| r.cross_validate(Some(1)))),
        (
            "anneal.cooling",
            Box::new(|r| {
                r.anneal(AnnealOptions {
                    cooling: 1.5,
                    ..AnnealOptions::default()
                })
            }),
        ),
        (
            "switch.window",
            Box::new(|r| {
                r.switch(SwitchRule {
                    window: 0,
                    ..SwitchRule::default()
                })
            }),
        ),
        (
            "global.max_starts",
            Box::new(|r| {
                r.global(GlobalOptions {
                    max_starts: 0,
                    ..GlobalOptions::default()
                })
            }),
        ),
        (
            "lm.max_iterations",
            Box::new(|r| r.lm(LmOptions::default().max_iterations(0))),
        ),
    ];
    for (field, bad) in &cases {
        assert_eq!(field_of(bad(shipped()).build()), *field, "{field}");
    }
    // The refusals name the values as given.
    match shipped().method("newton").build() {
        Err(CalibrationError::Option(e)) => {
            assert_eq!(
                e.to_string(),
                "method = \"newton\": one of lm, sa, hybrid, global"
            );
        }
        other => panic!("{other:?}"),
    }
    match shipped().robust(Some("bogus"), None).build() {
        Err(CalibrationError::Option(e)) => {
            assert_eq!(
                e.to_string(),
                "robust.loss = \"bogus\": one of huber, cauchy"
            );
        }
        other => panic!("{other:?}"),
    }
    // The identification reads the same intents.
    assert_eq!(
        field_of(shipped().prior(Some("theta5=1mm")).identify()),
        "prior"
    );
    assert_eq!(field_of(shipped().threads(Some(0)).identify()), "threads");
    let loud = user_noise(None, Some(f64::INFINITY), 0.0005, None);
    assert_eq!(field_of(shipped().noise(loud).identify()), "noise.probe_mm");
    // And the good intents build.
    let (problem, settings) = (shipped().fix("theta1,d1,theta6,alpha6,Bx,By"))
        .robust(Some("cauchy"), None)
        .method("lm")
        .threads(Some(3))
        .seed(7)
        .cross_validate(Some(3))
        .build()
        .unwrap();
    let model = problem.model();
    assert_eq!(model.fix.describe(6), "theta1,d1,theta6,alpha6,Bx,By");
    assert_eq!(model.robust.unwrap().scale_k, 2.65);
    assert_eq!(model.prior, None);
    assert_eq!(model.noise.probe_mm, Some(0.01));
    assert_eq!(
        (settings.method.name(), settings.threads, settings.seed),
        ("lm", 3, 7)
    );
}

#[test]
fn the_arm_files_prior_is_used_dropped_or_overridden_entry_by_entry() {
    let m = "examples/mukca/kinova-1";
    let read = || {
        Request::read(
            repo(&format!("{m}/arm.toml")),
            repo(&format!("{m}/poses.csv")),
            AngleUnit::Rad,
        )
        .unwrap()
    };
    let file = read()
        .arm()
        .prior
        .clone()
        .expect("the arm file has a [prior]");
    assert_eq!(read().tolerances().unwrap(), Some(file.clone()));
    assert_eq!(read().prior(Some("none")).tolerances().unwrap(), None);
    let over = read()
        .prior(Some("theta2=0.05deg,d3=3mm"))
        .tolerances()
        .unwrap()
        .unwrap();
    let request = read();
    let params = &request.arm().params;
    let (before, after) = (file.sigmas_for(params), over.sigmas_for(params));
    let names: Vec<String> = params.param_ids().map(|p| p.to_string()).collect();
    for ((name, b), a) in names.iter().zip(&before).zip(&after) {
        match name.as_str() {
            "theta2" => assert_eq!(*a, Some(0.05f64.to_radians())),
            "d3" => assert_eq!(*a, Some(3.0)),
            _ => assert_eq!(a, b, "{name}: only the entries given change"),
        }
    }
    let theta2 = names.iter().position(|n| n == "theta2").unwrap();
    assert_ne!(
        before[theta2], after[theta2],
        "the file's theta2 is another"
    );
    // The model carries what was resolved.
    let (problem, _) = read().prior(Some("theta2=0.05deg,d3=3mm")).build().unwrap();
    assert_eq!(problem.model().prior, Some(over));
}

/// The paper's nominal arm with joint 3 limited to ±30°, written beside the
/// test's other files.
fn limited_arm(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repo(ARM)).unwrap();
    assert!(text.contains("d = 250.0"));
    let path = dir.join("limited.toml");
    std::fs::write(
        &path,
        text.replacen("d = 250.0", "d = 250.0\nlimits = [-30, 30]", 1),
    )
    .unwrap();
    path
}

#[test]
fn every_warning_is_kept_in_the_request_and_the_report() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("aacmm-request-warnings");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let arm = limited_arm(&dir);
    let poses = repo(POSES);
    let limit = format!(
        "{}:3: field `q3`: 85 readings outside the arm's joint limits (first: \
         146.60792432509484° > 30°); check the arm file, the angle unit and the encoder zeros",
        poses.display()
    );
    let request = Request::read(&arm, &poses, AngleUnit::Deg)
        .unwrap()
        .read_lengths(repo(LENGTHS))
        .unwrap()
        .noise(user_noise(Some(0.005), Some(0.01), 0.0005, None))
        .method("lm");
    assert_eq!(request.warnings(), std::slice::from_ref(&limit));
    // Held-out data are checked against the same limits.
    let request = request.validate_on_files(&poses, None).unwrap();
    assert_eq!(request.warnings(), [limit.clone(), limit.clone()]);
    let (problem, report) = request.run().unwrap();
    assert_eq!(problem.sources().warnings, [limit.clone(), limit.clone()]);
    assert_eq!(report.warnings, [limit.clone(), limit]);
    assert!(report.to_json().contains("146.60792432509484° > 30°"));

    // A reader's warning: degrees read as radians.
    let request = Request::read(repo(ARM), &poses, AngleUnit::Rad).unwrap();
    let warnings = request.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].starts_with(&format!("{}:2: field `q", poses.display()))
            && warnings[0].contains("these angles look like degrees"),
        "{warnings:?}"
    );
    let (problem, _) = request.build().unwrap();
    assert_eq!(problem.sources().warnings, warnings);
    // The arm file's warnings come first, as read: an arm in metres whose
    // links are hundreds of metres long.
    let text = std::fs::read_to_string(repo(ARM)).unwrap();
    assert!(text.contains("length_unit = \"mm\""));
    let metres = dir.join("metres.toml");
    std::fs::write(
        &metres,
        text.replace("length_unit = \"mm\"", "length_unit = \"m\""),
    )
    .unwrap();
    let warnings = Request::read(&metres, &poses, AngleUnit::Rad)
        .unwrap()
        .warnings();
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(
        warnings[0].starts_with(&metres.display().to_string())
            && warnings[0].contains("these lengths look like millimetres"),
        "{warnings:?}"
    );
    assert!(
        warnings[1].starts_with(&poses.display().to_string()),
        "{warnings:?}"
    );
}
