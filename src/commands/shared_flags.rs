//! What `identify` and `calibrate` share: the flags of the arm, the touches,
//! the reference lengths, the noise and the prior, read into the library's
//! [`Request`], and the flag of each library setting.

use std::path::{Path, PathBuf};

use aacmm_core::calibrate::{CalibrationError, MAX_THREADS, check_threads};
use aacmm_core::error::{OptionError, quoted};
use aacmm_core::residuals::DEFAULT_LENGTH_SIGMA_MM;
use aacmm_core::residuals::Noise;
use aacmm_core::session::{Request, user_noise};
use aacmm_core::setting::{Setting, Spelling};
use anyhow::{Result, anyhow};

use crate::output::warn;
use aacmm_core::io::AngleUnit;

/// The flags of a fit: arm, poses, reference lengths, reference
/// positions, noise.
#[derive(clap::Args)]
pub struct FitInput {
    /// Arm file (TOML) with 1 to 12 `[[joint]]` entries.
    #[arg(long)]
    pub arm: PathBuf,
    /// Poses file (CSV `point,q1,...,qn`: touches of points in many poses);
    /// `-` reads standard input. Optional with --positions or --spheres.
    #[arg(long, required_unless_present_any = ["positions", "spheres"])]
    pub data: Option<PathBuf>,
    /// Unit of the joint readings (q1..qn) in the poses and positions
    /// files (and calibrate's held-out --validate files); the arm file
    /// states its own (`angle_unit`), and --encoder-noise is in degrees
    /// whatever this is.
    #[arg(long, default_value = "deg", value_parser = super::angle_unit())]
    pub angle_unit: AngleUnit,
    /// Reference lengths (CSV `point_a,point_b,distance[,uncertainty]`, mm).
    #[arg(long, value_name = "L.csv", requires = "data")]
    pub lengths: Option<PathBuf>,
    /// Reference positions an instrument saw (a laser tracker) or an
    /// artefact's certified centres: CSV `point,q1,...,qn,x,y,z[,frame]
    /// [,tool][,uncertainty]`, mm in the instrument's frame; each frame's
    /// pose is fitted, and each tool the `tool` column names (the arm
    /// file's `[[tool]]`: markers, SMRs; empty: the probe) its offset. With
    /// --data too, both are fitted together.
    #[arg(long, value_name = "P.csv")]
    pub positions: Option<PathBuf>,
    /// Points probed on the surface of reference spheres: CSV
    /// `sphere,q1,...,qn` (one row per point, at least 4 per sphere, over
    /// a cap rather than one circle); each sphere's centre is fitted. The
    /// probe's ball diameter is the arm file's `[probe] ball_diameter_mm`.
    /// Alone or with --data, --lengths, --positions.
    #[arg(long, value_name = "S.csv")]
    pub spheres: Option<PathBuf>,
    /// The reference spheres' diameter, mm: fixes the arm's scale without
    /// reference lengths. Without it each sphere's diameter is fitted, and
    /// the scale needs --lengths or --positions.
    #[arg(long, value_name = "MM", requires = "spheres")]
    pub sphere_diameter: Option<f64>,
    /// σ per coordinate of a reference position whose file states none:
    /// `A` mm, or `A+B/m` (B mm per metre from the instrument: a tracker's
    /// `0.015+0.006/m`). Without it (and without an `uncertainty` column)
    /// the σ is estimated from the fit.
    #[arg(long, value_name = "MM[+MM/m]", value_parser = position_noise)]
    pub position_noise: Option<(f64, Option<f64>)>,
    /// σ of a tool orientation seen, degrees per axis: what a positions
    /// file's `qw,qx,qy,qz` columns (a 6-D target's orientation) are
    /// weighed by. A file with orientations needs it.
    #[arg(long, value_name = "DEG")]
    pub orientation_noise: Option<f64>,
    /// σ of each encoder reading, degrees (with --probe-noise: the touch
    /// weights; without either, the touch σ is estimated from the fit).
    #[arg(long, value_name = "DEG")]
    pub encoder_noise: Option<f64>,
    /// σ of the probe seating per axis, mm.
    #[arg(long, value_name = "MM")]
    pub probe_noise: Option<f64>,
    /// σ of a reference length whose file gives no uncertainty, mm.
    #[arg(long, value_name = "MM", default_value_t = DEFAULT_LENGTH_SIGMA_MM)]
    pub length_uncertainty: f64,
    /// Weight of every reference-length residual, 1/mm (overrides the
    /// uncertainties).
    #[arg(long, value_name = "W")]
    pub length_weight: Option<f64>,
    /// Tolerances of the nominal geometry (1σ prior; a MAP fit): `none`
    /// (ignore the arm file's prior table) or comma-separated TARGET=VALUEUNIT,
    /// e.g. `length=0.5mm,angle=0.1deg,theta5=0.05deg` (targets length,
    /// angle, a, d, alpha, theta, probe or a parameter; units mm, m, deg,
    /// rad); overrides the arm file's prior table entry by entry.
    #[arg(long, value_name = "none|SPEC")]
    pub prior: Option<String>,
    /// Joint compliance under gravity for the listed joints (e.g. `2,3,4`):
    /// each deflects by its compliance (rad per N·m, fitted) times the
    /// gravity torque of the masses outboard of it, from the arm file's
    /// `mass_kg` (links and `[probe]`) and `gravity`.
    #[arg(long, value_name = "JOINTS")]
    pub compliance: Option<String>,
    /// Encoder harmonics `a_k sin(k q) + b_k cos(k q)` added to the listed
    /// joints' readings, JOINT:ORDERS (e.g. `2:1,5:1-2`; order 1 is the
    /// disc's eccentricity).
    #[arg(long, value_name = "J:K[,J:K1-K2]")]
    pub harmonics: Option<String>,
    /// Backlash of the listed joints (e.g. `2,3`): each reads off by a
    /// half-play (deg; mm for a prismatic joint; fitted) on the gear flank
    /// the gravity torque of the arm file's masses presses, or the one an
    /// `approach` column of the data names (`+-0…`, one sign per joint). A
    /// joint whose flank never changes over the poses cannot tell it from
    /// its zero offset: it is held.
    #[arg(long, value_name = "JOINTS")]
    pub backlash: Option<String>,
    /// Fit a thermal expansion coefficient of the lengths (ppm/K) against
    /// the `temperature` column (°C) of the data; lengths are at 20 °C.
    #[arg(long)]
    pub thermal: bool,
    /// Fit a linear drift of the arm's base against the instrument (mm/h)
    /// against the `time` column (s) of the data.
    #[arg(long)]
    pub drift: bool,
    /// Worker threads, 1 to 1024 (default: every core); results do not
    /// depend on it.
    #[arg(long, value_name = "N", value_parser = threads_flag)]
    pub threads: Option<usize>,
}

