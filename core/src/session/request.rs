//! One request path for every front end: what a user asks for — an arm and
//! its touches, and the settings as text and values (`fix = "auto"`,
//! `robust = "huber"`, `prior = "length=0.5mm"`, `method = "lm"`, threads,
//! seed, the solvers' tunables) — turned into the checked [`Problem`] and
//! [`SolverSettings`] in this one place. The command line, the Python
//! package and programs only translate their arguments into a [`Request`]
//! and map the [`OptionError`] fields back to their own spelling.
//!
//! A request also owns every warning about its inputs: the readers' (the
//! arm file's and the poses files'), and one for readings outside the arm
//! file's joint limits, kept in the report whatever the front end.
//!
//! ```
//! # std::env::set_current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/..")).unwrap();
//! use aacmm_core::{io::AngleUnit, session::{Request, user_noise}};
//! let read = || Request::read("examples/paper-table-1.toml", "examples/paper-campaign/poses.csv", AngleUnit::Deg);
//! let request = read()?
//!     .read_lengths("examples/paper-campaign/lengths.csv")?
//!     .noise(user_noise(Some(0.005), Some(0.01), 0.0005, None))
//!     .method("lm");
//! assert!(request.warnings().is_empty());
//! let (_problem, report) = request.run()?;
//! assert!(report.is_usable());
//! // A refusal names the library's setting.
//! let refused = read()?.fix("theta9").build().unwrap_err();
//! assert!(matches!(refused, aacmm_core::CalibrationError::Option(ref o) if o.field() == "fix"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::Path;

use super::identification::IdentifyReport;
use super::{CalibrationReport, HeldOutData, Problem, Sources};
use crate::calibrate::{
    AnnealOptions, CalibrationError, FixSpec, GlobalOptions, LmOptions, Loss, Method, ModelOptions,
    Robust, SolverSettings, SwitchRule, available_threads,
};
use crate::corrections::Beyond;
use crate::dataset::DataSet;
use crate::domain::{Arm, Spheres};
use crate::error::{InputError, OptionError};
use crate::io::spheres::read_spheres;
use crate::io::{AngleUnit, JointColumns, read_arm, read_lengths, read_positions, source_name};
use crate::kernel::ArmKernel;
use crate::residuals::Noise;
use crate::residuals::spheres::{SphereSize, SphereTerm, check_sphere_diameter, check_spheres};
use crate::setting::Setting;
use crate::tolerances::Tolerances;

/// A calibration (or identification) as asked for: the inputs, their
/// names and warnings, and every setting as the user gave it, checked only
/// when the request is built.
#[derive(Clone, Debug)]
pub struct Request {
    arm: Arm,
    data: DataSet,
    sources: Sources,
    unit: AngleUnit,
    held_out: Option<(HeldOutData, Vec<String>)>,
    register_held_out: bool,
    /// Held-out points on spheres and their file.
    held_out_spheres: Option<(Spheres, String)>,
    cross_validate: Option<usize>,
    fix: String,
    noise: Noise,
    robust: Option<String>,
    robust_scale: Option<f64>,
    prior: Option<String>,
    accept_poor_fit: bool,
    beyond: BeyondRequest,
    method: String,
    threads: Option<usize>,
    seed: u64,
    lm: LmOptions,
    anneal: AnnealOptions,
    switch: SwitchRule,
    global: GlobalOptions,
    spheres: Option<SphereInput>,
    /// The tool every row that names none was measured with (`None`: the
    /// arm's `[probe]`).
    tool: Option<String>,
}

/// Points probed on reference spheres as read, and their size as asked.
#[derive(Clone, Debug)]
struct SphereInput {
    rows: Spheres,
    file: String,
    diameter_mm: Option<f64>,
}

/// The models beyond geometry as asked for (parsed with the model).
#[derive(Clone, Debug, Default)]
struct BeyondRequest {
    compliance: Option<String>,
    harmonics: Option<String>,
    backlash: Option<String>,
    thermal: bool,
    drift: bool,
}

