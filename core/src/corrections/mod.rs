//! Beyond geometry: joint compliance under gravity, encoder harmonics,
//! backlash, thermal expansion and drift — small physical models a user switches on,
//! identified with the geometry.
//!
//! What an arm states beyond its D-H table is its [`Physics`]: link and
//! tool masses and the gravity direction (what loads the joints), and the
//! values of the corrections (a compliance per joint, harmonics per joint
//! and order, a thermal expansion coefficient). A fit switches models on
//! with [`Beyond`]; their unknowns are one auxiliary parameter block
//! ([`crate::residuals::CorrectionBlock`], the layout's first after the
//! geometry), and a
//! correction the arm states but the fit does not estimate is applied at
//! its stated value.
//!
//! Each pose's readings `q` and conditions (temperature `T`, time `t`)
//! become what the chain sees:
//!
//! ```text
//! q'_j = q_j + Σ_k (s_jk sin(k q_j) + c_jk cos(k q_j)) + κ_j τ_j(q) + b_j sgn τ_j(q)
//! p    = (1 + c·(T − T0)) · p_chain(q') + v·(t − t_0)
//! ```
//!
//! with `τ_j` the gravity torque about joint `j` ([`gravity`]), `κ_j` its
//! compliance, `c` the expansion coefficient (every length scales, so the
//! position about the base does), `T0` the reference temperature (20 °C,
//! ISO 1) and `v` the drift of the base against the instrument over the
//! session (`t_0` its first time). The harmonics are functions of the
//! encoder's own reading (an eccentric disc errs by where it is read).
//!
//! Backlash: a reducer's play lets the link sit anywhere within `±b_j` of
//! where its motor's encoder says; at rest under gravity the load presses
//! one gear flank, so the link sits `b_j` further along the gravity torque
//! `τ_j` (for a prismatic joint, `τ_j` is the gravity force along the
//! slide, N, and `b_j` is in mm). A joint whose torque is exactly zero (a
//! vertical axis) floats: its correction is zero, as is its column. Where
//! a readings file records the direction each joint approached the pose
//! from ([`crate::io::approach`], [`Conditions::approach`]), a known
//! direction `s_j = ±1` replaces `sgn τ_j`: `q_j + b_j s_j`.
//!
//! The Jacobian columns: a reading correction moves the probe as the joint
//! does — `∂p/∂κ_j = τ_j ∂p/∂θ_j` (the joint's zero offset column), `∂p/∂s_jk
//! = sin(k q_j) ∂p/∂θ_j`, `∂p/∂b_j = sgn τ_j ∂p/∂θ_j` (`∂p/∂d_j` for a
//! slide) — the expansion `∂p/∂c = (T − T0) p_chain`, the
//! drift `∂p/∂v = (t − t_0) I`. `τ` is computed at the arm being evaluated
//! and its own dependence on the geometry is left out of the Jacobian
//! (κτ is a few µrad; its change with a millimetre of geometry is 10⁻³ of
//! that).
//!
//! What the data can separate is the identifiability analysis's business:
//! a compliance is not identifiable from poses that all load the joint
//! alike (its column is then its zero offset's); a first harmonic's `cos`
//! is the zero offset's over a joint that barely turns; an expansion
//! coefficient from data at one temperature is the scale; a backlash of a
//! joint whose torque keeps one sign over every pose is the zero offset
//! (its column is `±∂p/∂θ_j`: only poses that load both flanks separate
//! it), and is held as not separable. Internal units
//! keep the columns near the geometry's size: µrad/(N·m), ppm/K, mm/h.

mod effects;
pub mod gravity;

use serde::{Deserialize, Serialize};

pub use effects::{Conditions, Effects};
pub(crate) use effects::{SeenCache, angles_for, readings_for};

use crate::error::OptionError;
use crate::setting::Setting;

/// ISO 1's reference temperature, °C: the calibrated lengths are at it.
pub const REFERENCE_TEMPERATURE_C: f64 = 20.0;

/// A mass and where it is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mass {
    /// kg.
    pub kg: f64,
    /// Its centre in its link's D-H frame, mm; `None`: halfway between the
    /// link's frame origins (the tool: at the probe).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub com_mm: Option<[f64; 3]>,
}

