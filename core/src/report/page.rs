//! The HTML report's page and figures: their files, the inputs they are
//! drawn from, and the entry points (see the [module docs](super)).

use crate::calibrate::Calibration;
use crate::calibrate::validate::BeforeAfter;
use crate::dataset::DataSet;
use crate::kernel::KernelError;
use crate::metrics::MetricsError;
use crate::params::DhParams;
use crate::plan::UncertaintyMap;

use super::{data, figures, html};

/// The page.
pub const HTML_FILE: &str = "report.html";
/// Single-point error `e` per point, before and after (paper Fig. 6).
pub const SINGLE_POINT_SVG: &str = "single-point-errors.svg";
/// Length errors: eq. 19 per pair and against reference lengths (Fig. 7).
pub const LENGTHS_SVG: &str = "length-errors.svg";
/// Parameter corrections with ± 2σ.
pub const PARAMETERS_SVG: &str = "parameter-corrections.svg";
/// Singular values and the correlation matrix.
pub const IDENTIFIABILITY_SVG: &str = "identifiability.svg";
/// Per-touch residual lengths, before and after.
pub const RESIDUALS_SVG: &str = "residuals.svg";
/// The solver's progress.
pub const SOLVER_SVG: &str = "solver-progress.svg";
/// The 3-D errors at reference positions, when the calibration had them
/// (not among [`CALIBRATION_FILES`], which every calibration writes).
pub const POSITIONS_SVG: &str = "position-errors.svg";
/// How far each fitted model beyond geometry moves the probe, when the
/// calibration fitted any (not among [`CALIBRATION_FILES`]).
pub const BEYOND_SVG: &str = "beyond-geometry.svg";
/// The predicted position uncertainty over the sampled workspace, when the
/// calibration has an uncertainty map (not among [`CALIBRATION_FILES`]:
/// a calibration whose covariance is not finite has none).
pub const UNCERTAINTY_MAP_SVG: &str = "uncertainty-map.svg";

/// Every file `calibration_report` writes for touches, page first
/// (without touches, the three touch figures — [`SINGLE_POINT_SVG`],
/// [`LENGTHS_SVG`], [`RESIDUALS_SVG`] — are left out).
pub const CALIBRATION_FILES: [&str; 7] = [
    HTML_FILE,
    SINGLE_POINT_SVG,
    LENGTHS_SVG,
    PARAMETERS_SVG,
    IDENTIFIABILITY_SVG,
    RESIDUALS_SVG,
    SOLVER_SVG,
];

/// Every file `evaluation_report` writes, page first.
pub const EVALUATION_FILES: [&str; 4] = [HTML_FILE, SINGLE_POINT_SVG, LENGTHS_SVG, RESIDUALS_SVG];

/// Eq. 19 pairs drawn one marker each, per series; more are drawn as the
/// mean per distance bin.
pub(crate) const MAX_PAIR_MARKERS: usize = 2000;

/// Why a report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The positions do not fit the data set.
    #[error("report: {what}: {got} positions for {expected} touches")]
    Positions {
        /// Which positions (`fitted, before`, …).
        what: String,
        /// Touches of the data set.
        expected: usize,
        /// Positions given.
        got: usize,
    },
    /// The metrics refused the positions (non-finite, too few touches).
    #[error("report: {0}")]
    Metrics(#[from] MetricsError),
    /// The kernel refused an arm ([`positions`]).
    #[error("report: {0}")]
    Kernel(#[from] KernelError),
    /// The data could not be seen through an arm's corrections beyond
    /// geometry, or another refusal of the calibration's.
    #[error("report: {0}")]
    Calibration(#[from] Box<crate::calibrate::CalibrationError>),
    /// Plotters failed to draw a figure.
    #[error("report: figure {file}: {message}")]
    Draw {
        /// The figure's file name.
        file: &'static str,
        /// Plotters' message.
        message: String,
    },
}

/// One figure: its file name, its title and the SVG document.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// File name (one of the `*_SVG` constants).
    pub file: &'static str,
    /// Title, as in the page.
    pub title: String,
    /// The SVG document.
    pub svg: String,
}

/// A report: the page and its figures, ready to be written.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// The self-contained page ([`HTML_FILE`]); it holds every figure.
    pub html: String,
    /// The figures, each also a file of its own.
    pub figures: Vec<Figure>,
}