/// Touch noise as users state it — encoders in degrees, the probe and the
/// lengths in mm, a length weight of 0 meaning none — in the library's
/// units (checked when a request is built, or by [`Noise::check`]).
///
/// ```
/// let n = aacmm_core::session::user_noise(Some(0.005), None, 0.0005, Some(0.0));
/// assert_eq!(n.encoder_rad, Some(0.005f64.to_radians()));
/// assert_eq!(n.length_weight, None);
/// ```
pub fn user_noise(
    encoder_deg: Option<f64>,
    probe_mm: Option<f64>,
    length_default_mm: f64,
    length_weight: Option<f64>,
) -> Noise {
    Noise {
        encoder_rad: encoder_deg.map(f64::to_radians),
        probe_mm,
        length_default_mm,
        length_weight: length_weight.filter(|&w| w != 0.0),
        ..Noise::default()
    }
}

impl Request {
    /// A request for `arm` on `data`, with the library's defaults: `fix =
    /// "auto"`, no noise stated, plain least squares, the arm file's prior,
    /// `global`, every core, seed 0. Name the inputs and give the readers'
    /// warnings with [`Request::sources`].
    pub fn new(arm: Arm, data: DataSet) -> Request {
        let solver = SolverSettings::default();
        Request {
            arm,
            data,
            sources: Sources::default(),
            unit: AngleUnit::Rad,
            held_out: None,
            register_held_out: false,
            held_out_spheres: None,
            cross_validate: None,
            fix: "auto".to_string(),
            noise: Noise::default(),
            robust: None,
            robust_scale: None,
            prior: None,
            accept_poor_fit: false,
            beyond: BeyondRequest::default(),
            method: solver.method.name().to_string(),
            threads: None,
            seed: solver.seed,
            lm: solver.lm,
            anneal: solver.anneal,
            switch: solver.switch,
            global: solver.global,
            spheres: None,
            tool: None,
        }
    }

    /// Reads the arm file and the poses file (angles in `unit`; `-` reads
    /// standard input), keeping the readers' warnings in the order read.
    ///
    /// # Errors
    ///
    /// The readers' errors, naming file, line and field.
    pub fn read(
        arm: impl AsRef<Path>,
        poses: impl AsRef<Path>,
        unit: AngleUnit,
    ) -> Result<Request, InputError> {
        let (arm, poses) = (arm.as_ref(), poses.as_ref());
        let (read, arm_warnings) = read_arm(arm)?;
        let (data, data_warnings) = DataSet::read(poses, None, unit, &read)?;
        let warnings = (arm_warnings.iter().chain(&data_warnings))
            .map(ToString::to_string)
            .collect();
        let sources = Sources {
            arm_file: source_name(arm),
            data_file: source_name(poses),
            lengths_file: None,
            warnings,
        };
        Ok(Request::new(read, data).sources(sources).angle_unit(unit))
    }

    /// Reads the arm file and a reference-positions file (readings in
    /// `unit`): a calibration against an instrument's positions alone.
    ///
    /// # Errors
    ///
    /// The readers' errors, naming file, line and field.
    pub fn read_positions_only(
        arm: impl AsRef<Path>,
        positions: impl AsRef<Path>,
        unit: AngleUnit,
    ) -> Result<Request, InputError> {
        let (arm, positions) = (arm.as_ref(), positions.as_ref());
        let (read, arm_warnings) = read_arm(arm)?;
        let name = source_name(positions);
        let rows = read_positions(positions, unit, &read)?;
        let data = DataSet::from_positions(rows, &name)?;
        let sources = Sources {
            arm_file: source_name(arm),
            data_file: name,
            lengths_file: None,
            warnings: arm_warnings.iter().map(ToString::to_string).collect(),
        };
        Ok(Request::new(read, data).sources(sources).angle_unit(unit))
    }

    /// Reads the arm file and a sphere-surface file (readings in `unit`):
    /// a calibration on points probed on reference spheres alone.
    ///
    /// # Errors
    ///
    /// The readers' errors, naming file, line and field, and points that
    /// fix no sphere where the arm puts them ([`check_spheres`]).
    pub fn read_spheres_only(
        arm: impl AsRef<Path>,
        spheres: impl AsRef<Path>,
        unit: AngleUnit,
    ) -> Result<Request, InputError> {
        let arm = arm.as_ref();
        let (read, arm_warnings) = read_arm(arm)?;
        let data = DataSet::without_touches(
            read.params.joint_count(),
            JointColumns::from(&read).prismatic_mask(),
        );
        let sources = Sources {
            arm_file: source_name(arm),
            data_file: source_name(spheres.as_ref()),
            lengths_file: None,
            warnings: arm_warnings.iter().map(ToString::to_string).collect(),
        };
        Request::new(read, data)
            .sources(sources)
            .angle_unit(unit)
            .read_spheres(spheres)
    }

