//! The settings of a simulated campaign — exactly what `campaign.toml` holds
//! besides the nominal arm — and their validation.

use std::collections::HashSet;
use std::collections::hash_map::{Entry, HashMap};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::SimError;
use super::sockets::round_nm;
use crate::domain::Arm;
use crate::error::quoted;
use crate::io::read_points;

/// Default standard deviation of the random length errors (`a`, `d`, probe),
/// mm: the RMS of the paper's Table 2 length errors (0.40 mm).
pub const DEFAULT_LENGTH_SIGMA_MM: f64 = 0.4;

/// The largest scale of the random errors' σ ([`ErrorModel::check_scale`]).
pub const MAX_ERROR_SCALE: f64 = 1000.0;
/// Default standard deviation of the random twist errors, degrees: the RMS of
/// the paper's Table 2 `Δβ` (0.07°).
pub const DEFAULT_TWIST_SIGMA_DEG: f64 = 0.07;
/// Default standard deviation of the random zero-offset errors, degrees: the
/// RMS of the paper's Table 2 `Δθ` (0.45°).
pub const DEFAULT_ZERO_SIGMA_DEG: f64 = 0.45;
/// Default minimum difference between two touches of one socket: some joint
/// must differ by at least this much (degrees, wrapped to ±180°).
pub(crate) const DEFAULT_MIN_POSE_SEPARATION_DEG: f64 = 20.0;
/// Default budget of inverse-kinematics starts per requested touch.
pub(crate) const DEFAULT_STARTS_PER_POSE: usize = 50;
/// Fewest touches per socket: a mean and a spread need at least three.
pub const MIN_POSES_PER_SOCKET: usize = 3;
/// Most sockets of a campaign (a bound on time and memory, far beyond any
/// real campaign).
pub(crate) const MAX_SOCKETS: usize = 1000;
/// Most touches per socket.
///
/// Every touch of a socket must differ from all the others by at least
/// [`CampaignSettings::min_pose_separation_deg`] in some joint, and the
/// articulations that put the probe on one point form a family of only
/// `joints − 3` free parameters (3 for a 6-joint arm). At the default 20°
/// such a family holds only a few thousand separated poses — for a socket in
/// the middle of the paper's nominal arm's volume, 10 000 asked for ended
/// after 500 000 starts and minutes with 7029 found; fewer fit near the edges
/// or within joint limits — and the random search slows with the square of
/// the count as the family fills up. 1000 is well within reach and takes
/// seconds; real campaigns use tens.
pub(crate) const MAX_POSES_PER_SOCKET: usize = 1000;
/// Most IK starts per touch (a bound on time).
pub(crate) const MAX_STARTS_PER_POSE: usize = 10_000;

/// How the true arm differs from the nominal one.
///
/// ```
/// use aacmm_core::simulate::ErrorModel;
/// let m = ErrorModel::random(2.0, false);
/// let ErrorModel::Random { length_sigma_mm, .. } = m else { unreachable!() };
/// assert_eq!(length_sigma_mm, 0.8);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "lowercase", deny_unknown_fields)]
pub enum ErrorModel {
    /// The paper's identified errors (method.md §7, Table 2) added to a
    /// 6-joint nominal: `Δθ`, `Δβ` (= `Δα`), `Δa`, `Δd` per joint (none for
    /// `θ6`, `β6`), `ΔBz = 0.094` mm, `ΔBx = ΔBy = 0`.
    Paper,
    /// Independent Gaussian errors on every parameter.
    Random {
        /// σ of every length error (`a`, `d`, `Bx`, `By`, `Bz`), mm.
        length_sigma_mm: f64,
        /// σ of every twist error `Δα`, degrees.
        twist_sigma_deg: f64,
        /// σ of every zero-offset error `Δθ`, degrees (unused when
        /// `zero_uniform`).
        zero_sigma_deg: f64,
        /// A newly assembled arm: the zero offsets are unknown anywhere in
        /// ±180° (uniform), not small.
        zero_uniform: bool,
    },
    /// A given true arm (same joint count as the nominal).
    File {
        /// The true arm; written into `campaign.toml` as an arm-file table.
        #[serde(with = "super::files::arm_table")]
        arm: Arm,
    },
}

