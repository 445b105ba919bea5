//! The built-in terms' sums: the same bits as the plain loops they stand
//! for, on any thread count; the weights' streamed change is the built one.

use super::rank3::BLOCK;
use super::sym3::{sym_inv, sym_mul};
use super::touches::{POINTS_PER_CHUNK, TOUCHES_PER_CHUNK};
use super::*;
use crate::dataset::DataSet;
use crate::io::{AngleUnit, parse_lengths, parse_poses};
use crate::kernel::ArmKernel;
use crate::params::DhParams;

/// The touches and (when `data` has them) the lengths of `data` under
/// `noise`, weighed at `arm` (unit σ `sigma`) on `threads` threads.
fn weighed<'d>(
    data: &'d DataSet,
    noise: &Noise,
    arm: &DhParams,
    sigma: f64,
    threads: usize,
) -> (TouchTerm<'d>, Option<LengthTerm<'d>>) {
    let (mut touches, mut lengths) = (
        TouchTerm::new(data, *noise),
        (!data.references().is_empty()).then(|| LengthTerm::new(data, *noise)),
    );
    at(arm, threads, |at| {
        let mut shared = Shared::default();
        touches.weigh(at, &mut shared, sigma)?;
        if let Some(l) = &mut lengths {
            l.weigh(at, &mut shared, sigma)?;
        }
        Ok(())
    })
    .unwrap();
    (touches, lengths)
}

/// Stated encoder (1e-4 rad) and probe (0.01 mm) noise, lengths of 1 µm.
fn stated_noise() -> Noise {
    Noise {
        encoder_rad: Some(1e-4),
        probe_mm: Some(0.01),
        length_default_mm: 0.001,
        length_weight: None,
        ..Noise::default()
    }
}

