//! Calibration on simulated campaigns with a known true arm.

use aacmm_core::calibrate::{
    Calibration, FixSpec, ModelOptions, SolverSettings, calibrate, validate,
};
use aacmm_core::domain::Arm;
use aacmm_core::identify::identify;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::{DhParams, ParamId};
use aacmm_core::residuals::Noise;
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};

fn nominal() -> Arm {
    Arm::without_limits("nominal", DhParams::paper_nominal())
}

fn campaign(seed: u64, encoder_deg: f64, probe_mm: f64) -> aacmm_core::simulate::Campaign {
    let mut s = CampaignSettings::new(seed, ErrorModel::Paper, 10, 10);
    s.reference_lengths = 3;
    s.encoder_noise_deg = encoder_deg;
    s.probe_noise_mm = probe_mm;
    simulate(&nominal(), &s).unwrap()
}

const UNOBSERVABLE: &str = "theta1,d1,theta6,alpha6,Bx,By";

#[test]
fn zero_noise_recovers_every_identifiable_parameter() {
    let c = campaign(3, 0.0, 0.0);
    let data = c.data_set().unwrap();
    let options = ModelOptions {
        fix: FixSpec::parse(UNOBSERVABLE, 6).unwrap(),
        ..ModelOptions::default()
    };
    let cal = calibrate(
        &c.nominal.params,
        &data,
        &options,
        &SolverSettings::default(),
    )
    .unwrap();
    assert!(cal.solver.is_solution_usable(), "{:?}", cal.solver.stop);
    let fixed = FixSpec::parse(UNOBSERVABLE, 6).unwrap();
    let FixSpec::Columns(fixed) = fixed else {
        unreachable!()
    };
    for (c_, id) in ParamId::all(6).enumerate() {
        if fixed.contains(&c_) {
            continue;
        }
        let (got, want) = (cal.params.get(id), c.true_arm.params.get(id));
        assert!((got - want).abs() <= 1e-6, "{id}: {got} vs {want}");
    }
    // Held-out touches of the same true arm: positions agree up to the base motion.
    let fresh = campaign(4, 0.0, 0.0);
    let mut moved = fresh.true_arm.params.clone();
    moved.joints[0].theta = cal.params.joints[0].theta;
    moved.joints[0].d = cal.params.joints[0].d;
    let (a, b) = (
        ArmKernel::new(&moved).unwrap(),
        ArmKernel::new(&cal.params).unwrap(),
    );
    for q in fresh.poses.rows() {
        let (p, r) = (a.position(q).unwrap(), b.position(q).unwrap());
        let d = (0..3).map(|k| (p[k] - r[k]).powi(2)).sum::<f64>().sqrt();
        assert!(d <= 1e-6, "{d}");
    }
}

#[test]
fn identify_finds_rank_20_without_lengths_and_21_with() {
    let c = campaign(1, 0.005, 0.01);
    let data = c.data_set().unwrap();
    let noise = Noise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        length_default_mm: 0.001,
        length_weight: None,
        ..Noise::default()
    };
    let with = identify(&c.nominal.params, &data, &noise, 1).unwrap();
    assert_eq!(with.rank, 21, "{:?}", with.analysed_singular_values);
    let bare = aacmm_core::dataset::DataSet::from_poses(&c.poses, "poses.csv").unwrap();
    let without = identify(&c.nominal.params, &bare, &noise, 1).unwrap();
    assert_eq!(without.rank, 20, "{:?}", without.analysed_singular_values);
    assert!(without.rules.iter().any(|r| r.name == "scale"));
    assert!(!with.rules.iter().any(|r| r.name == "scale"));
    // With lengths, the recommended fixed set is the unobservable one.
    let mut fixed: Vec<String> = with.fixed.iter().map(|f| f.id.to_string()).collect();
    fixed.sort_unstable();
    assert_eq!(fixed, ["Bx", "By", "alpha6", "d1", "theta1", "theta6"]);
    // Without, one length parameter more, fixed for scale.
    assert_eq!(without.fixed.len(), 7);
    assert!(without.fixed.iter().any(|f| f.reason.starts_with("scale")));
    // The redundant last link shows up as relations between named parameters.
    let texts: Vec<&str> = with
        .null_relations
        .iter()
        .map(|r| r.text.as_str())
        .collect();
    assert_eq!(texts.len(), 4, "{texts:?}");
    assert!(
        texts.iter().any(|t| t.contains("a6") && t.contains("Bx")),
        "{texts:?}"
    );
    assert!(
        texts.iter().any(|t| t.contains("d6") && t.contains("By")),
        "{texts:?}"
    );
    println!("{texts:#?}\n{:#?}\n{:#?}", with.fixed, without.fixed);
}

