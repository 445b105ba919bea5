//! `aacmm.Noise`: what is known of the measurement noise, in the units the
//! command line uses (degrees for encoders, mm otherwise).

use aacmm_core::calibrate::DEFAULT_LENGTH_SIGMA_MM;
use aacmm_core::residuals::Noise as CoreNoise;
use aacmm_core::session::user_noise;
use pyo3::prelude::*;

use crate::error::Result;

/// What is known of the measurement noise (the command line's noise
/// options). With neither touch noise stated, the touch σ is estimated from
/// the fit.
#[pyclass(frozen, module = "aacmm")]
#[derive(Clone)]
pub struct Noise {
    pub(crate) noise: CoreNoise,
    encoder_deg: Option<f64>,
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
    ) -> Result<Noise> {
        let noise = user_noise(encoder_deg, probe_mm, length_default_mm, length_weight);
        noise.check()?;
        Ok(Noise { noise, encoder_deg })
    }
}

#[pymethods]
impl Noise {
    /// `encoder_deg`: σ of each encoder reading, degrees; `probe_mm`: σ of
    /// the probe seating per axis, mm; `length_default_mm`: σ of a reference
    /// length that states none, mm; `length_weight`: weight of every
    /// reference-length residual, 1/mm, overriding the uncertainties (0:
    /// none). Values must be finite and ≥ 0, and stated touch noise not 0
    /// on both counts (`ValueError`, from the library's check).
    #[new]
    #[pyo3(signature = (encoder_deg = None, probe_mm = None, length_default_mm = DEFAULT_LENGTH_SIGMA_MM, length_weight = None))]
    fn new(
        encoder_deg: Option<f64>,
        probe_mm: Option<f64>,
        length_default_mm: f64,
        length_weight: Option<f64>,
    ) -> PyResult<Noise> {
        Ok(Noise::checked(
            encoder_deg,
            probe_mm,
            length_default_mm,
            length_weight,
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

    /// Whether any touch noise is stated.
    #[getter]
    fn stated(&self) -> bool {
        self.noise.stated()
    }

    fn __repr__(&self) -> String {
        let opt = |v: Option<f64>| v.map_or("None".to_string(), |v| v.to_string());
        format!(
            "Noise(encoder_deg={}, probe_mm={}, length_default_mm={}, length_weight={})",
            opt(self.encoder_deg),
            opt(self.noise.probe_mm),
            self.noise.length_default_mm,
            opt(self.noise.length_weight)
        )
    }
}
