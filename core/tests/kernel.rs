//! The generated kernel against its oracles, over random parameter sets near
//! and far from nominal and random joint angles, for 6 and 7 joints:
//! position against the reference nalgebra model, parameter and joint
//! Jacobians against num-dual autodiff and central differences.

use aacmm_core::kernel::{
    self, ArmKernel, Chain, Dh, Hayati, Jacobians, PreparedParams, PreparedPoses,
};
use aacmm_core::params::{DhJoint, DhParams, JointModel};
use aacmm_core::reference_model;
use proptest::prelude::*;
use std::f64::consts::PI;

/// A 7-joint arm: the paper's 6 plus a short wrist link.
fn nominal(n: usize) -> DhParams {
    let mut arm = DhParams::paper_nominal();
    if n == 7 {
        arm.joints.push(DhJoint {
            a: 20.0,
            d: 60.0,
            alpha: -PI / 2.0,
            theta: 0.0,
            ..DhJoint::default()
        });
    }
    arm
}

/// Parameter sets near nominal (small errors, the calibration case) or far
/// (anything: a newly assembled arm, a wrong model).
fn arm(n: usize) -> impl Strategy<Value = DhParams> {
    let near = prop::collection::vec(-1.0f64..1.0, 4 * n + 3).prop_map(move |e| {
        let mut p = nominal(n).to_vec();
        for (i, (v, e)) in p.iter_mut().zip(e).enumerate() {
            let angle = (2 * n..4 * n).contains(&i);
            *v += if angle { 0.01 * e } else { 2.0 * e };
        }
        DhParams::from_slice(&p).expect("4n + 3 values")
    });
    let far = (
        prop::collection::vec(-500.0f64..500.0, 2 * n),
        prop::collection::vec(-PI..PI, 2 * n),
        prop::collection::vec(-200.0f64..200.0, 3),
    )
        .prop_map(|(len, ang, b)| {
            let mut v = len;
            v.extend(ang);
            v.extend(b);
            DhParams::from_slice(&v).expect("4n + 3 values")
        });
    prop_oneof![near, far]
}

/// [`arm`] with a random subset of joints made Hayati, each with a random β
/// (small, the near-parallel case, or anything).
fn hayati_arm(n: usize) -> impl Strategy<Value = DhParams> {
    (
        arm(n),
        prop::collection::vec(any::<bool>(), n),
        prop::collection::vec(prop_oneof![-0.02f64..0.02, -PI..PI], n),
    )
        .prop_map(|(mut p, mask, beta)| {
            for ((j, h), b) in p.joints.iter_mut().zip(mask).zip(beta) {
                if h {
                    j.model = JointModel::Hayati;
                    j.beta = b;
                }
            }
            p
        })
}

fn readings(n: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-PI..PI, n)
}