impl Mass {
    /// `kg` at the default centre.
    pub fn at_middle(kg: f64) -> Mass {
        Mass { kg, com_mm: None }
    }
}

/// One encoder harmonic: `sin·sin(k q) + cos·cos(k q)` added to joint
/// `joint`'s reading.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Harmonic {
    /// Joint, 0-based.
    pub joint: usize,
    /// Order `k ≥ 1` (1: the disc's eccentricity).
    pub order: u32,
    /// Its sine amplitude, rad.
    pub sin: f64,
    /// Its cosine amplitude, rad.
    pub cos: f64,
}

/// What an arm states beyond its geometry: masses and gravity, and the
/// values of the corrections. Empty by default (a purely geometric arm).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Physics {
    /// Per joint, the mass of the link after it (empty: none stated).
    #[serde(default)]
    pub link_masses: Vec<Option<Mass>>,
    /// The tool's (probe's, target's) mass.
    #[serde(default)]
    pub probe_mass: Option<Mass>,
    /// Gravity's direction in the base frame; `None`: −z.
    #[serde(default)]
    pub gravity: Option<[f64; 3]>,
    /// Per joint, its compliance, rad/(N·m) (empty: none).
    #[serde(default)]
    pub compliance: Vec<Option<f64>>,
    /// Encoder harmonics, rad.
    #[serde(default)]
    pub harmonics: Vec<Harmonic>,
    /// Per joint, its backlash (half the reducer's play): rad, mm for a
    /// prismatic joint (empty: none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub backlash: Vec<Option<f64>>,
    /// Thermal expansion coefficient of the lengths, 1/K.
    #[serde(default)]
    pub cte_per_k: Option<f64>,
    /// The temperature the geometry is at, °C (default
    /// [`REFERENCE_TEMPERATURE_C`]).
    #[serde(default)]
    pub reference_temperature_c: Option<f64>,
    /// Drift of the base against the instrument, mm/h (a fit's result,
    /// never an arm file's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drift_mm_per_h: Option<[f64; 3]>,
}

impl Physics {
    /// Whether any correction changes a position (masses alone do not).
    pub fn corrects(&self) -> bool {
        self.compliance.iter().any(|c| c.is_some_and(|v| v != 0.0))
            || self.harmonics.iter().any(|h| h.sin != 0.0 || h.cos != 0.0)
            || self.backlash.iter().any(|b| b.is_some_and(|v| v != 0.0))
            || self.cte_per_k.is_some_and(|c| c != 0.0)
            || self.drift_mm_per_h.is_some_and(|v| v != [0.0; 3])
    }

    /// Whether any mass is stated.
    pub(crate) fn has_masses(&self) -> bool {
        self.probe_mass.is_some() || self.link_masses.iter().any(Option::is_some)
    }

    /// Joint `j`'s compliance, rad/(N·m), 0 when none is stated.
    pub fn compliance_of(&self, j: usize) -> f64 {
        self.compliance.get(j).copied().flatten().unwrap_or(0.0)
    }

    /// Joint `j`'s backlash (rad, mm for a slide), 0 when none is stated.
    pub fn backlash_of(&self, j: usize) -> f64 {
        self.backlash.get(j).copied().flatten().unwrap_or(0.0)
    }

    /// Whether a reading correction needs the gravity loads: a compliance
    /// or a backlash, stated or fitted.
    pub(crate) fn needs_loads(&self, fit: &Beyond) -> bool {
        !fit.compliance.is_empty()
            || !fit.backlash.is_empty()
            || self.compliance.iter().any(|c| c.is_some_and(|v| v != 0.0))
            || self.backlash.iter().any(|b| b.is_some_and(|v| v != 0.0))
    }

    /// The reference temperature, °C.
    pub fn reference_c(&self) -> f64 {
        self.reference_temperature_c
            .unwrap_or(REFERENCE_TEMPERATURE_C)
    }