impl ErrorModel {
    /// Why `scale` cannot scale the random errors' σ, if it cannot: it
    /// must be finite, not negative and at most `MAX_ERROR_SCALE` (beyond,
    /// a length σ of metres and a zero's of turns make no arm).
    ///
    /// ```
    /// use aacmm_core::simulate::ErrorModel;
    /// assert!(ErrorModel::check_scale(3.0).is_ok());
    /// assert_eq!(
    ///     ErrorModel::check_scale(1e308).unwrap_err(),
    ///     "at most 1000 (a length σ of 400 mm; beyond, no arm), got 1e308"
    /// );
    /// assert!(ErrorModel::check_scale(-1.0).unwrap_err().starts_with("must be finite"));
    /// ```
    pub fn check_scale(scale: f64) -> Result<(), String> {
        let shown = crate::error::short(scale);
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("must be finite and not negative, got {shown}"));
        }
        if scale > MAX_ERROR_SCALE {
            return Err(format!(
                "at most {MAX_ERROR_SCALE} (a length σ of {} mm; beyond, no arm), got {shown}",
                DEFAULT_LENGTH_SIGMA_MM * MAX_ERROR_SCALE
            ));
        }
        Ok(())
    }

    /// Random errors with the default σ ([`DEFAULT_LENGTH_SIGMA_MM`],
    /// [`DEFAULT_TWIST_SIGMA_DEG`], [`DEFAULT_ZERO_SIGMA_DEG`]) times `scale`;
    /// `zero_uniform` for a newly assembled arm.
    pub fn random(scale: f64, zero_uniform: bool) -> ErrorModel {
        ErrorModel::Random {
            length_sigma_mm: DEFAULT_LENGTH_SIGMA_MM * scale,
            twist_sigma_deg: DEFAULT_TWIST_SIGMA_DEG * scale,
            zero_sigma_deg: DEFAULT_ZERO_SIGMA_DEG * scale,
            zero_uniform,
        }
    }

    /// A one-line description for summaries.
    ///
    /// ```
    /// assert_eq!(aacmm_core::simulate::ErrorModel::Paper.describe(), "paper Table 2 errors");
    /// ```
    pub fn describe(&self) -> String {
        match self {
            ErrorModel::Paper => "paper Table 2 errors".to_string(),
            ErrorModel::Random {
                length_sigma_mm,
                twist_sigma_deg,
                zero_sigma_deg,
                zero_uniform,
            } => {
                let zero = if *zero_uniform {
                    "zero offsets uniform in ±180°".to_string()
                } else {
                    format!("zero offsets σ {zero_sigma_deg}°")
                };
                format!(
                    "random errors (lengths σ {length_sigma_mm} mm, twists σ {twist_sigma_deg}°, {zero})"
                )
            }
            ErrorModel::File { arm } => format!("given true arm {}", quoted(&arm.name)),
        }
    }
}

/// One given socket centre (mm, base frame).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SocketPoint {
    /// The socket's label (the `point` of the poses file).
    pub label: String,
    /// x, mm.
    pub x: f64,
    /// y, mm.
    pub y: f64,
    /// z, mm.
    pub z: f64,
}

/// Where the sockets are.
///
/// ```
/// use aacmm_core::simulate::SocketPlan;
/// assert_eq!(SocketPlan::Spread { count: 10 }.count(), 10);
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum SocketPlan {
    /// `count` sockets `S1..Scount` spread over the true arm's comfortable
    /// volume (see [`place_sockets`](super::sockets::place_sockets)).
    Spread {
        /// Number of sockets.
        count: usize,
    },
    /// Sockets at given centres (e.g. read from a `point,x,y,z` file),
    /// rounded to 1 nm so that `sockets.csv` holds them exactly.
    Given {
        /// The file they were read from (informational).
        file: Option<String>,
        /// The centres, in order.
        points: Vec<SocketPoint>,
    },
}