/// Largest column norm: the scale the Jacobian tolerances are relative to.
fn scale(cols: &[[f64; 3]]) -> f64 {
    cols.iter()
        .map(|c| (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt())
        .fold(1.0, f64::max)
}

fn check_columns(got: &[[f64; 3]], want: &[[f64; 3]], rel: f64) -> Result<(), TestCaseError> {
    prop_assert_eq!(got.len(), want.len());
    for (c, (g, w)) in got.iter().zip(want).enumerate() {
        let s = scale(std::slice::from_ref(w)).max(1.0);
        for r in 0..3 {
            prop_assert!(
                (g[r] - w[r]).abs() <= rel * s,
                "column {} row {}: {} vs {} (scale {})",
                c,
                r,
                g[r],
                w[r],
                s
            );
        }
    }
    Ok(())
}

fn kernel_matches<const N: usize, const P: usize>(
    params: &DhParams,
    q: &[f64],
) -> Result<(), TestCaseError>
where
    Dh: Chain<N>,
    Hayati: Chain<N>,
{
    let k = PreparedParams::<N>::new(params).unwrap();
    let q: [f64; N] = q.try_into().unwrap();
    let models = params.models();

    let want = reference_model::position_with(&params.to_vec(), &q, &models);
    let got = kernel::position(&k, &q);
    for r in 0..3 {
        prop_assert!((got[r] - want[r]).abs() <= 1e-9, "{:?} vs {:?}", got, want);
    }

    let poses = PreparedPoses::new(N, &[q]).unwrap();
    let mut batch = Jacobians::new(1, P);
    ArmKernel::new(params)
        .unwrap()
        .jacobians(&poses, &mut batch)
        .unwrap();
    let pos = batch.position(0);
    for r in 0..3 {
        prop_assert!((pos[r] - want[r]).abs() <= 1e-9);
    }
    let jac: Vec<[f64; 3]> = (0..P).map(|c| batch.column(0, c)).collect();
    let dual = reference_model::param_jacobian_dual::<P>(params, &q).unwrap();
    check_columns(&jac, &dual, 1e-9)?;
    let central = reference_model::param_jacobian_central(params, &q, 1e-5).unwrap();
    check_columns(&jac, &central, 1e-6)?;

    let (p, jq) = kernel::joint_jacobian(&k, &q);
    for r in 0..3 {
        prop_assert!((p[r] - want[r]).abs() <= 1e-9);
    }
    let dual_q = reference_model::joint_jacobian_dual::<N>(params, &q).unwrap();
    check_columns(&jq, &dual_q, 1e-9)?;
    let flat = params.to_vec();
    let h = 1e-5;
    let central_q: Vec<[f64; 3]> = (0..N)
        .map(|j| {
            let (mut plus, mut minus) = (q, q);
            plus[j] += h;
            minus[j] -= h;
            let (p, m) = (
                reference_model::position_with(&flat, &plus, &models),
                reference_model::position_with(&flat, &minus, &models),
            );
            [0, 1, 2].map(|r| (p[r] - m[r]) / (2.0 * h))
        })
        .collect();
    check_columns(&jq, &central_q, 1e-6)?;
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn six_joint_kernel_matches_oracles(params in arm(6), q in readings(6)) {
        kernel_matches::<6, 27>(&params, &q)?;
    }

    #[test]
    fn seven_joint_kernel_matches_oracles(params in arm(7), q in readings(7)) {
        kernel_matches::<7, 31>(&params, &q)?;
    }
}

proptest! {
    // Fewer cases than the D-H chains': the joint subsets are random too, and
    // the extended chain shares the D-H chain's frames.
    #![proptest_config(ProptestConfig::with_cases(1000))]

    #[test]
    fn six_joint_hayati_kernel_matches_oracles(params in hayati_arm(6), q in readings(6)) {
        kernel_matches::<6, 27>(&params, &q)?;
    }

    #[test]
    fn seven_joint_hayati_kernel_matches_oracles(params in hayati_arm(7), q in readings(7)) {
        kernel_matches::<7, 31>(&params, &q)?;
    }
}

/// The extended chain with no Hayati joint is the D-H chain (it is only
/// picked when a joint is Hayati, but it must agree where both apply).
#[test]
fn extended_chain_without_hayati_joints_is_the_dh_chain() {
    for n in [6, 7] {
        let params = nominal(n);
        for i in 0..20 {
            let q: Vec<f64> = (0..n)
                .map(|j| ((i * 5 + j) as f64 * 0.77).sin() * 3.0)
                .collect();
            let (cq, sq): (Vec<f64>, Vec<f64>) = q.iter().map(|v| (v.cos(), v.sin())).unzip();
            if n == 6 {
                let k = PreparedParams::<6>::new(&params).unwrap();
                let (cq, sq) = (
                    cq.clone().try_into().unwrap(),
                    sq.clone().try_into().unwrap(),
                );
                let (mut a, mut b) = (vec![[0.0; 3]; 27], vec![[0.0; 3]; 27]);
                let pd = <Dh as Chain<6>>::position_jacobian(&k, &cq, &sq, &mut a);
                let ph = <Hayati as Chain<6>>::position_jacobian(&k, &cq, &sq, &mut b);
                for r in 0..3 {
                    assert!((pd[r] - ph[r]).abs() < 1e-9);
                }
                for (x, y) in a.iter().zip(&b) {
                    for r in 0..3 {
                        assert!((x[r] - y[r]).abs() < 1e-9);
                    }
                }
            } else {
                let k = PreparedParams::<7>::new(&params).unwrap();
                let (cq, sq) = (
                    cq.clone().try_into().unwrap(),
                    sq.clone().try_into().unwrap(),
                );
                let pd = <Dh as Chain<7>>::position(&k, &cq, &sq);
                let ph = <Hayati as Chain<7>>::position(&k, &cq, &sq);
                for r in 0..3 {
                    assert!((pd[r] - ph[r]).abs() < 1e-9);
                }
            }
        }
    }
}

/// `len` poses of `n` readings (rad), spread over ±3 rad.
fn spread_readings(n: usize, len: usize) -> Vec<Vec<f64>> {
    (0..len)
        .map(|i| {
            (0..n)
                .map(|j| ((i * 7 + j * 3) as f64 * 0.37).sin() * 3.0)
                .collect()
        })
        .collect()
}

/// The joint Jacobians in lanes are the one-pose ones bit for bit: 6 and 7
/// joints, D-H and Hayati, every length around the lane width, ranges that
/// start mid-batch; a range past the poses is an error.
#[test]
fn joint_jacobians_in_lanes_are_the_same_bits() {
    for n in [6usize, 7] {
        for hayati in [false, true] {
            let mut params = nominal(n);
            if hayati {
                params.joints[2].model = JointModel::Hayati;
                params.joints[2].beta = 0.003;
            }
            let k = ArmKernel::new(&params).unwrap();
            let poses = PreparedPoses::new(n, &spread_readings(n, 23)).unwrap();
            for (start, end) in [(0, 0), (0, 3), (0, 4), (0, 9), (3, 23), (1, 18)] {
                let mut seen = start;
                k.for_each_joint_jacobian(&poses, start..end, |i, jq| {
                    assert_eq!(i, seen);
                    seen += 1;
                    let mut one = vec![[0.0; 3]; n];
                    k.joint_jacobian_at(&poses, i, &mut one).unwrap();
                    assert_eq!(jq, &one[..], "n={n} hayati={hayati} pose {i}");
                })
                .unwrap();
                assert_eq!(seen, end);
            }
            assert!(
                k.for_each_joint_jacobian(&poses, 20..24, |_, _| {})
                    .is_err()
            );
        }
    }
}

/// With a Hayati joint the batch paths (SIMD lanes and scalar tail) give the
/// one-pose results of the extended chain bit for bit.
#[test]
fn hayati_batches_equal_single_poses_bit_for_bit() {
    for n in [6usize, 7] {
        let mut params = nominal(n);
        params.joints[2].model = JointModel::Hayati;
        params.joints[2].beta = 0.003;
        params.joints[n - 1].model = JointModel::Hayati;
        params.joints[n - 1].beta = -0.2;
        let arm = ArmKernel::new(&params).unwrap();
        let p = params.param_count();
        for len in [0usize, 3, 4, 5, 9] {
            let q = spread_readings(n, len);
            let poses = PreparedPoses::new(n, &q).unwrap();
            let mut pos = vec![[0.0; 3]; len];
            arm.positions(&poses, 0..len, &mut pos).unwrap();
            let mut batch = Jacobians::new(len, p);
            arm.jacobians(&poses, &mut batch).unwrap();
            let mut seen = 0;
            arm.for_each_jacobian(&poses, 0..len, |i, pi, cols| {
                seen += 1;
                assert_eq!(*pi, batch.position(i));
                for (c, col) in cols.iter().enumerate() {
                    assert_eq!(*col, batch.column(i, c));
                }
            })
            .unwrap();
            assert_eq!(seen, len);
            for i in 0..len {
                assert_eq!(pos[i], arm.position(&q[i]).unwrap());
                let mut one = vec![[0.0; 3]; p];
                let pi = arm.position_jacobian(&q[i], &mut one).unwrap();
                assert_eq!(pi, batch.position(i));
                for (c, col) in one.iter().enumerate() {
                    assert_eq!(*col, batch.column(i, c), "n={n} pose {i} column {c}");
                }
            }
        }
    }
}

/// The batch paths (SIMD lanes plus a scalar tail) give the one-pose results
/// bit for bit, for every batch length around the lane width (pairs of
/// batches, an odd batch, a scalar tail).
#[test]
fn batches_equal_single_poses_bit_for_bit() {
    let params = nominal(6);
    let k = PreparedParams::<6>::new(&params).unwrap();
    let arm = ArmKernel::new(&params).unwrap();
    for len in 0..19 {
        let q: Vec<[f64; 6]> = (0..len)
            .map(|i| std::array::from_fn(|j| ((i * 7 + j * 3) as f64 * 0.37).sin() * 3.0))
            .collect();
        let poses = PreparedPoses::new(6, &q).unwrap();
        let mut pos = vec![[0.0; 3]; len];
        arm.positions(&poses, 0..len, &mut pos).unwrap();
        let mut batch = Jacobians::new(len, 27);
        arm.jacobians(&poses, &mut batch).unwrap();
        let jpos: Vec<[f64; 3]> = (0..len).map(|i| batch.position(i)).collect();
        let jac: Vec<[f64; 3]> = (0..len)
            .flat_map(|i| (0..27).map(move |c| (i, c)))
            .map(|(i, c)| batch.column(i, c))
            .collect();
        let mut seen = 0;
        arm.for_each_jacobian(&poses, 0..len, |i, p, cols| {
            assert_eq!(i, seen);
            seen += 1;
            assert_eq!(*p, jpos[i]);
            assert_eq!(cols, &jac[i * 27..(i + 1) * 27]);
        })
        .unwrap();
        assert_eq!(seen, len);
        for i in 0..len {
            let (cq, sq) = (q[i].map(f64::cos), q[i].map(f64::sin));
            assert_eq!(pos[i], <Dh as Chain<6>>::position(&k, &cq, &sq));
            let mut one = vec![[0.0; 3]; 27];
            let p = <Dh as Chain<6>>::position_jacobian(&k, &cq, &sq, &mut one);
            assert_eq!(p, jpos[i]);
            assert_eq!(one, &jac[i * 27..(i + 1) * 27]);
        }
    }
}

#[test]
fn shape_errors_are_typed_not_panics() {
    let six = nominal(6);
    assert!(PreparedParams::<7>::new(&six).is_err());
    assert!(PreparedPoses::new(6, &[vec![0.0; 5]]).is_err());
    assert!(reference_model::param_jacobian_dual::<31>(&six, &[0.0; 6]).is_err());
    assert!(reference_model::param_jacobian_central(&six, &[0.0; 7], 1e-6).is_err());
    assert_eq!(
        ArmKernel::new(&DhParams::from_slice(&[0.0; 23]).unwrap()),
        Err(kernel::KernelError::Unsupported(5))
    );
}