    /// This physics with the fitted values `values` (a
    /// [`crate::residuals::CorrectionBlock`]'s columns, internal units) of
    /// the models `fit` in place of the stated ones, for an arm of `joints`
    /// joints.
    pub(crate) fn with_fitted(&self, fit: &Beyond, values: &[f64], joints: usize) -> Physics {
        let mut out = self.clone();
        if !fit.compliance.is_empty() {
            out.compliance.resize(joints, None);
        }
        if !fit.backlash.is_empty() {
            out.backlash.resize(joints, None);
        }
        for (column, &v) in fit.columns().iter().zip(values) {
            match *column {
                Column::Compliance(j) => out.compliance[j] = Some(v * 1e-6),
                Column::Backlash(j) => out.backlash[j] = Some(v),
                Column::Sin(j, k) => out.harmonic_mut(j, k).sin = v,
                Column::Cos(j, k) => out.harmonic_mut(j, k).cos = v,
                Column::Expansion => out.cte_per_k = Some(v * 1e-6),
                Column::Drift(a) => out.drift_mm_per_h.get_or_insert([0.0; 3])[a] = v,
            }
        }
        out.harmonics.sort_by_key(|h| (h.joint, h.order));
        out
    }

    /// Joint `joint`'s harmonic of order `order`, added at zero if absent.
    fn harmonic_mut(&mut self, joint: usize, order: u32) -> &mut Harmonic {
        let at = match (self.harmonics.iter()).position(|h| (h.joint, h.order) == (joint, order)) {
            Some(at) => at,
            None => {
                self.harmonics.push(Harmonic {
                    joint,
                    order,
                    sin: 0.0,
                    cos: 0.0,
                });
                self.harmonics.len() - 1
            }
        };
        &mut self.harmonics[at]
    }

    /// The stated values of the models `fit` estimates, as the block's
    /// start (internal units): what a fit starts from.
    pub(crate) fn start_of(&self, fit: &Beyond) -> Vec<f64> {
        let harmonic =
            |j: usize, k: u32| (self.harmonics.iter()).find(|h| (h.joint, h.order) == (j, k));
        (fit.columns().into_iter())
            .map(|column| match column {
                Column::Compliance(j) => self.compliance_of(j) * 1e6,
                Column::Backlash(j) => self.backlash_of(j),
                Column::Sin(j, k) => harmonic(j, k).map_or(0.0, |h| h.sin),
                Column::Cos(j, k) => harmonic(j, k).map_or(0.0, |h| h.cos),
                Column::Expansion => self.cte_per_k.unwrap_or(0.0) * 1e6,
                Column::Drift(a) => self.drift_mm_per_h.map_or(0.0, |d| d[a]),
            })
            .collect()
    }
}

/// The models a fit estimates beyond the geometry. Empty by default.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Beyond {
    /// Joints (0-based) with a compliance.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub compliance: Vec<usize>,
    /// Encoder harmonics: (joint 0-based, order ≥ 1).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub harmonics: Vec<(usize, u32)>,
    /// Joints (0-based) with a backlash.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub backlash: Vec<usize>,
    /// A thermal expansion coefficient (needs temperatures).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub thermal: bool,
    /// A linear drift of the base in time (needs times).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub drift: bool,
}

/// One column of the models a fit switches on: what the block's names,
/// start, fitted values and Jacobian all follow ([`Beyond::columns`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Column {
    /// Joint `j`'s compliance (µrad/(N·m)).
    Compliance(usize),
    /// The sine amplitude of joint `j`'s harmonic of order `k` (rad).
    Sin(usize, u32),
    /// Its cosine amplitude (rad).
    Cos(usize, u32),
    /// Joint `j`'s backlash (rad; mm for a slide).
    Backlash(usize),
    /// The expansion coefficient (ppm/K).
    Expansion,
    /// The drift along base axis `a` (mm/h).
    Drift(usize),
}

/// Harmonic orders above this are refused: an encoder's errors of interest
/// are the first few; beyond, a term fits the data's noise.
pub const MAX_HARMONIC_ORDER: u32 = 16;

impl Beyond {
    /// Whether no model is switched on.
    pub fn is_empty(&self) -> bool {
        self.compliance.is_empty()
            && self.harmonics.is_empty()
            && self.backlash.is_empty()
            && !self.thermal
            && !self.drift
    }