    /// Adds the points probed on reference spheres of a sphere-surface file
    /// (readings in the request's angle unit), fitted with the rest; their
    /// size is [`Request::sphere_diameter`]'s.
    ///
    /// # Errors
    ///
    /// The reader's errors, naming file, line and field, and points that
    /// fix no sphere where the arm puts them ([`check_spheres`]).
    pub fn read_spheres(mut self, path: impl AsRef<Path>) -> Result<Request, InputError> {
        let path = path.as_ref();
        let (rows, warnings) = read_spheres(path, self.unit, &self.arm)?;
        (self.sources.warnings).extend(warnings.iter().map(ToString::to_string));
        self.spheres_of(rows, &source_name(path))
    }

    /// [`Request::read_spheres`] of rows in memory (readings in rad, mm
    /// for a slide), named `name` in messages and the report (`<arrays>`).
    ///
    /// # Errors
    ///
    /// Another joint count than the arm's (named by `name`); points that
    /// fix no sphere where the arm puts them ([`check_spheres`]).
    pub fn spheres_of(mut self, rows: Spheres, name: &str) -> Result<Request, InputError> {
        let rows = self.checked_spheres(rows, name)?;
        let diameter_mm = self.spheres.take().and_then(|s| s.diameter_mm);
        self.spheres = Some(SphereInput {
            rows,
            file: name.to_string(),
            diameter_mm,
        });
        Ok(self)
    }

    /// `rows` of `name` for this request's arm: its joint count, its
    /// slides, and points that fix a sphere where it puts them.
    fn checked_spheres(&self, rows: Spheres, name: &str) -> Result<Spheres, InputError> {
        let joints = self.arm.params.joint_count();
        if rows.joints() != joints {
            return Err(InputError::file_error(
                name,
                format!(
                    "{} readings per point for an arm of {joints} joints",
                    rows.joints()
                ),
            ));
        }
        let rows = match self.arm.params.shape() {
            Ok(shape) => rows.with_shape(shape),
            Err(_) => rows,
        };
        crate::io::spheres::check_counts(&rows, name)?;
        crate::io::spheres::check_one_tool_per_sphere(&rows, name)?;
        check_spheres(&rows, name, &self.arm.params)?;
        Ok(rows)
    }

    /// Validates on points probed on reference spheres of a sphere-surface
    /// file (readings in the request's angle unit) too: each sphere
    /// refitted on its points with the arm held fixed — its diameter the
    /// stated one ([`Request::sphere_diameter`]) when stated, else
    /// refitted as well.
    ///
    /// # Errors
    ///
    /// The reader's errors, naming file, line and field, and points that
    /// fix no sphere where the arm puts them ([`check_spheres`]).
    pub fn validate_on_spheres(mut self, path: impl AsRef<Path>) -> Result<Request, InputError> {
        let path = path.as_ref();
        let (rows, warnings) = read_spheres(path, self.unit, &self.arm)?;
        (self.sources.warnings).extend(warnings.iter().map(ToString::to_string));
        self.validate_on_spheres_of(rows, &source_name(path))
    }

    /// [`Request::validate_on_spheres`] of rows in memory (readings in rad,
    /// mm for a slide), named `name`.
    ///
    /// # Errors
    ///
    /// As [`Request::spheres_of`].
    pub fn validate_on_spheres_of(
        mut self,
        rows: Spheres,
        name: &str,
    ) -> Result<Request, InputError> {
        let rows = self.checked_spheres(rows, name)?;
        self.held_out_spheres = Some((rows, name.to_string()));
        Ok(self)
    }

    /// The spheres' diameter, mm (`None`: fitted per sphere; the scale then
    /// needs reference lengths or positions).
    pub fn sphere_diameter(mut self, diameter_mm: Option<f64>) -> Request {
        match &mut self.spheres {
            Some(s) => s.diameter_mm = diameter_mm,
            None => {
                self.spheres = diameter_mm.map(|d| SphereInput {
                    rows: Spheres::new(0, 0),
                    file: String::new(),
                    diameter_mm: Some(d),
                })
            }
        }
        self
    }