impl FitInput {
    /// The input files, for output-path checks.
    pub fn paths(&self) -> Vec<(&'static str, &Path)> {
        let mut v = vec![("--arm", self.arm.as_path())];
        v.extend(self.data.as_deref().map(|d| ("--data", d)));
        v.extend(self.lengths.as_deref().map(|l| ("--lengths", l)));
        v.extend(self.positions.as_deref().map(|l| ("--positions", l)));
        v.extend(self.spheres.as_deref().map(|l| ("--spheres", l)));
        v
    }

    /// The noise flags in internal units (the library checks them:
    /// [`Noise::check`], with [`flag_error`] naming the flag).
    pub fn noise(&self) -> Noise {
        Noise {
            position_mm: self.position_noise.map(|(a, _)| a),
            position_mm_per_m: self.position_noise.and_then(|(_, b)| b),
            orientation_rad: self.orientation_noise.map(f64::to_radians),
            ..user_noise(
                self.encoder_noise,
                self.probe_noise,
                self.length_uncertainty,
                self.length_weight,
            )
        }
    }

    /// The library's request for these flags: the arm, the touches and
    /// reference lengths read (the readers' warnings, and the one for
    /// readings outside the arm's joint limits, printed here and kept by
    /// the request for the report), the noise, `--prior` and `--threads`.
    pub fn request(&self) -> Result<Request> {
        let unit = self.angle_unit;
        let mut request = match (&self.data, &self.positions, &self.spheres) {
            (Some(data), _, _) => Request::read(&self.arm, data, unit)?,
            (None, Some(positions), _) => Request::read_positions_only(&self.arm, positions, unit)?,
            (None, None, Some(spheres)) => Request::read_spheres_only(&self.arm, spheres, unit)?,
            (None, None, None) => return Err(anyhow!("give --data, --positions or --spheres")),
        };
        // Shown before the lengths are read, so that a bad lengths file
        // does not hide them.
        request.warnings().iter().try_for_each(warn)?;
        if let Some(path) = &self.lengths {
            request = request.read_lengths(path)?;
        }
        if let (Some(_), Some(path)) = (&self.data, &self.positions) {
            request = request.read_positions(path)?;
        }
        if let (true, Some(path)) = (
            self.data.is_some() || self.positions.is_some(),
            &self.spheres,
        ) {
            request = request.read_spheres(path)?;
        }
        Ok(request
            .sphere_diameter(self.sphere_diameter)
            .noise(self.noise())
            .beyond(
                self.compliance.as_deref(),
                self.harmonics.as_deref(),
                self.thermal,
                self.drift,
            )
            .backlash(self.backlash.as_deref())
            .prior(self.prior.as_deref())
            .threads(self.threads))
    }
}

