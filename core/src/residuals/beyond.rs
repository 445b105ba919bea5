//! The corrections beyond geometry as a parameter block
//! ([`crate::corrections`]): the layout's first after the geometry.

use super::{Block, Parameter, Unit};
use crate::corrections::{Beyond, Column, Physics};

/// The unknowns of the models a fit switches on, with the arm's physics
/// (masses, stated values) they act through: the layout's first block.
#[derive(Clone, Debug, PartialEq)]
pub struct CorrectionBlock {
    /// What is fitted.
    pub(crate) fit: Beyond,
    /// The arm's physics: masses, and the stated values of what is not.
    pub(crate) physics: Physics,
    /// Joints of the arm.
    pub(crate) joints: usize,
    /// Its prismatic joints (bit `j`: joint `j` slides): their backlash is
    /// a length.
    pub(crate) prismatic: u16,
}

/// The largest plausible backlash of a revolute joint: 0.5°, rad.
pub(crate) const MAX_BACKLASH_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// The largest plausible backlash of a slide, mm.
pub(crate) const MAX_SLIDE_BACKLASH_MM: f64 = 0.5;

/// The name of the correction block in a layout.
pub const BLOCK_NAME: &str = "beyond";

impl CorrectionBlock {
    /// The physics at the block's values `x` (internal units).
    pub(crate) fn physics_at(&self, x: &[f64]) -> Physics {
        self.physics.with_fitted(&self.fit, x, self.joints)
    }
}

impl Block for CorrectionBlock {
    fn name(&self) -> &str {
        BLOCK_NAME
    }

    fn parameters(&self) -> Vec<Parameter> {
        let other = |s: &str| Unit::Other(s.to_string());
        (self.fit.columns().into_iter())
            .map(|column| {
                let (name, unit) = match column {
                    Column::Compliance(j) => (format!("compliance{}", j + 1), other("µrad/(N·m)")),
                    Column::Sin(j, k) => (format!("harmonic{}.sin{k}", j + 1), Unit::Angle),
                    Column::Cos(j, k) => (format!("harmonic{}.cos{k}", j + 1), Unit::Angle),
                    Column::Backlash(j) if self.prismatic & (1 << j) != 0 => {
                        (format!("backlash{}", j + 1), Unit::Length)
                    }
                    Column::Backlash(j) => (format!("backlash{}", j + 1), Unit::Angle),
                    Column::Expansion => ("thermal.cte".to_string(), other("ppm/K")),
                    Column::Drift(a) => (format!("drift.{}", ["x", "y", "z"][a]), other("mm/h")),
                };
                Parameter { name, unit }
            })
            .collect()
    }

    fn start(&self) -> Vec<f64> {
        self.physics.start_of(&self.fit)
    }

    /// Without naming every column (the layout asks often).
    fn len(&self) -> usize {
        self.fit.len()
    }

    fn implausible(&self, _start: &[f64], x: &[f64]) -> Option<String> {
        let names = self.parameters();
        // No real joint gives a tenth of a degree per N·m, no encoder errs
        // by a degree, no structural material expands by 0.1 % per kelvin,
        // no reducer a calibration is worth has half a degree (a slide half
        // a millimetre) of play each way.
        for (p, v) in names.iter().zip(x) {
            let limit = match &p.unit {
                Unit::Length if p.name.starts_with("backlash") => MAX_SLIDE_BACKLASH_MM,
                Unit::Angle if p.name.starts_with("backlash") => MAX_BACKLASH_RAD,
                Unit::Angle => 1f64.to_radians(),
                Unit::Other(u) if u.starts_with("µrad") => 1745.0,
                Unit::Other(u) if u == "ppm/K" => 1000.0,
                _ => continue,
            };
            if v.abs() > limit || !v.is_finite() {
                return Some(format!(
                    "{} = {:.4} {}: beyond any real arm ({} at most)",
                    p.name,
                    p.unit.to_user(*v),
                    p.unit.name(),
                    p.unit.to_user(limit)
                ));
            }
        }
        None
    }
}