/// Noisy campaigns, the unobservable set fixed: the σ are honest (the
/// truth lies within 3σ̂ and the normalised errors have RMS near 1), and a
/// fresh campaign of the same true arm is measured nearly as well as the
/// true arm measures it.
#[test]
fn uncertainties_are_honest_over_seeds() {
    let seeds = 50u64;
    let options = ModelOptions {
        fix: FixSpec::parse(UNOBSERVABLE, 6).unwrap(),
        noise: Noise {
            encoder_rad: Some(0.005f64.to_radians()),
            probe_mm: Some(0.01),
            length_default_mm: 0.001,
            length_weight: None,
            ..Noise::default()
        },
        ..ModelOptions::default()
    };
    let (mut inside, mut total, mut sum_z2) = (0usize, 0usize, 0.0);
    // Held-out figures averaged over the seeds: ours and the true arm's.
    let (mut e_ours, mut e_true, mut len_ours, mut len_true) = (0.0, 0.0, 0.0, 0.0);
    for seed in 0..seeds {
        let c = campaign(100 + seed, 0.005, 0.01);
        let data = c.data_set().unwrap();
        let cal = calibrate(
            &c.nominal.params,
            &data,
            &options,
            &SolverSettings::default(),
        )
        .unwrap();
        assert!(cal.solver.is_solution_usable());
        for (id, est) in ParamId::all(6).zip(&cal.parameters) {
            let Some(sigma) = est.sigma else { continue };
            let mut err = est.calibrated - c.true_arm.params.get(id);
            if id.kind == aacmm_core::params::ParamKind::Theta {
                err = aacmm_core::params::wrap(err);
            }
            let z = err / sigma;
            sum_z2 += z * z;
            total += 1;
            inside += usize::from(z.abs() <= 3.0);
        }
        // Held out: fresh sockets of the same true arm.
        let mut s = CampaignSettings::new(10_000 + seed, ErrorModel::Paper, 10, 10);
        s.reference_lengths = 3;
        s.encoder_noise_deg = 0.005;
        s.probe_noise_mm = 0.01;
        let fresh = simulate(&nominal(), &s).unwrap().data_set().unwrap();
        let truth = validate::figures(&c.true_arm.params, &fresh).unwrap();
        let ours = validate::figures(&cal.params, &fresh).unwrap();
        e_ours += ours.e_mean;
        e_true += truth.e_mean;
        len_ours += ours.length_rms.unwrap();
        len_true += truth.length_rms.unwrap();
    }
    let coverage = inside as f64 / total as f64;
    let rms_z = (sum_z2 / total as f64).sqrt();
    let (e_ratio, len_ratio) = (e_ours / e_true, len_ours / len_true);
    println!(
        "coverage {coverage:.4}, rms z {rms_z:.3}, held-out e ratio {e_ratio:.4}, length RMS ratio {len_ratio:.4}"
    );
    assert!(coverage >= 0.99, "{coverage}");
    assert!((0.7..=1.4).contains(&rms_z), "{rms_z}");
    assert!(e_ratio <= 1.08, "{e_ratio}");
    assert!(len_ratio <= 1.30, "{len_ratio}");
}

