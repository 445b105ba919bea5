//! `calibrate --out DIR`: the report (report.html and one SVG per figure)
//! beside calibration.json, from the very numbers written there.

use aacmm_core::dataset::DataSet;
use aacmm_core::io::Arm;
use aacmm_core::report::{
    Arms, CalibrationInput, Measured, ValidationRow, calibration_report, positions,
};
use anyhow::{Context, Result};

use super::{Args, Report};

/// Writes the report of `report` into `--out`; returns the line to print.
pub(super) fn write(
    args: &Args,
    arm: &Arm,
    data: &DataSet,
    held_out: Option<&DataSet>,
    report: &Report,
) -> Result<String> {
    let cal = report.calibration;
    let fitted_before = positions(&arm.params, data)?;
    let fitted_after = positions(&cal.params, data)?;
    let held = held_out
        .map(|h| {
            Ok::<_, anyhow::Error>((h, positions(&arm.params, h)?, positions(&cal.params, h)?))
        })
        .transpose()?;
    let mut measured = vec![Measured {
        data,
        held_out: false,
        before: Some(&fitted_before),
        after: &fitted_after,
    }];
    if let Some((h, before, after)) = &held {
        measured.push(Measured {
            data: h,
            held_out: true,
            before: Some(before),
            after,
        });
    }
    let v = &report.validation;
    let mut validation = vec![ValidationRow {
        name: "fitted".to_string(),
        held_out: false,
        figures: &v.fitted,
        json: Some("/validation/fitted".to_string()),
    }];
    if let Some(h) = &v.held_out {
        validation.push(ValidationRow {
            name: format!("held out ({})", h.data_file),
            held_out: true,
            figures: &h.figures,
            json: Some("/validation/held_out/figures".to_string()),
        });
    }
    if let Some(cv) = &v.cross_validation {
        for (i, f) in cv.folds.iter().enumerate() {
            validation.push(ValidationRow {
                name: format!("fold {} ({} points)", i + 1, f.held_out.len()),
                held_out: true,
                figures: &f.figures,
                json: Some(format!("/validation/cross_validation/folds/{i}/figures")),
            });
        }
    }
    let input = CalibrationInput {
        title: format!("Calibration of arm `{}`", report.arm),
        inputs: inputs(args, report),
        calibration: cal,
        calibration_json: Some("/calibration".to_string()),
        measured,
        arms: Arms {
            before: "nominal".to_string(),
            after: "calibrated".to_string(),
        },
        validation,
        truth: None,
    };
    let page = calibration_report(&input).context("--out")?;
    let path = crate::commands::report::write("--out", &args.out, &page)?;
    Ok(crate::commands::report::wrote(&path, &page))
}

/// What went in, for the page's heading.
fn inputs(args: &Args, r: &Report) -> Vec<(String, String)> {
    let n = r.noise;
    let noise = match (n.encoder_rad, n.probe_mm) {
        (None, None) => "not stated: the touch σ is estimated from the fit".to_string(),
        (e, p) => format!(
            "encoders {} deg, probe seating {} mm per axis; reference lengths {} mm unless the \
             file states one",
            e.map_or("0".to_string(), |v| format!("{}", v.to_degrees())),
            p.map_or("0".to_string(), |v| format!("{v}")),
            n.length_default_mm
        ),
    };
    let mut lines = vec![
        (
            "nominal arm".to_string(),
            format!("`{}` ({})", r.arm, r.arm_file),
        ),
        (
            "touches".to_string(),
            format!(
                "{}: {} touches of {} points",
                r.data_file, r.touches, r.points
            ),
        ),
        (
            "reference lengths".to_string(),
            match &r.lengths_file {
                Some(f) => format!("{f}: {}", r.reference_lengths),
                None => "none (scale is not tested)".to_string(),
            },
        ),
    ];
    if let Some(h) = &r.validation.held_out {
        lines.push((
            "held out (--validate)".to_string(),
            match &h.lengths_file {
                Some(l) => format!("{} with lengths {l}", h.data_file),
                None => h.data_file.clone(),
            },
        ));
    }
    lines.push(("noise".to_string(), noise));
    lines.push((
        "method, fixed set, seed".to_string(),
        format!(
            "{}; --fix {}; seed {}",
            r.calibration.solver.method.name(),
            r.fix,
            args.seed
        ),
    ));
    if let Some(cv) = &r.validation.cross_validation {
        lines.push((
            "cross-validation".to_string(),
            format!("{} folds over points, seed {}", cv.folds.len(), cv.seed),
        ));
    }
    lines.push((
        "written beside this page".to_string(),
        format!(
            "{}, {}, {} (every number of the tables below that is also in {} is marked \
             with its place there)",
            super::CALIBRATED_FILE,
            super::REPORT_FILE,
            super::TIMING_FILE,
            super::REPORT_FILE
        ),
    ));
    lines
}