    /// The block's columns, in order: the compliances, each harmonic's sine
    /// and cosine, the backlashes, the expansion, the drift's three axes.
    pub(crate) fn columns(&self) -> Vec<Column> {
        let mut out: Vec<Column> = self
            .compliance
            .iter()
            .map(|&j| Column::Compliance(j))
            .collect();
        for &(j, k) in &self.harmonics {
            out.extend([Column::Sin(j, k), Column::Cos(j, k)]);
        }
        out.extend(self.backlash.iter().map(|&j| Column::Backlash(j)));
        if self.thermal {
            out.push(Column::Expansion);
        }
        if self.drift {
            out.extend((0..3).map(Column::Drift));
        }
        out
    }

    /// Columns of the block.
    pub fn len(&self) -> usize {
        self.compliance.len()
            + 2 * self.harmonics.len()
            + self.backlash.len()
            + usize::from(self.thermal)
            + 3 * usize::from(self.drift)
    }

    /// Parses `2,3,4` (1-based joints) into compliances.
    ///
    /// ```
    /// use aacmm_core::corrections::Beyond;
    /// assert_eq!(Beyond::parse_compliance("2,3").unwrap(), vec![1, 2]);
    /// assert!(Beyond::parse_compliance("0").is_err());
    /// ```
    ///
    /// # Errors
    ///
    /// A joint that is not a positive integer, or one listed twice.
    pub fn parse_compliance(text: &str) -> Result<Vec<usize>, OptionError> {
        parse_joints(text, Setting::Compliance)
    }

    /// Parses `2,3` (1-based joints) into backlashes.
    ///
    /// ```
    /// use aacmm_core::corrections::Beyond;
    /// assert_eq!(Beyond::parse_backlash("3, 2").unwrap(), vec![1, 2]);
    /// assert_eq!(Beyond::parse_backlash("2,2").unwrap_err().field(), "backlash");
    /// ```
    ///
    /// # Errors
    ///
    /// A joint that is not a positive integer, or one listed twice.
    pub fn parse_backlash(text: &str) -> Result<Vec<usize>, OptionError> {
        parse_joints(text, Setting::Backlash)
    }

    /// Parses `2:1,5:1-2` (joint:orders, orders a number or a range) into
    /// harmonics.
    ///
    /// ```
    /// use aacmm_core::corrections::Beyond;
    /// assert_eq!(Beyond::parse_harmonics("2:1,5:1-2").unwrap(), vec![(1, 1), (4, 1), (4, 2)]);
    /// assert_eq!(Beyond::parse_harmonics("2").unwrap_err().field(), "harmonics");
    /// ```
    ///
    /// # Errors
    ///
    /// A malformed entry, an order outside 1..=[`MAX_HARMONIC_ORDER`], or
    /// a harmonic listed twice.
    pub fn parse_harmonics(text: &str) -> Result<Vec<(usize, u32)>, OptionError> {
        let mut out = Vec::new();
        for part in text.split(',').map(str::trim) {
            let Some((joint, orders)) = part.split_once(':') else {
                return Err(OptionError::new(
                    Setting::Harmonics,
                    part,
                    "expected JOINT:ORDERS, e.g. 2:1 or 5:1-2",
                ));
            };
            let j = parse_joint(joint.trim(), Setting::Harmonics)?;
            let (lo, hi) = match orders.split_once('-') {
                Some((a, b)) => (parse_order(a, part)?, parse_order(b, part)?),
                None => (parse_order(orders, part)?, parse_order(orders, part)?),
            };
            if lo > hi {
                return Err(OptionError::new(
                    Setting::Harmonics,
                    part,
                    "empty order range",
                ));
            }
            for k in lo..=hi {
                if out.contains(&(j, k)) {
                    return Err(OptionError::new(Setting::Harmonics, part, "listed twice"));
                }
                out.push((j, k));
            }
        }
        out.sort_unstable();
        Ok(out)
    }

    /// Checks the models against an arm of `joints` joints: every joint in
    /// range.
    ///
    /// # Errors
    ///
    /// The first refused setting, by its field.
    pub(crate) fn check(&self, joints: usize) -> Result<(), OptionError> {
        let last = self
            .compliance
            .iter()
            .chain(self.harmonics.iter().map(|(j, _)| j))
            .chain(&self.backlash)
            .find(|&&j| j >= joints);
        if let Some(&j) = last {
            let field = if self.compliance.contains(&j) {
                Setting::Compliance
            } else if self.harmonics.iter().any(|h| h.0 == j) {
                Setting::Harmonics
            } else {
                Setting::Backlash
            };
            return Err(OptionError::new(
                field,
                j + 1,
                format!("joint {}: the arm has {joints} joints", j + 1),
            ));
        }
        Ok(())
    }

