//! Tool orientations: where an instrument that sees a 6-D target (a
//! tracker's, a motion-capture rigid body) saw the target turned, in its
//! own frame. Row `i` of frame `f` with an orientation `R_i` seen:
//!
//! ```text
//! r_i = w · log(R_i · (R_f R_t(q_i; x) R_m)ᵀ)        (3 rows, rad · w)
//! ```
//!
//! the small rotation from the predicted orientation (the arm's last frame
//! `R_t` with the corrections applied, turned into the target's frame by
//! the mount `R_m` and into the instrument's frame by the frame's
//! registration `R_f`) to the one seen, whitened by `w = 1/σ`, the
//! orientation noise per axis (`--orientation-noise`). Its position rows
//! are the positions term's, unchanged ([`super::positions`]).
//!
//! The mount ([`Mount`](super::blocks::Mount), block `mount`) is how the target sits on the
//! flange: fitted, as a real target is never mounted exactly square. It
//! starts from the closed-form mean of `R_tᵀ R_fᵀ R_i` over the oriented
//! rows at the start arm ([`mount_start`]). It absorbs every constant turn
//! of the last frame: the last joint's `alpha` and `theta` then turn the
//! target only as the mount does, and are seen through the positions
//! alone (the identifiability analysis, the frames and the mount
//! eliminated, finds it). A layout without the block (one a caller built)
//! takes the mount as the identity.
//!
//! A separate term rather than 6-row observations in the positions term:
//! its rows are in radians, not mm, so it has its own χ² and degrees of
//! freedom (the orientation's σ judged on its own, the report's section of
//! its own), a file may give orientations on some rows only (a 6-D target
//! that lost its lock), and the positions term — and every output of data
//! without orientations — stays as it is, bit for bit.
//!
//! Jacobians, with `P = R_f R_t R_m`, `e = log E`, `E = R_i Pᵀ` and
//! `J_r⁻¹(e)` the inverse right Jacobian of SO(3) (a turn `P ← exp(u) P`
//! moves `e` by `−J_r⁻¹(e) u`): an arm column `c` turns the tool by `ω_c`
//! (base frame, [`crate::kernel::ArmKernel::pose_jacobian`]), so `P ←
//! exp(R_f ω_c δ) P` and `∂r/∂x_c = −w J_r⁻¹(e) R_f ω_c`; the frame's step
//! `R_f ← exp(δω) R_f` gives `∂r/∂δω = −w J_r⁻¹(e)`, and its translation
//! nothing; the mount's step `R_m ← exp(δ) R_m` turns `P` by `exp(R_f R_t
//! δ)`: `∂r/∂δ = −w J_r⁻¹(e) R_f R_t`. The frame's rotation is thus seen
//! directly, not only through the positions' lever arms.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

use super::blocks::{Frame, MOUNT_BLOCK, rotation_vector};
use super::{At, BlockId, Layout, Noise, Normal, Origin, Shared, Standardised, Term, TermError};
use crate::dataset::PositionData;
use crate::kernel::{ArmKernel, KernelError, Pose};
use crate::params::DhParams;

/// The name of the term, in reports and messages.
const NAME: &str = "orientations";

/// The orientations of a data set's positions on its frames' blocks.
#[derive(Clone)]
pub(crate) struct OrientationTerm<'d> {
    data: &'d PositionData,
    /// Per frame, its block.
    frames: Vec<BlockId>,
    /// The mount's block ([`Mount`](super::blocks::Mount)); the identity without one.
    mount: Option<BlockId>,
    /// The rows that give an orientation, in file order (observation `k`
    /// is row `oriented[k]`).
    oriented: Vec<usize>,
    /// Per row of the data (`None` where it gives no orientation), the
    /// orientation seen.
    seen: Vec<Option<Rotation3<f64>>>,
    /// σ per axis, rad.
    sigma: f64,
    /// Per observation, a robust fit's weight (1 without one).
    robust: Vec<f64>,
    /// Oriented rows per frame (each frame's leverage).
    per_frame: Vec<usize>,
}