    /// Adds the reference positions of a positions file (readings in the
    /// request's angle unit), fitted with the touches.
    ///
    /// # Errors
    ///
    /// The reader's errors, naming file, line and field.
    pub fn read_positions(mut self, path: impl AsRef<Path>) -> Result<Request, InputError> {
        let path = path.as_ref();
        let rows = read_positions(path, self.unit, &self.arm)?;
        self.data = self.data.with_positions(rows, &source_name(path))?;
        Ok(self)
    }

    /// Validates on the reference positions of a positions file too: with
    /// held-out touches ([`Request::validate_on_files`], called first) as
    /// part of them, else on their own.
    ///
    /// # Errors
    ///
    /// The reader's errors, naming file, line and field.
    pub fn validate_on_positions(mut self, path: impl AsRef<Path>) -> Result<Request, InputError> {
        let path = path.as_ref();
        let name = source_name(path);
        let rows = read_positions(path, self.unit, &self.arm)?;
        let held_out = match self.held_out.take() {
            Some((mut h, warnings)) => {
                h.data = h.data.with_positions(rows, &name)?;
                (h, warnings)
            }
            None => (
                HeldOutData {
                    data: DataSet::from_positions(rows, &name)?,
                    data_file: name,
                    lengths_file: None,
                },
                Vec::new(),
            ),
        };
        self.held_out = Some(held_out);
        Ok(self)
    }

    /// Adds the reference lengths of a lengths file (`-` reads standard
    /// input) between the data's points.
    ///
    /// # Errors
    ///
    /// The reader's errors, naming file, line and field; a length naming
    /// an unknown point.
    pub fn read_lengths(mut self, path: impl AsRef<Path>) -> Result<Request, InputError> {
        let path = path.as_ref();
        let name = source_name(path);
        self.data = self.data.with_lengths(&read_lengths(path)?, &name)?;
        self.sources.lengths_file = Some(name);
        Ok(self)
    }

    /// Names the inputs in the report; `sources.warnings` are the readers'
    /// warnings of the arm and its data.
    pub fn sources(mut self, sources: Sources) -> Request {
        self.sources = sources;
        self
    }

    /// The unit the readings were written in (default rad): a warning shows
    /// a reading as written.
    pub fn angle_unit(mut self, unit: AngleUnit) -> Request {
        self.unit = unit;
        self
    }

    /// The unit the readings are written in ([`Request::angle_unit`]).
    pub fn unit(&self) -> AngleUnit {
        self.unit
    }

    /// Validates on `held_out` too; `warnings` are its readers'.
    pub fn validate_on(mut self, held_out: HeldOutData, warnings: Vec<String>) -> Request {
        self.held_out = Some((held_out, warnings));
        self
    }

    /// [`Request::validate_on`] the touches of another poses file (and
    /// lengths file), read as the request's own data.
    ///
    /// # Errors
    ///
    /// The readers' errors, naming file, line and field.
    pub fn validate_on_files(
        self,
        poses: impl AsRef<Path>,
        lengths: Option<&Path>,
    ) -> Result<Request, InputError> {
        let poses = poses.as_ref();
        let (data, warnings) = DataSet::read(poses, lengths, self.unit, &self.arm)?;
        let held_out = HeldOutData {
            data,
            data_file: source_name(poses),
            lengths_file: lengths.map(source_name),
        };
        let warnings = warnings.iter().map(ToString::to_string).collect();
        Ok(self.validate_on(held_out, warnings))
    }

    /// Whether held-out positions in a frame the fit does not have are
    /// registered on themselves (and said so) rather than refused
    /// ([`Problem::registering_held_out_frames`]; default `false`).
    pub fn register_held_out(mut self, yes: bool) -> Request {
        self.register_held_out = yes;
        self
    }

    /// Cross-validates over `k` folds of points (`None`: not).
    pub fn cross_validate(mut self, k: Option<usize>) -> Request {
        self.cross_validate = k;
        self
    }

    /// The fixed set: `auto` (what the data cannot determine) or
    /// comma-separated parameter names (`theta1,d1,Bx`).
    pub fn fix(mut self, fix: &str) -> Request {
        self.fix = fix.to_string();
        self
    }

    /// What is known of the noise (see [`user_noise`]).
    pub fn noise(mut self, noise: Noise) -> Request {
        self.noise = noise;
        self
    }

