//! Points probed on the surface of reference spheres: one residual row per
//! point, the distance of the probe ball's centre from the sphere's centre
//! less the two radii,
//!
//! ```text
//! r_i = w_i (|p_i − c_s| − (R_s + r_ball))
//! ```
//!
//! with `p_i` the probe centre at pose `i` (the arm's corrections beyond
//! geometry applied, [`At::for_each_tool`]), `c_s` the centre of sphere `s`
//! (a 3-column block per sphere, started at the algebraic sphere fit of the
//! nominal arm's points), `R_s` its radius — stated (`--sphere-diameter`)
//! or a 1-column block per sphere — and `r_ball` the probe ball's radius
//! (the arm file's `[probe] ball_diameter_mm`). Its Jacobian is
//! `w n̂ᵀ ∂p/∂x` on the arm's columns, `−w n̂ᵀ` on the centre and `−w` on a
//! fitted radius, `n̂ = (p_i − c_s)/|p_i − c_s|` the radial direction.
//!
//! **Weights**: the touches' noise model projected on the one direction a
//! surface point measures, `σ_i² = σ_probe² + σ_enc² ‖n̂ᵀ J_q‖²` (`J_q` the
//! joint Jacobian), at the arm and centres the fit starts from and fixed
//! during it (so the cost is one function); without stated noise, a σ the
//! fit estimates.
//!
//! **What it sees**: the centres are free, so a rigid motion of the whole
//! arm (a turn about, or a slide along, its base axis) is absorbed by them:
//! neither is seen. A stated diameter fixes the arm's size (scaling the arm
//! would scale every sphere); with the diameters fitted, it does not, and
//! the identifiability rules say so (a reference length or positions must).
//!
//! The term is written with public items of the library only, as a user's
//! own term would be (`tests/integration/sphere_term.rs` writes a minimal
//! one outside the crate and gets the same fit).

mod folds;

use crate::corrections::Conditions;
use crate::domain::Spheres;
use crate::error::InputError;
use crate::kernel::{ArmKernel, PreparedPoses};
use crate::params::DhParams;
use crate::residuals::{
    At, Block, BlockId, Layout, LayoutError, Noise, Normal, Origin, Role, Scalar, Sees, Shared,
    Standardised, Term, TermError, Unit, Vector,
};
use crate::setting::Setting;

/// The term's name in reports.
pub(crate) const TERM: &str = "spheres";

/// The smallest stated sphere diameter, mm: below it the value was most
/// likely given in metres (a 25 mm sphere as `0.025`).
pub const MIN_SPHERE_DIAMETER_MM: f64 = 1.0;
/// The largest, mm: no reference sphere an arm probes is a metre across.
pub const MAX_SPHERE_DIAMETER_MM: f64 = 1000.0;

/// Checks a stated sphere diameter (mm): finite, between
/// [`MIN_SPHERE_DIAMETER_MM`] (below it, metres) and
/// [`MAX_SPHERE_DIAMETER_MM`].
///
/// ```
/// use aacmm_core::residuals::spheres::check_sphere_diameter;
/// assert!(check_sphere_diameter(25.4).is_ok());
/// let e = check_sphere_diameter(0.0254).unwrap_err();
/// assert_eq!(e.field(), "sphere_diameter_mm");
/// assert!(e.to_string().contains("metres"), "{e}");
/// ```
///
/// # Errors
///
/// An [`crate::error::OptionError`] on `sphere_diameter_mm`.
pub fn check_sphere_diameter(d: f64) -> Result<(), crate::error::OptionError> {
    let why = if !d.is_finite() || d <= 0.0 {
        "a sphere's diameter is a positive number of mm".to_string()
    } else if d < MIN_SPHERE_DIAMETER_MM {
        format!(
            "a reference sphere of {d} mm is smaller than any ({MIN_SPHERE_DIAMETER_MM} mm): in \
             metres? the diameter is in mm ({} mm)",
            crate::error::short(d * 1000.0)
        )
    } else if d > MAX_SPHERE_DIAMETER_MM {
        format!("a reference sphere of {d} mm is larger than any ({MAX_SPHERE_DIAMETER_MM} mm)")
    } else {
        return Ok(());
    };
    Err(crate::error::OptionError::new(
        Setting::SphereDiameter,
        crate::error::short(d),
        why,
    ))
}