impl std::fmt::Debug for OrientationTerm<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OrientationTerm")
            .field("orientations", &self.oriented.len())
            .field("frames", &self.frames.len())
            .field("mount", &self.mount.is_some())
            .field("sigma_rad", &self.sigma)
            .finish()
    }
}

/// The rotation of a unit quaternion `[w, x, y, z]` (normalised: the reader
/// let it be off unit length by rounding).
fn rotation_of(q: [f64; 4]) -> Rotation3<f64> {
    let u = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
    u.to_rotation_matrix()
}

/// The inverse right Jacobian of SO(3) at `e`: `log(exp(e) exp(u)) ≈ e +
/// J_r⁻¹(e) u`.
fn inverse_right_jacobian(e: &Vector3<f64>) -> Matrix3<f64> {
    let th = e.norm();
    let k = e.cross_matrix();
    // 1/θ² − (1 + cos θ)/(2θ sin θ), by its series (1/12 + θ²/720) near 0.
    let c = if th < 1e-4 {
        1.0 / 12.0 + th * th / 720.0
    } else {
        1.0 / (th * th) - (1.0 + th.cos()) / (2.0 * th * th.sin())
    };
    Matrix3::identity() + 0.5 * k + c * k * k
}

/// The rotation of a kernel pose (rows of the kernel's matrix are
/// `rotation[row][col]`).
fn rotation_of_pose(tool: &Pose) -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(Matrix3::from_fn(|r, c| tool.rotation[r][c]))
}

/// The mount's start `[rx, ry, rz]` (rad): the rotation nearest, in the
/// chordal (Frobenius) sense, to every oriented row's `R_tᵀ R_fᵀ R_i` — the
/// sum's projection onto the rotations by its SVD — with `R_t` the arm
/// `params`' last frame and `R_f` its frame's start `frames[f]`
/// (`[rx, ry, rz, …]`); `None` when no row gives an orientation.
///
/// # Errors
///
/// The kernel's.
pub(crate) fn mount_start(
    params: &DhParams,
    data: &PositionData,
    frames: &[[f64; 6]],
) -> Result<Option<[f64; 3]>, KernelError> {
    let rows = data.rows();
    if rows.oriented_rows() == 0 {
        return Ok(None);
    }
    let kernel = ArmKernel::new(params)?;
    let mut tools = vec![Pose::default(); data.len()];
    kernel.poses(data.poses(), 0..data.len(), &mut tools)?;
    let mut sum = Matrix3::zeros();
    for (i, tool) in tools.iter().enumerate() {
        if let Some(q) = rows.orientation(i) {
            let r_f = Frame::rotation(&frames[rows.frame(i)]);
            let m = rotation_of_pose(tool).inverse() * r_f.inverse() * rotation_of(q);
            sum += m.matrix();
        }
    }
    let svd = sum.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Ok(Some([0.0; 3]));
    };
    // det = −1 would be a mirror: flip the weakest axis instead.
    let d = (u * v_t).determinant().signum();
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * v_t;
    Ok(Some(rotation_vector(&Rotation3::from_matrix_unchecked(r))))
}