/// `f` at the arm `arm`.
fn at<R>(
    arm: &DhParams,
    threads: usize,
    f: impl FnOnce(&At<'_>) -> Result<R, TermError>,
) -> Result<R, TermError> {
    let kernel = ArmKernel::new(arm)?;
    let layout = Layout::new(arm.clone());
    let x = arm.to_vec();
    f(&At {
        x: &x,
        arm,
        kernel: &kernel,
        layout: &layout,
        threads,
    })
}

/// The normal equations of the touches (and lengths) at `arm` over
/// `free`, and the centres the touches left.
fn normal_equations(
    arm: &DhParams,
    touches: &TouchTerm<'_>,
    lengths: Option<&LengthTerm<'_>>,
    free: &[usize],
    threads: usize,
) -> (Normal, Centres) {
    at(arm, threads, |at| {
        let mut normal = Normal::new(free);
        let mut shared = Shared {
            want_centre_jacobians: lengths.is_some(),
            ..Shared::default()
        };
        let cost = touches.accumulate(at, &mut shared, &mut normal)?;
        normal.costs.push(cost);
        if let Some(l) = lengths {
            let cost = l.accumulate(at, &mut shared, &mut normal)?;
            normal.costs.push(cost);
        }
        Ok((normal, shared.centres.unwrap()))
    })
    .unwrap()
}

/// The largest relative change of the weights weighed at `arm` (`sigma`)
/// against `touches`' and `lengths'`, on `threads` threads.
fn change(
    arm: &DhParams,
    touches: &TouchTerm<'_>,
    lengths: Option<&LengthTerm<'_>>,
    sigma: f64,
    threads: usize,
) -> f64 {
    at(arm, threads, |at| {
        let mut shared = Shared::default();
        let mut c = touches.weight_change(at, &mut shared, sigma)?;
        if let Some(l) = lengths {
            c = c.max(l.weight_change(at, &mut shared, sigma)?);
        }
        Ok(c)
    })
    .unwrap()
}

/// `‖a − b‖/‖b‖` per touch and `|a − b|/|b|` per length, the largest.
fn built_change(
    (ta, la): (&TouchTerm<'_>, Option<&LengthTerm<'_>>),
    (tb, lb): (&TouchTerm<'_>, Option<&LengthTerm<'_>>),
) -> f64 {
    let norm = |a: &[f64; 6]| {
        (a[..3].iter().map(|v| v * v).sum::<f64>()
            + 2.0 * a[3..].iter().map(|v| v * v).sum::<f64>())
        .sqrt()
    };
    let touch = ta.weights().iter().zip(tb.weights()).map(|(a, b)| {
        let d: [f64; 6] = std::array::from_fn(|k| a[k] - b[k]);
        norm(&d) / norm(b)
    });
    let length = la
        .map(|l| l.weights().to_vec())
        .unwrap_or_default()
        .into_iter()
        .zip(lb.map(|l| l.weights().to_vec()).unwrap_or_default())
        .map(|(a, b)| (a - b).abs() / b.abs());
    touch.chain(length).fold(0.0, f64::max)
}

/// A simulated campaign (paper errors, `sockets` × `touches`, `lengths`
/// reference lengths, 0.005° and 0.01 mm noise), its noise and the nominal
/// arm.
fn simulated(seed: u64, sockets: usize, touches: usize, lengths: usize) -> (DataSet, Noise) {
    use crate::simulate::{CampaignSettings, ErrorModel, simulate};
    let nominal = crate::domain::Arm::without_limits("n", DhParams::paper_nominal());
    let mut settings = CampaignSettings::new(seed, ErrorModel::Paper, sockets, touches);
    settings.reference_lengths = lengths;
    settings.encoder_noise_deg = 0.005;
    settings.probe_noise_mm = 0.01;
    let data = simulate(&nominal, &settings).unwrap().data_set().unwrap();
    let noise = Noise {
        encoder_rad: Some(0.005f64.to_radians()),
        probe_mm: Some(0.01),
        ..Noise::default()
    };
    (data, noise)
}

/// The free columns' normal equations are the full system's principal
/// submatrix, to the bit (what the first LM step reuses).
#[test]
fn the_free_columns_system_is_the_restriction_of_the_full_one() {
    let (data, noise) = simulated(9, 10, 10, 3);
    let arm = DhParams::paper_nominal();
    let (t, l) = weighed(&data, &noise, &arm, 1.0, 1);
    let all: Vec<usize> = (0..27).collect();
    let full = normal_equations(&arm, &t, l.as_ref(), &all, 1).0;
    let free: Vec<usize> = vec![1, 0, 7, 12, 19, 26];
    let direct = normal_equations(&arm, &t, l.as_ref(), &free, 1).0;
    // Same products summed in the same order: equal to the bit.
    assert_eq!(full.restrict(&free).unwrap(), direct);
    assert!(full.restrict(&[27]).is_none());
    assert!(direct.restrict(&[2]).is_none());
}

/// With no free column the touches and the lengths give their costs
/// alone (the touches' rank-3 rows of stride 0 are not cut; the lengths
/// read no centre Jacobians, which a pass that did not ask for them
/// leaves none of): the lengths' cost of the pass over every column, to
/// the bit.
#[test]
fn lengths_without_free_columns_give_their_cost() {
    let (data, noise) = simulated(9, 10, 10, 3);
    let arm = DhParams::paper_nominal();
    let (t, l) = weighed(&data, &noise, &arm, 1.0, 1);
    let l = l.expect("lengths");
    let all: Vec<usize> = (0..27).collect();
    let full = normal_equations(&arm, &t, Some(&l), &all, 1).0;
    let none = at(&arm, 1, |at| {
        let (mut normal, mut shared) = (Normal::new(&[]), Shared::default());
        t.accumulate(at, &mut shared, &mut normal)?;
        l.accumulate(at, &mut shared, &mut normal)
    })
    .unwrap();
    assert_eq!(none.to_bits(), full.costs[1].to_bits());
}

/// The blocked, lane-wise accumulation adds every product in the order
/// of the plain loops it replaced (touch by touch, `b ≤ i`, then the
/// point's Schur term): the same bits, with points of more touches than
/// a block and an odd number of free columns.
#[test]
fn blocked_normal_equations_are_the_plain_loops_bits() {
    // No lengths: the touches' sums alone.
    let (data, noise) = simulated(5, 7, 2 * BLOCK + 3, 0);
    let arm = DhParams::paper_nominal();
    let kernel = ArmKernel::new(&arm).unwrap();
    let (t, _) = weighed(&data, &noise, &arm, 1.0, 1);
    for free in [
        (0..27).collect::<Vec<usize>>(),
        vec![2, 3, 5, 8, 13, 21, 26],
    ] {
        let p = free.len();
        let (mut jtj, mut jtr, mut cost) = (vec![0.0; p * p], vec![0.0; p], 0.0);
        let mut rows = Vec::new();
        kernel
            .for_each_jacobian(data.poses(), 0..data.len(), |_, pos, jac| {
                rows.push((*pos, jac.to_vec()))
            })
            .unwrap();
        for point in data.points() {
            let origin = rows[point.touches.start].0;
            let (mut g, mut jap) = (vec![[0.0; 3]; p], vec![0.0; p]);
            let (mut ap, mut pap, mut sa) = ([0.0; 3], 0.0, [0.0; 6]);
            for i in point.touches.clone() {
                let (pos, jac) = &rows[i];
                let a = &t.weights()[i];
                let d: [f64; 3] = std::array::from_fn(|k| pos[k] - origin[k]);
                let ad = sym_mul(a, &d);
                (0..3).for_each(|k| ap[k] += ad[k]);
                pap += d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
                (0..6).for_each(|k| sa[k] += a[k]);
                let wa: Vec<[f64; 3]> = free.iter().map(|&c| sym_mul(a, &jac[c])).collect();
                for i in 0..p {
                    (0..3).for_each(|k| g[i][k] += wa[i][k]);
                    jap[i] += wa[i][0] * d[0] + wa[i][1] * d[1] + wa[i][2] * d[2];
                    for b in 0..=i {
                        let j = jac[free[b]];
                        jtj[i * p + b] += wa[i][0] * j[0] + wa[i][1] * j[1] + wa[i][2] * j[2];
                    }
                }
            }
            let cinv = sym_inv(&sa);
            let c = sym_mul(&cinv, &ap);
            cost += pap - (c[0] * ap[0] + c[1] * ap[1] + c[2] * ap[2]);
            let mean: Vec<[f64; 3]> = g.iter().map(|gi| sym_mul(&cinv, gi)).collect();
            for i in 0..p {
                let gi = g[i];
                jtr[i] += jap[i] - (gi[0] * c[0] + gi[1] * c[1] + gi[2] * c[2]);
                for b in 0..=i {
                    let mb = mean[b];
                    jtj[i * p + b] -= gi[0] * mb[0] + gi[1] * mb[1] + gi[2] * mb[2];
                }
            }
        }
        for a in 0..p {
            for b in 0..a {
                jtj[b * p + a] = jtj[a * p + b];
            }
        }
        // One chunk of points (under POINTS_PER_CHUNK): no partial sums.
        assert!(data.points().len() <= POINTS_PER_CHUNK);
        let n = normal_equations(&arm, &t, None, &free, 1).0;
        assert_eq!(n.jtj, jtj);
        assert_eq!(n.jtr, jtr);
        assert_eq!(n.costs, [cost]);
    }
}

/// `n` points of 3 touches each, spread in joint space, with 20
/// reference lengths between them.
fn points_of_three_touches(n: usize) -> DataSet {
    points_of_touches(n, |_| 3)
}

/// `n` points, point `p` of `touches(p)` touches, and 20 lengths.
fn points_of_touches(n: usize, touches: impl Fn(usize) -> usize) -> DataSet {
    let mut text = String::from("point,q1,q2,q3,q4,q5,q6\n");
    for p in 0..n {
        for k in 0..touches(p) {
            let q: Vec<String> = (0..6)
                .map(|j| {
                    let base = ((p * 7 + j * 13) as f64 * 0.37).sin() * 120.0;
                    format!("{}", base + (k * 20 + j) as f64 * 0.5)
                })
                .collect();
            text.push_str(&format!("P{p},{}\n", q.join(",")));
        }
    }
    let (poses, _) = parse_poses(&text, "p.csv", AngleUnit::Deg, Some(6)).unwrap();
    let mut lengths = String::from("point_a,point_b,distance\n");
    for i in 0..20 {
        lengths.push_str(&format!("P{i},P{},{}\n", n - 1 - i, 500 + i));
    }
    DataSet::from_poses(&poses, "p.csv")
        .unwrap()
        .with_lengths(&parse_lengths(&lengths, "l.csv").unwrap(), "l.csv")
        .unwrap()
}

/// The weights' change to another arm, streamed a chunk of points at a
/// time, is the change built-then-compared, to the bit, on any thread
/// count; with and without stated noise.
#[test]
fn the_streamed_change_of_weights_is_the_built_one() {
    // 9000 touches: 8 chunks of 1024 and more, on 2 threads.
    let data = points_of_three_touches(3000);
    let chunks = data.len() / TOUCHES_PER_CHUNK;
    assert_eq!(
        crate::parallel::threads_for(chunks, 2),
        2,
        "{chunks} chunks"
    );
    let here = DhParams::paper_nominal();
    let mut there = DhParams::paper_nominal();
    there.joints[1].d += 3.0;
    there.joints[2].theta += 0.02;
    let stated = stated_noise();
    let unstated = Noise {
        encoder_rad: None,
        probe_mm: None,
        ..stated
    };
    for (noise, sigma) in [(&stated, 1.0), (&unstated, 0.7)] {
        let (t, l) = weighed(&data, noise, &here, 1.0, 1);
        let (nt, nl) = weighed(&data, noise, &there, sigma, 1);
        let built = built_change((&nt, nl.as_ref()), (&t, l.as_ref()));
        assert!(built > 0.0 && built.is_finite());
        for threads in [1, 2, 4] {
            let streamed = change(&there, &t, l.as_ref(), sigma, threads);
            assert_eq!(streamed.to_bits(), built.to_bits(), "{threads} threads");
        }
        assert_eq!(change(&here, &t, l.as_ref(), 1.0, 2), 0.0);
    }
    // Weights of another shape than the data's: an infinite change.
    let (t, l) = weighed(&data, &stated, &here, 1.0, 1);
    let short = t.without_last_weight();
    assert_eq!(change(&here, &short, l.as_ref(), 1.0, 1), f64::INFINITY);
}

/// 3000 points of 3 touches with stated noise and reference lengths:
/// 47 chunks of points and 8 of touches' weights, so 2 and 4 threads
/// really split the work ([`crate::parallel::threads_for`]: one thread
/// below 8 chunks for two). The normal equations, their cost and the
/// centroids are the same bits on 1, 2 and 4 threads.
#[test]
fn normal_equations_are_the_same_bits_on_any_thread_count() {
    use crate::parallel::threads_for;
    let n = 3000;
    let data = points_of_three_touches(n);
    assert_eq!(data.points().len(), n);
    assert_eq!(
        threads_for(n.div_ceil(POINTS_PER_CHUNK), 4),
        4,
        "points split"
    );
    let arm = DhParams::paper_nominal();
    let noise = stated_noise();
    let (t, l) = weighed(&data, &noise, &arm, 1.0, 1);
    let weight_chunks = data.len() / TOUCHES_PER_CHUNK;
    assert_eq!(threads_for(weight_chunks, 2), 2, "weights split too");
    for threads in [2, 4] {
        let (tw, lw) = weighed(&data, &noise, &arm, 1.0, threads);
        assert_eq!(tw.weights(), t.weights(), "{threads} threads");
        assert_eq!(lw.unwrap().weights(), l.as_ref().unwrap().weights());
    }
    let free: Vec<usize> = (0..27).collect();
    let bits = |threads: usize| {
        let (ne, centres) = normal_equations(&arm, &t, l.as_ref(), &free, threads);
        let mut v: Vec<u64> = ne.jtj.iter().chain(&ne.jtr).map(|x| x.to_bits()).collect();
        v.extend(ne.costs.iter().chain([&ne.cost()]).map(|c| c.to_bits()));
        v.extend(centres.points.iter().flatten().map(|x| x.to_bits()));
        assert!(ne.costs.iter().all(|&c| c > 0.0));
        v
    };
    let one = bits(1);
    assert_eq!(bits(2), one);
    assert_eq!(bits(4), one);
}

/// The cost pass, a chunk of points at a time into a slot of scratch per
/// thread, is the plain pass to the bit — every touch's position at once,
/// then the points summed in order — on 1, 2 and 4 threads, and so are
/// the centres it leaves.
#[test]
fn the_cost_pass_is_the_plain_one_on_any_thread_count() {
    // Points of three touches; and points of up to 1100 touches, whose
    // chunks of 64 points are costed in batches of about 1024 touches, a
    // point of more in a batch of its own.
    let mixed = |p: usize| [3, 300, 1100, 40, 3, 3, 3, 3][p % 8];
    for (n, data) in [
        (3000usize, points_of_three_touches(3000)),
        (600, points_of_touches(600, mixed)),
    ] {
        assert!(crate::parallel::threads_for(n.div_ceil(POINTS_PER_CHUNK), 4) >= 2);
        the_cost_pass_is_the_plain_one_on(&data);
    }
}

fn the_cost_pass_is_the_plain_one_on(data: &DataSet) {
    let noise = stated_noise();
    let mut arm = DhParams::paper_nominal();
    let (t, _) = weighed(data, &noise, &arm, 1.0, 1);
    arm.joints[1].d += 0.3;
    arm.joints[2].theta += 0.002;
    let kernel = ArmKernel::new(&arm).unwrap();
    let mut xyz = vec![[0.0; 3]; data.len()];
    kernel
        .positions(data.poses(), 0..data.len(), &mut xyz)
        .unwrap();
    let (mut want, mut centres) = (0.0, Vec::new());
    for point in data.points() {
        let origin = xyz[point.touches.start];
        let (mut ap, mut pap, mut sum) = ([0.0; 3], 0.0, [0.0; 6]);
        for i in point.touches.clone() {
            let a = &t.weights()[i];
            let d: [f64; 3] = std::array::from_fn(|k| xyz[i][k] - origin[k]);
            let ad = sym_mul(a, &d);
            (0..3).for_each(|k| ap[k] += ad[k]);
            pap += d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
            (0..6).for_each(|k| sum[k] += a[k]);
        }
        let c = sym_mul(&sym_inv(&sum), &ap);
        want += pap - (c[0] * ap[0] + c[1] * ap[1] + c[2] * ap[2]);
        centres.push(std::array::from_fn::<f64, 3, _>(|k| c[k] + origin[k]));
    }
    assert!(want > 1.0, "the arm moved: {want}");
    let mut scratch = Vec::new();
    for threads in [1, 2, 4, 1] {
        let (total, got) = at(&arm, threads, |at| {
            let (mut shared, mut total) = (Shared::default(), 0.0);
            t.add_cost(at, &[], &mut shared, &mut scratch, &mut total)?;
            Ok((total, shared.centres.unwrap().points))
        })
        .unwrap();
        assert_eq!(total.to_bits(), want.to_bits(), "{threads} threads");
        assert_eq!(got, centres, "{threads} threads");
    }
    // The scratch holds a few batches' positions, not every touch's.
    assert!(
        scratch.len() < data.len() / 4,
        "{} positions",
        scratch.len()
    );
}

/// The leverage tests' free columns.
const LEVERAGE_FREE: [usize; 7] = [1, 3, 7, 12, 16, 19, 23];

/// The leverage tests' touches, unit-weighted, and their normal equations
/// over [`LEVERAGE_FREE`] at `arm`.
fn leverage_problem<'d>(
    data: &'d DataSet,
    noise: &Noise,
    arm: &DhParams,
) -> (TouchTerm<'d>, Normal) {
    let (t, _) = weighed(data, noise, arm, 1.0, 1);
    let normal = normal_equations(arm, &t, None, &LEVERAGE_FREE, 1).0;
    (t, normal)
}

