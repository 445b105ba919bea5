//! Tool orientations: where an instrument that sees a 6-D target (a
//! tracker's, a motion-capture rigid body) saw the tool frame turned, in
//! its own frame. Row `i` of frame `f` with an orientation `R_i` seen:
//!
//! ```text
//! r_i = w · log(R_i · (R_f R_t(q_i; x))ᵀ)        (3 rows, rad · w)
//! ```
//!
//! the small rotation from the predicted orientation (the tool frame `R_t`
//! with the corrections applied, turned into the instrument's frame by the
//! frame's registration `R_f`) to the one seen, whitened by `w = 1/σ`, the
//! orientation noise per axis (`--orientation-noise`). Its position rows
//! are the positions term's, unchanged ([`super::positions`]).
//!
//! A separate term rather than 6-row observations in the positions term:
//! its rows are in radians, not mm, so it has its own χ² and degrees of
//! freedom (the orientation's σ judged on its own, the report's section of
//! its own), a file may give orientations on some rows only (a 6-D target
//! that lost its lock), and the positions term — and every output of data
//! without orientations — stays as it is, bit for bit.
//!
//! Jacobians, with `e = log E`, `E = R_i (R_f R_t)ᵀ` and `J_r⁻¹(e)` the
//! inverse right Jacobian of SO(3): an arm column `c` turns the tool by
//! `ω_c` (base frame, [`crate::kernel::ArmKernel::pose_jacobian`]), so
//! `R_f R_t ← exp(R_f ω_c δ) R_f R_t` and `∂r/∂x_c = −w J_r⁻¹(e) R_f ω_c`;
//! the frame's step `R_f ← exp(δω) R_f` gives `∂r/∂δω = −w J_r⁻¹(e)`, and
//! its translation nothing. The frame's rotation is thus seen directly,
//! not only through the positions' lever arms.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

use super::blocks::{Frame, rotation_vector};
use super::{At, BlockId, Layout, Noise, Normal, Origin, Shared, Standardised, Term, TermError};
use crate::dataset::PositionData;
use crate::kernel::Pose;

/// The name of the term, in reports and messages.
const NAME: &str = "orientations";

/// The orientations of a data set's positions on its frames' blocks.
#[derive(Clone)]
pub(crate) struct OrientationTerm<'d> {
    data: &'d PositionData,
    /// Per frame, its block.
    frames: Vec<BlockId>,
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
            robust: vec![1.0; oriented.len()],
            oriented,
            seen,
            sigma,
            per_frame,
        }))
    }

    /// Per frame, `R` at `at`.
    fn rotations_at(&self, at: &At<'_>) -> Vec<Rotation3<f64>> {
        (self.frames.iter())
            .map(|&id| Frame::rotation(at.block(id)))
            .collect()
    }

    /// Row `i`'s unwhitened residual `log(R_i (R_f R_t)ᵀ)`, rad, for the
    /// tool pose `tool`; `None` for a row without an orientation.
    fn error(&self, frames: &[Rotation3<f64>], i: usize, tool: &Pose) -> Option<Vector3<f64>> {
        let seen = self.seen[i]?;
        let r_t = Rotation3::from_matrix_unchecked(Matrix3::from_fn(|r, c| tool.rotation[r][c]));
        let predicted = frames[self.data.rows().frame(i)] * r_t;
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
                let mr = m * frames[f].matrix();
                for (a, &c) in free.iter().enumerate() {
                    let d = if c < arm {
                        mr * Vector3::new(jac[c][3], jac[c][4], jac[c][5])
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
    use crate::simulate::{PositionSettings, orient_positions, simulate_positions};

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
        // Every other row oriented: a 6-D target that lost its lock.
        let p = orient_positions(&truth, &c.positions, &c.frames, 2e-4, 6).unwrap();
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
        let delta: Vec<f64> = (0..free.len())
            .map(|a| 1e-3 * ((a as f64) * 0.7).sin())
            .collect();
        let x = o.plus(&start, &free, &delta);
        let check = check_gradients(&o, &x, &free, &CheckOptions::default()).unwrap();
        assert!(check.passed(), "{check}");
        let blocks: Vec<&str> = (check.terms[1].blocks.iter())
            .map(|b| b.block.as_str())
            .collect();
        assert_eq!(blocks, ["geometry", "beyond", "station1", "station2"]);
        // Beyond the checker's tolerance: where the gradient is not zero it
        // agrees to 1e-6 (a length's column turns nothing: its zero is
        // judged against the differences' noise floor, as the checker does).
        for b in &check.terms[1].blocks[1..] {
            assert!(b.analytic.abs() > 0.0, "{check}");
            assert!(b.relative_error < 1e-6, "{check}");
        }
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
        let p = orient_positions(&truth, &c.positions, &c.frames, 2e-4, 6).unwrap();
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