impl SocketPlan {
    /// Reads sockets from a point file (`point,x,y,z`, mm); errors name the
    /// file, line and field.
    ///
    /// ```no_run
    /// let plan = aacmm_core::simulate::SocketPlan::from_file(std::path::Path::new("sockets.csv"))?;
    /// # Ok::<(), aacmm_core::simulate::SimError>(())
    /// ```
    pub fn from_file(path: &Path) -> Result<SocketPlan, SimError> {
        let points = read_points(path)?
            .into_iter()
            .map(|(label, [x, y, z])| SocketPoint { label, x, y, z })
            .collect();
        Ok(SocketPlan::Given {
            file: Some(crate::io::source_name(path)),
            points,
        })
    }

    /// The first two given sockets at the same place (equal centres once
    /// rounded to 1 nm, as simulated), by index: `(earlier, later)`.
    ///
    /// ```
    /// use aacmm_core::simulate::{SocketPlan, SocketPoint};
    /// let p = |label: &str, x| SocketPoint { label: label.into(), x, y: 0.0, z: 0.0 };
    /// let plan = SocketPlan::Given { file: None, points: vec![p("A", 1.0), p("B", 2.0), p("C", 1.0)] };
    /// assert_eq!(plan.same_place(), Some((0, 2)));
    /// ```
    pub fn same_place(&self) -> Option<(usize, usize)> {
        let SocketPlan::Given { points, .. } = self else {
            return None;
        };
        let mut seen: HashMap<[u64; 3], usize> = HashMap::with_capacity(points.len());
        points.iter().enumerate().find_map(|(j, p)| {
            // +0.0 makes -0 and 0 the same place.
            let key = [p.x, p.y, p.z].map(|v| (round_nm(v) + 0.0).to_bits());
            match seen.entry(key) {
                Entry::Occupied(i) => Some((*i.get(), j)),
                Entry::Vacant(v) => {
                    v.insert(j);
                    None
                }
            }
        })
    }

    /// Number of sockets.
    pub fn count(&self) -> usize {
        match self {
            SocketPlan::Spread { count } => *count,
            SocketPlan::Given { points, .. } => points.len(),
        }
    }
}

/// Every setting of a simulated campaign, and the seed: with the nominal arm,
/// enough to regenerate the identical files (see
/// [`read_campaign`](super::read_campaign)).
///
/// ```
/// use aacmm_core::simulate::{CampaignSettings, ErrorModel};
/// let s = CampaignSettings::new(7, ErrorModel::Paper, 10, 10);
/// assert_eq!(s.seed, 7);
/// assert_eq!(s.reference_lengths, 3);
/// assert!(s.validate(6).is_ok());
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignSettings {
    /// Seed of every random draw (at most `i64::MAX`, the TOML integer range).
    pub seed: u64,
    /// The nominal arm's file, if it came from one (informational; the arm
    /// itself is stored in `campaign.toml`).
    pub nominal_file: Option<String>,
    /// Touches per socket (at least `MIN_POSES_PER_SOCKET`).
    pub poses_per_socket: usize,
    /// σ of the Gaussian noise on each encoder reading, degrees.
    pub encoder_noise_deg: f64,
    /// σ of the probe seating, mm, per axis: each touch seats the ball at the
    /// socket centre plus isotropic Gaussian noise.
    pub probe_noise_mm: f64,
    /// Number of reference lengths (distinct socket pairs).
    pub reference_lengths: usize,
    /// Standard uncertainty of the reference lengths, mm: when given, each
    /// recorded distance carries Gaussian noise of this σ and the file an
    /// `uncertainty` column.
    pub length_uncertainty_mm: Option<f64>,
    /// Two touches of one socket differ by at least this much in some joint,
    /// degrees.
    pub min_pose_separation_deg: f64,
    /// Budget of inverse-kinematics starts per requested touch.
    pub starts_per_pose: usize,
    /// How the true arm differs from the nominal.
    pub errors: ErrorModel,
    /// Where the sockets are.
    pub sockets: SocketPlan,
}

