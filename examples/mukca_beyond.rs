//! Real recorded data (MUKCa), beyond geometry: leave one placement out with
//! the geometry alone against each model beyond it (encoder harmonics, joint
//! compliance under gravity, both), with the arm files' stated tolerances
//! and without.
//!
//! ```text
//! cargo run --release --example mukca_beyond                     # the three folders
//! cargo run --release --example mukca_beyond -- examples/mukca/kinova-1 [--folds]
//! cargo run --release --example mukca_beyond -- --model geometry --model backlash
//! ```
//!
//! The procedure is `examples/mukca.rs`'s (the README's "Real data
//! (MUKCa)" figures): each placement held out in turn, the arm calibrated
//! with the library's defaults (`global`, `--fix auto`) on the others, the
//! held-out placement scored with the nominal and the calibrated arm —
//! consistency (mean distance of a socket's touches to their centroid,
//! averaged over its sockets) and `|d − 50|` where it has both sockets —
//! once with the arm file's `[prior]` and once without (`--prior none`).
//! It is `aacmm_core::calibrate::validate::placements::leave_one_placement_out`
//! written out, because that function fits the geometry only: here each fold
//! is the session `aacmm calibrate` runs (`Problem::new(arm, training data,
//! model)` with the held-out placement as its held-out data, `run`): the
//! arm's masses and the models switched on are fitted, the held-out touches
//! are scored as the calibrated arm sees them, through its fitted
//! corrections, and the fold gets the command line's verdict. For the
//! geometry alone the program checks that this gives the library function's
//! figures bit for bit, and stops if not.
//!
//! The models, for an arm of `n` joints: `harmonics 1` (order 1 on every
//! joint: `1:1,…,n:1`), `harmonics 1-2` (orders 1 and 2 on every joint),
//! `compliance 2,3` (Kinova) or `2,4` (Panda) — the joints gravity loads
//! most —, `compliance all` (every joint), and `harmonics 1` with each
//! compliance; `backlash 2,3` (`2,4`) and `backlash all`, a half-play per
//! joint on the gear flank its gravity torque presses (the arm files' link
//! masses). `--model PREFIX` (repeatable) runs only the models whose label
//! starts with it. A correction the training data cannot separate from the
//! geometry is held at zero by the fit (counted as `held`). A fold is
//! refused when its calibration fails (the error) or when the command
//! line's verdict refuses it (not converged, a gross geometry, or a
//! correction beyond any real arm: `implausible`); the figures are over
//! every fold all the same, as the library's procedure scores them.
//!
//! Output: one Markdown row per folder, prior and model — the held-out
//! consistency and distance-error changes (calibrated against nominal) per
//! fold, min..max, their mean over the folds, and the change of the means
//! (the README's `mean` row); the folds refused and why; and the correction
//! columns fitted and held (summed over the folds). `--folds` adds each
//! fold's figures, verdict and fitted corrections.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use aacmm_core::calibrate::validate::Figures;
use aacmm_core::calibrate::validate::placements::{leave_one_placement_out, placement_of};
use aacmm_core::calibrate::{ModelOptions, SolverSettings};
use aacmm_core::corrections::Beyond;
use aacmm_core::dataset::DataSet;
use aacmm_core::domain::Arm;
use aacmm_core::io::{AngleUnit, read_arm, read_lengths, read_poses};
use aacmm_core::session::{CalibrationReport, HeldOutData, Problem};
use anyhow::{Context as _, bail};

/// One held-out placement.
struct Fold {
    placement: String,
    nominal: Figures,
    /// The calibrated arm's figures, or why the fold's calibration failed.
    calibrated: Result<Figures, String>,
    successful: bool,
    /// Why the command line's verdict refuses the fold (empty: usable).
    refused: Vec<String>,
    /// Correction columns fitted, and held (name: why).
    fitted: Vec<String>,
    held: Vec<String>,
}

impl Fold {
    fn consistency_change(&self) -> Option<f64> {
        let c = self.calibrated.as_ref().ok()?;
        Some(percent(self.nominal.e_mean, c.e_mean))
    }

    fn distance_change(&self) -> Option<f64> {
        let c = self.calibrated.as_ref().ok()?;
        Some(percent(self.nominal.length_max?, c.length_max?))
    }
}

fn percent(before: f64, after: f64) -> f64 {
    100.0 * (after - before) / before
}

