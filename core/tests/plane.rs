//! The least squares is open: a new kind of measurement is one new
//! residual term, written here, outside the library, against its public
//! API — the probe touching a known plane (one row per touch: its signed
//! distance to the plane). A plane parallel to the arm's base axis, added
//! to a campaign without reference lengths, fixes the scale the touches
//! alone cannot see; with the plane's offset unknown, an auxiliary
//! parameter block carries it. The term reads the probe through
//! `At::for_each_tool`, so the arm's corrections beyond geometry
//! (compliance, harmonics, …) apply to it as to the built-in terms.

use aacmm_core::corrections::Conditions;
use aacmm_core::kernel::{ArmKernel, PreparedPoses};
use aacmm_core::prelude::*;
use aacmm_core::residuals::{Scalar, Unit};
use aacmm_core::simulate::solve_point;

/// The probe on the plane `n·p = offset` (a unit normal in the arm's base
/// frame), each touch one row `(n·p(q) − offset)/σ`.
#[derive(Clone, Debug)]
struct PlaneTerm {
    poses: PreparedPoses,
    normal: [f64; 3],
    /// Where the plane is: a known offset, mm, or an unknown one in a block.
    offset: Offset,
    sigma: f64,
}

#[derive(Clone, Copy, Debug)]
enum Offset {
    Known(f64),
    Fitted(BlockId),
}

impl PlaneTerm {
    /// The offset at `at`, and its column when it is fitted.
    fn offset(&self, at: &At<'_>) -> (f64, Option<usize>) {
        match self.offset {
            Offset::Known(d) => (d, None),
            Offset::Fitted(id) => (at.block(id)[0], Some(at.layout.columns(id).start)),
        }
    }

    fn residual(&self, p: &[f64; 3], offset: f64) -> f64 {
        let n = self.normal;
        (n[0] * p[0] + n[1] * p[1] + n[2] * p[2] - offset) / self.sigma
    }
}

impl Term for PlaneTerm {
    fn name(&self) -> &str {
        "plane"
    }

    fn rows(&self, _free: &[usize]) -> usize {
        self.poses.len()
    }

    /// The plane's normal is in the base frame: a turn about the base axis
    /// tilts the touches off it unless it is horizontal. A slide along the
    /// axis moves them off a plane that is not parallel to it — unless the
    /// offset is unknown (the plane slides along). Scale: an arm scaled
    /// about a point of its base axis (the slide makes up the rest) keeps
    /// the touches on a plane through that point, so only a known plane
    /// parallel to the axis, away from it, fixes the size.
    fn sees(&self) -> Sees {
        let n = self.normal;
        let parallel = n[2].abs() < 1e-9;
        let known = match self.offset {
            Offset::Known(d) => Some(d),
            Offset::Fitted(_) => None,
        };
        Sees {
            base_rotation: !parallel || n[0] != 0.0 || n[1] != 0.0,
            base_slide: known.is_some() && !parallel,
            scale: known.is_some_and(|d| parallel && d.abs() > 1e-9),
        }
    }

