//! aacmm-core: the geometric model of D-H measuring arms and everything that
//! evaluates it — parameters, the reference (autodiff) model, the generated
//! kernel, data files, metrics, the campaign simulator.
//!
//! Data flows one way: the nouns (`domain`) and their files (`io`) → typed
//! data set → kernel → residuals/metrics → solver → report; no module
//! reaches back up that chain.
//!
//! # The front door
//!
//! A [`Problem`] — an arm, its touches (a [`DataSet`]) and what to fit
//! ([`ModelOptions`]) — run with a solver's [`SolverSettings`] gives a
//! [`CalibrationReport`]: the calibration, read by parameter
//! ([`Calibration::estimate`]); the calibrated arm
//! ([`CalibrationReport::calibrated_arm`]); and the verdict
//! ([`session::Verdict`]), whose reasons ([`session::Reason`]) are data a
//! program matches on, not sentences:
//!
//! ```
//! use aacmm_core::session::Reason;
//! use aacmm_core::simulate::{CampaignSettings, ErrorModel};
//! use aacmm_core::{Arm, DhParams, FixSpec, Method, ModelOptions, Problem, SolverSettings, simulate};
//!
//! // An arm and its touches, from memory: here a campaign simulated on it.
//! let nominal = Arm::without_limits("mine", DhParams::paper_nominal());
//! let campaign = CampaignSettings { reference_lengths: 2, ..CampaignSettings::new(1, ErrorModel::Paper, 5, 6) };
//! let data = simulate(&nominal, &campaign)?.data_set()?;
//! let model = ModelOptions { fix: FixSpec::parse("theta1,d1,theta6,alpha6,Bx,By", 6)?, ..ModelOptions::default() };
//! let settings = SolverSettings { method: Method::Lm, ..SolverSettings::default() };
//! let report = Problem::new(nominal, data, model)?.run(&settings)?;
//! for reason in &report.verdict.reasons {
//!     match reason {
//!         Reason::ChiSquare { .. } => println!("the residuals and the stated noise disagree"),
//!         other => println!("refused: {other:?}"),
//!     }
//! }
//! assert!(report.is_usable(), "{:?}", report.verdict);
//! let theta5 = report.calibration.estimate("theta5".parse()?).unwrap();
//! println!("θ5 corrected by {:.4}°", theta5.correction.to_degrees());
//! assert_eq!(report.calibrated_arm().unwrap().name, "mine-calibrated");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! From files, a [`Request`] reads the arm and its touches and takes what
//! to fit and how as text and values, as the command line does (the
//! README's Rust example, run from the repository's root):
//!
//! ```
//! # std::env::set_current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).unwrap();
//! use aacmm_core::{Request, io::AngleUnit};
//!
//! let request = Request::read("examples/paper-table-1.toml", "examples/paper-campaign/poses.csv", AngleUnit::Deg)?
//!     .read_lengths("examples/paper-campaign/lengths.csv")?;
//! let (_problem, report) = request.fix("auto").method("global").run()?;
//! assert!(report.is_usable());
//! for p in report.calibration.parameters.iter().filter(|p| p.fixed.is_none()).map(|p| p.user()) {
//!     println!("{:<7} {:>12.4} ± {:.4} {}", p.name, p.calibrated, p.sigma.unwrap_or(f64::NAN), p.unit);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! A program that does more than this imports the [`prelude`]: reading,
//! simulating, calibrating and the extension points (a new residual term,
//! parameter block or solver) in one `use`.

pub mod acceptance;
pub mod calibrate;
pub mod corrections;
mod damping;
pub mod dataset;
pub mod domain;
pub mod error;
pub mod geometry;
pub mod hayati;
pub mod identify;
pub mod io;
pub mod kernel;
pub mod memory;
pub mod metrics;
pub mod objective;
pub mod parallel;
pub mod params;
pub mod plan;
pub mod prelude;
pub(crate) mod random;
#[cfg(feature = "reference-model")]
pub mod reference_model;
pub mod report;
pub mod residuals;
pub mod session;
pub mod setting;
mod simd;
pub mod simulate;
pub mod stats;
pub mod tolerances;
pub mod urdf;

pub use calibrate::{
    Calibration, CalibrationError, FixSpec, Method, ModelOptions, SolverSettings, calibrate,
};
pub use dataset::DataSet;
pub use domain::Arm;
pub use io::read_arm;
pub use metrics::evaluate;
pub use params::{DhParams, ParamId};
pub use residuals::Noise;
pub use session::{CalibrationReport, Problem, Request};
pub use simulate::simulate;