/// The centre and radius of the sphere through `points` of least algebraic
/// error (`|p|² = 2c·p + k` in least squares, `R² = k + |c|²`): the start
/// of the geometric fit, which the term's own residual is. `None` for
/// fewer than 4 points or points on one circle.
///
/// ```
/// use aacmm_core::residuals::spheres::algebraic_sphere;
/// let p = [[11.0, 2.0, 3.0], [1.0, 12.0, 3.0], [1.0, 2.0, 13.0], [-9.0, 2.0, 3.0], [1.0, -8.0, 3.0]];
/// let (c, r) = algebraic_sphere(&p).unwrap();
/// assert!((c[0] - 1.0).abs() < 1e-9 && (c[2] - 3.0).abs() < 1e-9 && (r - 10.0).abs() < 1e-9);
/// ```
pub fn algebraic_sphere(points: &[[f64; 3]]) -> Option<([f64; 3], f64)> {
    if points.len() < 4 {
        return None;
    }
    // About the centroid, for conditioning.
    let o = crate::geometry::centroid(points);
    let n = points.len();
    let a = nalgebra::DMatrix::from_fn(n, 4, |i, k| match k {
        3 => 1.0,
        k => 2.0 * (points[i][k] - o[k]),
    });
    let b = nalgebra::DVector::from_fn(n, |i, _| {
        (0..3).map(|k| (points[i][k] - o[k]).powi(2)).sum::<f64>()
    });
    let svd = a.svd(true, true);
    let s = &svd.singular_values;
    if s.min() <= 1e-9 * s.max() {
        return None;
    }
    let x = svd.solve(&b, 0.0).ok()?;
    let c = [x[0] + o[0], x[1] + o[1], x[2] + o[2]];
    let r2 = x[3] + x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
    (r2 > 0.0 && c.iter().all(|v| v.is_finite())).then(|| (c, r2.sqrt()))
}

/// The spheres' size: stated, or fitted per sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SphereSize {
    /// Every sphere's diameter, mm (`--sphere-diameter`): fixes the scale.
    Known(f64),
    /// Each sphere's radius a block of its own: the scale then needs
    /// reference lengths or positions.
    Fitted,
}

/// Points probed on reference spheres ([`crate::io::spheres`]) as a
/// residual term: see the module's documentation.
#[derive(Clone)]
pub struct SphereTerm {
    spheres: Spheres,
    file: String,
    poses: PreparedPoses,
    /// When rows name tools, per tool its rows (ascending) and their poses:
    /// each tool's kernel evaluates its own rows only. Empty without tools.
    by_tool: Vec<(Vec<usize>, PreparedPoses)>,
    /// Per sphere, its centre block.
    centres: Vec<BlockId>,
    /// Per sphere, its radius block when fitted.
    radii: Vec<Option<BlockId>>,
    /// The stated spheres' radius, mm.
    known_radius: Option<f64>,
    /// The probe ball's radius, mm (0 when not stated and not needed): the
    /// default tool's.
    ball_radius: f64,
    /// Per tool of the rows ([`Spheres::tools`]), its ball's radius, mm.
    balls: Vec<f64>,
    /// σ of an encoder reading (rad) and of the probe's seating (mm).
    encoder: Option<f64>,
    probe: Option<f64>,
    /// Per row, a robust fit's weight (1 without one).
    robust: Vec<f64>,
    /// Per row, its σ (mm) under the stated noise; empty until weighed.
    sigmas: Vec<f64>,
    /// Per row, `w_i` (1/mm); empty until weighed.
    weights: Vec<f64>,
}

impl std::fmt::Debug for SphereTerm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SphereTerm")
            .field("file", &self.file)
            .field("points", &self.spheres.len())
            .field("spheres", &self.centres.len())
            .field("known_radius", &self.known_radius)
            .finish()
    }
}

/// When `spheres`' rows name tools, per tool its rows (ascending) and their
/// poses for a chain of `shape` (`None`: revolute joints); else nothing.
///
/// # Errors
///
/// The kernel's refusal of the readings.
fn by_tool(
    spheres: &Spheres,
    shape: Option<crate::params::ChainShape>,
) -> Result<Vec<(Vec<usize>, PreparedPoses)>, TermError> {
    if !spheres.has_tools() {
        return Ok(Vec::new());
    }
    let mut rows = vec![Vec::new(); spheres.tools().len()];
    for i in 0..spheres.len() {
        rows[spheres.tool(i)].push(i);
    }
    (rows.into_iter())
        .map(|of| {
            let poses = prepared(spheres, &of, shape)?;
            Ok((of, poses))
        })
        .collect()
}

/// The poses of `spheres`' rows `rows` for a chain of `shape` (`None`:
/// revolute joints).
///
/// # Errors
///
/// The kernel's refusal of the readings.
fn prepared(
    spheres: &Spheres,
    rows: &[usize],
    shape: Option<crate::params::ChainShape>,
) -> Result<PreparedPoses, TermError> {
    let readings: Vec<&[f64]> = rows.iter().map(|&i| spheres.reading(i)).collect();
    Ok(match shape {
        Some(shape) => PreparedPoses::for_shape(shape, &readings)?,
        None => PreparedPoses::new(spheres.joints(), &readings)?,
    })
}