fn main() -> anyhow::Result<()> {
    let mut dirs = Vec::new();
    let mut folds_detail = false;
    let mut only: Vec<String> = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--folds" => folds_detail = true,
            "--model" => only.push(args.next().context("--model needs a label prefix")?),
            _ if a.starts_with("--") => bail!("unknown option `{a}`"),
            _ => dirs.push(a),
        }
    }
    if dirs.is_empty() {
        dirs = ["kinova-1", "kinova-2", "panda-1"]
            .map(|d| format!("examples/mukca/{d}"))
            .to_vec();
    }
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "| data | prior | model | consistency per fold | mean of folds | of the means | \
         distance per fold | mean of folds | of the means | folds refused | \
         columns fitted / held | seconds |"
    )?;
    writeln!(out, "|{}", " --- |".repeat(12))?;
    let mut details = Vec::new();
    for dir in &dirs {
        let (arm, data, file_prior) = load(Path::new(dir))?;
        let n = arm.params.joint_count();
        let name = Path::new(dir)
            .file_name()
            .map_or(dir.clone(), |f| f.to_string_lossy().into_owned());
        for (prior_name, prior) in [("stated", file_prior.clone()), ("none", None)] {
            let model = ModelOptions {
                prior,
                ..ModelOptions::default()
            };
            let settings = SolverSettings::default();
            check_geometry_is_the_library(&arm, &data, &model, &settings)
                .with_context(|| format!("{dir}, prior {prior_name}"))?;
            let chosen = (models(n).into_iter())
                .filter(|(label, _)| only.is_empty() || only.iter().any(|p| label.starts_with(p)));
            for (label, beyond) in chosen {
                let model = ModelOptions {
                    beyond,
                    ..model.clone()
                };
                let timer = Instant::now();
                let folds = lopo(&arm, &data, &model, &settings)?;
                let seconds = timer.elapsed().as_secs_f64();
                writeln!(out, "{}", row(&name, prior_name, &label, &folds, seconds))?;
                if folds_detail {
                    details.push(detail(&name, prior_name, &label, &folds));
                }
            }
        }
    }
    for d in details {
        write!(out, "{d}")?;
    }
    Ok(())
}

/// The arm (its `[prior]` taken out), the touches and lengths of `dir`.
fn load(dir: &Path) -> anyhow::Result<(Arm, DataSet, Option<aacmm_core::tolerances::Tolerances>)> {
    let (mut arm, _) = read_arm(&dir.join("arm.toml"))?;
    let prior = arm.prior.take();
    let (poses, _) = read_poses(
        &dir.join("poses.csv"),
        AngleUnit::Rad,
        Some(arm.params.joint_count()),
    )?;
    let lengths_path = dir.join("lengths.csv");
    let data = DataSet::from_poses(&poses, &dir.join("poses.csv").display().to_string())?
        .with_lengths(
            &read_lengths(&lengths_path)?,
            &lengths_path.display().to_string(),
        )?;
    Ok((arm, data, prior))
}

/// The models measured, for an arm of `n` joints.
fn models(n: usize) -> Vec<(String, Beyond)> {
    let all: Vec<usize> = (0..n).collect();
    // The joints gravity loads most: shoulder and elbow (the Panda's elbow
    // is joint 4).
    let loaded = if n == 7 { vec![1, 3] } else { vec![1, 2] };
    let loaded_name = if n == 7 { "2,4" } else { "2,3" };
    let h1: Vec<(usize, u32)> = all.iter().map(|&j| (j, 1)).collect();
    let h12: Vec<(usize, u32)> = all.iter().flat_map(|&j| [(j, 1), (j, 2)]).collect();
    let with = |compliance: &[usize], harmonics: &[(usize, u32)]| Beyond {
        compliance: compliance.to_vec(),
        harmonics: harmonics.to_vec(),
        ..Beyond::default()
    };
    vec![
        ("geometry".into(), Beyond::default()),
        ("harmonics 1".into(), with(&[], &h1)),
        ("harmonics 1-2".into(), with(&[], &h12)),
        (format!("compliance {loaded_name}"), with(&loaded, &[])),
        ("compliance all".into(), with(&all, &[])),
        (
            format!("harmonics 1 + compliance {loaded_name}"),
            with(&loaded, &h1),
        ),
        ("harmonics 1 + compliance all".into(), with(&all, &h1)),
        (
            format!("backlash {loaded_name}"),
            Beyond {
                backlash: loaded.clone(),
                ..Beyond::default()
            },
        ),
        (
            "backlash all".into(),
            Beyond {
                backlash: all.clone(),
                ..Beyond::default()
            },
        ),
    ]
}