impl Report {
    /// Every file of the report as (file name, content), page first.
    pub fn files(&self) -> impl Iterator<Item = (&str, &str)> {
        std::iter::once((HTML_FILE, self.html.as_str()))
            .chain(self.figures.iter().map(|f| (f.file, f.svg.as_str())))
    }
}

/// One data set as measured by the arms compared: probe positions (mm) of
/// its touches in the data set's touch order.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Measured<'a> {
    /// The touches (points, reference lengths, where they came from).
    pub data: &'a DataSet,
    /// Whether the data were held out from the fit (drawn as triangles).
    pub held_out: bool,
    /// Positions with the arm before calibration (grey); `None` when one
    /// arm is evaluated.
    pub before: Option<&'a [[f64; 3]]>,
    /// Positions with the arm after calibration (or the one arm evaluated).
    pub after: &'a [[f64; 3]],
}

/// Probe positions of every touch of `data` (its touch order) with the arm
/// `params`, mm: what the report draws for a data set.
///
/// ```
/// use aacmm_core::{dataset::DataSet, io::{AngleUnit, parse_poses}, params::DhParams, report};
/// let text = "point,q1,q2,q3,q4,q5,q6\nA,0,0,0,0,0,0\nA,0,0,0,0,0,1\nA,0,0,0,0,1,0\n";
/// let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Deg, Some(6)).unwrap();
/// let data = DataSet::from_poses(&poses, "p.csv").unwrap();
/// let xyz = report::positions(&DhParams::paper_nominal(), &data).unwrap();
/// assert_eq!(xyz.len(), 3);
/// ```
pub fn positions(params: &DhParams, data: &DataSet) -> Result<Vec<[f64; 3]>, ReportError> {
    // Touches by several tools each at its tool's nominal offset.
    Ok(crate::residuals::tools::touch_positions_at(
        params,
        data,
        &[],
    )?)
}

/// Names of the two arms compared, for legends and tables.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Arms {
    /// The arm before calibration (`nominal`).
    pub before: String,
    /// The arm after calibration (`calibrated`), or the one arm evaluated.
    pub after: String,
}

/// One row pair of the validation table: figures of the arm before and
/// after calibration on one data set.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ValidationRow<'a> {
    /// What the data are (`fitted`, `held out (v.csv)`, `fold 1 (3 points)`).
    pub name: String,
    /// Whether the data were held out from the fit.
    pub held_out: bool,
    /// The figures.
    pub figures: &'a BeforeAfter,
    /// JSON Pointer of the same figures in the JSON written beside the
    /// report (e.g. `/validation/fitted`), if any.
    pub json: Option<String>,
}

