//! `aacmm.Noise`: what is known of the measurement noise, in the units the
//! command line uses (degrees for encoders, mm otherwise; mm per metre for
//! the distance-dependent part of a reference position's σ).

use aacmm_core::residuals::DEFAULT_LENGTH_SIGMA_MM;
use aacmm_core::residuals::Noise as CoreNoise;
use aacmm_core::session::user_noise;
use aacmm_core::setting::Setting;
use pyo3::prelude::*;

use crate::error::Result;

/// What is known of the measurement noise (the command line's noise
/// options). With neither touch noise stated, the touch σ is estimated from
/// the fit; likewise the σ of reference positions that state none, without
/// a position noise.
#[pyclass(frozen, module = "aacmm")]
#[derive(Clone)]
pub struct Noise {
    pub(crate) noise: CoreNoise,
    encoder_deg: Option<f64>,
    /// As given (the library keeps rad): its repr and getter show it.
    orientation_deg: Option<f64>,
}

impl Noise {
    /// The noise in the library's units, checked by the library
    /// ([`CoreNoise::check`]; a refusal names the Python argument). A
    /// length weight of 0 means none, as on the command line.
    fn checked(
        encoder_deg: Option<f64>,
        probe_mm: Option<f64>,
        length_default_mm: f64,
        length_weight: Option<f64>,
        position_mm: Option<f64>,
        position_mm_per_m: Option<f64>,
        orientation_deg: Option<f64>,
    ) -> Result<Noise> {
        // Judged here in the unit given: the library's check would show
        // the value in rad under a name in degrees.
        if let Some(d) = orientation_deg.filter(|d| !(d.is_finite() && *d > 0.0)) {
            let field = Setting::OrientationNoise;
            let e = aacmm_core::error::OptionError::new(field, d, "must be a finite number > 0");
            return Err(e.into());
        }
        let noise = CoreNoise {
            position_mm,
            position_mm_per_m,
            orientation_rad: orientation_deg.map(f64::to_radians),
            ..user_noise(encoder_deg, probe_mm, length_default_mm, length_weight)
        };
        noise.check()?;
        Ok(Noise {
            noise,
            encoder_deg,
            orientation_deg,
        })
    }
}

#[pymethods]
impl Noise {
    /// `encoder_deg`: σ of each encoder reading, degrees; `probe_mm`: σ of
    /// the probe seating per axis, mm; `length_default_mm`: σ of a reference
    /// length that states none, mm; `length_weight`: weight of every
    /// reference-length residual, 1/mm, overriding the uncertainties (0:
    /// none); `position_mm` and `position_mm_per_m`: σ per coordinate of a
    /// reference position that states no uncertainty, `A + B·distance`
    /// with `A = position_mm` (mm) and `B = position_mm_per_m` (mm per
    /// metre from the instrument; a laser tracker's 0.015 and 0.006; `B`
    /// needs `A`); `orientation_deg`: σ per axis of a tool orientation a
    /// positions file gives (`qw,qx,qy,qz`), degrees (> 0). Values must be finite and ≥ 0 (`position_mm` > 0), and
    /// stated touch noise not 0 on both counts (`ValueError`, from the
    /// library's check).
    #[new]
    #[pyo3(signature = (encoder_deg = None, probe_mm = None, length_default_mm = DEFAULT_LENGTH_SIGMA_MM, length_weight = None, position_mm = None, position_mm_per_m = None, orientation_deg = None))]
    fn new(
        encoder_deg: Option<f64>,
        probe_mm: Option<f64>,
        length_default_mm: f64,
        length_weight: Option<f64>,
        position_mm: Option<f64>,
        position_mm_per_m: Option<f64>,
        orientation_deg: Option<f64>,
    ) -> PyResult<Noise> {
        Ok(Noise::checked(
            encoder_deg,
            probe_mm,
            length_default_mm,
            length_weight,
            position_mm,
            position_mm_per_m,
            orientation_deg,
        )?)
    }

    /// σ of each encoder reading, degrees (`None`: not stated).
    #[getter]
    fn encoder_deg(&self) -> Option<f64> {
        self.encoder_deg
    }

    /// σ of the probe seating per axis, mm (`None`: not stated).
    #[getter]
    fn probe_mm(&self) -> Option<f64> {
        self.noise.probe_mm
    }

    /// σ of a reference length that states none, mm.
    #[getter]
    fn length_default_mm(&self) -> f64 {
        self.noise.length_default_mm
    }

    /// Weight of every reference-length residual, 1/mm (`None`: from the
    /// uncertainties).
    #[getter]
    fn length_weight(&self) -> Option<f64> {
        self.noise.length_weight
    }

    /// σ per coordinate of a reference position that states none, its
    /// constant part `A`, mm (`None`: not stated).
    #[getter]
    fn position_mm(&self) -> Option<f64> {
        self.noise.position_mm
    }

    /// The part of that σ that grows with the distance from the
    /// instrument, `B`, mm per metre (`None`: not stated).
    #[getter]
    fn position_mm_per_m(&self) -> Option<f64> {
        self.noise.position_mm_per_m
    }

    /// σ per axis of a tool orientation seen, degrees (`None`: not
    /// stated).
    #[getter]
    fn orientation_deg(&self) -> Option<f64> {
        self.orientation_deg
    }

    /// Whether any touch noise is stated.
    #[getter]
    fn stated(&self) -> bool {
        self.noise.stated()
    }

    fn __repr__(&self) -> String {
        // Debug: `1e308` as Python writes it, not 309 digits.
        let opt = |v: Option<f64>| v.map_or("None".to_string(), |v| format!("{v:?}"));
        format!(
            "Noise(encoder_deg={}, probe_mm={}, length_default_mm={:?}, length_weight={}, \
             position_mm={}, position_mm_per_m={}{})",
            opt(self.encoder_deg),
            opt(self.noise.probe_mm),
            self.noise.length_default_mm,
            opt(self.noise.length_weight),
            opt(self.noise.position_mm),
            opt(self.noise.position_mm_per_m),
            // Only when stated: the repr of every noise without it as before.
            (self.orientation_deg)
                .map(|o| format!(", orientation_deg={o:?}"))
                .unwrap_or_default()
        )
    }
}