impl CampaignSettings {
    /// Settings with `count` spread sockets, `poses` touches each, no noise,
    /// `min(3, pairs)` reference lengths and the default IK settings.
    pub fn new(seed: u64, errors: ErrorModel, count: usize, poses: usize) -> CampaignSettings {
        CampaignSettings {
            seed,
            nominal_file: None,
            poses_per_socket: poses,
            encoder_noise_deg: 0.0,
            probe_noise_mm: 0.0,
            reference_lengths: 3.min(pair_count(count)),
            length_uncertainty_mm: None,
            min_pose_separation_deg: DEFAULT_MIN_POSE_SEPARATION_DEG,
            starts_per_pose: DEFAULT_STARTS_PER_POSE,
            errors,
            sockets: SocketPlan::Spread { count },
        }
    }

    /// Checks every setting for an arm with `joints` joints; the error names
    /// the setting.
    ///
    /// ```
    /// use aacmm_core::simulate::{CampaignSettings, ErrorModel};
    /// let mut s = CampaignSettings::new(1, ErrorModel::Paper, 4, 10);
    /// s.reference_lengths = 7; // 4 sockets make 6 pairs
    /// let e = s.validate(6).unwrap_err().to_string();
    /// assert!(e.starts_with("setting `reference_lengths`: 7 reference lengths"), "{e}");
    /// ```
    pub fn validate(&self, joints: usize) -> Result<(), SimError> {
        if self.seed > crate::error::MAX_SEED {
            return bad("seed", crate::error::seed_bound(self.seed));
        }
        self.validate_counts(joints)?;
        self.validate_noise()?;
        self.validate_selection()?;
        self.validate_errors(joints)?;
        self.validate_given_sockets()
    }

    /// The sockets, and the touches per socket (`joints`: what leaves
    /// articulations free).
    fn validate_counts(&self, joints: usize) -> Result<(), SimError> {
        let sockets = self.sockets.count();
        if sockets == 0 {
            return bad("sockets", "at least one socket is needed".into());
        }
        if sockets > MAX_SOCKETS {
            return bad(
                "sockets",
                format!("at most {MAX_SOCKETS} sockets, got {sockets}"),
            );
        }
        if self.poses_per_socket > MAX_POSES_PER_SOCKET {
            return bad(
                "poses_per_socket",
                format!(
                    "at most {MAX_POSES_PER_SOCKET} touches per socket, got {}: each touch \
                     must differ from every other touch of its socket by at least {}° in some \
                     joint, and the articulations that reach one point leave only {} joint(s) \
                     free, so only a few thousand such touches can be found, and the search \
                     for them slows with the square of their number (real campaigns use tens)",
                    self.poses_per_socket,
                    self.min_pose_separation_deg,
                    joints.saturating_sub(3)
                ),
            );
        }
        if self.poses_per_socket < MIN_POSES_PER_SOCKET {
            return bad(
                "poses_per_socket",
                format!(
                    "at least {MIN_POSES_PER_SOCKET} touches per socket (a mean and a spread), \
                     got {}",
                    self.poses_per_socket
                ),
            );
        }
        Ok(())
    }

    fn validate_noise(&self) -> Result<(), SimError> {
        non_negative("encoder_noise_deg", self.encoder_noise_deg)?;
        let max = crate::residuals::MAX_ENCODER_SIGMA_DEG;
        if self.encoder_noise_deg > max {
            return bad(
                "encoder_noise_deg",
                format!(
                    "σ = {}° is more than {max}°: beyond half a turn an angle's σ means nothing \
                     (a real encoder's is 0.001–0.01°)",
                    crate::error::short(self.encoder_noise_deg)
                ),
            );
        }
        non_negative("probe_noise_mm", self.probe_noise_mm)?;
        if let Some(u) = self.length_uncertainty_mm {
            non_negative("length_uncertainty_mm", u)?;
        }
        Ok(())
    }

