//! The shipped campaign (the paper's arm, its poses and lengths) and the
//! noise it was recorded with, for tests that calibrate it.

use aacmm_core::calibrate::ModelOptions;
use aacmm_core::io::{AngleUnit, read_arm};
use aacmm_core::residuals::Noise;
use aacmm_core::{Arm, DataSet};

fn root(file: &str) -> String {
    format!("{}/../examples/{file}", env!("CARGO_MANIFEST_DIR"))
}

/// The paper's arm and the shipped campaign, read without a warning.
pub fn shipped() -> (Arm, DataSet) {
    let (arm, _) = read_arm(root("paper-table-1.toml").as_ref()).unwrap();
    let lengths = root("paper-campaign/lengths.csv");
    let (data, warnings) = DataSet::read(
        root("paper-campaign/poses.csv").as_ref(),
        Some(lengths.as_ref()),
        AngleUnit::Deg,
        6,
    )
    .unwrap();
    assert!(warnings.is_empty());
    (arm, data)
}

/// The model with the campaign's noise stated: encoders 0.005°, probe
/// 0.01 mm.
pub fn stated_noise() -> ModelOptions {
    ModelOptions {
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        },
        ..ModelOptions::default()
    }
}
