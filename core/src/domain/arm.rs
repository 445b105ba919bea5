//! An arm: its name, geometry, joint limits and what it states beyond
//! them. Its file is [`crate::io::arm`].

use crate::corrections::Physics;
use crate::params::DhParams;
use crate::tolerances::Tolerances;

/// An arm: its name, its geometry (mm, rad) and its optional joint limits.
#[derive(Clone, Debug, PartialEq)]
pub struct Arm {
    /// Free-form name (may be empty).
    pub name: String,
    /// Geometry, mm and rad.
    pub params: DhParams,
    /// Per joint, the optional `[min, max]` of the encoder reading `q`, rad.
    /// Has one entry per joint when read from a file.
    pub limits: Vec<Option<[f64; 2]>>,
    /// The stated tolerances of the nominal geometry (the arm file's
    /// `[prior]` table), if any: a fit uses them as a prior unless told
    /// otherwise.
    pub prior: Option<Tolerances>,
    /// What the arm states beyond its geometry: masses, gravity and the
    /// corrections' values ([`crate::corrections`]); empty by default.
    /// Boxed: most arms have none, and an arm is moved by value often.
    pub physics: Box<Physics>,
    /// The diameter of the probe's ball, mm (`[probe] ball_diameter_mm`),
    /// if stated: points probed on a surface lie a ball radius from the
    /// probe centre the chain ends in (sphere surfaces, [`crate::residuals::spheres`]).
    pub ball_diameter_mm: Option<f64>,
    /// The named tool points beyond the probe (`[[tool]]`,
    /// [`crate::io::tools`]), in file order; empty for most arms.
    pub tools: Vec<super::Tool>,
}

impl Arm {
    /// An arm without joint limits.
    ///
    /// ```
    /// use aacmm_core::{domain::Arm, params::DhParams};
    /// let arm = Arm::without_limits("nominal", DhParams::paper_nominal());
    /// assert_eq!(arm.limits, vec![None; 6]);
    /// ```
    pub fn without_limits(name: impl Into<String>, params: DhParams) -> Arm {
        let n = params.joint_count();
        Arm {
            name: name.into(),
            params,
            limits: vec![None; n],
            prior: None,
            physics: Box::default(),
            ball_diameter_mm: None,
            tools: Vec::new(),
        }
    }
}