    /// Models beyond geometry to fit, as users write them: compliances of
    /// the joints `compliance` (`"2,3,4"`), the encoder harmonics
    /// `harmonics` (`"2:1,5:1-2"`), a thermal expansion coefficient, a
    /// drift ([`crate::corrections`]).
    pub fn beyond(
        mut self,
        compliance: Option<&str>,
        harmonics: Option<&str>,
        thermal: bool,
        drift: bool,
    ) -> Request {
        self.beyond = BeyondRequest {
            compliance: compliance.map(str::to_string),
            harmonics: harmonics.map(str::to_string),
            backlash: self.beyond.backlash.take(),
            thermal,
            drift,
        };
        self
    }

    /// Backlashes to fit, as users write them: the joints `joints`
    /// (`"2,3"`, `--backlash`), each a half-play on the gear flank its
    /// gravity torque presses ([`crate::corrections`]); `None`: none.
    pub fn backlash(mut self, joints: Option<&str>) -> Request {
        self.beyond.backlash = joints.map(str::to_string);
        self
    }

    /// A robust refit with the loss `huber` or `cauchy` and its tuning
    /// constant `k` (`None`: the loss's default); no loss, plain least
    /// squares.
    pub fn robust(mut self, loss: Option<&str>, k: Option<f64>) -> Request {
        self.robust = loss.map(str::to_string);
        self.robust_scale = k;
        self
    }

    /// Tolerances over the arm file's `[prior]`: `None`, the file's as
    /// they are; `none`, no prior; a spec such as
    /// `length=0.5mm,theta5=0.05deg` overrides the file's entry by entry.
    pub fn prior(mut self, spec: Option<&str>) -> Request {
        self.prior = spec.map(str::to_string);
        self
    }

    /// Every row the data do not give a tool was measured with the arm's
    /// `[[tool]]` `name` (a stylus, a marker; `probe`: the arm's `[probe]`,
    /// the default): that tool's offset is fitted, the probe's held as
    /// unseen, and the calibrated arm writes the fitted offset to its
    /// `[[tool]]`. Checked when built: a tool the arm does not have, and
    /// data files that name their tools already (a `tool` column), are
    /// refused.
    pub fn tool(mut self, name: &str) -> Request {
        self.tool = (name != crate::domain::DEFAULT_TOOL).then(|| name.to_string());
        self
    }

    /// Calls a poor χ² or a fit worse than nominal usable (never a wrong
    /// geometry).
    pub fn accept_poor_fit(mut self, accept: bool) -> Request {
        self.accept_poor_fit = accept;
        self
    }

    /// The solver: `global`, `lm`, `sa` or `hybrid`.
    pub fn method(mut self, name: &str) -> Request {
        self.method = name.to_string();
        self
    }

    /// Worker threads (`None`: every core); results do not depend on them.
    pub fn threads(mut self, threads: Option<usize>) -> Request {
        self.threads = threads;
        self
    }

    /// Seed of every random draw.
    pub fn seed(mut self, seed: u64) -> Request {
        self.seed = seed;
        self
    }

    /// Levenberg–Marquardt's tolerances.
    pub fn lm(mut self, lm: LmOptions) -> Request {
        self.lm = lm;
        self
    }

    /// The annealer's settings (`sa`, `hybrid`).
    pub fn anneal(mut self, anneal: AnnealOptions) -> Request {
        self.anneal = anneal;
        self
    }

    /// The hybrid's switching rule.
    pub fn switch(mut self, switch: SwitchRule) -> Request {
        self.switch = switch;
        self
    }

    /// The global method's settings.
    pub fn global(mut self, global: GlobalOptions) -> Request {
        self.global = global;
        self
    }

    /// The start (nominal) arm.
    pub fn arm(&self) -> &Arm {
        &self.arm
    }

    /// The arm file's name as the report gives it (empty when not named).
    pub fn arm_file(&self) -> &str {
        &self.sources.arm_file
    }

    /// Every warning about the inputs, in order: the readers' of the arm
    /// and its data, readings outside the arm's joint limits, then the same
    /// for the held-out data.
    pub fn warnings(&self) -> Vec<String> {
        let limits = &self.arm.limits;
        let mut all = self.sources.warnings.clone();
        all.extend(
            self.data
                .limit_warning(limits, self.unit)
                .map(|w| w.to_string()),
        );
        if let Some((held_out, warnings)) = &self.held_out {
            all.extend(warnings.iter().cloned());
            let w = held_out.data.limit_warning(limits, self.unit);
            all.extend(w.map(|w| w.to_string()));
        }
        all
    }