/// The nominal positions of every row of `spheres` at `arm`, mm.
fn positions_at(spheres: &Spheres, arm: &DhParams) -> Result<Vec<[f64; 3]>, TermError> {
    let kernel = ArmKernel::new(arm)?;
    let rows: Vec<&[f64]> = (0..spheres.len()).map(|i| spheres.reading(i)).collect();
    Ok(kernel.positions_of(&rows)?)
}

/// Refuses spheres whose points, where `arm` puts them, fix no sphere
/// (`Spheres::check_geometry`), naming `file`'s line and field.
///
/// # Errors
///
/// As `Spheres::check_geometry`; a kernel that refuses the arm (as the
/// file's error, naming the file).
pub fn check_spheres(spheres: &Spheres, file: &str, arm: &DhParams) -> Result<(), InputError> {
    let p = positions_at(spheres, arm).map_err(|e| InputError::file_error(file, e.to_string()))?;
    spheres.check_geometry(file, &p)
}

impl SphereTerm {
    /// The term of `spheres` (read from `file`) for a fit starting at
    /// `arm`, of spheres of `size`, probed with a ball of `ball_diameter_mm`
    /// (the arm file's), under `noise` (the touches' encoder and probe σ):
    /// its blocks — per sphere its centre `sphere.NAME` (x, y, z, mm) and,
    /// when fitted, its radius `sphere.NAME.radius` — go to the fit through
    /// `add` (`Problem::add_boxed_block`, `Layout::add`), each started at
    /// the algebraic fit of `arm`'s points.
    ///
    /// # Errors
    ///
    /// Points that fix no sphere ([`check_spheres`], the message naming the
    /// file, line and field); a stated diameter without the ball's (the arm
    /// file's `[probe] ball_diameter_mm`), or out of range
    /// ([`check_sphere_diameter`]); a block the layout refuses.
    pub fn new(
        spheres: Spheres,
        file: &str,
        arm: &DhParams,
        size: SphereSize,
        ball_diameter_mm: Option<f64>,
        noise: &Noise,
        mut add: impl FnMut(Box<dyn Block>) -> Result<BlockId, LayoutError>,
    ) -> Result<SphereTerm, TermError> {
        check_spheres(&spheres, file, arm).map_err(|e| TermError::invalid(TERM, e.to_string()))?;
        let known_radius = match size {
            SphereSize::Known(d) => {
                check_sphere_diameter(d).map_err(|e| TermError::invalid(TERM, e.to_string()))?;
                if ball_diameter_mm.is_none() {
                    return Err(TermError::invalid(
                        TERM,
                        "a stated sphere diameter needs the probe ball's: the arm file's \
                         `[probe] ball_diameter_mm` (the probe centre is a ball radius off the \
                         surface)",
                    ));
                }
                Some(d / 2.0)
            }
            SphereSize::Fitted => None,
        };
        let ball_radius = ball_diameter_mm.unwrap_or(0.0) / 2.0;
        let balls = tool_balls(&spheres, ball_radius, known_radius.is_some())?;
        add_tool_blocks(&spheres, &mut add)?;
        let p = positions_at(&spheres, arm)?;
        let (mut centres, mut radii) = (Vec::new(), Vec::new());
        for (s, name) in spheres.spheres().iter().enumerate() {
            let points: Vec<[f64; 3]> = spheres.rows_of(s).iter().map(|&i| p[i]).collect();
            let ball = balls[spheres.tool_of_sphere(s)];
            let (c, r) = algebraic_sphere(&points).ok_or_else(|| {
                TermError::invalid(TERM, format!("sphere `{name}`: no sphere fits its points"))
            })?;
            let block = format!("sphere.{name}");
            centres.push(add(Box::new(Vector {
                name: block.clone(),
                names: ["x", "y", "z"].map(|k| format!("{block}.{k}")).to_vec(),
                unit: Unit::Length,
                start: c.to_vec(),
                tolerances: vec![None; 3],
            }))?);
            radii.push(match known_radius {
                Some(_) => None,
                None => Some(add(Box::new(Scalar {
                    name: format!("{block}.radius"),
                    unit: Unit::Length,
                    start: r - ball,
                    tolerance: None,
                    limit: None,
                }))?),
            });
        }
        let shape = arm
            .shape()
            .map_err(|e| TermError::invalid(TERM, e.to_string()))?;
        let rows: Vec<&[f64]> = (0..spheres.len()).map(|i| spheres.reading(i)).collect();
        let poses = PreparedPoses::for_shape(shape, &rows)?;
        let n = spheres.len();
        Ok(SphereTerm {
            by_tool: by_tool(&spheres, Some(shape))?,
            spheres,
            file: file.to_string(),
            poses,
            centres,
            radii,
            known_radius,
            ball_radius,
            balls,
            encoder: noise.encoder_rad,
            probe: noise.probe_mm,
            robust: vec![1.0; n],
            sigmas: Vec::new(),
            weights: Vec::new(),
        })
    }

