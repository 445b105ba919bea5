//! Observations of any row count take part in the robust loss and the
//! outlier test as touches do: a term written here, outside the library,
//! whose observations are one row (a target's distance along a direction)
//! or six (two targets at once), is weighed by a robust fit on each
//! observation's own norm and screened against the `χ²_k` quantile of its
//! own row count — and a planted gross error is found and named.

use aacmm_core::calibrate::robust::{DOWNWEIGHTED, Loss, Robust};
use aacmm_core::kernel::PreparedPoses;
use aacmm_core::prelude::*;
use aacmm_core::residuals::{Origin, ParameterLeverage, Standardised};

/// Known targets of the probe in the arm's base frame, `per` poses to an
/// observation; with a `direction`, each pose one row (its distance along
/// it), else three.
#[derive(Clone, Debug)]
struct Targets {
    name: &'static str,
    poses: PreparedPoses,
    targets: Vec<[f64; 3]>,
    per: usize,
    direction: Option<[f64; 3]>,
    sigma: f64,
    /// Per observation, the robust fit's weight.
    weights: Vec<f64>,
    /// A deliberate mistake: this column's Jacobian with the wrong sign.
    wrong_column: Option<usize>,
}

impl Targets {
    fn rows_per_pose(&self) -> usize {
        if self.direction.is_some() { 1 } else { 3 }
    }

    /// Pose `i`'s whitened rows at the probe position `p`, and the
    /// derivative of each along a probe move `d`.
    fn whitened(&self, i: usize, p: &[f64; 3]) -> Vec<f64> {
        let s = self.weights[i / self.per].sqrt() / self.sigma;
        let e: Vec<f64> = (0..3).map(|a| p[a] - self.targets[i][a]).collect();
        match self.direction {
            Some(n) => vec![s * (n[0] * e[0] + n[1] * e[1] + n[2] * e[2])],
            None => e.iter().map(|v| s * v).collect(),
        }
    }

    fn positions(&self, at: &At<'_>) -> Result<Vec<[f64; 3]>, TermError> {
        let mut p = vec![[0.0; 3]; self.poses.len()];
        at.kernel
            .positions(&self.poses, 0..self.poses.len(), &mut p)?;
        Ok(p)
    }
}

impl Term for Targets {
    fn name(&self) -> &str {
        self.name
    }

    fn rows(&self, _free: &[usize]) -> usize {
        self.poses.len() * self.rows_per_pose()
    }

    fn sees(&self) -> Sees {
        Sees {
            base_rotation: true,
            base_slide: self.direction.is_none_or(|n| n[2] != 0.0),
            scale: true,
        }
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let geometry = at.layout.geometry_columns();
        let free = normal.free().to_vec();
        let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
        at.kernel
            .for_each_jacobian(&self.poses, 0..self.poses.len(), |i, p, jac| {
                let r = self.whitened(i, p);
                // The rows are linear in the probe position: the row of a
                // column is the whitening applied to that column's move.
                let moved = |c: usize| -> Vec<f64> {
                    let origin = self.whitened(i, &[0.0; 3]);
                    let step = self.whitened(i, &jac[c]);
                    step.iter().zip(&origin).map(|(s, o)| s - o).collect()
                };
                let cols: Vec<Vec<f64>> = (free.iter())
                    .map(|&c| {
                        if Some(c) == self.wrong_column {
                            moved(c).iter().map(|v| -v).collect()
                        } else if c < geometry {
                            moved(c)
                        } else {
                            vec![0.0; r.len()]
                        }
                    })
                    .collect();
                for (a, &ra) in r.iter().enumerate() {
                    rows.push((cols.iter().map(|col| col[a]).collect(), ra));
                }
            })?;
        let mut cost = 0.0;
        for (row, r) in rows {
            normal.add_row(&row, r);
            cost += r * r;
        }
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
        let p = self.positions(at)?;
        for (i, p) in p.iter().enumerate() {
            *total += self.whitened(i, p).iter().map(|r| r * r).sum::<f64>();
        }
        Ok(())
    }