impl<'d> OrientationTerm<'d> {
    /// The orientations of `data` on the frame blocks of `layout` (one
    /// named as each frame); `None` when no row gives one.
    ///
    /// # Errors
    ///
    /// Orientations without `noise.orientation_rad` (their σ is not
    /// estimated: say it, `--orientation-noise DEG`), and a frame without
    /// its block in the layout.
    pub(crate) fn new(
        data: &'d PositionData,
        layout: &Layout,
        noise: &Noise,
    ) -> Result<Option<OrientationTerm<'d>>, TermError> {
        let rows = data.rows();
        let oriented: Vec<usize> = (0..rows.len())
            .filter(|&i| rows.orientation(i).is_some())
            .collect();
        let Some(&first) = oriented.first() else {
            return Ok(None);
        };
        let Some(sigma) = noise.orientation_rad else {
            return Err(TermError::invalid(
                NAME,
                format!(
                    "{}: fields `qw,qx,qy,qz`: the file gives the tool's orientation but no \
                     orientation noise is stated: give its σ per axis (--orientation-noise \
                     DEG; a tracker's 6-D target is about 0.01°)",
                    data.at(first)
                ),
            ));
        };
        let frames = super::positions::frame_blocks(data, layout, NAME)?;
        let mount = layout.block_named(MOUNT_BLOCK);
        let mut per_frame = vec![0; frames.len()];
        for &i in &oriented {
            per_frame[rows.frame(i)] += 1;
        }
        let seen = (0..rows.len())
            .map(|i| rows.orientation(i).map(rotation_of))
            .collect();
        Ok(Some(OrientationTerm {
            data,
            frames,
            mount,
            robust: vec![1.0; oriented.len()],
            oriented,
            seen,
            sigma,
            per_frame,
        }))
    }

    /// Per frame, `R` at `at`; then the mount's `R_m` (the identity
    /// without its block).
    fn rotations_at(&self, at: &At<'_>) -> (Vec<Rotation3<f64>>, Rotation3<f64>) {
        let frames = (self.frames.iter())
            .map(|&id| Frame::rotation(at.block(id)))
            .collect();
        let mount = self
            .mount
            .map_or_else(Rotation3::identity, |id| Frame::rotation(at.block(id)));
        (frames, mount)
    }

    /// Row `i`'s unwhitened residual `log(R_i (R_f R_t R_m)ᵀ)`, rad, for
    /// the tool pose `tool`; `None` for a row without an orientation.
    fn error(
        &self,
        (frames, mount): &(Vec<Rotation3<f64>>, Rotation3<f64>),
        i: usize,
        tool: &Pose,
    ) -> Option<Vector3<f64>> {
        let seen = self.seen[i]?;
        let predicted = frames[self.data.rows().frame(i)] * rotation_of_pose(tool) * mount;
        Some(Vector3::from(rotation_vector(
            &(seen * predicted.inverse()),
        )))
    }

    /// The observation's weight `w = √robust / σ`.
    fn weight(&self, k: usize) -> f64 {
        self.robust[k].sqrt() / self.sigma
    }

    /// Every oriented row's residual (whitened) at `at`, in observation
    /// order, from the tool poses with the corrections applied.
    fn residuals(&self, at: &At<'_>) -> Result<Vec<Vector3<f64>>, TermError> {
        let frames = self.rotations_at(at);
        let n = self.data.len();
        let mut tools = vec![Pose::default(); n];
        let effects = at.corrected_poses(self.data.poses(), self.data.conditions())?;
        let poses = effects.as_ref().map_or(self.data.poses(), |e| &e.poses);
        at.kernel.poses(poses, 0..n, &mut tools)?;
        Ok((self.oriented.iter().enumerate())
            .filter_map(|(k, &i)| Some(self.weight(k) * self.error(&frames, i, &tools[i])?))
            .collect())
    }
}