    /// The rows.
    pub(crate) fn spheres(&self) -> &Spheres {
        &self.spheres
    }

    /// The file they were read from.
    pub(crate) fn file(&self) -> &str {
        &self.file
    }

    /// The default probe's ball radius, mm (the arm file's `[probe]`).
    pub(crate) fn ball_radius(&self) -> f64 {
        self.ball_radius
    }

    /// The radius of the ball sphere `s` was probed with, mm (its tool's).
    pub(crate) fn ball_radius_of(&self, s: usize) -> f64 {
        self.balls[self.spheres.tool_of_sphere(s)]
    }

    /// The stated spheres' radius, mm (none when fitted).
    pub(crate) fn stated_radius(&self) -> Option<f64> {
        self.known_radius
    }

    /// Sphere `s`'s radius at `at` (mm), and its column when fitted.
    pub fn radius(&self, at: &At<'_>, s: usize) -> (f64, Option<usize>) {
        match (self.known_radius, self.radii[s]) {
            (Some(r), _) => (r, None),
            (None, Some(id)) => (at.block(id)[0], Some(at.layout.columns(id).start)),
            (None, None) => (0.0, None),
        }
    }

    /// Sphere `s`'s centre at `at`, mm.
    pub fn centre(&self, at: &At<'_>, s: usize) -> [f64; 3] {
        let c = at.block(self.centres[s]);
        [c[0], c[1], c[2]]
    }

    /// Per row, the probe centre's distance from its sphere's centre less
    /// the two radii at `at`, mm (unweighted): the radial errors a report
    /// shows (their RMS and range per sphere, its form).
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub(crate) fn radial_errors(&self, at: &At<'_>) -> Result<Vec<f64>, TermError> {
        let p = self.positions(at)?;
        Ok((0..p.len())
            .map(|i| {
                let s = self.spheres.sphere(i);
                let (d, _) = self.offset(at, s, &p[i]);
                d - self.radius(at, s).0 - self.balls[self.spheres.tool(i)]
            })
            .collect())
    }

    /// Where `at` puts each row's probe centre (its tool's; the arm's
    /// corrections applied), mm.
    ///
    /// # Errors
    ///
    /// The kernel's.
    pub fn positions(&self, at: &At<'_>) -> Result<Vec<[f64; 3]>, TermError> {
        let mut p = vec![[0.0; 3]; self.spheres.len()];
        if !self.spheres.has_tools() {
            at.tool_positions(&self.poses, Conditions::default(), &mut p)?;
            return Ok(p);
        }
        let mut q = Vec::new();
        self.per_tool(at, |at, _, poses, rows| {
            q.resize(poses.len(), [0.0; 3]);
            at.tool_positions(poses, Conditions::default(), &mut q)?;
            for (j, x) in q.iter().enumerate() {
                p[rows.map_or(j, |r| r[j])] = *x;
            }
            Ok(())
        })?;
        Ok(p)
    }