    /// Each observation's `rᵀr` (the leverage left out: the arm's share of
    /// it is small against so many touches).
    fn standardised(
        &self,
        at: &At<'_>,
        _leverage: Option<&ParameterLeverage>,
    ) -> Result<Option<Standardised>, TermError> {
        let p = self.positions(at)?;
        let mut values = vec![0.0; self.observations()];
        for (i, p) in p.iter().enumerate() {
            values[i / self.per] += self.whitened(i, p).iter().map(|r| r * r).sum::<f64>();
        }
        Ok(Some(Standardised {
            rows: self.per * self.rows_per_pose(),
            values,
        }))
    }

    fn observations(&self) -> usize {
        self.poses.len() / self.per
    }

    fn origin(&self, i: usize) -> Origin {
        Origin {
            at: format!("targets.csv:{}", i + 2),
            group: format!("T{}", i + 1),
        }
    }

    fn weigh_observations(&mut self, w: &[f64]) -> bool {
        self.weights.iter_mut().zip(w).for_each(|(a, b)| *a *= b);
        true
    }
}

/// A deterministic standard normal draw per `i` (Box–Muller on a
/// splitmix64 stream).
fn gauss(seed: u64, i: u64) -> f64 {
    let mix = |mut z: u64| {
        z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let u = |k: u64| ((mix(seed ^ mix(2 * i + k)) >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    (-2.0 * u(0).ln()).sqrt() * (2.0 * std::f64::consts::PI * u(1)).cos()
}

fn nominal() -> Arm {
    Arm::without_limits("paper", DhParams::paper_nominal())
}

fn campaign() -> Campaign {
    let mut s = CampaignSettings::new(5, ErrorModel::Paper, 8, 8);
    s.reference_lengths = 3;
    s.encoder_noise_deg = 0.005;
    s.probe_noise_mm = 0.01;
    simulate(&nominal(), &s).unwrap()
}

/// 40 of the campaign's poses as targets the true arm reaches, with 0.01 mm
/// of noise per coordinate, `per` poses to an observation; observation
/// `gross` (if any) displaced by 2 mm along x.
fn targets(c: &Campaign, per: usize, direction: Option<[f64; 3]>, gross: Option<usize>) -> Targets {
    let rows: Vec<&[f64]> = c.poses.rows().take(40).collect();
    let truth = aacmm_core::kernel::ArmKernel::new(&c.true_arm.params).unwrap();
    let sigma = 0.01;
    let mut xyz = truth.positions_of(&rows).unwrap();
    for (i, p) in xyz.iter_mut().enumerate() {
        for (a, v) in p.iter_mut().enumerate() {
            *v += sigma * gauss(17, (3 * i + a) as u64);
        }
        if gross == Some(i / per) {
            p[0] += 2.0;
        }
    }
    let owned: Vec<Vec<f64>> = rows.iter().map(|r| r.to_vec()).collect();
    Targets {
        name: "targets",
        poses: PreparedPoses::new(6, &owned).unwrap(),
        targets: xyz,
        per,
        direction,
        sigma,
        weights: vec![1.0; 40 / per],
        wrong_column: None,
    }
}

fn fit(c: &Campaign, term: Targets, robust: bool) -> CalibrationReport {
    fit_with(c, term, robust, None)
}

fn fit_with(
    c: &Campaign,
    term: Targets,
    robust: bool,
    prior: Option<aacmm_core::tolerances::Tolerances>,
) -> CalibrationReport {
    let model = ModelOptions {
        prior,
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            ..Noise::default()
        },
        robust: robust.then(|| Robust::new(Loss::Cauchy)),
        ..ModelOptions::default()
    };
    let problem = Problem::new(nominal(), c.data_set().unwrap(), model).unwrap();
    let lm = SolverSettings::default().with_method(Method::Lm);
    problem.with_term(term).run(&lm).unwrap()
}

/// The planted observation, and only it among the targets, is weighed down
/// by the robust fit and named by the plain fit's outlier test.
fn planted_error_is_found(per: usize, direction: Option<[f64; 3]>) {
    let c = campaign();
    let gross = 7;
    let named = format!("targets.csv:{}", gross + 2);
    let robust = fit(&c, targets(&c, per, direction, Some(gross)), true);
    let weights = &robust.calibration.robust.as_ref().unwrap().weights;
    let ours: Vec<_> = (weights.iter())
        .filter(|w| w.at.starts_with("targets.csv"))
        .collect();
    assert_eq!(ours.len(), 40 / per);
    let down: Vec<&str> = (ours.iter())
        .filter(|w| w.weight < DOWNWEIGHTED)
        .map(|w| w.at.as_str())
        .collect();
    assert_eq!(down, [named.as_str()], "{ours:?}");
    assert!(robust.is_usable(), "{:?}", robust.verdict);

    let plain = fit(&c, targets(&c, per, direction, Some(gross)), false);
    let outliers = &plain.calibration.checks.outliers;
    let ours: Vec<&str> = (outliers.iter())
        .filter(|o| o.at.starts_with("targets.csv"))
        .map(|o| o.at.as_str())
        .collect();
    assert_eq!(ours, [named.as_str()], "{outliers:?}");

    // Without the gross error, nothing of the targets is named.
    let clean = fit(&c, targets(&c, per, direction, None), false);
    let outliers = &clean.calibration.checks.outliers;
    assert!(
        !outliers.iter().any(|o| o.at.starts_with("targets.csv")),
        "{outliers:?}"
    );
}

#[test]
fn a_one_row_observation_with_a_gross_error_is_named() {
    planted_error_is_found(1, Some([1.0, 0.0, 0.0]));
}

#[test]
fn a_six_row_observation_with_a_gross_error_is_named() {
    planted_error_is_found(2, None);
}

/// A term's name is only words: one named `prior`, beside stated
/// tolerances, is neither counted as the prior nor replaced by it when the
/// tolerances are carried onto redundant parameters' partners — the fit is
/// the same bits as under any other name.
#[test]
fn an_outside_term_named_prior_is_not_the_prior() {
    let c = campaign();
    let prior = || aacmm_core::tolerances::Tolerances::parse("length=0.5mm,angle=0.1deg", 6);
    let run = |name| {
        let mut term = targets(&c, 1, Some([1.0, 0.0, 0.0]), None);
        term.name = name;
        fit_with(&c, term, false, prior().unwrap())
    };
    let (plain, named) = (run("targets"), run("prior"));
    let (a, b) = (&plain.calibration, &named.calibration);
    assert!(a.prior.is_some() && a.dof.prior_rows > 0);
    assert_eq!(a.dof.prior_rows, b.dof.prior_rows);
    let other = |d: &aacmm_core::calibrate::Dof| -> Vec<(String, usize)> {
        (d.other_rows.iter())
            .map(|r| (r.term.clone(), r.rows))
            .collect()
    };
    assert_eq!(other(&a.dof), [("targets".to_string(), 40)]);
    assert_eq!(other(&b.dof), [("prior".to_string(), 40)]);
    assert_eq!(a.params.to_vec(), b.params.to_vec());
    assert_eq!(a.dof.degrees_of_freedom, b.dof.degrees_of_freedom);
}

/// The public gradient checker passes this file's term and names it, its
/// block and its column when one column of its Jacobian is wrong.
#[test]
fn the_gradient_checker_names_a_wrong_jacobian() {
    use aacmm_core::objective::{CheckOptions, check_gradients};
    let c = campaign();
    let layout = Layout::new(nominal().params);
    let x = layout.start();
    let free: Vec<usize> = (0..layout.len()).collect();
    let check = |term: Targets| {
        let objective = Objective::new(layout.clone(), vec![Box::new(term)], 1);
        check_gradients(&objective, &x, &free, &CheckOptions::default()).unwrap()
    };
    for (per, direction) in [(1, Some([0.6, 0.0, 0.8])), (2, None)] {
        let good = check(targets(&c, per, direction, None));
        assert!(good.passed(), "{good}");
        let mut bad = targets(&c, per, direction, None);
        bad.wrong_column = Some(1);
        let bad = check(bad);
        assert!(!bad.passed());
        let failures = bad.failures();
        assert_eq!(failures.len(), 1, "{bad}");
        let (term, block) = failures[0];
        assert_eq!(
            (
                term.term.as_str(),
                block.block.as_str(),
                block.column.as_str()
            ),
            ("targets", "geometry", "a2")
        );
        assert!(bad.to_string().contains("WRONG: term `targets`"), "{bad}");
    }
}