/// What [`calibration_report`] shows.
#[derive(Clone, Debug)]
pub(crate) struct CalibrationInput<'a> {
    /// The page's heading.
    pub title: String,
    /// What went in, as (what, value) lines: files, noise, method, seed.
    pub inputs: Vec<(String, String)>,
    /// The calibration.
    pub calibration: &'a Calibration,
    /// JSON Pointer of the calibration in the JSON written beside the
    /// report (e.g. `/calibration`), if any.
    pub calibration_json: Option<String>,
    /// The data sets with positions before and after: the fitted data and
    /// any held-out data.
    pub measured: Vec<Measured<'a>>,
    /// Names of the arms.
    pub arms: Arms,
    /// Rows of the validation table (fitted, held out, cross-validation).
    pub validation: Vec<ValidationRow<'a>>,
    /// The true arm, when known (simulations): its errors are drawn beside
    /// the corrections.
    pub truth: Option<&'a DhParams>,
    /// The 3-D errors at the reference positions, per data set and arm
    /// (none without positions: the figure is then left out).
    pub positions: Vec<PoseErrors>,
    /// Per model beyond geometry the fit switched on, how far it moves the
    /// probe at each fitted pose (`error_mm`), against the reach (none:
    /// the section is left out).
    pub beyond: Vec<PoseErrors>,
    /// The predicted position uncertainty over a sampled workspace (none:
    /// the section and its figure are left out).
    pub uncertainty_map: Option<&'a UncertaintyMap>,
    /// JSON Pointer of the map in the JSON written beside the report (e.g.
    /// `/uncertainty_map`), if any.
    pub uncertainty_map_json: Option<String>,
    /// Points probed on reference spheres, when fitted: their section.
    pub spheres: Option<&'a crate::session::spheres::SphereReport>,
    /// The cross-validation's folds (none without it): the spheres'
    /// section shows the points each held out
    /// ([`crate::calibrate::validate::Fold::terms`]).
    pub folds: &'a [crate::calibrate::validate::Fold],
    /// Points on reference spheres held out (`--validate-spheres`): a
    /// table in the spheres' section (which it opens without fitted
    /// spheres).
    pub held_out_spheres: Option<&'a crate::session::spheres::HeldOutSpheres>,
    /// Several tool points, when rows name them: their section.
    pub tools: Option<&'a crate::session::tools::ToolReport>,
    /// Touches by several probes, when the poses name them: a table in
    /// the tool points' section (which it opens without positions').
    pub touch_tools: Option<&'a crate::session::tools::ToolReport>,
    /// The same poses as each fitted frame's instrument sees the probe, its
    /// registration included: a table each in the map's section (none
    /// without frames). Their JSON Pointers are
    /// `/uncertainty_maps_in_frames/<i>` when the map has one.
    pub uncertainty_maps_in_frames: &'a [UncertaintyMap],
    /// The same poses at each fitted tool point, its offset's uncertainty
    /// included: a table each in the map's section (none without). Their
    /// JSON Pointers are `/uncertainty_maps_at_tools/<i>` when the map has
    /// one.
    pub uncertainty_maps_at_tools: &'a [UncertaintyMap],
    /// Whether the calibration may be used, and why not: the page opens
    /// with it. `None` for a calibration drawn outside a session, which
    /// the page then says has no verdict.
    pub verdict: Option<&'a crate::session::Verdict>,
    /// The session's seed: draws the pairs of points the length figure
    /// samples when all of them would cost too much (the metrics'
    /// budget), so that the same seed gives the same page.
    pub seed: u64,
}

/// The 3-D errors of one arm at one data set's reference positions, each
/// frame registered (the before arm's closed form, the fit's frames).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PoseErrors {
    /// The series' name (`nominal, fitted`).
    pub name: String,
    /// Held out from the fit.
    pub held_out: bool,
    /// The calibrated arm's (else the start arm's).
    pub after: bool,
    /// Per pose, the probe's distance from the base axis, mm.
    pub(crate) reach_mm: Vec<f64>,
    /// Per pose, `|R p + t − y|`, mm.
    pub(crate) error_mm: Vec<f64>,
    /// Per pose, its frame: an index into `frame_names` (empty when the
    /// series has no frames, as a model's effect beyond geometry).
    pub(crate) frame: Vec<usize>,
    /// The frames' names (`instrument`, a station's).
    pub(crate) frame_names: Vec<String>,
    /// Per pose, its orientation error, degrees, where the row gives the
    /// tool's orientation (empty when none does).
    pub(crate) orientation_deg: Vec<Option<f64>>,
}

/// What [`evaluation_report`] shows.
#[derive(Clone, Debug)]
pub(crate) struct EvaluationInput<'a> {
    /// The page's heading.
    pub title: String,
    /// What went in, as (what, value) lines.
    pub inputs: Vec<(String, String)>,
    /// The data set and the positions the arm gives (`before` is `None`).
    pub measured: Measured<'a>,
    /// The arm's name.
    pub arm: String,
    /// JSON Pointer of the evaluation in the JSON written beside the report
    /// (e.g. `/evaluation`), if any.
    pub evaluation_json: Option<String>,
}

