//! What `identify` reports, built once for every front end: which
//! parameters the data can determine at the stated noise
//! ([`crate::identify`]), with the prior's rank and conditioning when the arm
//! has tolerances ([`crate::calibrate::prior::conditioning`]), as the JSON of
//! `aacmm identify --json` ([`IdentifyReport::to_json`]) and the tables it
//! prints ([`IdentifyReport::summary`]), both rendered in [`crate::report`].

use serde::{Deserialize, Serialize};

use super::Sources;
use crate::calibrate::prior::conditioning_with;
use crate::calibrate::{CalibrationError, PriorConditioning};
use crate::corrections::Beyond;
use crate::domain::Arm;
use crate::identify::{Evidence, Identification, identify_with};
use crate::io::AngleUnit;
use crate::residuals::Noise;
use crate::tolerances::Tolerances;

/// The identifiability of an arm's parameters from a data set: the schema
/// of `aacmm identify --json` ([`IdentifyReport::to_json`]) and the tables
/// it prints ([`IdentifyReport::summary`]), built once for every front end —
/// which parameters the data can determine at the stated noise
/// ([`crate::identify`]), with the prior's rank and conditioning when the
/// arm has tolerances ([`crate::calibrate::prior::conditioning`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdentifyReport {
    /// The arm's name.
    pub arm: String,
    /// Its file.
    pub arm_file: String,
    /// The poses file.
    pub data_file: String,
    /// The lengths file, if any.
    pub(crate) lengths_file: Option<String>,
    /// Touches.
    pub touches: usize,
    /// Points.
    pub points: usize,
    /// Reference lengths.
    pub reference_lengths: usize,
    /// Reference positions (their frames fitted and eliminated).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub positions: usize,
    /// The noise the touches are weighed with, in words (degrees and mm).
    pub noise: String,
    /// The analysis.
    pub identification: Identification,
    /// The rank and conditioning with the arm's tolerances, when it has
    /// any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior: Option<PriorConditioning>,
    /// The columns of the models beyond geometry asked for, judged after
    /// the geometry: kept or held, with the σ the data predict.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub corrections: Vec<CorrectionColumn>,
    /// Points probed on reference spheres analysed with the data (their
    /// centres, and sizes unless stated, fitted and eliminated); absent
    /// without them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spheres: Option<SphereCount>,
}

/// The points on spheres an analysis saw.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SphereCount {
    /// Their file.
    pub file: String,
    /// Points.
    pub points: usize,
    /// Spheres.
    pub spheres: usize,
    /// The spheres' stated diameter, mm (none: fitted per sphere).
    pub(crate) stated_diameter: Option<f64>,
}

/// A correction column beyond geometry as the data see it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CorrectionColumn {
    /// Its name (`compliance2`, `harmonic5.sin1`).
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Its predicted σ (k = 1) at the stated noise, with the free geometry,
    /// the frames and the other kept corrections fitted; `None` when held.
    pub sigma: Option<f64>,
    /// The fitted column it correlates with most, and `ρ`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) most_correlated: Option<(String, f64)>,
    /// Why it is held at its stated value, when the data cannot separate
    /// it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) held: Option<String>,
}

impl IdentifyReport {
    /// Analyses `data` at `arm` with touches weighed from `noise` (without
    /// stated noise, as a 0.01 mm touch) on `threads` threads, and, with
    /// `prior`, the rank and conditioning it adds; `sources` names the
    /// inputs.
    ///
    /// # Errors
    ///
    /// An [`OptionError`](crate::error::OptionError) on `noise.…` or `threads`;
    /// [`CalibrationError::Joints`] when the data have another joint count;
    /// the kernel's refusal of the arm or of weights that are not finite.
    #[allow(clippy::too_many_arguments)] // the inputs of `aacmm identify`, each named
    pub(crate) fn new(
        arm: &Arm,
        evidence: Evidence<'_>,
        noise: &Noise,
        prior: Option<&Tolerances>,
        beyond: &Beyond,
        threads: usize,
        sources: &Sources,
    ) -> Result<IdentifyReport, CalibrationError> {
        let data = evidence.data;
        noise.check()?;
        beyond.check(arm.params.joint_count())?;
        beyond.check_inputs(&arm.physics, &data.condition_sets())?;
        crate::calibrate::check_threads(threads)?;
        let joints = arm.params.joint_count();
        if data.joints() != joints {
            return Err(CalibrationError::Joints {
                arm: joints,
                data: data.joints(),
            });
        }
        // Each tool's touches seen through its nominal offset, a tool the
        // arm does not list refused by file, line and field.
        let resolved;
        let (data, evidence) = if data.touch_tools().is_some() {
            resolved = super::checks::of_arm_tools(arm, data.clone())?;
            let evidence = crate::identify::Evidence {
                data: &resolved,
                added: evidence.added,
            };
            (&resolved, evidence)
        } else {
            (data, evidence)
        };
        let identification = identify_with(&arm.params, data, noise, evidence.added, threads)?;
        let corrections = if beyond.is_empty() {
            Vec::new()
        } else {
            correction_columns(arm, evidence, noise, beyond, &identification, threads)?
        };
        let prior = match prior {
            Some(t) => Some(conditioning_with(
                &arm.params,
                evidence,
                noise,
                t,
                &identification,
                threads,
            )?),
            None => None,
        };
        Ok(IdentifyReport {
            arm: arm.name.clone(),
            arm_file: sources.arm_file.clone(),
            data_file: sources.data_file.clone(),
            lengths_file: sources.lengths_file.clone(),
            touches: data.len(),
            points: data.points().len(),
            reference_lengths: data.references().len(),
            positions: data.positions().map_or(0, |p| p.len()),
            noise: noise_text(noise),
            identification,
            prior,
            corrections,
            spheres: None,
        })
    }