    /// Checks the models against what the arm and the data provide: a
    /// compliance needs masses that load the joints, an expansion (fitted
    /// or stated) temperatures, a drift times — in every set of poses
    /// `sets` (each its file's name and conditions:
    /// [`crate::dataset::DataSet::condition_sets`]).
    ///
    /// # Errors
    ///
    /// The first model its inputs cannot support, by its field, with what
    /// to add.
    pub(crate) fn check_inputs(
        &self,
        physics: &Physics,
        sets: &[(String, Conditions<'_>)],
    ) -> Result<(), OptionError> {
        let stated_cte = physics.cte_per_k.is_some_and(|c| c != 0.0);
        for (file, c) in sets {
            if (self.thermal || stated_cte) && c.temperature_c.is_none() {
                let (field, value) = if self.thermal {
                    (Setting::Thermal, "on".to_string())
                } else {
                    (
                        Setting::CtePerK,
                        format!("{}", physics.cte_per_k.unwrap_or(0.0)),
                    )
                };
                return Err(OptionError::new(
                    field,
                    value,
                    format!(
                        "thermal expansion needs the temperature of every pose: {file} has \
                         no `temperature` column (°C)"
                    ),
                ));
            }
            if self.drift && c.time_s.is_none() {
                return Err(OptionError::new(
                    Setting::Drift,
                    "on",
                    format!(
                        "a drift needs the time of every pose: {file} has no `time` column (s)"
                    ),
                ));
            }
        }
        if !physics.has_masses() {
            let stated = physics.backlash.iter().any(|b| b.is_some_and(|v| v != 0.0));
            let refused = [
                (Setting::Compliance, joints_text(&self.compliance), ""),
                (
                    Setting::Backlash,
                    joints_text(&self.backlash),
                    ", and their torque decides which flank a backlash takes",
                ),
                (
                    Setting::Backlash,
                    if stated {
                        "stated".into()
                    } else {
                        String::new()
                    },
                    ", and their torque decides which flank a backlash takes",
                ),
            ];
            if let Some((field, value, why)) = refused.into_iter().find(|r| !r.1.is_empty()) {
                return Err(OptionError::new(
                    field,
                    value,
                    format!(
                        "no mass loads the joints{why}: state `mass_kg` of the links (in their \
                         [[joint]] tables) and of the tool ([probe]) in the arm file"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// `1,2,3`: 0-based joints as users number them.
fn joints_text(joints: &[usize]) -> String {
    (joints.iter().map(|j| (j + 1).to_string()))
        .collect::<Vec<_>>()
        .join(",")
}

/// Comma-separated 1-based joints, each once, into sorted 0-based ones.
fn parse_joints(text: &str, field: Setting) -> Result<Vec<usize>, OptionError> {
    let mut out = Vec::new();
    for part in text.split(',').map(str::trim) {
        let j = parse_joint(part, field)?;
        if out.contains(&j) {
            return Err(OptionError::new(field, part, "joint listed twice"));
        }
        out.push(j);
    }
    out.sort_unstable();
    Ok(out)
}

fn parse_joint(text: &str, field: Setting) -> Result<usize, OptionError> {
    match text.parse::<usize>() {
        Ok(j) if j >= 1 => Ok(j - 1),
        _ => Err(OptionError::new(
            field,
            text,
            "a joint is a number from 1 (the base joint)",
        )),
    }
}

fn parse_order(text: &str, part: &str) -> Result<u32, OptionError> {
    match text.trim().parse::<u32>() {
        Ok(k) if (1..=MAX_HARMONIC_ORDER).contains(&k) => Ok(k),
        _ => Err(OptionError::new(
            Setting::Harmonics,
            part,
            format!("an order is a whole number from 1 to {MAX_HARMONIC_ORDER}"),
        )),
    }
}