/// The report of a calibration: the page and six figures
/// ([`CALIBRATION_FILES`]; three without touches), and those of what the
/// input has besides (reference positions, models beyond geometry, an
/// uncertainty map). A section per kind of evidence present: reference
/// positions lead with their 3-D errors; the touch sections only with
/// touches.
///
/// # Errors
///
/// [`ReportError::Positions`] when positions do not fit their data set;
/// [`ReportError::Metrics`] for positions the metrics refuse;
/// [`ReportError::Draw`] if plotters fails.
pub(crate) fn calibration_report(input: &CalibrationInput) -> Result<Report, ReportError> {
    let evaluated = data::evaluate_all(&input.measured, input.seed)?;
    // The touch figures only where there are touches: reference positions
    // alone have none to draw.
    let touches = !evaluated.is_empty();
    let mut figures = Vec::new();
    if touches {
        figures.push(figures::points::figure(&evaluated, &input.arms)?);
        figures.push(figures::lengths::figure(&evaluated, &input.arms)?);
    }
    figures.push(figures::parameters::figure(input.calibration, input.truth)?);
    figures.push(figures::identifiability::figure(input.calibration)?);
    if touches {
        figures.push(figures::residuals::figure(&evaluated, &input.arms)?);
    }
    figures.push(figures::solver::figure(input.calibration)?);
    if !input.positions.is_empty() {
        figures.push(figures::positions::figure(&input.positions)?);
    }
    if !input.beyond.is_empty() {
        figures.push(figures::beyond::figure(&input.beyond)?);
    }
    if let Some(map) = input.uncertainty_map {
        figures.push(figures::map::figure(map)?);
    }
    let html = html::calibration_page(input, &evaluated, &figures);
    Ok(Report { html, figures })
}

/// The report of one arm on one data set: the page and three figures
/// ([`EVALUATION_FILES`]).
///
/// # Errors
///
/// As [`calibration_report`].
pub(crate) fn evaluation_report(input: &EvaluationInput) -> Result<Report, ReportError> {
    let measured = [input.measured];
    // The pairs `aacmm evaluate`'s figures are over too.
    let evaluated = data::evaluate_all(&measured, crate::metrics::DEFAULT_PAIR_SEED)?;
    let arms = Arms {
        before: String::new(),
        after: input.arm.clone(),
    };
    let figures = vec![
        figures::points::figure(&evaluated, &arms)?,
        figures::lengths::figure(&evaluated, &arms)?,
        figures::residuals::figure(&evaluated, &arms)?,
    ];
    let html = html::evaluation_page(input, &evaluated, &figures);
    Ok(Report { html, figures })
}

impl crate::session::EvaluationReport<'_> {
    /// The HTML report of the evaluation (the page and its figures);
    /// `json_file` names the JSON written beside it, if any, whose numbers
    /// the page then points to.
    ///
    /// # Errors
    ///
    /// When a figure cannot be drawn.
    pub fn html(&self, json_file: Option<&str>) -> Result<Report, ReportError> {
        let mut inputs = vec![
            (
                "arm".to_string(),
                format!("`{}` ({})", self.arm, self.arm_file),
            ),
            (
                "touches".to_string(),
                format!(
                    "{}: {} touches of {} points",
                    self.data_file,
                    self.data.len(),
                    self.data.points().len()
                ),
            ),
            (
                "reference lengths".to_string(),
                match &self.lengths_file {
                    Some(l) => format!("{l}: {}", self.data.references().len()),
                    None => "none (scale is not tested)".to_string(),
                },
            ),
        ];
        if let Some(json) = json_file {
            inputs.push((
                "written beside".to_string(),
                format!(
                    "{json} (every number of the tables that is also there is marked with its \
                     place)"
                ),
            ));
        }
        evaluation_report(&EvaluationInput {
            title: format!("Evaluation of arm `{}`", self.arm),
            inputs,
            measured: Measured {
                data: self.data,
                held_out: false,
                before: None,
                after: self.xyz,
            },
            arm: self.arm.clone(),
            evaluation_json: json_file.map(|_| "/evaluation".to_string()),
        })
    }
}