    /// The tolerances the fit uses: the arm file's `[prior]`, overridden
    /// entry by entry by the request's spec (`none`: no prior).
    ///
    /// # Errors
    ///
    /// An [`OptionError`] on `prior`: a spec that does not parse, or a
    /// tolerance of a parameter the arm does not have.
    pub fn tolerances(&self) -> Result<Option<Tolerances>, OptionError> {
        let file = self.arm.prior.clone();
        let prior = match self.prior.as_deref() {
            None => file,
            Some(spec) => Tolerances::parse(spec, self.arm.params.joint_count())?
                .map(|given| file.unwrap_or_default().overridden_by(&given)),
        };
        if let Some(t) = &prior {
            t.check_for(&self.arm.params)?;
        }
        Ok(prior)
    }

    /// The model's settings as asked for.
    ///
    /// # Errors
    ///
    /// An [`OptionError`] on `prior`, `fix`, `robust.loss` or
    /// `robust.scale_k` (the rest are checked with the problem).
    pub fn model(&self) -> Result<ModelOptions, OptionError> {
        let prior = self.tolerances()?;
        let fix = FixSpec::parse_for(&self.fix, &self.arm.params)?;
        let robust = match (self.robust.as_deref(), self.robust_scale) {
            (None, None) => None,
            (None, Some(k)) => {
                return Err(OptionError::new(
                    Setting::RobustScale,
                    k,
                    "needs a robust loss (huber or cauchy)",
                ));
            }
            (Some(name), k) => {
                let loss = Loss::parse(name).ok_or_else(|| {
                    let names: Vec<&str> = Loss::ALL.iter().map(|l| l.name()).collect();
                    OptionError::new(
                        Setting::Robust,
                        format!("{name:?}"),
                        format!("one of {}", names.join(", ")),
                    )
                })?;
                Some(Robust {
                    loss,
                    scale_k: k.unwrap_or(loss.default_k()),
                })
            }
        };
        let beyond = self.beyond_options()?;
        Ok(ModelOptions {
            fix,
            noise: self.noise,
            accept_poor_fit: self.accept_poor_fit,
            robust,
            prior,
            beyond,
        })
    }

    /// The models beyond geometry as asked for, parsed.
    fn beyond_options(&self) -> Result<Beyond, OptionError> {
        let b = &self.beyond;
        Ok(Beyond {
            compliance: match &b.compliance {
                Some(c) => Beyond::parse_compliance(c)?,
                None => Vec::new(),
            },
            harmonics: match &b.harmonics {
                Some(h) => Beyond::parse_harmonics(h)?,
                None => Vec::new(),
            },
            backlash: match &b.backlash {
                Some(j) => Beyond::parse_backlash(j)?,
                None => Vec::new(),
            },
            thermal: b.thermal,
            drift: b.drift,
        })
    }

    /// The solver's settings as asked for, checked.
    ///
    /// # Errors
    ///
    /// An [`OptionError`] on `method`, `threads`, `lm.…`, `anneal.…`,
    /// `switch.…` or `global.…`.
    pub fn settings(&self) -> Result<SolverSettings, OptionError> {
        let method = Method::parse(&self.method).ok_or_else(|| {
            let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
            OptionError::new(
                Setting::Method,
                format!("{:?}", self.method),
                format!("one of {}", names.join(", ")),
            )
        })?;
        let settings = SolverSettings {
            method,
            lm: self.lm,
            anneal: self.anneal,
            switch: self.switch,
            global: self.global,
            threads: self.threads.unwrap_or_else(available_threads),
            seed: self.seed,
        };
        settings.check()?;
        Ok(settings)
    }

    /// The problem and the run's settings, every setting checked, the
    /// report's warnings all of [`Request::warnings`].
    ///
    /// # Errors
    ///
    /// [`CalibrationError::Option`] naming the setting refused;
    /// [`CalibrationError::Joints`] when a data set has another joint count
    /// than the arm; the kernel's refusal of the arm; lengths in another
    /// unit than the arm.
    pub fn build(self) -> Result<(Problem, SolverSettings), CalibrationError> {
        ArmKernel::new(&self.arm.params)?;
        let tooled = self.measured_with_tool()?;
        tooled.build_measured()
    }