    /// Says which points on spheres the analysis saw (the evidence's added
    /// term): the summary's first line and the JSON name them.
    pub(crate) fn with_spheres(mut self, spheres: SphereCount) -> IdentifyReport {
        self.spheres = Some(spheres);
        self
    }
}

/// The correction columns of `beyond` at `arm` on `data`: each judged after
/// the free geometry of `id` and the frames
/// ([`crate::calibrate::correction_columns`]), the kept ones' σ and
/// strongest correlation from the normal equations of everything fitted.
fn correction_columns(
    arm: &Arm,
    evidence: Evidence<'_>,
    noise: &Noise,
    beyond: &Beyond,
    id: &Identification,
    threads: usize,
) -> Result<Vec<CorrectionColumn>, CalibrationError> {
    let data = evidence.data;
    let mut layout =
        crate::residuals::positions::layout_with(&arm.params, data, &arm.physics, beyond)?;
    let terms = match evidence.added {
        Some(add) => add(&mut layout)?,
        None => Vec::new(),
    };
    let objective = crate::objective::Objective::of_data(
        layout.clone(),
        data,
        noise,
        terms,
        None,
        0.01,
        threads,
    )?;
    let all: Vec<usize> = (0..layout.len()).collect();
    let full = (objective.normal(&objective.start(), &all))?;
    let geometry = layout.geometry_columns();
    let free: Vec<usize> = (id.free_columns().into_iter())
        .chain(geometry..layout.len())
        .collect();
    let (free, held) = crate::calibrate::correction_columns(&full, &layout, free)?;
    let n = full.restrict(&free).ok_or(CalibrationError::Shape)?;
    let k = free.len();
    let m = nalgebra::DMatrix::from_row_slice(k, k, &n.jtj);
    let cov = m.cholesky().map(|c| c.inverse());
    let name = |c: usize| layout.parameter(c).map_or(String::new(), |p| p.name);
    let cols = layout.corrections().map_or(0..0, |(_, c)| c);
    Ok(cols
        .filter_map(|c| {
            let p = layout.parameter(c)?;
            let held = held.iter().find(|(h, _)| *h == c).map(|(_, w)| w.clone());
            let at = free.iter().position(|&f| f == c);
            let (sigma, most_correlated) = match (&cov, at) {
                (Some(cov), Some(a)) => {
                    let s = cov[(a, a)].max(0.0).sqrt();
                    let rho = |b: usize| cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt();
                    let best = (0..k)
                        .filter(|&b| b != a)
                        .max_by(|&x, &y| rho(x).abs().total_cmp(&rho(y).abs()))
                        .map(|b| (name(free[b]), rho(b)));
                    (Some(p.unit.to_user(s)), best)
                }
                _ => (None, None),
            };
            Some(CorrectionColumn {
                name: p.name,
                unit: p.unit.name().to_string(),
                sigma,
                most_correlated,
                held,
            })
        })
        .collect())
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// The start of [`IdentifyReport::noise`] when no touch noise is stated.
pub(crate) const NOT_STATED: &str = "not stated";

/// The noise in words: degrees as the user stated them (the library holds
/// radians; [`AngleUnit::from_internal_exact`] gives back the number typed).
fn noise_text(noise: &Noise) -> String {
    let positions = match (noise.position_mm, noise.position_mm_per_m) {
        (Some(a), Some(b)) => format!("; positions {a} mm + {b} mm/m"),
        (Some(a), None) => format!("; positions {a} mm"),
        _ => String::new(),
    };
    if !noise.stated() {
        return format!("{NOT_STATED}: σ as for a 0.01 mm touch{positions}");
    }
    let encoder = noise
        .encoder_rad
        .map_or(0.0, |r| AngleUnit::Deg.from_internal_exact(r));
    format!(
        "encoders {encoder}°, probe {} mm{positions}",
        noise.probe_mm.unwrap_or(0.0)
    )
}
