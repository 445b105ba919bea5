//! Real recorded data (MUKCa): leave one placement out.
//!
//! ```text
//! cargo run --release --example mukca -- DIR [--method lm|sa|hybrid|global] [--fix auto|NAMES] [--prior none|SPEC]
//! cargo run --release --example mukca -- examples/mukca/kinova-1
//! ```
//!
//! `DIR` holds `arm.toml` (the nominal arm), `poses.csv` (readings in rad,
//! points labelled `PLACEMENT-hK`) and `lengths.csv` (the 50 mm between the
//! two sockets of a placement); see `examples/mukca/README.md`. For each
//! placement the arm is calibrated with `aacmm_core::calibrate::calibrate`
//! (the library's defaults unless `--method`/`--fix` say otherwise) on all
//! the other placements, and the held-out one is scored with the nominal and
//! the calibrated arm: consistency (mean distance of a socket's touches to
//! their centroid, averaged over its sockets) and `|d − 50|` where it has
//! both sockets. The logic is `aacmm_core::calibrate::validate::placements`.
//! The arm file's `[prior]` table (stated tolerances) is used unless
//! `--prior none`; `--prior SPEC` (`length=0.5mm,angle=0.1deg,…`) overrides
//! it entry by entry, as on the command line of `aacmm calibrate`.
//! `--in-sample` adds a diagnostic: each placement's consistency under the
//! arm calibrated on every placement, itself included (what this model can
//! reach at best).

use std::io::Write;
use std::path::Path;

use aacmm_core::calibrate::validate::placements::{
    PlacementSummary, leave_one_placement_out, placement_of,
};
use aacmm_core::calibrate::{FixSpec, Method, ModelOptions, SolverSettings};
use aacmm_core::dataset::DataSet;
use aacmm_core::io::{AngleUnit, read_arm, read_lengths, read_poses};
use aacmm_core::tolerances::Tolerances;
use anyhow::{Context, bail};

