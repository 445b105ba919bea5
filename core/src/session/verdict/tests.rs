//! Every reason and note in every front end's words.

use super::*;
use crate::calibrate::checks::ChiSquareVerdict;

fn chi(statistic: f64, dof: usize, p_upper: f64, p_lower: f64) -> ChiSquare {
    ChiSquare {
        statistic,
        dof,
        p_upper,
        p_lower,
        verdict: ChiSquareVerdict::from_tails(p_upper, p_lower),
    }
}

fn gross() -> GrossCorrection {
    GrossCorrection {
        name: "theta5".into(),
        unit: "deg".into(),
        nominal: 0.0,
        calibrated: 20.0,
        tolerance: 15.0,
    }
}

fn outlier() -> Outlier {
    Outlier {
        at: "poses.csv:12".into(),
        point: "P3".into(),
        standardised: 9.87,
        kind: None,
    }
}

fn noise() -> StatedNoise {
    StatedNoise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        position_mm: Some(0.015),
        position_mm_per_m: Some(0.006),
        orientation_rad: Some(0.01f64.to_radians()),
    }
}

/// Every reason, with sample data (each remedy's branches: an option
/// in use and not).
fn reasons() -> Vec<Reason> {
    let search = |prior_in_use| UnconfirmedSearch {
        starts: 100,
        prior_in_use,
    };
    vec![
        Reason::RadiansAsDegrees {
            poses_file: "poses.csv".into(),
        },
        Reason::DataDisagreeWithArm {
            minima_of_other_kinds: Some(7),
            far_sigma0: Some(512.0),
            touch_sigma_mm: 0.02,
            joints: 6,
        },
        Reason::Outliers {
            count: 1,
            named: vec![outlier()],
            what: "touch".into(),
            robust_in_use: false,
        },
        Reason::Outliers {
            count: 7,
            named: vec![outlier(); 5],
            what: "target".into(),
            robust_in_use: true,
        },
        Reason::Unconfirmed {
            stop: "no two starts agreed".into(),
            search: Some(search(false)),
        },
        Reason::Unconfirmed {
            stop: "no two starts agreed".into(),
            search: Some(search(true)),
        },
        Reason::Unconfirmed {
            stop: "iteration limit".into(),
            search: None,
        },
        Reason::NotNominalGeometry {
            moves: vec![gross()],
        },
        Reason::Undetermined {
            moves: vec![(gross(), 6.0)],
            prior_in_use: false,
        },
        Reason::Undetermined {
            moves: vec![(gross(), 6.0)],
            prior_in_use: true,
        },
        Reason::ImplausibleBlocks {
            blocks: vec!["thermal: 1 m/K".into()],
        },
        Reason::ChiSquare {
            chi: chi(9000.0, 1000, 1e-300, 1.0),
            stated: Some(noise()),
        },
        Reason::ChiSquare {
            chi: chi(100.0, 1000, 1.0, 1e-300),
            stated: Some(noise()),
        },
        Reason::ChiSquare {
            chi: chi(9000.0, 1000, 1e-300, 1.0),
            stated: None,
        },
        Reason::RobustScale {
            description: "robust cauchy fit, scale 3.000 of the stated noise".into(),
        },
        Reason::WorseAtPositions {
            before_mm: 0.1,
            after_mm: 0.2,
        },
        Reason::WorseOnData {
            what: "RMS touch scatter".into(),
            before_mm: 0.1,
            after_mm: 0.2,
        },
        Reason::Recorded {
            text: "read back".into(),
        },
    ]
}