/// The outlier test takes the covariance's `N⁻¹` when its leverage is
/// unscaled (`calibrate::assess`): the same Cholesky of the same entries,
/// so the same bits as a leverage of its own; an inverse that failed (the
/// covariance's infinite matrix) is no leverage, as a failed Cholesky is.
#[test]
fn a_leverage_from_the_covariances_inverse_is_the_same_bits() {
    let (data, noise) = simulated(4, 4, 6, 0);
    let (_, normal) = leverage_problem(&data, &noise, &DhParams::paper_nominal());
    let p = LEVERAGE_FREE.len();
    let n = nalgebra::DMatrix::from_row_slice(p, p, &normal.jtj);
    let inverse = cholesky_inverse(&n.cholesky().unwrap());
    let shared = ParameterLeverage::from_inverse(&normal, &inverse).unwrap();
    let own = ParameterLeverage::of(&normal, 1.0).unwrap();
    let bits = |l: &ParameterLeverage| l.n_inv.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&shared), bits(&own));
    assert_eq!(shared.free(), own.free());
    // Scaled, it is another matrix: not what the covariance inverted.
    assert_ne!(
        bits(&ParameterLeverage::of(&normal, 4.0).unwrap()),
        bits(&own)
    );
    let failed = nalgebra::DMatrix::from_element(p, p, f64::INFINITY);
    assert!(ParameterLeverage::from_inverse(&normal, &failed).is_none());
}