/// `N` of `--threads`: the library's bound ([`MAX_THREADS`]) in its words,
/// as Python's `threads` and C's setter refuse it; a number too large for
/// any integer type is above that bound too, not "not a number".
pub fn threads_flag(s: &str) -> Result<usize, String> {
    use std::num::IntErrorKind;
    let n = match s.trim().parse::<usize>() {
        Ok(n) => n,
        Err(e) if *e.kind() == IntErrorKind::PosOverflow => usize::MAX,
        Err(_) => {
            return Err(format!(
                "{} is not a whole number of threads (1 to {MAX_THREADS})",
                quoted(s)
            ));
        }
    };
    check_threads(n).map_err(|e| e.reason)?;
    Ok(n)
}

// The bound quoted in the help text is the library's.
const _: () = assert!(MAX_THREADS == 1024);

/// `A` or `A+B/m` of --position-noise: mm, and mm per metre.
pub fn position_noise(s: &str) -> Result<(f64, Option<f64>), String> {
    let number = |t: &str| {
        t.trim().parse::<f64>().map_err(|_| {
            format!(
                "{} is not a number: give A or A+B/m, both mm (e.g. 0.015+0.006/m)",
                quoted(t)
            )
        })
    };
    match s.split_once('+') {
        None => Ok((number(s)?, None)),
        Some((a, b)) => {
            let b = b.trim().strip_suffix("/m").ok_or_else(|| {
                format!(
                    "{}: the distance part is B/m, mm per metre (e.g. 0.015+0.006/m)",
                    quoted(s)
                )
            })?;
            Ok((number(a)?, Some(number(b)?)))
        }
    }
}

/// A library error in the command line's words: a refused setting names
/// its flag (the value as typed is on the command line; the library's may
/// be in internal units), anything else passes through.
pub fn flag_error(e: impl Into<CalibrationError>) -> anyhow::Error {
    match e.into() {
        CalibrationError::Option(o) => option_error(&o),
        other => anyhow::Error::new(other),
    }
}

fn option_error(o: &OptionError) -> anyhow::Error {
    match o.setting.argument(Spelling::Cli) {
        // The library holds the encoder noise in radians; the flag is in
        // degrees.
        Some(flag) if o.setting == Setting::EncoderNoise => match o.value.parse::<f64>() {
            Ok(rad) if rad.is_finite() => {
                // Rounded back to what was typed where that is ordinary;
                // `1e300`, not 301 digits, otherwise.
                let deg = rad.to_degrees();
                let deg = if (1e-4..1e3).contains(&deg.abs()) {
                    (deg * 1e12).round() / 1e12
                } else {
                    deg
                };
                anyhow!("{flag} {}: {}", aacmm_core::error::short(deg), o.reason)
            }
            _ => anyhow!("{flag} {}: {}", o.value, o.reason),
        },
        Some(flag) => anyhow!("{flag} {}: {}", o.value, o.reason),
        None => anyhow!("{o}"),
    }
}