fn main() -> anyhow::Result<()> {
    let mut dir = None;
    let mut options = ModelOptions::default();
    let mut settings = SolverSettings::default();
    let mut fix_text = None;
    let mut prior_text = None;
    let mut in_sample = false;
    let mut hayati: Vec<usize> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--method" => {
                let m = args.next().context("--method needs a value")?;
                settings.method = Method::parse(&m).with_context(|| {
                    format!("--method `{m}`: expected lm, sa, hybrid or global")
                })?;
            }
            "--fix" => fix_text = Some(args.next().context("--fix needs a value")?),
            "--prior" => prior_text = Some(args.next().context("--prior needs a value")?),
            "--robust" => {
                let l = args.next().context("--robust needs a value")?;
                let loss = aacmm_core::calibrate::Loss::parse(&l)
                    .with_context(|| format!("--robust `{l}`: expected huber or cauchy"))?;
                options.robust = Some(aacmm_core::calibrate::Robust::new(loss));
            }
            "--hayati" => {
                let j = args.next().context("--hayati needs a joint number")?;
                hayati.push(
                    j.parse::<usize>()
                        .ok()
                        .filter(|&j| j >= 1)
                        .with_context(|| format!("--hayati `{j}`: a joint number from 1"))?,
                );
            }
            "--in-sample" => in_sample = true,
            _ if a.starts_with("--") => bail!("unknown option `{a}`"),
            _ if dir.is_none() => dir = Some(a),
            _ => bail!("one data folder only (got `{a}` too)"),
        }
    }
    let dir = dir.context(
        "usage: mukca DIR [--method M] [--fix auto|NAMES] [--prior none|SPEC] [--robust huber|cauchy] [--hayati J]… [--in-sample]",
    )?;
    let dir = Path::new(&dir);
    let (mut arm, warnings) = read_arm(&dir.join("arm.toml"))?;
    let file_prior = arm.prior.take();
    for &j in &hayati {
        arm = arm
            .with_hayati(j - 1)
            .with_context(|| format!("--hayati {j}"))?;
    }
    let (poses, pose_warnings) = read_poses(
        &dir.join("poses.csv"),
        AngleUnit::Rad,
        Some(arm.params.joint_count()),
    )?;
    let mut err = std::io::stderr().lock();
    for w in warnings.iter().chain(&pose_warnings) {
        writeln!(err, "warning: {w}")?;
    }
    options.prior = match prior_text.as_deref() {
        None => file_prior,
        Some(spec) => Tolerances::parse(spec, arm.params.joint_count())?
            .map(|flag| file_prior.unwrap_or_default().overridden_by(&flag)),
    };
    // A joint made Hayati has no `d` any more: a tolerance stated for it
    // (the arm file's, written for the D-H arm) holds nothing and goes.
    if let Some(t) = &mut options.prior {
        for &j in &hayati {
            if t.remove(&format!("d{j}")) {
                writeln!(
                    err,
                    "note: prior d{j} dropped: joint {j} is Hayati (its d-slot is hbeta{j}, \
                     covered by `angle`)"
                )?;
            }
        }
    }
    if let Some(f) = &fix_text {
        options.fix = FixSpec::parse(f, arm.params.joint_count())?;
    }
    let poses_file = dir.join("poses.csv").display().to_string();
    let lengths_path = dir.join("lengths.csv");
    let lengths = read_lengths(&lengths_path)?;
    let data = DataSet::from_poses(&poses, &poses_file)?
        .with_lengths(&lengths, &lengths_path.display().to_string())?;
    let folds = leave_one_placement_out(&arm.params, &data, &options, &settings)?;
    let summary = PlacementSummary::of(&folds);

    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}: {} touches, {} sockets, {} lengths; arm `{}`; method {}, fix {}, prior {}",
        dir.display(),
        data.len(),
        data.points().len(),
        data.references().len(),
        arm.name,
        settings.method.name(),
        fix_text.as_deref().unwrap_or("auto"),
        options
            .prior
            .as_ref()
            .map_or("none".to_string(), |t| t.describe(arm.params.joint_count())),
    )?;
    writeln!(
        out,
        "Leave one placement out: calibrated on the others, scored on the held-out one (mm)"
    )?;
    writeln!(
        out,
        "{:<22} {:>7} {:>7}  {:>9} {:>9} {:>7}  {:>9} {:>9} {:>7}  fit",
        "held out",
        "sockets",
        "touches",
        "cons nom",
        "cons cal",
        "change",
        "|d-50| nom",
        "|d-50| cal",
        "change"
    )?;
    for f in &folds {
        let (dn, dc, dch) = match (f.nominal.length_max, f.calibrated.length_max) {
            (Some(n), Some(c)) => (
                format!("{n:.3}"),
                format!("{c:.3}"),
                format!("{:+.0} %", 100.0 * (c - n) / n),
            ),
            _ => ("-".into(), "-".into(), "".into()),
        };
        writeln!(
            out,
            "{:<22} {:>7} {:>7}  {:>9.3} {:>9.3} {:>7}  {:>10} {:>10} {:>7}  {}",
            f.placement,
            f.sockets.len(),
            f.touches,
            f.nominal.e_mean,
            f.calibrated.e_mean,
            format!(
                "{:+.0} %",
                100.0 * (f.calibrated.e_mean - f.nominal.e_mean) / f.nominal.e_mean
            ),
            dn,
            dc,
            dch,
            fit_column(f)
        )?;
    }
    let (dn, dc, dch) = match (
        summary.distance_nominal,
        summary.distance_calibrated,
        summary.distance_change_percent(),
    ) {
        (Some(n), Some(c), Some(p)) => (format!("{n:.3}"), format!("{c:.3}"), format!("{p:+.0} %")),
        _ => ("-".into(), "-".into(), "".into()),
    };
    writeln!(
        out,
        "{:<22} {:>7} {:>7}  {:>9.3} {:>9.3} {:>7}  {:>10} {:>10} {:>7}",
        "mean",
        "",
        "",
        summary.consistency_nominal,
        summary.consistency_calibrated,
        format!("{:+.0} %", summary.consistency_change_percent()),
        dn,
        dc,
        dch
    )?;
    if in_sample {
        let all = aacmm_core::calibrate::calibrate(&arm.params, &data, &options, &settings)?;
        writeln!(
            out,
            "In sample (calibrated on every placement, this one included): consistency (mm)"
        )?;
        for f in &folds {
            let held: Vec<usize> = (0..data.points().len())
                .filter(|&p| placement_of(&data.points()[p].label) == f.placement)
                .collect();
            let e = aacmm_core::calibrate::validate::figures(&all.params, &data.subset(&held))?;
            writeln!(
                out,
                "{:<22} {:>9.3} ({:+.0} % from nominal)",
                f.placement,
                e.e_mean,
                100.0 * (e.e_mean - f.nominal.e_mean) / f.nominal.e_mean
            )?;
        }
    }
    Ok(())
}

/// The fold's fit as the command line would judge its solver and its
/// plausibility: `ok`, `NOT CONVERGED`, or the parameters that moved past
/// the plausibility check.
fn fit_column(f: &aacmm_core::calibrate::validate::placements::PlacementFold) -> String {
    let mut what = Vec::new();
    if !f.successful {
        what.push("NOT CONVERGED".to_string());
    }
    if !f.implausible.is_empty() {
        what.push(format!("implausible: {}", f.implausible.join(", ")));
    }
    if what.is_empty() {
        "ok".to_string()
    } else {
        what.join("; ")
    }
}