/// A touch's full leverage is its block of the hat matrix of the whole
/// problem — the free columns and every point's centre carried as unknowns
/// — against a dense computation: `h_i = tr(A_i X_i (Xᵀ A X)⁻¹ X_iᵀ)/3`,
/// `X_i = [J_i, −E_k]`. The values agree with `rᵀ A r/(1 − h)` to 1e-9, and
/// summed over the touches `3h` is `3·points + p`.
#[test]
fn the_full_leverage_is_the_hat_matrix_block() {
    use nalgebra::{DMatrix, Matrix3};
    let (data, noise) = simulated(4, 4, 6, 0);
    let arm = DhParams::paper_nominal();
    let (t, normal) = leverage_problem(&data, &noise, &arm);
    let free = LEVERAGE_FREE;
    let leverage = ParameterLeverage::of(&normal, 1.0).unwrap();
    let got = at(&arm, 1, |at| t.standardised(at, Some(&leverage)))
        .unwrap()
        .unwrap()
        .values;
    // Dense: columns `free`, then 3 per point.
    let (q, k, n) = (free.len(), data.points().len(), data.len());
    let kernel = ArmKernel::new(&arm).unwrap();
    let a = |i: usize| {
        let w = t.weights()[i];
        Matrix3::new(w[0], w[3], w[4], w[3], w[1], w[5], w[4], w[5], w[2])
    };
    let mut x = vec![DMatrix::<f64>::zeros(3, q + 3 * k); n];
    let mut pos = vec![[0.0; 3]; n];
    let mut jac = vec![[0.0; 3]; arm.param_count()];
    for (p, point) in data.points().iter().enumerate() {
        for i in point.touches.clone() {
            kernel.position_jacobian(data.reading(i), &mut jac).unwrap();
            pos[i] = kernel.position(data.reading(i)).unwrap();
            for r in 0..3 {
                for (c, &f) in free.iter().enumerate() {
                    x[i][(r, c)] = jac[f][r];
                }
                x[i][(r, q + 3 * p + r)] = -1.0;
            }
        }
    }
    let mut info = DMatrix::<f64>::zeros(q + 3 * k, q + 3 * k);
    for (i, xi) in x.iter().enumerate() {
        let ai = DMatrix::from_fn(3, 3, |r, c| a(i)[(r, c)]);
        info += xi.transpose() * &ai * xi;
    }
    let inv = info.try_inverse().unwrap();
    let mut total = 0.0;
    for point in data.points() {
        let s: Matrix3<f64> = point.touches.clone().map(a).sum();
        let sp: nalgebra::Vector3<f64> = (point.touches.clone())
            .map(|i| a(i) * nalgebra::Vector3::from(pos[i]))
            .sum();
        let c = s.try_inverse().unwrap() * sp;
        for i in point.touches.clone() {
            let ai = DMatrix::from_fn(3, 3, |r, cc| a(i)[(r, cc)]);
            let h = (&ai * &x[i] * &inv * x[i].transpose()).trace() / 3.0;
            total += 3.0 * h;
            let r = nalgebra::Vector3::from(pos[i]) - c;
            let want = (r.transpose() * a(i) * r)[(0, 0)] / (1.0 - h);
            assert!(
                (got[i] - want).abs() <= 1e-9 * want,
                "touch {i}: {} vs {want}",
                got[i]
            );
        }
    }
    assert!((total - (3 * k + q) as f64).abs() < 1e-9, "{total}");
}