    /// [`Request::build`] once the data say their tools.
    fn build_measured(self) -> Result<(Problem, SolverSettings), CalibrationError> {
        // Refusals come in the order of the settings' homes: the problem's,
        // then the run's.
        let settings = self.settings();
        let model = self.model()?;
        let sources = Sources {
            warnings: self.warnings(),
            ..self.sources
        };
        let arm_file = sources.arm_file.clone();
        let ball_diameter_mm = self.arm.ball_diameter_mm;
        let mut problem = Problem::new(self.arm, self.data, model)
            .map_err(|e| match e {
                // The arm file at fault, by the name the request knows.
                CalibrationError::ArmUnits {
                    reach_mm, ratio, ..
                } => CalibrationError::ArmUnits {
                    file: arm_file,
                    reach_mm,
                    ratio,
                },
                e => e,
            })?
            .with_sources(sources);
        let stated_diameter = self.spheres.as_ref().and_then(|s| s.diameter_mm);
        if let Some((rows, file)) = self.held_out_spheres {
            problem =
                with_held_out_spheres(problem, rows, &file, stated_diameter, ball_diameter_mm)?;
        }
        if let Some(s) = self.spheres {
            problem = with_spheres(problem, s, ball_diameter_mm)?;
        }
        if self.register_held_out {
            problem = problem.registering_held_out_frames();
        }
        if let Some((held_out, _)) = self.held_out {
            problem = problem.with_held_out(held_out)?;
        }
        if let Some(k) = self.cross_validate {
            problem = problem.with_cross_validation(k)?;
        }
        Ok((problem, settings?))
    }

    /// Builds the request and runs it: the problem (to write the files)
    /// and the report.
    ///
    /// # Errors
    ///
    /// As [`Request::build`], and the calibration's when it cannot run.
    pub fn run(self) -> Result<(Problem, CalibrationReport), CalibrationError> {
        let (problem, settings) = self.build()?;
        let report = problem.run(&settings)?;
        Ok((problem, report))
    }

