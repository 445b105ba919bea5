//! What the sections' tests render: a small LM calibration of a simulated
//! campaign (4 sockets × 4 touches, 2 reference lengths), fitted once, and
//! its data evaluated with the nominal and the calibrated arm.

use std::sync::OnceLock;

use crate::calibrate::validate::{Figures, PositionErrors};
use crate::calibrate::{Calibration, Method, ModelOptions, SolverSettings, calibrate};
use crate::dataset::DataSet;
use crate::domain::Arm;
use crate::params::DhParams;
use crate::report::data::{Evaluated, evaluate_all};
use crate::report::{Arms, Measured, positions};
use crate::residuals::Noise;
use crate::simulate::{CampaignSettings, ErrorModel, simulate};

/// The campaign, the fit and the probe positions of both arms.
pub(super) struct Case {
    pub(super) data: DataSet,
    pub(super) cal: Calibration,
    before: Vec<[f64; 3]>,
    after: Vec<[f64; 3]>,
}

/// The case, simulated and fitted on first use.
pub(super) fn case() -> &'static Case {
    static CASE: OnceLock<Case> = OnceLock::new();
    CASE.get_or_init(|| {
        let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
        let mut s = CampaignSettings::new(7, ErrorModel::Paper, 4, 4);
        s.reference_lengths = 2;
        s.encoder_noise_deg = 0.005;
        s.probe_noise_mm = 0.01;
        let data = simulate(&nominal, &s).unwrap().data_set().unwrap();
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
            before: positions(&nominal.params, &data).unwrap(),
            after: positions(&cal.params, &data).unwrap(),
            data,
            cal,
        }
    })
}

/// The case's data with the nominal arm, then the calibrated one.
pub(super) fn evaluated() -> Vec<Evaluated<'static>> {
    let c = case();
    let measured = [Measured {
        data: &c.data,
        held_out: false,
        before: Some(&c.before),
        after: &c.after,
    }];
    evaluate_all(&measured, 0).unwrap()
}

/// `nominal` before, `calibrated` after.
pub(super) fn arms() -> Arms {
    Arms {
        before: "nominal".into(),
        after: "calibrated".into(),
    }
}

/// Figures of `points` points with these 3-D errors at reference positions
/// (none: `None`), no lengths.
pub(super) fn figures(points: usize, e_mean: f64, positions: Option<&[f64]>) -> Figures {
    Figures {
        points,
        e_mean,
        e_max: 2.0 * e_mean,
        two_s_mean: 0.5,
        delta_max: 0.25,
        lengths: 0,
        length_rms: None,
        length_max: None,
        positions: positions.map(PositionErrors::of),
        orientations: None,
    }
}

/// The number of `<tr>` rows of `html` (the header's included).
pub(super) fn rows(html: &str) -> usize {
    html.matches("<tr").count()
}
