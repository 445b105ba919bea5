//! A sphere term written here, outside the library, through its public API
//! only — the probe ball touching reference spheres of known diameter, one
//! row per point — fits a simulated sphere campaign exactly as the
//! library's own `SphereTerm` does: the built-in term is no more than what
//! a user could write.

use aacmm_core::corrections::Conditions;
use aacmm_core::kernel::PreparedPoses;
use aacmm_core::prelude::*;
use aacmm_core::residuals::spheres::{SphereSize, SphereTerm, algebraic_sphere};
use aacmm_core::residuals::{Unit, Vector};
use aacmm_core::simulate::{SphereCampaign, SphereSettings, simulate_spheres};

/// `(|p − c_s| − ρ)/σ_i` with `ρ` the sphere's and the ball's radii, `σ_i`
/// the probe's and the encoders' noise along the radial direction at the
/// start (fixed during the fit).
#[derive(Clone, Debug)]
struct MySphereTerm {
    poses: PreparedPoses,
    /// Per row, its sphere.
    sphere: Vec<usize>,
    centres: Vec<BlockId>,
    /// Sphere radius plus ball radius, mm.
    rho: f64,
    encoder: f64,
    probe: f64,
    weights: Vec<f64>,
}

impl MySphereTerm {
    fn centre(&self, at: &At<'_>, s: usize) -> [f64; 3] {
        let c = at.block(self.centres[s]);
        [c[0], c[1], c[2]]
    }

    /// `|p − c|` and the unit vector from `c` to `p`.
    fn radial(&self, at: &At<'_>, i: usize, p: &[f64; 3]) -> (f64, [f64; 3]) {
        let c = self.centre(at, self.sphere[i]);
        let v = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let d = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        (d, v.map(|x| x / d))
    }
}

impl MySphereTerm {
    /// Per row `1/σ_i` at `at`.
    fn weights_at(&self, at: &At<'_>) -> Result<Vec<f64>, TermError> {
        let n = self.sphere.len();
        let mut p = vec![[0.0; 3]; n];
        at.tool_positions(&self.poses, Conditions::default(), &mut p)?;
        let mut w = vec![0.0; n];
        at.kernel
            .for_each_joint_jacobian(&self.poses, 0..n, |i, jq| {
                let (_, u) = self.radial(at, i, &p[i]);
                let along: f64 = jq
                    .iter()
                    .map(|c| (u[0] * c[0] + u[1] * c[1] + u[2] * c[2]).powi(2))
                    .sum();
                w[i] = 1.0 / (self.probe.powi(2) + self.encoder.powi(2) * along).sqrt();
            })?;
        Ok(w)
    }
}

impl Term for MySphereTerm {
    fn name(&self) -> &str {
        "my-spheres"
    }

    fn rows(&self, _free: &[usize]) -> usize {
        self.sphere.len()
    }

    /// A stated diameter fixes the size; the free centres absorb any rigid
    /// motion.
    fn sees(&self) -> Sees {
        Sees {
            base_rotation: false,
            base_slide: false,
            scale: true,
        }
    }

    fn weigh(&mut self, at: &At<'_>, _: &mut Shared, _: f64) -> Result<(), TermError> {
        self.weights = self.weights_at(at)?;
        Ok(())
    }

    /// The weights follow the arm: the fit weighs again where they moved.
    fn weight_change(&self, at: &At<'_>, _: &mut Shared, _: f64) -> Result<f64, TermError> {
        let new = self.weights_at(at)?;
        Ok((new.iter().zip(&self.weights))
            .map(|(a, b)| (a / b - 1.0).abs())
            .fold(0.0, f64::max))
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let arm = at.layout.arm_columns();
        let free = normal.free().to_vec();
        let mut rows = Vec::new();
        at.for_each_tool(
            &self.poses,
            Conditions::default(),
            0..self.sphere.len(),
            |i, p, jac| {
                let (d, u) = self.radial(at, i, p);
                let w = self.weights[i];
                let mine = at.layout.columns(self.centres[self.sphere[i]]);
                let row: Vec<f64> = free
                    .iter()
                    .map(|&c| match c {
                        c if c < arm => {
                            w * (u[0] * jac[c][0] + u[1] * jac[c][1] + u[2] * jac[c][2])
                        }
                        c if mine.contains(&c) => -w * u[c - mine.start],
                        _ => 0.0,
                    })
                    .collect();
                rows.push((row, w * (d - self.rho)));
            },
        )?;
        Ok(normal.add_rows(rows))
    }

    fn add_cost(
        &self,
        at: &At<'_>,
        _: &[usize],
        _: &mut Shared,
        _: &mut Vec<[f64; 3]>,
        total: &mut f64,
    ) -> Result<(), TermError> {
        let mut p = vec![[0.0; 3]; self.sphere.len()];
        at.tool_positions(&self.poses, Conditions::default(), &mut p)?;
        for (i, p) in p.iter().enumerate() {
            let (d, _) = self.radial(at, i, p);
            *total += (self.weights[i] * (d - self.rho)).powi(2);
        }
        Ok(())
    }
}