#[test]
fn a_fixed_set_that_leaves_an_unseen_direction_is_refused() {
    let c = campaign(5, 0.005, 0.01);
    let with_lengths = c.data_set().unwrap();
    let bare = aacmm_core::dataset::DataSet::from_poses(&c.poses, "poses.csv").unwrap();
    let fix = |names: &str| ModelOptions {
        fix: FixSpec::parse(names, 6).unwrap(),
        ..ModelOptions::default()
    };
    // The paper's fixed set is enough with a reference length…
    assert!(
        calibrate(
            &c.nominal.params,
            &with_lengths,
            &fix(UNOBSERVABLE),
            &SolverSettings::default()
        )
        .is_ok()
    );
    // …but not without one: scale stays open.
    let e = calibrate(
        &c.nominal.params,
        &bare,
        &fix(UNOBSERVABLE),
        &SolverSettings::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("scale"), "{e}");
    // Fixing a length more closes it; d1 does not (a slide along the base axis).
    assert!(
        calibrate(
            &c.nominal.params,
            &bare,
            &fix(&format!("{UNOBSERVABLE},d3")),
            &SolverSettings::default()
        )
        .is_ok()
    );
    // Leaving theta1 or a redundant pair free is refused too.
    let e = calibrate(
        &c.nominal.params,
        &with_lengths,
        &fix("d1,theta6,alpha6,Bx,By"),
        &SolverSettings::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("theta1"), "{e}");
    let e = calibrate(
        &c.nominal.params,
        &with_lengths,
        &fix("theta1,d1,theta6,alpha6,By"),
        &SolverSettings::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("redundan"), "{e}");
}

fn stated_noise() -> Noise {
    Noise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        length_default_mm: 0.001,
        length_weight: None,
        ..Noise::default()
    }
}

/// A newly assembled arm (zeros anywhere in ±180°), 10 × 10 touches, 3
/// lengths, noise as in the comparison; held-out sockets of the
/// same true arm.
fn assembled(seed: u64) -> (aacmm_core::simulate::Campaign, aacmm_core::dataset::DataSet) {
    let settings = |seed, errors| {
        let mut s = CampaignSettings::new(seed, errors, 10, 10);
        s.reference_lengths = 3;
        s.encoder_noise_deg = 0.005;
        s.probe_noise_mm = 0.01;
        s
    };
    let c = simulate(&nominal(), &settings(seed, ErrorModel::random(1.0, true))).unwrap();
    let file = ErrorModel::File {
        arm: c.true_arm.clone(),
    };
    let fresh = simulate(&nominal(), &settings(1_000_000 + seed, file))
        .unwrap()
        .data_set()
        .unwrap();
    (c, fresh)
}

/// The fitted arm's single-point `e` on held-out sockets within 10 % of
/// the true arm's.
#[track_caller]
fn assert_held_out_close(
    fitted: &DhParams,
    truth: &DhParams,
    fresh: &aacmm_core::dataset::DataSet,
) {
    let truth = validate::figures(truth, fresh).unwrap().e_mean;
    let ours = validate::figures(fitted, fresh).unwrap().e_mean;
    assert!(ours <= 1.1 * truth, "held-out e {ours} vs true {truth}");
}

#[test]
fn global_converges_from_unknown_zeros_where_lm_fails() {
    use aacmm_core::calibrate::{GlobalStop, Method};
    // Seeds whose LM from nominal ends in a wrong basin.
    for seed in [4, 5] {
        let (c, fresh) = assembled(seed);
        let data = c.data_set().unwrap();
        let model = ModelOptions {
            noise: stated_noise(),
            ..ModelOptions::default()
        };
        let run = |method, threads| {
            let settings = SolverSettings {
                threads,
                ..SolverSettings::default().with_method(method)
            };
            calibrate(&c.nominal.params, &data, &model, &settings).unwrap()
        };
        let (lm, global) = (run(Method::Lm, 2), run(Method::Global, 2));
        // The grid's cells refined two at a time, judged in order: the
        // noise floor stops it at the same cell as on one thread, the
        // other of its pair not counted.
        assert_the_same_search(&run(Method::Global, 1), &global);
        assert!(
            lm.dof.sigma0 > 100.0,
            "seed {seed}: LM σ0 {}",
            lm.dof.sigma0
        );
        assert!(global.solver.is_solution_usable());
        assert!(
            global.dof.sigma0 < 1.3,
            "seed {seed}: σ0 {}",
            global.dof.sigma0
        );
        let trace = global.solver.global.as_ref().unwrap();
        assert_eq!(trace.stop, GlobalStop::NoiseFloor);
        assert!(trace.minima.len() >= 2, "the grid was needed");
        assert_held_out_close(&global.params, &c.true_arm.params, &fresh);
        // Reported in the nominal sign convention: twists near nominal.
        for (j, (fit, nom)) in global
            .params
            .joints
            .iter()
            .zip(&c.nominal.params.joints)
            .enumerate()
        {
            assert!(
                (fit.alpha - nom.alpha).abs() < 0.1,
                "seed {seed} joint {}: alpha {} vs {}",
                j + 1,
                fit.alpha,
                nom.alpha
            );
        }
    }
}