impl Term for OrientationTerm<'_> {
    fn name(&self) -> &str {
        NAME
    }

    fn role(&self) -> super::Role {
        super::Role::Orientations
    }

    fn rows(&self, _free: &[usize]) -> usize {
        3 * self.oriented.len()
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let frames = self.rotations_at(at);
        let free = normal.free().to_vec();
        let arm = at.layout.arm_columns();
        let frame_of: Vec<Option<(usize, usize)>> = (free.iter())
            .map(|&c| {
                (self.frames.iter().enumerate()).find_map(|(f, &id)| {
                    let cols = at.layout.columns(id);
                    cols.contains(&c).then(|| (f, c - cols.start))
                })
            })
            .collect();
        let mount_cols = self.mount.map(|id| at.layout.columns(id));
        let rows = self.data.rows();
        let mut k = 0;
        let mut cost = 0.0;
        let mut j = vec![[0.0; 3]; free.len()];
        at.for_each_tool_pose(
            self.data.poses(),
            self.data.conditions(),
            0..self.data.len(),
            |i, tool, jac| {
                let Some(e) = self.error(&frames, i, tool) else {
                    return;
                };
                let w = self.weight(k);
                k += 1;
                let f = rows.frame(i);
                let m = -w * inverse_right_jacobian(&e);
                let mr = m * frames.0[f].matrix();
                let mrt = mr * rotation_of_pose(tool).matrix();
                for (a, &c) in free.iter().enumerate() {
                    let d = if c < arm {
                        mr * Vector3::new(jac[c][3], jac[c][4], jac[c][5])
                    } else if let Some(cols) = mount_cols.as_ref().filter(|m| m.contains(&c)) {
                        mrt.column(c - cols.start).into_owned()
                    } else {
                        match frame_of[a] {
                            Some((g, col)) if g == f && col < 3 => m.column(col).into_owned(),
                            _ => Vector3::zeros(),
                        }
                    };
                    j[a] = d.into();
                }
                let r = w * e;
                cost += r.norm_squared();
                for row in 0..3 {
                    let jr: Vec<f64> = j.iter().map(|d| d[row]).collect();
                    normal.add_row(&jr, r[row]);
                }
            },
        )?;
        Ok(cost)
    }

    fn add_cost(
        &self,
        at: &At<'_>,
        _free: &[usize],
        _shared: &mut Shared,
        _scratch: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        *total += (self.residuals(at)?.iter())
            .map(Vector3::norm_squared)
            .sum::<f64>();
        Ok(())
    }

    /// `|r|²/(1 − h)` per orientation, `h = 1/n_f`: the average leverage of
    /// its frame's three rotations over the frame's `3 n_f` rows.
    fn standardised(
        &self,
        at: &At<'_>,
        _leverage: Option<&super::ParameterLeverage>,
    ) -> Result<Option<Standardised>, TermError> {
        let rows = self.data.rows();
        let values = (self.residuals(at)?.iter().enumerate())
            .map(|(k, r)| {
                let i = self.oriented[k];
                let h = (1.0 / self.per_frame[rows.frame(i)] as f64).min(0.999);
                // At the weights in force (the residual carries `√w`), as
                // a touch's and a position's: the robust fit divides once.
                r.norm_squared() / (1.0 - h)
            })
            .collect();
        Ok(Some(Standardised { rows: 3, values }))
    }

    fn observations(&self) -> usize {
        self.oriented.len()
    }

    fn origin(&self, k: usize) -> Origin {
        let i = self.oriented[k];
        Origin {
            at: self.data.at(i).to_string(),
            group: self.data.rows().label(i).to_string(),
        }
    }

    fn weigh_observations(&mut self, w: &[f64]) -> bool {
        for (r, &v) in self.robust.iter_mut().zip(w) {
            *r *= v;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corrections::{Beyond, Mass, Physics};
    use crate::objective::{CheckOptions, Objective, check_gradients};
    use crate::residuals::Role;
    use crate::residuals::positions::layout_with;
    use crate::simulate::{
        OrientationSettings, PositionSettings, orient_positions, simulate_positions,
    };

    /// Positions with orientations in two frames, on a layout with
    /// corrections beyond geometry (compliance, a harmonic), at a point off
    /// the start in every column: the orientation term's gradient agrees
    /// with central differences of its cost on every block it depends on,
    /// and depends on the corrections and the frames' rotations.
    #[test]
    fn the_orientation_gradient_passes_the_check_on_every_block() {
        let truth = crate::Arm::without_limits("t", crate::DhParams::paper_nominal());
        let noise = Noise {
            position_mm: Some(0.015),
            orientation_rad: Some(0.01f64.to_radians()),
            ..Noise::default()
        };
        let s = PositionSettings {
            poses: 10,
            frames: 2,
            noise,
            seed: 5,
        };
        let c = simulate_positions(&truth, &s).unwrap();
        // A target mounted turned by about a radian on the flange; every
        // other row oriented: a 6-D target that lost its lock.
        let o = OrientationSettings {
            mount: [0.6, -0.5, 0.7],
            sigma_rad: 2e-4,
            seed: 6,
        };
        let p = orient_positions(&truth, &c.positions, &c.frames, &o).unwrap();
        let some = (0..p.len()).map(|i| p.orientation(i).filter(|_| i % 2 == 0));
        let p = p.clone().with_orientations(some.collect());
        let data = crate::DataSet::from_positions(p, "p.csv").unwrap();
        let physics = Physics {
            link_masses: vec![Some(Mass::at_middle(2.0)); 6],
            probe_mass: Some(Mass::at_middle(0.5)),
            ..Physics::default()
        };
        let beyond = Beyond {
            compliance: vec![1, 2],
            harmonics: vec![(0, 1)],
            ..Beyond::default()
        };
        let layout = layout_with(&truth.params, &data, &physics, &beyond).unwrap();
        let start = layout.start();
        let free: Vec<usize> = (0..layout.len()).collect();
        let o = Objective::of_data(layout, &data, &noise, Vec::new(), None, 1.0, 1).unwrap();
        let roles: Vec<Role> = o.terms().map(|t| t.role()).collect();
        assert_eq!(roles, [Role::Positions, Role::Orientations]);
        let orientations = o.terms().nth(1).unwrap();
        assert_eq!(
            (orientations.observations(), orientations.rows(&free)),
            (10, 30)
        );
        let x = crate::objective::check::off_start(&o, &start, &free);
        let check = check_gradients(&o, &x, &free, &CheckOptions::default()).unwrap();
        assert!(check.passed(), "{check}");
        let blocks: Vec<&str> = (check.terms[1].blocks.iter())
            .map(|b| b.block.as_str())
            .collect();
        assert_eq!(
            blocks,
            ["geometry", "beyond", "station1", "station2", "mount"]
        );
        // Beyond the checker's tolerance: where the gradient is not zero it
        // agrees to 1e-6 (a length's column turns nothing: its zero is
        // judged against the differences' noise floor, as the checker does).
        for b in &check.terms[1].blocks[1..] {
            assert!(b.analytic.abs() > 0.0, "{check}");
            assert!(b.relative_error < 1e-6, "{check}");
        }
    }

    /// The mount starts at its closed form: at the true arm and frame, the
    /// mean of the rows' `R_tᵀ R_fᵀ R_i` is the true mount to the noise's
    /// σ/√n; the same positions without orientations have no mount block
    /// (and a frame named as it is refused only where orientations are).
    #[test]
    fn the_mount_starts_at_its_closed_form_mean() {
        let truth = crate::Arm::without_limits("t", crate::DhParams::paper_nominal());
        let noise = Noise {
            position_mm: Some(0.015),
            ..Noise::default()
        };
        let s = PositionSettings {
            poses: 25,
            frames: 1,
            noise,
            seed: 9,
        };
        let c = simulate_positions(&truth, &s).unwrap();
        let mount = [1.2, 0.4, -2.1];
        let o = OrientationSettings {
            mount,
            sigma_rad: 1e-4,
            seed: 10,
        };
        let p = orient_positions(&truth, &c.positions, &c.frames, &o).unwrap();
        let data = crate::DataSet::from_positions(p, "p.csv").unwrap();
        let layout = crate::residuals::positions::layout_for(&truth.params, &data).unwrap();
        let id = layout.block_named(MOUNT_BLOCK).unwrap();
        let start = &layout.start()[layout.columns(id)];
        let apart = Frame::rotation(start) * Frame::rotation(&mount).inverse();
        let angle = Vector3::from(rotation_vector(&apart)).norm();
        // σ/√n per axis over 25 rows: 2e-5 rad; the registration's own
        // error adds less.
        assert!(angle < 1e-4, "{angle} rad from the true mount");
        assert!(angle > 0.0);
        let plain = crate::DataSet::from_positions(c.positions.clone(), "p.csv").unwrap();
        let layout = crate::residuals::positions::layout_for(&truth.params, &plain).unwrap();
        assert_eq!(layout.block_named(MOUNT_BLOCK), None);
        // A frame named as the mount's block: refused by name with
        // orientations, a frame like any other without.
        let named = |p: &crate::domain::Positions| {
            let mut text = Vec::new();
            crate::io::positions::write_positions(&mut text, p, crate::io::AngleUnit::Rad).unwrap();
            let text = String::from_utf8(text).unwrap();
            let text = text.replacen("\n", ",frame\n", 1).replace('\n', ",mount\n");
            let text = text.replacen(",frame,mount\n", ",frame\n", 1);
            let rows = crate::io::parse_positions(&text, "m.csv", crate::io::AngleUnit::Rad, 6);
            crate::DataSet::from_positions(rows.unwrap(), "m.csv").unwrap()
        };
        let oriented = orient_positions(&truth, &c.positions, &c.frames, &o).unwrap();
        let e = crate::residuals::positions::layout_for(&truth.params, &named(&oriented));
        let e = e.unwrap_err().to_string();
        assert!(
            e.contains("frame `mount`: the name of the tool mount's block"),
            "{e}"
        );
        let fine = crate::residuals::positions::layout_for(&truth.params, &named(&c.positions));
        assert!(fine.unwrap().block_named(MOUNT_BLOCK).is_some());
    }

    /// Orientations without their σ are refused by file, line and fields,
    /// not weighed as if in mm.
    #[test]
    fn orientations_without_their_noise_are_refused() {
        let truth = crate::Arm::without_limits("t", crate::DhParams::paper_nominal());
        let noise = Noise {
            position_mm: Some(0.015),
            ..Noise::default()
        };
        let s = PositionSettings {
            poses: 4,
            frames: 1,
            noise,
            seed: 5,
        };
        let c = simulate_positions(&truth, &s).unwrap();
        let o = OrientationSettings {
            mount: [0.0; 3],
            sigma_rad: 2e-4,
            seed: 6,
        };
        let p = orient_positions(&truth, &c.positions, &c.frames, &o).unwrap();
        let data = crate::DataSet::from_positions(p, "p.csv").unwrap();
        let layout = layout_with(
            &truth.params,
            &data,
            &Physics::default(),
            &Beyond::default(),
        );
        let e = Objective::of_data(layout.unwrap(), &data, &noise, Vec::new(), None, 1.0, 1)
            .unwrap_err()
            .to_string();
        // Simulated rows have no line: the file is named alone.
        assert!(
            e.starts_with("orientations: p.csv: fields `qw,qx,qy,qz`"),
            "{e}"
        );
        assert!(e.contains("--orientation-noise"), "{e}");
    }

    /// The inverse right Jacobian is what its definition says: a small
    /// rotation `u` after `exp(e)` moves the log by `J_r⁻¹(e) u`, at a
    /// large angle and near zero (the series).
    #[test]
    fn the_inverse_right_jacobian_follows_its_definition() {
        for e in [
            Vector3::new(0.4, -1.1, 0.7),
            Vector3::new(2e-5, 1e-5, -3e-5),
        ] {
            let jr = inverse_right_jacobian(&e);
            let base = Rotation3::new(e);
            for axis in 0..3 {
                let h = 1e-6;
                let mut u = Vector3::zeros();
                u[axis] = h;
                let up = Vector3::from(rotation_vector(&(base * Rotation3::new(u))));
                let down = Vector3::from(rotation_vector(&(base * Rotation3::new(-u))));
                let numeric = (up - down) / (2.0 * h);
                let analytic = jr.column(axis);
                assert!(
                    (numeric - analytic).norm() < 1e-7,
                    "{numeric} vs {analytic}"
                );
            }
        }
    }
}