/// Leave one placement out as `leave_one_placement_out` does it (the same
/// placements, in the same order, the same training and held-out subsets),
/// each fold fitted with the arm's physics and `model.beyond`, the held-out
/// placement scored through the fitted corrections.
fn lopo(
    arm: &Arm,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
) -> anyhow::Result<Vec<Fold>> {
    let mut placements: Vec<(String, Vec<usize>)> = Vec::new();
    for (i, p) in data.points().iter().enumerate() {
        let name = placement_of(&p.label);
        match placements.iter_mut().find(|(n, _)| n == name) {
            Some((_, points)) => points.push(i),
            None => placements.push((name.to_string(), vec![i])),
        }
    }
    if placements.len() < 2 {
        bail!("leave one placement out needs two placements or more");
    }
    let mut out = Vec::new();
    for (name, held) in &placements {
        let train: Vec<usize> = (0..data.points().len())
            .filter(|p| !held.contains(p))
            .collect();
        let (train, test) = (data.subset(&train), data.subset(held));
        let nominal = aacmm_core::calibrate::validate::figures(&arm.params, &test)?;
        let fold = match fit(arm, train, test, model, settings) {
            Err(e) => Fold {
                placement: name.clone(),
                nominal,
                calibrated: Err(e),
                successful: false,
                refused: Vec::new(),
                fitted: Vec::new(),
                held: Vec::new(),
            },
            Ok(r) => {
                let c = &r.calibration;
                let figures = (r.validation.held_out.as_ref())
                    .context("the session scored no held-out data")?
                    .figures;
                // No positions here: every auxiliary column is a correction.
                let corrections = &c.auxiliary;
                Fold {
                    placement: name.clone(),
                    nominal: figures.before,
                    calibrated: Ok(figures.after),
                    successful: c.solver.is_solution_usable(),
                    refused: r
                        .verdict
                        .words(aacmm_core::session::Spelling::Cli)
                        .reasons
                        .clone(),
                    fitted: (corrections.iter())
                        .filter(|a| a.fixed.is_none())
                        .map(|a| format!("{} = {:.4} {}", a.name, a.calibrated, a.unit))
                        .collect(),
                    held: (corrections.iter())
                        .filter_map(|a| Some(format!("{}: {}", a.name, a.fixed.as_ref()?)))
                        .collect(),
                }
            }
        };
        out.push(fold);
    }
    Ok(out)
}

/// One fold as `aacmm calibrate --held-out` runs it: the session checks
/// the settings and the models' inputs against the arm's physics and the
/// data, fits the arm's layout with its physics and the models' block,
/// scores the held-out placement through the fitted corrections and gives
/// its verdict.
fn fit(
    arm: &Arm,
    train: DataSet,
    test: DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
) -> Result<CalibrationReport, String> {
    let held_out = HeldOutData {
        data: test,
        data_file: "held-out placement".into(),
        lengths_file: None,
    };
    Problem::new(arm.clone(), train, model.clone())
        .and_then(|p| p.with_held_out(held_out))
        .and_then(|p| p.run(settings))
        .map_err(|e| e.to_string())
}

/// The geometry alone through [`lopo`] gives the library's
/// `leave_one_placement_out` figures bit for bit (the same procedure).
fn check_geometry_is_the_library(
    arm: &Arm,
    data: &DataSet,
    model: &ModelOptions,
    settings: &SolverSettings,
) -> anyhow::Result<()> {
    let library = leave_one_placement_out(&arm.params, data, model, settings)?;
    let ours = lopo(arm, data, model, settings)?;
    for (a, b) in library.iter().zip(&ours) {
        let c = b
            .calibrated
            .as_ref()
            .map_err(|e| anyhow::anyhow!("{}: refused: {e}", b.placement))?;
        let same = a.placement == b.placement
            && a.nominal == b.nominal
            && a.calibrated.e_mean.to_bits() == c.e_mean.to_bits()
            && a.calibrated.length_max.map(f64::to_bits) == c.length_max.map(f64::to_bits)
            && a.successful == b.successful;
        if !same {
            bail!(
                "{}: the library's leave_one_placement_out gives {:?}, this program {:?}",
                a.placement,
                a.calibrated,
                c
            );
        }
    }
    if library.len() != ours.len() {
        bail!(
            "the library has {} folds, this program {}",
            library.len(),
            ours.len()
        );
    }
    Ok(())
}

