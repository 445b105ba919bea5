//! `aacmm identify`: which parameters the data can determine, how well, and
//! which to fix (see `aacmm_core::identify` for the method).

use std::path::PathBuf;

use aacmm_core::calibrate::{PriorConditioning, prior::conditioning};
use aacmm_core::identify::{Identification, identify};
use aacmm_core::io::source_name;
use anyhow::{Context, Result};
use serde::Serialize;

use super::fit::FitInput;
use crate::output::Stdout;
use crate::paths::check_output_file;

/// Identifiability of the arm's parameters from the data.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    fit: FitInput,
    /// Also write everything as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Serialize)]
struct Report<'a> {
    arm: &'a str,
    arm_file: String,
    data_file: String,
    lengths_file: Option<String>,
    touches: usize,
    points: usize,
    reference_lengths: usize,
    noise: String,
    identification: &'a Identification,
    #[serde(skip_serializing_if = "Option::is_none")]
    prior: Option<PriorConditioning>,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(json) = &args.json {
        check_output_file("--json", json, &args.fit.paths())?;
    }
    let noise = args.fit.noise();
    noise.check().map_err(super::fit::flag_error)?;
    let (arm, tolerances, data, _) = args.fit.read_with_prior()?;
    args.fit.input.kernel(&arm)?;
    // Without stated noise the singular values are in units of a 0.01 mm touch.
    let assumed = !noise.stated();
    let id = identify(&arm.params, &data, &noise, args.fit.threads())
        .with_context(|| source_name(&args.fit.input.arm))
        .map_err(|e| super::noise_flags(e, &args.fit))?;
    let noise_text = if assumed {
        "not stated: σ as for a 0.01 mm touch".to_string()
    } else {
        format!(
            "encoders {}°, probe {} mm",
            args.fit.encoder_noise.unwrap_or(0.0),
            args.fit.probe_noise.unwrap_or(0.0)
        )
    };
    let mut out = Stdout::new();
    out.print(format_args!(
        "arm `{}` ({}) on {}: {} touches of {} points, {} reference lengths\nnoise: {noise_text}\n\n",
        arm.name,
        args.fit.input.arm.display(),
        args.fit.input.data.display(),
        data.len(),
        data.points().len(),
        data.references().len()
    ))?;
    out.print(table(&id))?;
    let prior = match &tolerances {
        Some(t) => Some(
            conditioning(&arm.params, &data, &noise, t, &id, args.fit.threads())
                .with_context(|| source_name(&args.fit.input.arm))
                .map_err(|e| super::noise_flags(e, &args.fit))?,
        ),
        None => None,
    };
    if let Some(p) = &prior {
        let weighed = if assumed {
            "touches weighed as 0.01 mm, so the prior weighs little here: state \
             --probe-noise/--encoder-noise for its real weight"
        } else {
            "touches weighed from the stated noise"
        };
        out.print(format_args!(
            "\nWith the prior ({}; {} of {} parameters; {weighed}):\n  \
             rank {} of {} (data alone: {} after the rules)\n  condition number over the free \
             parameters {:.1} (data alone: {:.1})\n",
            p.tolerances,
            p.parameters_with_tolerance,
            p.parameters,
            p.rank_with,
            p.parameters,
            p.rank_without,
            p.condition_with,
            p.condition_without
        ))?;
    }
    out.finish()?;
    if let Some(path) = &args.json {
        let report = Report {
            arm: &arm.name,
            arm_file: source_name(&args.fit.input.arm),
            data_file: source_name(&args.fit.input.data),
            lengths_file: args.fit.lengths.as_deref().map(source_name),
            touches: data.len(),
            points: data.points().len(),
            reference_lengths: data.references().len(),
            noise: noise_text,
            identification: &id,
            prior,
        };
        super::write_json(path, &report)?;
    }
    Ok(())
}

/// Worker threads for the normal equations (results do not depend on it).
fn table(id: &Identification) -> String {
    let mut s = String::new();
    let sv: Vec<String> = id
        .singular_values
        .iter()
        .map(|v| format!("{v:.3e}"))
        .collect();
    s += &format!("Scaling: {}\n", id.scaling);
    s += &format!(
        "Singular values of the scaled Jacobian (all {} columns):\n",
        sv.len()
    );
    for chunk in sv.chunks(9) {
        s += &format!("  {}\n", chunk.join("  "));
    }
    if !id.recommendations.is_empty() {
        s += "\nModel (nearly parallel axes):\n";
        for r in &id.recommendations {
            s += &format!("  {r}\n");
        }
    }
    s += "\nStructural rules (hold whatever the noise does to the singular values):\n";
    for r in &id.rules {
        s += &format!("  {}: {}\n", r.name, r.explanation);
    }
    s += &format!(
        "\nRank: {} identifiable combinations (threshold {:.2e} = 1e-7 × s_max, after the rules); \
         condition number of the identifiable part {:.1}\n",
        id.rank, id.threshold, id.condition_number
    );
    if !id.null_relations.is_empty() {
        s += "\nUnidentifiable directions (one per redundant parameter; s = singular value of the scaled direction):\n";
        for r in &id.null_relations {
            s += &format!("  s = {:.1e}  {}\n", r.singular_value, r.text);
        }
    }
    if !id.weak_relations.is_empty() {
        s += "\nWeak directions (s < 1e-3 s_max):\n";
        for r in &id.weak_relations {
            s += &format!("  s = {:.1e}  {}\n", r.singular_value, r.text);
        }
    }
    let names: Vec<String> = id.fixed.iter().map(|f| f.id.to_string()).collect();
    s += &format!(
        "\nRecommended fixed set (--fix auto): {}\n",
        names.join(",")
    );
    let w = names.iter().map(String::len).max().unwrap_or(0);
    for (f, name) in id.fixed.iter().zip(&names) {
        s += &format!("  {name:<w$}  {}\n", f.reason);
    }
    s += "\nFree parameters at the stated noise:\n  parameter  unit   predicted sigma  identifiability\n";
    for f in &id.free {
        s += &format!(
            "  {:<9}  {:<4}  {:>15.3e}  {:>15.4}\n",
            f.id.to_string(),
            f.unit,
            f.sigma,
            f.identifiability
        );
    }
    if id.correlations.is_empty() {
        s += "\nNo pair of free parameters correlates with |rho| > 0.9.\n";
    } else {
        s += "\nCorrelations |rho| > 0.9:\n";
        for c in &id.correlations {
            s += &format!("  {:<8} {:<8} {:+.4}\n", c.a, c.b, c.rho);
        }
    }
    s
}