    fn accumulate(
        &self,
        at: &At<'_>,
        _shared: &mut Shared,
        normal: &mut Normal,
    ) -> Result<f64, TermError> {
        let (offset, column) = self.offset(at);
        // The arm's columns: the geometry's and its corrections'.
        let arm = at.layout.arm_columns();
        let free = normal.free().to_vec();
        let mut rows = Vec::with_capacity(self.poses.len());
        let all = 0..self.poses.len();
        at.for_each_tool(&self.poses, Conditions::default(), all, |_, p, jac| {
            let n = self.normal;
            let row: Vec<f64> = free
                .iter()
                .map(|&c| match c {
                    c if c < arm => {
                        (n[0] * jac[c][0] + n[1] * jac[c][1] + n[2] * jac[c][2]) / self.sigma
                    }
                    c if Some(c) == column => -1.0 / self.sigma,
                    _ => 0.0,
                })
                .collect();
            rows.push((row, self.residual(p, offset)));
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
        let (offset, _) = self.offset(at);
        let mut xyz = vec![[0.0; 3]; self.poses.len()];
        at.tool_positions(&self.poses, Conditions::default(), &mut xyz)?;
        *total += xyz
            .iter()
            .map(|p| self.residual(p, offset).powi(2))
            .sum::<f64>();
        Ok(())
    }
}

fn nominal() -> Arm {
    Arm::without_limits("paper", DhParams::paper_nominal())
}

/// A campaign of the paper's errors with `lengths` reference lengths
/// (without any, its touches cannot tell the arm's size).
fn campaign(lengths: usize) -> Campaign {
    let mut s = CampaignSettings::new(11, ErrorModel::Paper, 10, 10);
    s.reference_lengths = lengths;
    s.encoder_noise_deg = 0.005;
    s.probe_noise_mm = 0.01;
    simulate(&nominal(), &s).unwrap()
}

/// Readings that put the TRUE arm's probe on the plane `x = at`, parallel
/// to the base axis: the sockets' (y, z), each from three start poses.
fn plane_poses(c: &Campaign, at: f64) -> PreparedPoses {
    let truth = ArmKernel::new(&c.true_arm.params).unwrap();
    let mut rows = Vec::new();
    for (k, (_, s)) in c.sockets.iter().enumerate() {
        for start in 0..3 {
            let q0: Vec<f64> = (0..6)
                .map(|j| ((k * 5 + start * 3 + j) as f64 * 0.9).sin())
                .collect();
            let target = [at, s[1] + 20.0 * start as f64, s[2]];
            let found = solve_point(&truth, target, &q0).unwrap();
            if found.converged() {
                rows.push(found.q);
            }
        }
    }
    assert!(rows.len() >= 20, "{} plane touches", rows.len());
    PreparedPoses::new(6, &rows).unwrap()
}

/// The plane term of touches on `x = at` (σ 0.01 mm), its offset `offset`.
fn plane_on_x(c: &Campaign, at: f64, offset: Offset) -> PlaneTerm {
    PlaneTerm {
        poses: plane_poses(c, at),
        normal: [1.0, 0.0, 0.0],
        offset,
        sigma: 0.01,
    }
}

/// A plane `x = const` through the middle of the sockets.
fn plane_x(c: &Campaign) -> f64 {
    let xs: Vec<f64> = c.sockets.iter().map(|(_, s)| s[0]).collect();
    xs.iter().sum::<f64>() / xs.len() as f64
}

fn stated() -> Noise {
    Noise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        ..Noise::default()
    }
}

fn run(problem: Problem) -> CalibrationReport {
    let lm = SolverSettings::default().with_method(Method::Lm);
    problem.run(&lm).unwrap()
}

/// How far the calibrated arm puts the campaign's touches from where the
/// true arm puts them, after the best rigid motion (mm, RMS): what scale
/// and shape errors leave.
fn shape_error(c: &Campaign, params: &DhParams) -> f64 {
    let rows: Vec<&[f64]> = c.poses.rows().collect();
    let xyz = |p: &DhParams| ArmKernel::new(p).unwrap().positions_of(&rows).unwrap();
    aacmm_core::geometry::rigid_distance(&xyz(params), &xyz(&c.true_arm.params), false)
}

#[test]
fn a_known_plane_fixes_the_scale_the_touches_cannot_see() {
    let c = campaign(0);
    let data: DataSet = c.data_set().unwrap();
    let model = ModelOptions {
        noise: stated(),
        ..ModelOptions::default()
    };
    let at = plane_x(&c);
    let plane = plane_on_x(&c, at, Offset::Known(at));
    let rows = plane.poses.len();
    let bare = run(Problem::new(nominal(), data.clone(), model.clone()).unwrap());
    let with = run(Problem::new(nominal(), data, model)
        .unwrap()
        .with_term(plane));
    let rules = |r: &CalibrationReport| -> Vec<String> {
        let id = r.calibration.identification.as_ref().unwrap();
        id.rules.iter().map(|r| r.name.clone()).collect()
    };
    // The touches alone: base motion and scale structurally unseen.
    assert_eq!(rules(&bare), ["base-motion", "scale"]);
    // With a known plane parallel to the base axis: scale and the turn
    // about the axis are seen; the slide along it still is not.
    assert_eq!(rules(&with), ["base-motion"]);
    let id = with.calibration.identification.as_ref().unwrap();
    assert!(id.rules[0].explanation.contains("d1"), "{:?}", id.rules);
    let fixed: Vec<String> = id.fixed.iter().map(|f| f.id.to_string()).collect();
    assert!(fixed.contains(&"d1".to_string()) && !fixed.contains(&"theta1".to_string()));
    assert!(with.is_usable(), "{:?}", with.verdict);
    let dof = &with.calibration.dof;
    assert_eq!(dof.other_rows.len(), 1);
    assert_eq!(
        (dof.other_rows[0].term.as_str(), dof.other_rows[0].rows),
        ("plane", rows)
    );
    assert_eq!(
        dof.degrees_of_freedom,
        dof.touch_rows + rows - dof.centre_coordinates - dof.free_parameters
    );
    // The length fixed for scale is now calibrated, and the arm's shape
    // comes out far closer to the truth.
    let (b, w) = (
        shape_error(&c, &bare.calibration.params),
        shape_error(&c, &with.calibration.params),
    );
    assert!(w < 0.05 && w < b / 5.0, "shape error {b:.4} → {w:.4} mm");
}

/// Seed 3's campaign with a plane beside it whose offset is a block of its
/// own, started 2 mm from the true plane and allowed to move `limit` mm:
/// the report, and where the plane is.
fn offset_fit(limit: f64) -> (CalibrationReport, f64) {
    let c = campaign(3);
    let data = c.data_set().unwrap();
    let model = ModelOptions {
        noise: stated(),
        ..ModelOptions::default()
    };
    let at = plane_x(&c);
    let mut problem = Problem::new(nominal(), data, model).unwrap();
    let offset = problem
        .add_block(Scalar {
            name: "plane.offset".into(),
            unit: Unit::Length,
            start: at + 2.0,
            tolerance: None,
            limit: Some(limit),
        })
        .unwrap();
    let plane = plane_on_x(&c, at, Offset::Fitted(offset));
    (run(problem.with_term(plane)), at)
}

#[test]
fn an_unknown_plane_offset_is_a_block_of_its_own() {
    // Reference lengths fix the size; the plane, its offset unknown, adds
    // the turn about the base axis.
    // Started 2 mm off, allowed to move 10: the fit finds it.
    let (report, at) = offset_fit(10.0);
    assert!(report.is_usable(), "{:?}", report.verdict);
    let aux = &report.calibration.auxiliary;
    assert_eq!(aux.len(), 1);
    let e = &aux[0];
    assert_eq!(
        (e.name.as_str(), e.unit.as_str(), e.start),
        ("plane.offset", "mm", at + 2.0)
    );
    let sigma = e.sigma.unwrap();
    // The plane is parallel to the base axis, so the slide along the axis
    // (d1, fixed by the rules) does not move it, and the lengths fix the
    // size: the offset comes out where the true arm's plane is.
    let id = report.calibration.identification.as_ref().unwrap();
    let rules: Vec<&str> = id.rules.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(rules, ["base-motion"]);
    let d1 = &report.calibration.parameters[6];
    assert_eq!(d1.id.to_string(), "d1");
    assert_eq!(d1.fixed.as_deref(), Some("base motion: never identifiable"));
    assert!(sigma > 0.0 && sigma < 0.1, "σ {sigma}");
    assert!(
        (e.calibrated - at).abs() < 4.0 * sigma,
        "offset {} ± {sigma}, the plane at {at}",
        e.calibrated
    );
    // In the summary and in the JSON, beside the geometry's estimates.
    let summary = report.summary();
    assert!(summary.contains("Auxiliary blocks") && summary.contains("plane.offset"));
    assert!(
        summary.contains("Other residual terms (in the dof): plane"),
        "{summary}"
    );
    let json = report.to_json();
    assert!(json.contains("\"auxiliary\"") && json.contains("plane.offset"));
}

/// A block's own limits judge the result: an offset that had to move by
/// more than its limit makes the calibration unusable, by name.
#[test]
fn a_block_beyond_its_limits_is_refused_by_name() {
    // Started 2 mm off, allowed to move 1 mm.
    let (report, _) = offset_fit(1.0);
    assert!(!report.is_usable());
    let reasons = report
        .verdict
        .words(aacmm_core::session::Spelling::Cli)
        .reasons
        .join("; ");
    assert!(
        reasons.contains("no real instrument could have: plane.offset moved by -1.99"),
        "{reasons}"
    );
    assert_eq!(report.calibration.checks.implausible_blocks.len(), 1);
}

/// The annealer's energy is the touches' and lengths': with a plane term
/// `sa` would ignore it while claiming a fit, so it is refused, naming the
/// term.
#[test]
fn annealing_alone_refuses_evidence_its_energy_ignores() {
    let c = campaign(0);
    let problem = || {
        let data = c.data_set().unwrap();
        let at = plane_x(&c);
        Problem::new(nominal(), data, ModelOptions::default())
            .unwrap()
            .with_term(plane_on_x(&c, at, Offset::Known(at)))
    };
    let sa = SolverSettings::default().with_method(Method::Sa);
    let message = problem().run(&sa).unwrap_err().to_string();
    assert!(
        message.contains("which the term `plane` is no part of"),
        "{message}"
    );
    // Without the term, the same campaign anneals.
    let data = c.data_set().unwrap();
    let bare = Problem::new(nominal(), data, ModelOptions::default()).unwrap();
    assert!(bare.run(&sa).is_ok());
}

/// A block held at its start is not fitted: the plane's offset, measured
/// elsewhere, stays where it was put (0.5 mm off the true plane here, so a
/// fit would move it), and the report says it was held and why.
#[test]
fn a_held_block_stays_at_its_start() {
    let c = campaign(3);
    let model = ModelOptions {
        noise: stated(),
        ..ModelOptions::default()
    };
    let at = plane_x(&c);
    let mut problem = Problem::new(nominal(), c.data_set().unwrap(), model).unwrap();
    let offset = problem
        .add_block(Scalar {
            name: "plane.offset".into(),
            unit: Unit::Length,
            start: at + 0.5,
            tolerance: None,
            limit: None,
        })
        .unwrap();
    problem.hold_block(offset);
    let plane = plane_on_x(&c, at, Offset::Fitted(offset));
    let report = run(problem.with_term(plane));
    let e = &report.calibration.auxiliary[0];
    assert_eq!((e.calibrated, e.sigma), (at + 0.5, None));
    let why = e.fixed.as_deref().unwrap_or_default();
    assert!(why.contains("held at its start"), "{why}");
}

/// With the arm's compliance fitted (`--compliance`), the plane term sees
/// it: its gradient on the correction columns is not zero and agrees with
/// its cost's (the public gradient checker), and a stated compliance moves
/// its residuals. It read the bare chain before and saw neither.
#[test]
fn the_plane_term_sees_the_arms_compliance() {
    use aacmm_core::corrections::{Beyond, Mass, Physics};
    use aacmm_core::objective::{CheckOptions, check_gradients};
    let c = campaign(0);
    let data = c.data_set().unwrap();
    let physics = Physics {
        link_masses: vec![Some(Mass::at_middle(2.0)); 6],
        probe_mass: Some(Mass::at_middle(0.5)),
        ..Physics::default()
    };
    let beyond = Beyond {
        compliance: vec![1, 2],
        ..Beyond::default()
    };
    let params = nominal().params;
    let layout =
        aacmm_core::residuals::positions::layout_with(&params, &data, &physics, &beyond).unwrap();
    let at = plane_x(&c);
    let plane = plane_on_x(&c, at, Offset::Known(at));
    let x = layout.start();
    let free: Vec<usize> = (0..layout.len()).collect();
    let objective = Objective::new(layout.clone(), vec![Box::new(plane)], 1);
    let check = check_gradients(&objective, &x, &free, &CheckOptions::default()).unwrap();
    assert!(check.passed(), "{check}");
    let beyond = (check.terms[0].blocks.iter())
        .find(|b| b.block == "beyond")
        .unwrap();
    assert!(beyond.analytic.abs() > 1.0, "{check}");
    // A compliance of 10 µrad/(N·m) on joints 2 and 3 moves the cost.
    let (a, b) = layout
        .corrections()
        .map(|(_, cols)| (cols.start, cols.end))
        .unwrap();
    let mut bent = x.clone();
    bent[a..b].iter_mut().for_each(|v| *v = 10.0);
    let cost = |x: &[f64]| objective.cost(x, &free, &mut Vec::new()).unwrap();
    assert!(
        (cost(&bent) - cost(&x)).abs() > 1.0,
        "{} {}",
        cost(&bent),
        cost(&x)
    );
}