/// `a..b` of the values (rounded to whole per cent), or `-`.
fn range(v: &[f64]) -> String {
    if v.is_empty() {
        return "-".into();
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    format!("{lo:+.0}..{hi:+.0} %")
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn pct(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:+.1} %"))
}

/// The Markdown row of one folder, prior and model.
fn row(data: &str, prior: &str, model: &str, folds: &[Fold], seconds: f64) -> String {
    let cons: Vec<f64> = folds.iter().filter_map(Fold::consistency_change).collect();
    let dist: Vec<f64> = folds.iter().filter_map(Fold::distance_change).collect();
    let scored: Vec<(&Fold, &Figures)> = (folds.iter())
        .filter_map(|f| Some((f, f.calibrated.as_ref().ok()?)))
        .collect();
    // The change of the means, over the folds scored (the README's `mean`
    // row when none is refused).
    let of_means = |get: &dyn Fn(&Figures) -> Option<f64>| {
        let pairs: Vec<(f64, f64)> = (scored.iter())
            .filter_map(|(f, c)| Some((get(&f.nominal)?, get(c)?)))
            .collect();
        let n = mean(&pairs.iter().map(|p| p.0).collect::<Vec<_>>());
        let c = mean(&pairs.iter().map(|p| p.1).collect::<Vec<_>>());
        Some(percent(n?, c?))
    };
    let refused: Vec<String> = (folds.iter())
        .filter_map(|f| {
            let e = f.calibrated.as_ref().err()?;
            Some(format!("{} ({e})", f.placement))
        })
        .collect();
    let refused: Vec<String> = refused
        .into_iter()
        .chain(
            (folds.iter())
                .filter(|f| !f.refused.is_empty())
                .map(|f| format!("{} ({})", f.placement, short(&f.refused))),
        )
        .collect();
    let count = |v: &[String]| {
        if v.is_empty() {
            "0".to_string()
        } else {
            format!("{}: {}", v.len(), v.join("; "))
        }
    };
    let (fitted, held): (usize, usize) = (
        folds.iter().map(|f| f.fitted.len()).sum(),
        folds.iter().map(|f| f.held.len()).sum(),
    );
    format!(
        "| {data} | {prior} | {model} | {} | {} | {} | {} | {} | {} | {} | {fitted} / {held} | {seconds:.2} |",
        range(&cons),
        pct(mean(&cons)),
        pct(of_means(&|f: &Figures| Some(f.e_mean))),
        range(&dist),
        pct(mean(&dist)),
        pct(of_means(&|f: &Figures| f.length_max)),
        count(&refused),
    )
}

/// The verdict's reasons in short: `not converged`, `gross geometry`, or
/// the implausible corrections' names and values.
fn short(reasons: &[String]) -> String {
    let mut out = Vec::new();
    for r in reasons {
        if r.starts_with("the solver did not reach") {
            out.push("not converged".to_string());
        } else if r.starts_with("the calibrated arm is not the nominal arm's geometry") {
            out.push("gross geometry".to_string());
        } else if let Some(rest) =
            r.strip_prefix("an auxiliary block has values no real instrument could have: ")
        {
            // `name = value unit: beyond any real arm (… at most)`.
            let names: Vec<&str> = rest
                .split("; ")
                .map(|b| b.split(": beyond").next().unwrap_or(b))
                .collect();
            out.push(format!("implausible {}", names.join(", ")));
        } else {
            out.push(r.clone());
        }
    }
    out.join("; ")
}

/// Each fold's figures, verdict and fitted corrections.
fn detail(data: &str, prior: &str, model: &str, folds: &[Fold]) -> String {
    let mut s = format!("\n{data}, prior {prior}, {model}:\n");
    for f in folds {
        let dist = match (
            f.nominal.length_max,
            f.calibrated.as_ref().ok().and_then(|c| c.length_max),
        ) {
            (Some(n), Some(c)) => format!(", |d-50| {n:.3} -> {c:.3} mm"),
            _ => String::new(),
        };
        match &f.calibrated {
            Ok(c) => {
                s += &format!(
                    "  {}: consistency {:.3} -> {:.3} mm{dist}{}\n",
                    f.placement,
                    f.nominal.e_mean,
                    c.e_mean,
                    if f.successful { "" } else { " (not converged)" }
                )
            }
            Err(e) => s += &format!("  {}: refused: {e}\n", f.placement),
        }
        for r in &f.refused {
            s += &format!("    verdict refuses: {r}\n");
        }
        for v in &f.fitted {
            s += &format!("    fitted {v}\n");
        }
        for v in &f.held {
            s += &format!("    held {v}\n");
        }
    }
    s
}