/// Every note, with sample data.
fn notes() -> Vec<Note> {
    let mut notes = vec![
        Note::ChiSquare {
            chi: chi(1150.0, 1000, 1e-4, 1.0),
        },
        Note::RobustScale {
            description: "robust huber fit, scale 1.300".into(),
        },
        Note::RobustUnsettled {
            tolerance: 1e-3,
            passes: 20,
        },
        Note::WeakData {
            rms_mm: 0.02,
            coverage: 0.95,
            touch_mm: 0.05,
        },
        Note::ScaleUndetermined {
            parameter: "d5".into(),
            nominal_mm: 270.0,
            reach_mm: 1000.0,
        },
        Note::Hayati {
            text: "joint 2: consider `model = \"hayati\"`".into(),
        },
        Note::Recorded {
            text: "read back".into(),
        },
    ];
    notes.extend(reasons().into_iter().map(|r| Note::Accepted {
        reason: Box::new(r),
    }));
    notes
}

#[test]
fn no_text_for_python_or_c_names_a_command_line_flag() {
    for spelling in [Spelling::Python, Spelling::C] {
        let (reasons, notes) = (reasons(), notes());
        let texts = (reasons.iter().map(|r| r.describe(spelling)))
            .chain(notes.iter().map(|n| n.describe(spelling)));
        for text in texts {
            assert!(!text.contains("--"), "{spelling:?}: {text}");
        }
        for s in Setting::ALL {
            assert!(!s.name(spelling).contains("--"), "{s:?}");
        }
    }
    // The C words name the real setters of the header.
    let header = include_str!("../../../../capi/include/aacmm.h");
    let c = reasons()
        .iter()
        .map(|r| r.describe(Spelling::C))
        .collect::<Vec<_>>();
    let named = (c
        .iter()
        .flat_map(|t| t.split(|ch: char| !ch.is_alphanumeric() && ch != '_')))
    .filter(|w| w.starts_with("aacmm_") || w.starts_with("AACMM_"));
    let mut count = 0;
    for word in named {
        assert!(header.contains(word), "{word} is not in aacmm.h");
        count += 1;
    }
    assert!(count >= 5, "{count}");
    for s in Setting::ALL {
        let name = s.name(Spelling::C);
        if name.starts_with("aacmm_") || name.starts_with("AACMM_") {
            assert!(header.contains(name), "{name} is not in aacmm.h");
        }
    }
}

/// The command line's words are the sentences the untyped verdict
/// said (pinned here; `.ci/same-results` compares whole campaigns).
#[test]
fn the_command_line_words_are_todays_sentences() {
    let r = reasons();
    assert_eq!(
        r[2].to_string(),
        "1 outlying observation pulls the fit: poses.csv:12 (point P3, 9.9 σ) — a \
         mislabelled or displaced touch? Check it: fix the label or remove the row, or \
         calibrate with --robust, which weighs them down"
    );
    assert_eq!(
        r[3].to_string(),
        "7 outlying observations pull the fit: poses.csv:12 (point P3, 9.9 σ), poses.csv:12 \
         (point P3, 9.9 σ), poses.csv:12 (point P3, 9.9 σ), poses.csv:12 (point P3, 9.9 σ), \
         poses.csv:12 (point P3, 9.9 σ), … — a mislabelled or displaced target? Check them: \
         fix the label or remove the row"
    );
    assert_eq!(
        r[4].to_string(),
        "the solver did not reach a confirmed minimum (no two starts agreed): give it more \
         starts than its 100 (--global-starts N), or state tolerances (`[prior]`, --prior) \
         for the parameters that differ between its minima"
    );
    assert_eq!(
        r[8].to_string(),
        "the data barely determine parameters that moved implausibly far, so they followed \
         noise and model error: theta5 0.0000 → 20.0000 deg (more than ±15.0000) (σ 6.0000 \
         deg) — state tolerances for them (`[prior]` in the arm file, or --prior) or fix \
         them (--fix), or add poses that turn the joints involved"
    );
    assert_eq!(
        notes()[4].to_string(),
        "positions are determined only up to scale: no reference length fixes the arm's \
         size, so d5 is held at its nominal 270.000 mm and every length follows it; each 0.1 \
         mm it is off scales the arm by 3.7e-4, 0.370 mm at the reach (1000 mm), an error no \
         uncertainty here includes. Add a reference length (--lengths) to fix the scale"
    );
    assert!(
        r[0].to_string()
            .ends_with(crate::calibrate::ANGLE_UNITS_REMEDY)
    );
}