    /// What the data can determine at the request's noise, with the prior
    /// it asks for, on its threads: `identify`'s report.
    ///
    /// # Errors
    ///
    /// An [`OptionError`] on `prior`, `noise.…` or `threads`; reference
    /// lengths in another unit than the arm ([`super::check_units`]); a
    /// data set the identification cannot analyse.
    pub fn identify(&self) -> Result<IdentifyReport, CalibrationError> {
        ArmKernel::new(&self.arm.params)?;
        super::check_units(&self.arm.params, &self.data, &self.sources.arm_file)?;
        crate::identify::room_to_identify(&self.data)?;
        let prior = self.tolerances()?;
        let threads = self.threads.unwrap_or_else(available_threads);
        let ball = self.arm.ball_diameter_mm;
        let spheres = match &self.spheres {
            Some(s) => Some((s, sphere_size(s, ball)?)),
            None => None,
        };
        // The sphere term on the analysis' layout, its centres (and sizes)
        // blocks of their own there: eliminated with the frames.
        let add = |layout: &mut crate::residuals::Layout| {
            let Some((s, size)) = spheres else {
                return Ok(Vec::new());
            };
            let term = SphereTerm::new(
                s.rows.clone(),
                &s.file,
                &self.arm.params,
                size,
                ball,
                &self.noise,
                crate::residuals::spheres::add_to(layout),
            )?;
            Ok(vec![Box::new(term) as Box<dyn crate::residuals::Term>])
        };
        let evidence = crate::identify::Evidence {
            data: &self.data,
            added: spheres
                .is_some()
                .then_some(&add as crate::identify::AddedTerms<'_>),
        };
        let report = IdentifyReport::new(
            &self.arm,
            evidence,
            &self.noise,
            prior.as_ref(),
            &self.beyond_options()?,
            threads,
            &self.sources,
        )?;
        Ok(match spheres {
            Some((s, size)) => report.with_spheres(super::identification::SphereCount {
                file: s.file.clone(),
                points: s.rows.len(),
                spheres: s.rows.spheres().len(),
                stated_diameter: match size {
                    SphereSize::Known(d) => Some(d),
                    SphereSize::Fitted => None,
                },
            }),
            None => report,
        })
    }
}

/// The size of `input`'s spheres: stated, or fitted per sphere, probed
/// with a ball of `ball_diameter_mm` (the arm file's).
///
/// # Errors
///
/// An [`OptionError`] on `sphere_diameter_mm`: out of range, without the
/// points it sizes, or stated without the ball's diameter.
fn sphere_size(
    input: &SphereInput,
    ball_diameter_mm: Option<f64>,
) -> Result<SphereSize, CalibrationError> {
    let Some(d) = input.diameter_mm else {
        return Ok(SphereSize::Fitted);
    };
    check_sphere_diameter(d)?;
    if input.rows.is_empty() {
        return Err(OptionError::new(
            Setting::SphereDiameter,
            d,
            "sizes the spheres of a sphere-surface file, and none was given",
        )
        .into());
    }
    if ball_diameter_mm.is_none() {
        return Err(OptionError::new(
            Setting::SphereDiameter,
            d,
            "a stated sphere diameter needs the probe ball's: state `ball_diameter_mm` in the arm \
             file's [probe] table (the probe centre is a ball radius off the surface)",
        )
        .into());
    }
    Ok(SphereSize::Known(d))
}

/// `problem` validated on the held-out points on spheres `rows` of `file`
/// too, the spheres of `diameter_mm` (stated) or refitted, probed with a
/// ball of `ball_diameter_mm`.
///
/// # Errors
///
/// The term's refusals (a stated diameter without the ball's).
fn with_held_out_spheres(
    problem: Problem,
    rows: Spheres,
    file: &str,
    diameter_mm: Option<f64>,
    ball_diameter_mm: Option<f64>,
) -> Result<Problem, CalibrationError> {
    let arm = problem.arm().params.clone();
    // Its blocks are never fitted: a layout of its own takes them.
    let mut own = crate::residuals::Layout::new(arm.clone());
    let term = SphereTerm::new(
        rows,
        file,
        &arm,
        diameter_mm.map_or(SphereSize::Fitted, SphereSize::Known),
        ball_diameter_mm,
        &problem.model().noise,
        crate::residuals::spheres::add_to(&mut own),
    )?;
    problem.with_held_out_spheres(term)
}

impl Request {
    /// The data as [`Request::tool`] says they were measured: every row
    /// without a tool given the tool.
    fn measured_with_tool(mut self) -> Result<Request, CalibrationError> {
        let Some(name) = self.tool.clone() else {
            return Ok(self);
        };
        crate::domain::arm_with_tool(&self.arm, &name)?;
        let Some(tool) = self.arm.tools.iter().find(|t| t.name == name).cloned() else {
            return Ok(self);
        };
        let refused = |e: InputError| OptionError::new(Setting::Tool, &name, e.to_string());
        self.data = self.data.measured_with(&name).map_err(refused)?;
        if let Some((mut held, warnings)) = self.held_out.take() {
            held.data = held.data.measured_with(&name).map_err(refused)?;
            self.held_out = Some((held, warnings));
        }
        let as_tool = |rows: Spheres, file: &str| {
            if rows.has_tools() {
                return Err(InputError::file_error(
                    file,
                    format!(
                        "the rows name their probes (a `tool` column): a probe for every row, \
                         {}, is for a file without one",
                        crate::error::quoted(&name)
                    ),
                ));
            }
            Ok(rows.as_tool(&tool))
        };
        if let Some(mut s) = self.spheres.take() {
            s.rows = as_tool(s.rows, &s.file).map_err(refused)?;
            self.spheres = Some(s);
        }
        if let Some((rows, file)) = self.held_out_spheres.take() {
            self.held_out_spheres = Some((as_tool(rows, &file).map_err(refused)?, file));
        }
        Ok(self)
    }
}

/// `problem` with the sphere term of `input` (its blocks added), probed
/// with a ball of `ball_diameter_mm` (the arm file's).
///
/// # Errors
///
/// An [`OptionError`] on `sphere_diameter_mm`: out of range, without the
/// points it sizes, or stated without the ball's diameter; the term's
/// refusals.
fn with_spheres(
    mut problem: Problem,
    input: SphereInput,
    ball_diameter_mm: Option<f64>,
) -> Result<Problem, CalibrationError> {
    let size = sphere_size(&input, ball_diameter_mm)?;
    let arm = problem.arm().params.clone();
    let noise = problem.model().noise;
    let term = SphereTerm::new(
        input.rows,
        &input.file,
        &arm,
        size,
        ball_diameter_mm,
        &noise,
        |b| problem.add_boxed_block(b),
    )?;
    Ok(problem.with_spheres(term))
}