const DIAMETER: f64 = 25.4;
const BALL: f64 = 6.0;

fn noise() -> Noise {
    Noise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        ..Noise::default()
    }
}

/// A true arm of the paper's errors and its sphere campaign.
fn campaign(seed: u64) -> (Arm, Arm, SphereCampaign) {
    let nominal = Arm::without_limits("paper", DhParams::paper_nominal());
    let settings = CampaignSettings::new(seed, ErrorModel::Paper, 4, 6);
    let truth = simulate(&nominal, &settings).unwrap().true_arm;
    let s = SphereSettings {
        placements: 8,
        diameter_mm: DIAMETER,
        ball_diameter_mm: BALL,
        encoder_rad: 0.005f64.to_radians(),
        probe_mm: 0.01,
        seed: seed + 100,
    };
    let c = simulate_spheres(&truth, &s).unwrap();
    (nominal, truth, c)
}

fn problem(nominal: &Arm) -> Problem {
    let data = DataSet::without_touches(6, 0);
    let model = ModelOptions {
        noise: noise(),
        ..ModelOptions::default()
    };
    Problem::new(nominal.clone(), data, model).unwrap()
}

fn fit(problem: Problem) -> CalibrationReport {
    let lm = SolverSettings::default().with_method(Method::Lm);
    problem.run(&lm).unwrap()
}

/// The built-in term's fit.
fn builtin(nominal: &Arm, c: &SphereCampaign) -> CalibrationReport {
    let mut p = problem(nominal);
    let term = SphereTerm::new(
        c.spheres.clone(),
        "spheres.csv",
        &nominal.params,
        SphereSize::Known(DIAMETER),
        Some(BALL),
        &noise(),
        |b| p.add_boxed_block(b),
    )
    .unwrap();
    fit(p.with_term(term))
}

/// The outside term's fit: the same blocks, started the same way.
fn outside(nominal: &Arm, c: &SphereCampaign) -> CalibrationReport {
    let mut p = problem(nominal);
    let rows: Vec<&[f64]> = (0..c.spheres.len()).map(|i| c.spheres.reading(i)).collect();
    let kernel = aacmm_core::kernel::ArmKernel::new(&nominal.params).unwrap();
    let xyz = kernel.positions_of(&rows).unwrap();
    let mut centres = Vec::new();
    for (s, name) in c.spheres.spheres().iter().enumerate() {
        let pts: Vec<[f64; 3]> = c.spheres.rows_of(s).iter().map(|&i| xyz[i]).collect();
        let (centre, _) = algebraic_sphere(&pts).unwrap();
        let block = format!("sphere.{name}");
        centres.push(
            p.add_block(Vector {
                name: block.clone(),
                names: ["x", "y", "z"].map(|k| format!("{block}.{k}")).to_vec(),
                unit: Unit::Length,
                start: centre.to_vec(),
                tolerances: vec![None; 3],
            })
            .unwrap(),
        );
    }
    let term = MySphereTerm {
        poses: PreparedPoses::new(6, &rows).unwrap(),
        sphere: (0..c.spheres.len()).map(|i| c.spheres.sphere(i)).collect(),
        centres,
        rho: (DIAMETER + BALL) / 2.0,
        encoder: 0.005f64.to_radians(),
        probe: 0.01,
        weights: Vec::new(),
    };
    fit(p.with_term(term))
}

#[test]
fn a_sphere_term_written_outside_fits_as_the_built_in_one() {
    let (nominal, _, c) = campaign(3);
    let (a, b) = (builtin(&nominal, &c), outside(&nominal, &c));
    assert!(a.is_usable(), "{:?}", a.verdict);
    let (ca, cb) = (&a.calibration, &b.calibration);
    let rel = |x: f64, y: f64| (x - y).abs() / x.abs().max(y.abs()).max(1e-300);
    assert!(
        rel(ca.solver.final_cost, cb.solver.final_cost) < 1e-9,
        "cost {} vs {}",
        ca.solver.final_cost,
        cb.solver.final_cost
    );
    let (pa, pb) = (ca.params.to_vec(), cb.params.to_vec());
    for (k, (x, y)) in pa.iter().zip(&pb).enumerate() {
        assert!(
            (x - y).abs() <= 1e-9 * x.abs().max(1.0),
            "column {k}: {x} vs {y}"
        );
    }
    for (x, y) in ca.auxiliary.iter().zip(&cb.auxiliary) {
        assert_eq!(x.name, y.name);
        assert!(
            rel(x.calibrated, y.calibrated) < 1e-9,
            "{} {} {}",
            x.name,
            x.calibrated,
            y.calibrated
        );
    }
    assert_eq!(ca.auxiliary.len(), 3 * 8);
}