    /// Calls `f(at, k, poses, rows)` for each tool `k` the rows name, `at`
    /// as the tool sees it — the arm's probe replaced by the tool's offset
    /// (its block's value when the layout fits one; else its nominal
    /// offset) —, `poses` the tool's rows' and `rows` their indices
    /// (`None`: every row, `poses` all of them). The default tool first,
    /// `at` itself.
    fn per_tool(
        &self,
        at: &At<'_>,
        mut f: impl FnMut(&At<'_>, usize, &PreparedPoses, Option<&[usize]>) -> Result<(), TermError>,
    ) -> Result<(), TermError> {
        if self.by_tool.is_empty() {
            return f(at, 0, &self.poses, None);
        }
        for (k, tool) in self.spheres.tools().iter().enumerate() {
            let (rows, poses) = &self.by_tool[k];
            if rows.is_empty() {
                continue;
            }
            if k == 0 {
                f(at, 0, poses, Some(rows))?;
                continue;
            }
            let block = at
                .layout
                .block_named(&crate::domain::block_name(&tool.name));
            let offset = block.map_or(tool.offset, |id| {
                let x = at.block(id);
                [x[0], x[1], x[2]]
            });
            crate::residuals::tools::with_probe_at(at, offset, |seen| {
                f(seen, k, poses, Some(rows))
            })?;
        }
        Ok(())
    }

    /// `|p − c_s|` and the unit vector from `c_s` to `p`.
    fn offset(&self, at: &At<'_>, s: usize, p: &[f64; 3]) -> (f64, [f64; 3]) {
        let c = self.centre(at, s);
        let v = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let d = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let n = if d > 0.0 {
            v.map(|x| x / d)
        } else {
            [0.0, 0.0, 1.0]
        };
        (d, n)
    }

    /// Per row, its σ (mm) at `at` under the stated noise: the probe's
    /// seating and the encoders' noise through the joint Jacobian, along
    /// the radial direction.
    fn sigmas_at(&self, at: &At<'_>) -> Result<Vec<f64>, TermError> {
        let (e2, p2) = (
            self.encoder.unwrap_or(0.0).powi(2),
            self.probe.unwrap_or(0.0).powi(2),
        );
        let n = self.spheres.len();
        let p = self.positions(at)?;
        let mut out = vec![0.0; n];
        self.per_tool(at, |seen, _, poses, rows| {
            seen.kernel
                .for_each_joint_jacobian(poses, 0..poses.len(), |j, jq| {
                    let i = rows.map_or(j, |r| r[j]);
                    let (_, u) = self.offset(at, self.spheres.sphere(i), &p[i]);
                    let along: f64 = (jq.iter())
                        .map(|c| (u[0] * c[0] + u[1] * c[1] + u[2] * c[2]).powi(2))
                        .sum();
                    out[i] = (p2 + e2 * along).sqrt();
                })?;
            Ok(())
        })?;
        Ok(out)
    }

    /// Whether touch noise was stated (else σ is estimated).
    fn stated(&self) -> bool {
        self.encoder.is_some() || self.probe.is_some()
    }

    /// Per row its weight for σ's `sigmas` (or `unit_sigma` each).
    fn weights_for(&self, sigmas: &[f64], unit_sigma: f64) -> Vec<f64> {
        (0..self.spheres.len())
            .map(|i| {
                let s = sigmas.get(i).copied().unwrap_or(unit_sigma);
                self.robust[i].sqrt() / s
            })
            .collect()
    }

    /// Per free column, what it is to this term: the arm's column `c`, the
    /// centre of sphere `s` (coordinate `k`), the radius of sphere `s`, or
    /// coordinate `k` of tool `t`'s offset.
    fn column_roles(&self, at: &At<'_>, free: &[usize]) -> Vec<Column> {
        let arm = at.layout.arm_columns();
        let mut of = vec![Column::None; at.layout.len()];
        for (t, tool) in self.spheres.tools().iter().enumerate().skip(1) {
            let name = crate::domain::block_name(&tool.name);
            if let Some(id) = at.layout.block_named(&name) {
                for (k, c) in at.layout.columns(id).enumerate() {
                    of[c] = Column::Tool(t, k);
                }
            }
        }
        for (s, &id) in self.centres.iter().enumerate() {
            for (k, c) in at.layout.columns(id).enumerate() {
                of[c] = Column::Centre(s, k);
            }
            if let Some(id) = self.radii[s] {
                of[at.layout.columns(id).start] = Column::Radius(s);
            }
        }
        (free.iter())
            .map(|&c| if c < arm { Column::Arm(c) } else { of[c] })
            .collect()
    }
}

/// What a free column is to the term.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Column {
    Arm(usize),
    Centre(usize, usize),
    Radius(usize),
    Tool(usize, usize),
    None,
}

impl Term for SphereTerm {
    fn name(&self) -> &str {
        TERM
    }

    fn role(&self) -> Role {
        Role::Spheres
    }

    fn rows(&self, _free: &[usize]) -> usize {
        self.spheres.len()
    }

    /// The free centres absorb any rigid motion of the arm; a stated
    /// diameter fixes its size, a fitted one does not.
    fn sees(&self) -> Sees {
        Sees {
            base_rotation: false,
            base_slide: false,
            scale: self.known_radius.is_some(),
        }
    }

    fn unit_weighted(&self) -> bool {
        !self.stated()
    }