#[test]
fn global_without_stated_noise_stops_on_agreement() {
    use aacmm_core::calibrate::{GlobalStop, Method};
    let (c, fresh) = assembled(1);
    let data = c.data_set().unwrap();
    let settings = SolverSettings::default().with_method(Method::Global);
    let cal = calibrate(
        &c.nominal.params,
        &data,
        &ModelOptions::default(),
        &settings,
    )
    .unwrap();
    let trace = cal.solver.global.as_ref().unwrap();
    assert_eq!(trace.stop, GlobalStop::Agreement);
    assert!(trace.best_hits >= 2);
    assert!(trace.noise_floor_cost.is_none());
    assert_held_out_close(&cal.params, &c.true_arm.params, &fresh);
}

/// A campaign of many points: 86 sockets spread by the simulator, each
/// seated at six places 5 mm apart — 516 points of 4 touches (placing 516
/// sockets apart would take seconds in a debug build).
fn many_points() -> aacmm_core::simulate::Campaign {
    use aacmm_core::simulate::{SocketPlan, SocketPoint, place_sockets};
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
    let spread = place_sockets(&nominal(), 86, &mut rng).unwrap();
    let points = spread
        .iter()
        .flat_map(|(label, c)| {
            [
                ("a", 0.0, 0.0),
                ("b", 5.0, 0.0),
                ("c", 0.0, 5.0),
                ("d", 5.0, 5.0),
                ("e", 10.0, 0.0),
                ("f", 0.0, 10.0),
            ]
            .map(|(k, dx, dy)| SocketPoint {
                label: format!("{label}{k}"),
                x: c[0] + dx,
                y: c[1] + dy,
                z: c[2],
            })
        })
        .collect();
    let mut s = CampaignSettings::new(4, ErrorModel::Paper, 0, 4);
    s.sockets = SocketPlan::Given { file: None, points };
    s.reference_lengths = 3;
    s.encoder_noise_deg = 0.005;
    s.probe_noise_mm = 0.01;
    simulate(&nominal(), &s).unwrap()
}

/// Enough points that the normal equations run in chunks on both threads:
/// the 10 × 10 touches this test once ran are one chunk, on one thread
/// whatever the count, so it could not fail.
#[test]
fn same_seed_same_bytes_whatever_the_threads() {
    use aacmm_core::calibrate::Method;
    use aacmm_core::parallel::threads_for;
    use aacmm_core::residuals::point_chunks;
    let c = many_points();
    let data = c.data_set().unwrap();
    let n = data.points().len();
    assert_eq!(
        threads_for(point_chunks(n), 2),
        2,
        "{n} points make {} chunk(s) of work: on one thread",
        point_chunks(n)
    );
    let model = ModelOptions {
        noise: stated_noise(),
        ..ModelOptions::default()
    };
    for method in [Method::Sa, Method::Hybrid, Method::Global] {
        let run = |threads: usize, seed: u64| {
            let settings = SolverSettings {
                method,
                // Few moves: the anneal runs on one thread; what the
                // threads split (weights, normal equations) is the fits'.
                anneal: aacmm_core::calibrate::AnnealOptions::default().chain(2),
                threads,
                seed,
                ..SolverSettings::default()
            };
            let cal = calibrate(&c.nominal.params, &data, &model, &settings).unwrap();
            serde_json::to_string(&cal).unwrap()
        };
        let one = run(1, 5);
        // Not assert_eq!: a thousand touches' JSON would flood the message.
        assert!(
            one == run(2, 5),
            "{method:?}: not the same bytes on 2 threads"
        );
        if method == Method::Sa {
            assert!(one != run(1, 6), "another seed, other moves");
        }
    }
}