/// The tool's whole pose through the corrections: its position and the
/// position rows of its Jacobian are the tool position's, and each
/// correction column's rows (rotation too) are the derivative of the tool
/// pose along that column.
#[test]
fn the_tool_pose_carries_the_corrections() {
    use crate::corrections::{Beyond, Conditions, Mass, Physics};
    let arm = DhParams::paper_nominal();
    let q: Vec<Vec<f64>> = (0..5)
        .map(|i| (0..6).map(|j| ((i * 6 + j) as f64 * 0.37).sin()).collect())
        .collect();
    let poses = crate::kernel::PreparedPoses::new(6, &q).unwrap();
    let physics = Physics {
        link_masses: vec![Some(Mass::at_middle(2.0)); 6],
        ..Physics::default()
    };
    let beyond = Beyond {
        compliance: vec![1],
        harmonics: vec![(0, 1)],
        ..Beyond::default()
    };
    let text = "point,q1,q2,q3,q4,q5,q6\nA,0,0,0,0,0,0\nA,0.1,0,0,0,0,0\nA,0.2,0,0,0,0,0\n";
    let (touches, _) = parse_poses(text, "p.csv", AngleUnit::Rad, Some(6)).unwrap();
    let data = DataSet::from_poses(&touches, "p.csv").unwrap();
    let layout = super::positions::layout_with(&arm, &data, &physics, &beyond).unwrap();
    let mut x = layout.start();
    let (_, cols) = layout.corrections().unwrap();
    x[cols.clone()].copy_from_slice(&[50.0, 1e-4, -2e-4]);
    let with = |x: &[f64], f: &mut dyn FnMut(&At<'_>)| {
        let arm = layout.arm(x).unwrap();
        let kernel = ArmKernel::new(&arm).unwrap();
        f(&At {
            x,
            arm: &arm,
            kernel: &kernel,
            layout: &layout,
            threads: 1,
        });
    };
    let none = Conditions::default();
    let mut tools = Vec::new();
    with(&x, &mut |at| {
        at.for_each_tool_pose(&poses, none, 0..5, |_, t, jac| {
            tools.push((*t, jac.to_vec()))
        })
        .unwrap();
        let mut p = vec![[0.0; 3]; 5];
        at.tool_positions(&poses, none, &mut p).unwrap();
        let mut k = 0;
        at.for_each_tool(&poses, none, 0..5, |i, pos, jac| {
            assert_eq!(jac.len(), layout.arm_columns());
            assert!((0..3).all(|r| (pos[r] - p[i][r]).abs() < 1e-9));
            assert!((0..3).all(|r| (tools[i].0.position[r] - pos[r]).abs() < 1e-9));
            for (c, col) in jac.iter().enumerate() {
                assert!(
                    (0..3).all(|r| (tools[i].1[c][r] - col[r]).abs() < 1e-9),
                    "{c}"
                );
            }
            k += 1;
        })
        .unwrap();
        assert_eq!(k, 5);
    });
    // Each correction column's six rows against central differences of the
    // tool pose (position, and the small rotation R' Rᵀ).
    for c in cols {
        let h = 1e-6 * x[c].abs().max(1.0);
        let moved = |d: f64| {
            let mut y = x.clone();
            y[c] += d;
            let mut out = Vec::new();
            with(&y, &mut |at| {
                at.for_each_tool_pose(&poses, none, 0..5, |_, t, _| out.push(*t))
                    .unwrap();
            });
            out
        };
        let (up, down) = (moved(h), moved(-h));
        for i in 0..5 {
            let m = |t: &crate::kernel::Pose| nalgebra::Matrix3::from_fn(|r, s| t.rotation[r][s]);
            let turn = (m(&up[i]) * m(&down[i]).transpose()).map(|v| v / (2.0 * h));
            let numeric = [
                (up[i].position[0] - down[i].position[0]) / (2.0 * h),
                (up[i].position[1] - down[i].position[1]) / (2.0 * h),
                (up[i].position[2] - down[i].position[2]) / (2.0 * h),
                turn[(2, 1)],
                turn[(0, 2)],
                turn[(1, 0)],
            ];
            let analytic = tools[i].1[c];
            for r in 0..6 {
                assert!(
                    (numeric[r] - analytic[r]).abs() < 1e-5 * (1.0 + analytic[r].abs()),
                    "pose {i}, column {c}, row {r}: {numeric:?} vs {analytic:?}"
                );
            }
        }
    }
}