    fn weigh(
        &mut self,
        at: &At<'_>,
        _shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<(), TermError> {
        self.sigmas = if self.stated() {
            self.sigmas_at(at)?
        } else {
            Vec::new()
        };
        self.weights = self.weights_for(&self.sigmas, unit_sigma);
        if let Some(i) = (self.weights.iter()).position(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(TermError::invalid(
                TERM,
                format!(
                    "{}:{}: the weight of this point is not a finite positive number: state the \
                     probe's and the encoders' noise (--probe-noise, --encoder-noise)",
                    self.file,
                    self.spheres.line(i)
                ),
            ));
        }
        Ok(())
    }

    fn weight_change(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        unit_sigma: f64,
    ) -> Result<f64, TermError> {
        if self.weights.len() != self.spheres.len() {
            return Ok(f64::INFINITY);
        }
        let sigmas = if self.stated() {
            self.sigmas_at(at)?
        } else {
            Vec::new()
        };
        let new = self.weights_for(&sigmas, unit_sigma);
        Ok((new.iter().zip(&self.weights))
            .map(|(a, b)| (a / b - 1.0).abs())
            .fold(0.0, f64::max))
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let roles = self.column_roles(at, normal.free());
        let probe = crate::residuals::tools::probe_columns(at.arm);
        let n = self.spheres.len();
        let mut rows: Vec<(Vec<f64>, f64)> = vec![(Vec::new(), 0.0); n];
        self.per_tool(at, |seen, t, poses, of| {
            let cond = Conditions::default();
            seen.for_each_tool(poses, cond, 0..poses.len(), |j, p, jac| {
                let i = of.map_or(j, |r| r[j]);
                let s = self.spheres.sphere(i);
                let w = self.weights[i];
                let (d, u) = self.offset(at, s, p);
                let (radius, _) = self.radius(at, s);
                let r = w * (d - radius - self.balls[t]);
                let along = |c: usize| w * (u[0] * jac[c][0] + u[1] * jac[c][1] + u[2] * jac[c][2]);
                let row: Vec<f64> = (roles.iter())
                    .map(|role| match *role {
                        // A tool's rows move with its offset, not the probe's.
                        Column::Arm(c) if t != 0 && probe.contains(&c) => 0.0,
                        Column::Arm(c) => along(c),
                        Column::Centre(q, k) if q == s => -w * u[k],
                        Column::Radius(q) if q == s => -w,
                        Column::Tool(q, k) if q == t => along(probe[k]),
                        _ => 0.0,
                    })
                    .collect();
                rows[i] = (row, r);
            })
        })?;
        Ok(normal.add_rows(rows))
    }

    fn add_cost(
        &self,
        at: &At<'_>,
        _free: &[usize],
        _shared: &mut Shared,
        _scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        let e = self.radial_errors(at)?;
        *total += (e.iter().zip(&self.weights))
            .map(|(e, w)| (w * e).powi(2))
            .sum::<f64>();
        Ok(())
    }

    /// `r_i² / (1 − h_i)`, `h_i` the share of its sphere's own unknowns
    /// (its centre, and its radius when fitted) each of its points carries.
    fn standardised(
        &self,
        at: &At<'_>,
        _leverage: Option<&crate::residuals::ParameterLeverage>,
    ) -> Result<Option<Standardised>, TermError> {
        let e = self.radial_errors(at)?;
        let unknowns = if self.known_radius.is_some() { 3 } else { 4 };
        let counts: Vec<usize> = (0..self.centres.len())
            .map(|s| self.spheres.rows_of(s).len())
            .collect();
        let values = (0..e.len())
            .map(|i| {
                let h = (unknowns as f64 / counts[self.spheres.sphere(i)] as f64).min(0.999);
                (self.weights[i] * e[i]).powi(2) / (1.0 - h)
            })
            .collect();
        Ok(Some(Standardised { rows: 1, values }))
    }

    fn observations(&self) -> usize {
        self.spheres.len()
    }

    fn origin(&self, i: usize) -> Origin {
        Origin {
            at: format!("{}:{}", self.file, self.spheres.line(i)),
            group: self.spheres.spheres()[self.spheres.sphere(i)].clone(),
        }
    }

    fn weigh_observations(&mut self, w: &[f64]) -> bool {
        for (r, &v) in self.robust.iter_mut().zip(w) {
            *r *= v;
        }
        for (x, &v) in self.weights.iter_mut().zip(w) {
            *x *= v.sqrt();
        }
        true
    }

    /// Each sphere's points dealt to the folds (never a whole sphere):
    /// see `folds::MIN_TRAINING_POINTS`'s module.
    fn split(
        &self,
        at: &At<'_>,
        k: usize,
        seed: u64,
    ) -> Result<Option<Vec<crate::residuals::TermFold>>, TermError> {
        folds::split(self, at, k, seed).map(Some)
    }

    fn typical_sigma(&self) -> Option<f64> {
        let mut s = self.sigmas.clone();
        if s.is_empty() {
            return None;
        }
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied()
    }
}

/// Per tool of `spheres`' rows, its ball's radius, mm: the default tool's
/// `default` (the arm file's `[probe]`), another's its `[[tool]]`
/// `ball_diameter_mm` — needed when the spheres' diameter is stated
/// (`known`), else 0 (the fitted radius takes the ball in).
fn tool_balls(spheres: &Spheres, default: f64, known: bool) -> Result<Vec<f64>, TermError> {
    (spheres.tools().iter().enumerate())
        .map(|(k, tool)| match (k, tool.ball_diameter_mm) {
            (0, _) => Ok(default),
            (_, Some(d)) => Ok(d / 2.0),
            (_, None) if !known => Ok(0.0),
            (_, None) => Err(TermError::invalid(
                TERM,
                format!(
                    "tool {} probes spheres of a stated diameter and has no ball: state its \
                     `ball_diameter_mm` in the arm file's [[tool]] (the probe centre is a ball \
                     radius off the surface)",
                    crate::error::quoted(&tool.name)
                ),
            )),
        })
        .collect()
}

/// Adds the offset block of each tool `spheres`' rows name (beyond the
/// default), started at its nominal offset — or shares the block of that
/// name already there (the same tool's positions).
fn add_tool_blocks(
    spheres: &Spheres,
    add: &mut impl FnMut(Box<dyn Block>) -> Result<BlockId, LayoutError>,
) -> Result<(), TermError> {
    for tool in spheres.tools().iter().skip(1) {
        let block = crate::domain::block_name(&tool.name);
        let added = add(Box::new(Vector {
            names: ["x", "y", "z"].map(|c| format!("{block}.{c}")).to_vec(),
            name: block,
            unit: Unit::Length,
            start: tool.offset.to_vec(),
            tolerances: vec![None; 3],
        }));
        match added {
            Ok(_) | Err(LayoutError::Duplicate { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(())
}

/// A layout's [`Layout::add`], for [`SphereTerm::new`]'s `add` in a
/// layout built by hand.
pub fn add_to(
    layout: &mut Layout,
) -> impl FnMut(Box<dyn Block>) -> Result<BlockId, LayoutError> + '_ {
    move |b| layout.add(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corrections::{Beyond, Mass, Physics};
    use crate::objective::{CheckOptions, Objective, check_gradients};
    use crate::residuals::positions::layout_with;
    use crate::simulate::{SphereSettings, simulate_spheres};

    fn nominal() -> crate::Arm {
        crate::Arm::without_limits("t", crate::DhParams::paper_nominal())
    }

    fn settings(placements: usize, seed: u64) -> SphereSettings {
        SphereSettings {
            placements,
            diameter_mm: 25.4,
            ball_diameter_mm: 6.0,
            encoder_rad: 0.005f64.to_radians(),
            probe_mm: 0.01,
            seed,
        }
    }

    fn stated() -> Noise {
        Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        }
    }

    /// The nominal arm's own points: each placement's 25 points are the
    /// ISO pattern, and the algebraic fit of their probe centres finds the
    /// centre and `R + r_ball` it was drawn with, to the noise.
    #[test]
    fn simulated_points_lie_on_their_spheres() {
        let arm = nominal();
        let c = simulate_spheres(&arm, &settings(3, 4)).unwrap();
        assert_eq!((c.spheres.len(), c.spheres.spheres().len()), (75, 3));
        let p = positions_at(&c.spheres, &arm.params).unwrap();
        for (s, (name, centre)) in c.centres.iter().enumerate() {
            assert_eq!(&c.spheres.spheres()[s], name);
            let pts: Vec<[f64; 3]> = c.spheres.rows_of(s).iter().map(|&i| p[i]).collect();
            let (fit, r) = algebraic_sphere(&pts).unwrap();
            assert!((r - 15.7).abs() < 0.05, "{r}");
            assert!(
                crate::geometry::distance(&fit, centre) < 0.05,
                "{fit:?} {centre:?}"
            );
        }
        // Deterministic per seed, another seed another campaign.
        assert_eq!(simulate_spheres(&arm, &settings(3, 4)).unwrap(), c);
        assert_ne!(simulate_spheres(&arm, &settings(3, 5)).unwrap(), c);
    }

    /// The term's gradient agrees with central differences of its cost on
    /// every block it depends on — the geometry, a fitted compliance, the
    /// centres and the fitted radii — at a point off the start in every
    /// column, with the diameter stated and fitted.
    #[test]
    fn the_sphere_gradient_passes_the_check_on_every_block() {
        let arm = nominal();
        let c = simulate_spheres(&arm, &settings(2, 7)).unwrap();
        let data = crate::DataSet::from_labels(&["A", "A", "A"], "none").unwrap();
        let physics = Physics {
            link_masses: vec![Some(Mass::at_middle(2.0)); 6],
            probe_mass: Some(Mass::at_middle(0.5)),
            ..Physics::default()
        };
        let beyond = Beyond {
            compliance: vec![1, 2],
            ..Beyond::default()
        };
        for size in [SphereSize::Known(25.4), SphereSize::Fitted] {
            let mut layout = layout_with(&arm.params, &data, &physics, &beyond).unwrap();
            let term = SphereTerm::new(
                c.spheres.clone(),
                "s.csv",
                &arm.params,
                size,
                Some(6.0),
                &stated(),
                add_to(&mut layout),
            )
            .unwrap();
            let start = layout.start();
            let free: Vec<usize> = (0..layout.len()).collect();
            let mut o = Objective::new(layout, vec![Box::new(term)], 1);
            o.weigh(&start, 1.0).unwrap();
            let x = crate::objective::check::off_start(&o, &start, &free);
            let check = check_gradients(&o, &x, &free, &CheckOptions::default()).unwrap();
            assert!(check.passed(), "{check}");
            let seen: Vec<&str> = (check.terms[0].blocks.iter())
                .map(|b| b.block.as_str())
                .collect();
            let mut want = vec!["geometry", "beyond", "sphere.S1"];
            if size == SphereSize::Fitted {
                want.push("sphere.S1.radius");
            }
            want.push("sphere.S2");
            if size == SphereSize::Fitted {
                want.push("sphere.S2.radius");
            }
            assert_eq!(seen, want, "{check}");
            for b in &check.terms[0].blocks {
                assert!(b.analytic.abs() > 0.0, "{check}");
            }
        }
    }

    /// With a second sphere probed by a stylus of its own (`tool` rows),
    /// the gradient passes on the stylus' offset block too, and the arm's
    /// probe columns see only the probe's sphere.
    #[test]
    fn the_sphere_gradient_passes_on_a_stylus_block() {
        let arm = nominal();
        let c = simulate_spheres(&arm, &settings(2, 7)).unwrap();
        let stylus = crate::domain::Tool {
            name: "long".into(),
            offset: [10.0, 0.0, 160.0],
            ball_diameter_mm: Some(3.0),
        };
        let mut rows = Spheres::new(6, 0);
        for i in 0..c.spheres.len() {
            let s = c.spheres.sphere(i);
            rows.push(&c.spheres.spheres()[s], c.spheres.reading(i), i + 2, None);
            if s == 1 {
                rows.set_tool(&stylus);
            }
        }
        let mut layout = Layout::new(arm.params.clone());
        let size = SphereSize::Known(25.4);
        let term = SphereTerm::new(
            rows,
            "s.csv",
            &arm.params,
            size,
            Some(6.0),
            &stated(),
            add_to(&mut layout),
        )
        .unwrap();
        assert_eq!((term.ball_radius_of(0), term.ball_radius_of(1)), (3.0, 1.5));
        let start = layout.start();
        let free: Vec<usize> = (0..layout.len()).collect();
        let mut o = Objective::new(layout, vec![Box::new(term)], 1);
        o.weigh(&start, 1.0).unwrap();
        let x = crate::objective::check::off_start(&o, &start, &free);
        let check = check_gradients(&o, &x, &free, &CheckOptions::default()).unwrap();
        assert!(check.passed(), "{check}");
        let seen: Vec<&str> = (check.terms[0].blocks.iter())
            .map(|b| b.block.as_str())
            .collect();
        assert_eq!(
            seen,
            ["geometry", "tool.long", "sphere.S1", "sphere.S2"],
            "{check}"
        );
        assert!(check.terms[0].blocks[1].analytic.abs() > 0.0, "{check}");
    }

    /// A stated sphere diameter needs the ball's; points on one circle and
    /// a diameter in metres are refused by name.
    #[test]
    fn what_the_term_refuses() {
        let arm = nominal();
        let c = simulate_spheres(&arm, &settings(1, 2)).unwrap();
        let make = |spheres: Spheres, size, ball| {
            let mut layout = Layout::new(arm.params.clone());
            SphereTerm::new(
                spheres,
                "s.csv",
                &arm.params,
                size,
                ball,
                &stated(),
                add_to(&mut layout),
            )
            .map(|_| ())
            .unwrap_err()
            .to_string()
        };
        let e = make(c.spheres.clone(), SphereSize::Known(25.4), None);
        assert!(e.contains("[probe] ball_diameter_mm"), "{e}");
        let e = make(c.spheres.clone(), SphereSize::Known(0.0254), Some(6.0));
        assert!(
            e.contains("sphere_diameter_mm") && e.contains("metres"),
            "{e}"
        );
        // The equator alone (rows 17–24): one circle.
        let ring = c.spheres.subset(&(17..25).collect::<Vec<_>>());
        let e = make(ring, SphereSize::Fitted, None);
        assert!(
            e.contains("s.csv:19: field `sphere`: sphere `S1`: its 8 points lie on one circle"),
            "{e}"
        );
    }
}