    /// How lengths and touches are picked: the reference lengths among the
    /// socket pairs, the separation of a socket's touches, the IK starts
    /// per touch.
    fn validate_selection(&self) -> Result<(), SimError> {
        let sockets = self.sockets.count();
        let pairs = pair_count(sockets);
        if self.reference_lengths > pairs {
            return bad(
                "reference_lengths",
                format!(
                    "{} reference lengths asked for, but {sockets} sockets make only {pairs} \
                     distinct pairs",
                    self.reference_lengths
                ),
            );
        }
        let sep = self.min_pose_separation_deg;
        if !(0.0..=180.0).contains(&sep) {
            return bad(
                "min_pose_separation_deg",
                format!("must be in [0, 180], got {sep}"),
            );
        }
        if !(1..=MAX_STARTS_PER_POSE).contains(&self.starts_per_pose) {
            return bad(
                "starts_per_pose",
                format!(
                    "between 1 and {MAX_STARTS_PER_POSE}, got {}",
                    self.starts_per_pose
                ),
            );
        }
        Ok(())
    }

    /// Sockets from a file: labelled uniquely, finite, each at its own place.
    fn validate_given_sockets(&self) -> Result<(), SimError> {
        let SocketPlan::Given { points, .. } = &self.sockets else {
            return Ok(());
        };
        let mut seen = HashSet::new();
        for p in points {
            if p.label.is_empty() || !seen.insert(p.label.as_str()) {
                return bad(
                    "sockets.points",
                    format!(
                        "socket labels must be non-empty and unique: {}",
                        quoted(&p.label)
                    ),
                );
            }
            if ![p.x, p.y, p.z].iter().all(|v| v.is_finite()) {
                return bad(
                    "sockets.points",
                    format!("socket {} has a non-finite coordinate", quoted(&p.label)),
                );
            }
        }
        if let Some((i, j)) = self.sockets.same_place() {
            let (a, b) = (&points[i], &points[j]);
            return bad(
                "sockets.points",
                format!(
                    "sockets {} and {} are at the same place ({}, {}, {} mm): every \
                     socket must be a different point",
                    quoted(&a.label),
                    quoted(&b.label),
                    b.x,
                    b.y,
                    b.z
                ),
            );
        }
        Ok(())
    }

    fn validate_errors(&self, joints: usize) -> Result<(), SimError> {
        match &self.errors {
            ErrorModel::Paper if joints != 6 => Err(SimError::Model(format!(
                "the paper's Table 2 errors are for a 6-joint arm; the nominal arm has \
                 {joints} joints (use random errors or a true arm file)"
            ))),
            ErrorModel::Paper => Ok(()),
            ErrorModel::Random {
                length_sigma_mm,
                twist_sigma_deg,
                zero_sigma_deg,
                ..
            } => {
                non_negative("errors.length_sigma_mm", *length_sigma_mm)?;
                non_negative("errors.twist_sigma_deg", *twist_sigma_deg)?;
                non_negative("errors.zero_sigma_deg", *zero_sigma_deg)
            }
            ErrorModel::File { arm } if arm.params.joint_count() != joints => {
                Err(SimError::Model(format!(
                    "the true arm {} has {} joints, the nominal arm {joints}",
                    quoted(&arm.name),
                    arm.params.joint_count()
                )))
            }
            ErrorModel::File { .. } => Ok(()),
        }
    }
}

/// Number of distinct pairs of `n` sockets.
///
/// ```
/// assert_eq!(aacmm_core::simulate::pair_count(10), 45);
/// assert_eq!(aacmm_core::simulate::pair_count(1), 0);
/// // Saturates rather than overflow: a count this large is refused later.
/// assert_eq!(aacmm_core::simulate::pair_count(1 << 62), usize::MAX);
/// assert_eq!(aacmm_core::simulate::pair_count(7), 21);
/// ```
pub fn pair_count(n: usize) -> usize {
    let (even, odd) = if n.is_multiple_of(2) {
        (n, n.saturating_sub(1))
    } else {
        (n - 1, n)
    };
    (even / 2).saturating_mul(odd)
}

/// A setting refused, by name.
fn bad(name: &str, msg: String) -> Result<(), SimError> {
    Err(SimError::setting(name, msg))
}

fn non_negative(name: &str, x: f64) -> Result<(), SimError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(SimError::setting(
            name,
            format!(
                "must be finite and not negative, got {}",
                crate::error::short(x)
            ),
        ))
    }
}