/// A robust weight scales a position's and an orientation's standardised
/// residual as it scales a touch's (`rᵀAr` at the weights in force; the
/// robust fit then divides by the weight once): the two terms divided by
/// it themselves as well, so a robust fit judged them at `u²/w`.
#[test]
fn a_robust_weight_scales_a_positions_standardised_residual_as_a_touchs() {
    use crate::simulate::{
        OrientationSettings, PositionSettings, orient_positions, simulate_positions,
    };
    let truth = crate::domain::Arm::without_limits("paper", DhParams::paper_nominal());
    let noise = Noise {
        position_mm: Some(0.02),
        orientation_rad: Some(2e-4),
        ..Noise::default()
    };
    let settings = PositionSettings {
        poses: 20,
        frames: 1,
        noise,
        seed: 3,
    };
    let campaign = simulate_positions(&truth, &settings).unwrap();
    let o = OrientationSettings {
        mount: [0.0; 3],
        sigma_rad: 2e-4,
        seed: 4,
    };
    let oriented = orient_positions(&truth, &campaign.positions, &campaign.frames, &o).unwrap();
    let data = DataSet::from_positions(oriented, "sim.csv").unwrap();
    let layout = positions::layout_for(&truth.params, &data).unwrap();
    let objective =
        crate::objective::Objective::of_data(layout, &data, &noise, Vec::new(), None, 1.0, 1)
            .unwrap();
    let x = objective.start();
    let plain = objective.standardised(&x, None).unwrap();
    // 20 positions, then their 20 orientations.
    assert_eq!(plain.values.len(), 40);
    for i in [0, 20] {
        let mut w = vec![1.0; plain.values.len()];
        w[i] = 0.25;
        let weighed = (objective.with_observation_weights(&w))
            .standardised(&x, None)
            .unwrap();
        let (a, b) = (weighed.values[i], plain.values[i]);
        assert!(
            b > 0.0 && (a - 0.25 * b).abs() <= 1e-12 * b,
            "observation {i}: {a} against 0.25 × {b}"
        );
        let others = |v: &[f64]| [&v[..i], &v[i + 1..]].concat();
        assert_eq!(others(&weighed.values), others(&plain.values));
    }
}