#[test]
fn the_hybrid_anneals_then_switches_to_lm() {
    use aacmm_core::calibrate::{AnnealStop, Method, Stop};
    let c = campaign(5, 0.005, 0.01);
    let data = c.data_set().unwrap();
    let model = ModelOptions {
        noise: stated_noise(),
        ..ModelOptions::default()
    };
    let run = |method| {
        let settings = SolverSettings::default().with_method(method);
        calibrate(&c.nominal.params, &data, &model, &settings).unwrap()
    };
    let hybrid = run(Method::Hybrid);
    let a = hybrid.solver.anneal.as_ref().unwrap();
    assert_eq!(a.stop, AnnealStop::Switched);
    assert!(a.best_energy < a.start_energy);
    let best = a.temperatures.iter().map(|t| t.best);
    assert!(
        best.clone().zip(best.skip(1)).all(|(x, y)| y <= x),
        "best never rises"
    );
    assert!(hybrid.solver.is_solution_usable());
    assert_eq!(
        hybrid
            .solver
            .phases
            .iter()
            .map(|p| p.name.as_str())
            .collect::<Vec<_>>()[..3],
        ["identify", "anneal", "lm"]
    );
    // The paper's annealing alone ends far from the minimum LM finds.
    let sa = run(Method::Sa);
    assert_eq!(sa.solver.stop, Stop::Anneal(AnnealStop::Cooled));
    assert_eq!(sa.solver.stop.lm(), None);
    assert_eq!(sa.solver.anneal.as_ref().unwrap().stop, AnnealStop::Cooled);
    assert!(sa.solver.final_cost > 10.0 * hybrid.solver.final_cost);
}

/// The global method's torus grid shares its cells' costs between threads
/// in chunks of 64 (the UR5 tracker's 1000 cells are 16 chunks: two
/// threads): the calibration on 1 and 2 threads is the same, to the bit,
/// and the grid costed every cell.
#[test]
fn the_global_search_is_the_same_on_one_and_two_threads() {
    use aacmm_core::DataSet;
    use aacmm_core::io::{AngleUnit, read_positions};
    let file = |f: &str| format!("{}/../examples/ur5-tracker/{f}", env!("CARGO_MANIFEST_DIR"));
    let arm = aacmm_core::read_arm(std::path::Path::new(&file("arm.toml")))
        .unwrap()
        .0;
    let rows = read_positions(
        std::path::Path::new(&file("positions-grid.csv")),
        AngleUnit::Deg,
        Some(6),
    )
    .unwrap();
    let data = DataSet::from_positions(rows, "positions-grid.csv").unwrap();
    let on_stated = |threads: usize, model: &ModelOptions| {
        let settings = SolverSettings {
            threads,
            ..SolverSettings::default()
        };
        calibrate(&arm.params, &data, model, &settings).unwrap()
    };
    let on = |threads: usize| on_stated(threads, &ModelOptions::default());
    let one = on(1);
    let grid = (one.solver.phases.iter()).find(|p| p.name == "torus grid");
    assert_eq!(
        grid.map(|p| p.cost_evaluations),
        Some(1000),
        "{:?}",
        one.solver.phases
    );
    assert_eq!(
        aacmm_core::parallel::threads_for(1000usize.div_ceil(64), 2),
        2
    );
    let two = on(2);
    assert_eq!(two.params, one.params);
    assert_eq!(two.solver.stop, one.solver.stop);
    assert_the_same_search(&one, &two);
    // Stated noise the fit misses (0.05 mm; it is nearer 0.06): the grid
    // finds no floor, and the first random start confirms the lowest
    // cost — on two threads a second start ran beside it, not counted.
    let mut model = ModelOptions::default();
    model.noise.position_mm = Some(0.05);
    let one = on_stated(1, &model);
    let trace = one.solver.global.as_ref().unwrap();
    // The start arm, 8 grid cells, 1 random start.
    assert_eq!(trace.minima.len(), 10, "{trace:?}");
    assert_the_same_search(&one, &on_stated(2, &model));
}

/// The same search: every start's minimum (the grid's cells are refined
/// side by side on two threads) and the evaluations of every phase.
#[track_caller]
fn assert_the_same_search(one: &Calibration, two: &Calibration) {
    assert_eq!(two.solver.global, one.solver.global);
    let counts = |c: &Calibration| -> Vec<(String, usize, usize)> {
        (c.solver.phases.iter())
            .map(|p| (p.name.clone(), p.cost_evaluations, p.jacobian_evaluations))
            .collect()
    };
    assert_eq!(counts(two), counts(one));
    assert_eq!(two.parameters, one.parameters);
    assert_eq!(two.dof, one.dof);
}