#[test]
fn python_and_c_say_the_remedies_in_their_own_words() {
    let r = reasons();
    let py = r[2].describe(Spelling::Python);
    assert!(py.ends_with("or calibrate with robust=\"huber\", which weighs them down"));
    let c = r[4].describe(Spelling::C);
    assert!(
        c.contains("(aacmm_calibrate_options_set_global_starts)"),
        "{c}"
    );
    let chi = r[11].describe(Spelling::Python);
    assert!(
        chi.contains(
            "the stated noise (Noise(encoder_deg=0.0050, probe_mm=0.0100, \
             position_mm=0.0150, position_mm_per_m=0.0060, orientation_deg=0.0100))"
        ),
        "{chi}"
    );
    assert!(chi.contains("leave it unstated (noise=None)"), "{chi}");
    assert!(chi.ends_with("accept_poor_fit=True."), "{chi}");
    let chi = r[11].describe(Spelling::C);
    assert!(
        chi.contains("aacmm_calibrate_options_set_encoder_noise_rad(o, 8.7266e-5)"),
        "{chi}"
    );
    assert!(
        chi.contains("aacmm_calibrate_options_set_position_noise_mm(o, 0.0150, 0.0060)"),
        "{chi}"
    );
}

/// The misstated-noise case is the Birge ratio, both ways, with what
/// leaving the noise unstated does; never "state it σ̂₀ times larger".
#[test]
fn a_misstated_noise_is_the_birge_ratio() {
    let r = reasons();
    let large = r[11].to_string();
    assert!(
        large.contains(
            "the Birge ratio σ̂₀ = √(χ²/dof) = 3.00: the residuals scatter 3.00 times what \
             the stated noise (--encoder-noise 0.0050 --probe-noise 0.0100 --position-noise \
             0.0150+0.0060/m --orientation-noise 0.0100) explains. If that noise is right, \
             look for outliers (--robust names them) or a model error; if it is a guess, \
             leave it unstated (without --encoder-noise, --probe-noise, --position-noise, \
             --orientation-noise): σ is then estimated from these residuals"
        ),
        "{large}"
    );
    let small = r[12].to_string();
    assert!(
        small.contains("= 0.32: the residuals scatter 3.16 times less than the stated noise"),
        "{small}"
    );
    for t in [&large, &small] {
        assert!(
            !t.contains("times larger") && !t.contains("consistent with the"),
            "{t}"
        );
        assert!(
            t.ends_with("or accept the fit as it is with --accept-poor-fit."),
            "{t}"
        );
    }
    // Not sound (a wrong minimum): the test alone, no remedy.
    assert!(!r[13].to_string().contains("Birge"));
}

/// `calibration.json` keeps the sentences; read back, each is a
/// recorded reason that says the same.
#[test]
fn a_verdict_is_written_as_its_sentences_and_read_back_as_them() {
    let v = Verdict {
        usable: false,
        reasons: reasons(),
        notes: notes(),
    };
    let json = serde_json::to_value(&v).unwrap();
    assert_eq!(json["usable"], false);
    assert_eq!(json["reasons"][2], reasons()[2].to_string());
    let back: Verdict = serde_json::from_value(json).unwrap();
    assert_eq!(back.words(Spelling::Cli), v.words(Spelling::Cli));
    assert!(back.reasons.iter().all(|r| r.kind() == "recorded"));
    // The kinds are the variants' JSON tags.
    for r in reasons() {
        assert_eq!(serde_json::to_value(&r).unwrap()["kind"], r.kind());
    }
    for n in notes() {
        assert_eq!(serde_json::to_value(&n).unwrap()["kind"], n.kind());
    }
}