/// The examples these items' documentation gave while they were public,
/// kept as tests.
#[cfg(test)]
mod examples {
    #[test]
    fn report_report_files() {
        use crate::report::{Figure, RESIDUALS_SVG, Report};
        let r = Report {
            html: "<!DOCTYPE html>".into(),
            figures: vec![Figure {
                file: RESIDUALS_SVG,
                title: "t".into(),
                svg: "<svg/>".into(),
            }],
        };
        let names: Vec<&str> = r.files().map(|(name, _)| name).collect();
        assert_eq!(names, ["report.html", "residuals.svg"]);
    }

    #[test]
    fn report_calibration_report() {
        use crate::{calibrate::*, domain::Arm, params::DhParams, report::*, simulate::*};
        let nominal = Arm::without_limits("nominal", DhParams::paper_nominal());
        let mut settings = CampaignSettings::new(1, ErrorModel::Paper, 5, 6);
        settings.reference_lengths = 2;
        let data = simulate(&nominal, &settings).unwrap().data_set().unwrap();
        let settings = SolverSettings::default().with_method(Method::Lm);
        let cal = calibrate(&nominal.params, &data, &ModelOptions::default(), &settings).unwrap();
        let before = positions(&nominal.params, &data).unwrap();
        let after = positions(&cal.params, &data).unwrap();
        let fitted = validate::before_after(&nominal.params, &cal.params, &data).unwrap();
        let report = calibration_report(&CalibrationInput {
            title: "Calibration".into(),
            inputs: vec![],
            calibration: &cal,
            calibration_json: None,
            measured: vec![Measured {
                data: &data,
                held_out: false,
                before: Some(&before),
                after: &after,
            }],
            arms: Arms {
                before: "nominal".into(),
                after: "calibrated".into(),
            },
            validation: vec![ValidationRow {
                name: "fitted".into(),
                held_out: false,
                figures: &fitted,
                json: None,
            }],
            truth: None,
            positions: Vec::new(),
            beyond: Vec::new(),
            uncertainty_map: None,
            uncertainty_map_json: None,
            spheres: None,
            folds: &[],
            held_out_spheres: None,
            tools: None,
            touch_tools: None,
            uncertainty_maps_in_frames: &[],
            uncertainty_maps_at_tools: &[],
            verdict: None,
            seed: 0,
        })
        .unwrap();
        assert_eq!(report.files().count(), CALIBRATION_FILES.len());
        assert!(report.html.starts_with("<!DOCTYPE html>"));
        assert!(!report.html.contains("<script"));
    }

    #[test]
    fn report_evaluation_report() {
        use crate::{
            dataset::DataSet,
            io::{AngleUnit, parse_poses},
            params::DhParams,
            report::*,
        };
        let text = "point,q1,q2,q3,q4,q5,q6\n\
            A,0,0,0,0,0,0\nA,0,0,0,0,0,1\nA,0,0,0,0,1,0\n\
            B,10,20,30,40,50,60\nB,10,20,30,40,50,61\nB,10,20,30,40,51,61\n";
        let (poses, _) = parse_poses(text, "p.csv", AngleUnit::Deg, Some(6)).unwrap();
        let data = DataSet::from_poses(&poses, "p.csv").unwrap();
        let xyz = positions(&DhParams::paper_nominal(), &data).unwrap();
        let report = evaluation_report(&EvaluationInput {
            title: "Evaluation".into(),
            inputs: vec![("poses".into(), "p.csv".into())],
            measured: Measured {
                data: &data,
                held_out: false,
                before: None,
                after: &xyz,
            },
            arm: "nominal".into(),
            evaluation_json: None,
        })
        .unwrap();
        let names: Vec<&str> = report.files().map(|(name, _)| name).collect();
        assert_eq!(names, EVALUATION_FILES);
    }
}