/// A thread keeps its chunk buffers from one normal pass to the next, of
/// another width between (a fit's start of every column, then its steps'
/// free ones): each pass is the bits of one on a fresh thread, which keeps
/// nothing yet.
#[test]
fn kept_chunk_buffers_give_the_bits_of_fresh_ones() {
    let params = DhParams::paper_nominal();
    // Three chunks of points, the last part-full; four touches a point.
    let points = 2 * POINTS_PER_CHUNK + 5;
    let data = crate::dataset::testing::spread_touches(4 * points, points);
    let layout = positions::layout_for(&params, &data).unwrap();
    let noise = Noise::default();
    let objective =
        crate::objective::Objective::of_data(layout, &data, &noise, Vec::new(), None, 1.0, 1)
            .unwrap();
    let x = objective.start();
    let narrow: Vec<usize> = (2..20).collect();
    let wide: Vec<usize> = (0..x.len()).collect();
    let fresh = |free: &[usize]| {
        std::thread::scope(|s| {
            s.spawn(|| objective.normal(&x, free).unwrap())
                .join()
                .unwrap()
        })
    };
    let bits = |n: &Normal| {
        let all = n.jtj.iter().chain(&n.jtr).chain(&n.costs);
        all.map(|v| v.to_bits()).collect::<Vec<_>>()
    };
    let want = [bits(&fresh(&narrow)), bits(&fresh(&wide))];
    for pass in 0..3 {
        for (free, want) in [&narrow, &wide].into_iter().zip(&want) {
            let n = objective.normal(&x, free).unwrap();
            assert_eq!(&bits(&n), want, "pass {pass}, {} columns", free.len());
        }
    }
}
