//! The kernels against their oracles, over random parameter sets near and
//! far from nominal (D-H and Hayati joints) and random readings: the
//! generated kernels of every shipped shape, and the generic kernel on those
//! shapes and on chains the library ships no kernel for (1 to 12 joints,
//! prismatic joints anywhere). Positions and the tool's orientation against
//! the reference model (an independent product of 4×4 matrices); the 3-row
//! and 6-row Jacobians, of the parameters and of the joints, against
//! num-dual autodiff and central differences of that product; batches in
//! SIMD lanes against one pose, bit for bit.

use aacmm_core::kernel::{
    self, ArmKernel, Chain, Generic, Jacobians, KernelKind, Pose, PreparedParams, PreparedPoses,
    SHIPPED_SHAPES,
};
use aacmm_core::params::{ChainShape, DhJoint, DhParams, JointKind, JointModel};
use aacmm_core::reference_model;
use proptest::prelude::*;
use std::f64::consts::PI;

/// The shipped 6- and 7-joint chains, D-H and extended, generated here by
/// the generator the library's own (internal) kernels come from: the same
/// code.
mod shipped {
    aacmm_core::dh_kernel! { pub mod arm6 { joints = "RRRRRR" } }
    aacmm_core::dh_kernel! { pub mod arm6h { joints = "RRRRRR", hayati = true } }
    aacmm_core::dh_kernel! { pub mod arm7 { joints = "RRRRRRR" } }
    aacmm_core::dh_kernel! { pub mod arm7h { joints = "RRRRRRR", hayati = true } }
}

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

/// The nominal arm of a shape: the paper's arm (with a wrist link for 7R),
/// a prismatic track or lift before it, a SCARA, the paper's first five
/// joints; any other shape a chain of alternating twists.
fn nominal_of(shape: ChainShape) -> DhParams {
    let h = PI / 2.0;
    let slide = |alpha: f64, theta: f64| {
        DhJoint::dh(0.0, 300.0, alpha, theta).with_kind(JointKind::Prismatic)
    };
    let text = shape.to_string();
    let mut arm = match text.as_str() {
        "RRRRRR" | "RRRRRRR" => nominal(shape.joints()),
        "PRRRRRR" | "PRRRRRRR" => {
            let mut arm = nominal(shape.joints() - 1);
            arm.joints.insert(0, slide(h, h));
            arm
        }
        "RRRRR" => {
            let mut arm = nominal(6);
            arm.joints.pop();
            arm
        }
        "RRPR" => DhParams {
            joints: vec![
                DhJoint::dh(350.0, 400.0, 0.0, 0.0),
                DhJoint::dh(300.0, 0.0, PI, 0.0),
                slide(0.0, 0.0),
                DhJoint::dh(0.0, 50.0, 0.0, 0.0),
            ],
            probe: [0.0, 0.0, 30.0],
        },
        _ => DhParams {
            joints: shape
                .kinds()
                .enumerate()
                .map(|(i, kind)| {
                    let alpha = if i % 2 == 0 { -h } else { h };
                    DhJoint::dh(40.0, 150.0, alpha, 0.0).with_kind(kind)
                })
                .collect(),
            probe: [0.0, 0.0, 100.0],
        },
    };
    for (j, kind) in arm.joints.iter_mut().zip(shape.kinds()) {
        j.kind = kind;
    }
    arm
}

/// Parameter sets of `shape` near nominal (small errors, the calibration
/// case) or far (anything: a newly assembled arm, a wrong model).
fn arm(shape: ChainShape) -> impl Strategy<Value = DhParams> {
    let n = shape.joints();
    let base = nominal_of(shape);
    let near = prop::collection::vec(-1.0f64..1.0, 4 * n + 3).prop_map(move |e| {
        let mut p = base.to_vec();
        for (i, (v, e)) in p.iter_mut().zip(e).enumerate() {
            let angle = (2 * n..4 * n).contains(&i);
            *v += if angle { 0.01 * e } else { 2.0 * e };
        }
        base.with_values(&p).expect("4n + 3 values")
    });
    let base = nominal_of(shape);
    let far = (
        prop::collection::vec(-500.0f64..500.0, 2 * n),
        prop::collection::vec(-PI..PI, 2 * n),
        prop::collection::vec(-200.0f64..200.0, 3),
    )
        .prop_map(move |(len, ang, b)| {
            let mut v = len;
            v.extend(ang);
            v.extend(b);
            base.with_values(&v).expect("4n + 3 values")
        });
    prop_oneof![near, far]
}

/// [`arm`] with a random subset of joints made Hayati, each with a random β
/// (small, the near-parallel case, or anything).
fn hayati_arm(shape: ChainShape) -> impl Strategy<Value = DhParams> {
    let n = shape.joints();
    (
        arm(shape),
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

/// Readings of `shape`: ±π rad turning, ±500 mm sliding.
fn readings(shape: ChainShape) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-1.0f64..1.0, shape.joints()).prop_map(move |u| {
        (u.iter().enumerate())
            .map(|(j, v)| {
                if shape.is_prismatic(j) {
                    500.0 * v
                } else {
                    PI * v
                }
            })
            .collect()
    })
}

/// Largest column norm: the scale the Jacobian tolerances are relative to.
fn scale<const R: usize>(cols: &[[f64; R]]) -> f64 {
    cols.iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .fold(1.0, f64::max)
}

fn check_columns<const R: usize>(
    got: &[[f64; R]],
    want: &[[f64; R]],
    rel: f64,
) -> Result<(), TestCaseError> {
    prop_assert_eq!(got.len(), want.len());
    for (c, (g, w)) in got.iter().zip(want).enumerate() {
        let s = scale(std::slice::from_ref(w)).max(1.0);
        for r in 0..R {
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

/// The reference tool pose of `params` at `q`.
fn reference_pose(params: &DhParams, q: &[f64]) -> Pose {
    let kinds: Vec<JointKind> = params.joints.iter().map(|j| j.kind).collect();
    let t = reference_model::tool_with(&params.to_vec(), q, &params.models(), &kinds);
    Pose::from_transform(std::array::from_fn(|r| std::array::from_fn(|c| t[(r, c)])))
}

fn check_pose(got: &Pose, want: &Pose) -> Result<(), TestCaseError> {
    for r in 0..3 {
        prop_assert!(
            (got.position[r] - want.position[r]).abs() <= 1e-9,
            "{:?} vs {:?}",
            got,
            want
        );
        for c in 0..3 {
            prop_assert!((got.rotation[r][c] - want.rotation[r][c]).abs() <= 1e-12);
        }
    }
    Ok(())
}

/// What the oracles say of `params` at `q`: the pose, and the 6-row
/// parameter and joint Jacobians by num-dual and by central differences.
struct Oracle {
    pose: Pose,
    dual: Vec<[f64; 6]>,
    central: Vec<[f64; 6]>,
    dual_q: Vec<[f64; 6]>,
    central_q: Vec<[f64; 6]>,
}

impl Oracle {
    fn new<const N: usize, const P: usize>(params: &DhParams, q: &[f64]) -> Oracle {
        Oracle {
            pose: reference_pose(params, q),
            dual: reference_model::param_pose_jacobian_dual::<P>(params, q).unwrap(),
            central: reference_model::param_pose_jacobian_central(params, q, 1e-5).unwrap(),
            dual_q: reference_model::joint_pose_jacobian_dual::<N>(params, q).unwrap(),
            central_q: reference_model::joint_pose_jacobian_central(params, q, 1e-5).unwrap(),
        }
    }
}

/// The position rows of 6-row columns.
fn three(cols: &[[f64; 6]]) -> Vec<[f64; 3]> {
    cols.iter().map(|c| [c[0], c[1], c[2]]).collect()
}

/// What `k` computes at `q` against the oracles: position and pose, the
/// parameter Jacobians (3 and 6 rows, one pose and a batch) and the joint
/// Jacobians (3 and 6 rows).
fn check_kernel<const N: usize, const P: usize>(
    k: &ArmKernel,
    q: &[f64],
    o: &Oracle,
) -> Result<(), TestCaseError> {
    let want = &o.pose;
    check_pose(&k.pose(q).unwrap(), want)?;
    let p = k.position(q).unwrap();
    check_pose(
        &Pose {
            position: p,
            ..*want
        },
        want,
    )?;

    let poses = PreparedPoses::for_shape(k.shape(), &[q]).unwrap();
    let mut batch = Jacobians::new(1, P);
    k.jacobians(&poses, &mut batch).unwrap();
    prop_assert_eq!(
        batch.position(0),
        k.position_jacobian(q, &mut [[0.0; 3]; P]).unwrap()
    );
    let jac: Vec<[f64; 3]> = (0..P).map(|c| batch.column(0, c)).collect();
    check_columns(&jac, &three(&o.dual), 1e-9)?;
    check_columns(&jac, &three(&o.central), 1e-6)?;
    let mut jac6 = vec![[0.0; 6]; P];
    check_pose(&k.pose_jacobian(q, &mut jac6).unwrap(), want)?;
    check_columns(&jac6, &o.dual, 1e-9)?;
    check_columns(&jac6, &o.central, 1e-6)?;
    prop_assert_eq!(three(&jac6), jac);

    let mut jq = vec![[0.0; 3]; N];
    k.joint_jacobian(q, &mut jq).unwrap();
    let mut jq6 = vec![[0.0; 6]; N];
    check_pose(&k.joint_pose_jacobian(q, &mut jq6).unwrap(), want)?;
    check_columns(&jq6, &o.dual_q, 1e-9)?;
    check_columns(&jq6, &o.central_q, 1e-6)?;
    prop_assert_eq!(three(&jq6), jq);
    Ok(())
}

/// The arm's own kernel (generated for a shipped shape) and the generic
/// one on the same arm, each against the oracles.
fn kernels_match<const N: usize, const P: usize>(
    params: &DhParams,
    q: &[f64],
) -> Result<(), TestCaseError> {
    let own = ArmKernel::new(params).unwrap();
    let shipped = SHIPPED_SHAPES.contains(&own.shape().to_string().as_str());
    let kind = if shipped {
        KernelKind::Generated
    } else {
        KernelKind::Generic
    };
    prop_assert_eq!(own.kind(), kind);
    let oracle = Oracle::new::<N, P>(params, q);
    check_kernel::<N, P>(&own, q, &oracle)?;
    if shipped {
        let generic = ArmKernel::with_chain::<Generic, N>(params).unwrap();
        check_kernel::<N, P>(&generic, q, &oracle)?;
    }
    Ok(())
}

/// One proptest per shape: D-H arms and arms with Hayati joints.
macro_rules! shape_tests {
    ($($name:ident: $shape:literal, $n:literal, $p:literal, $cases:literal, $hayati_cases:literal;)*) => {$(
        mod $name {
            use super::*;

            fn shape() -> ChainShape {
                $shape.parse().unwrap()
            }

            proptest! {
                #![proptest_config(ProptestConfig::with_cases($cases))]

                #[test]
                fn dh_kernels_match_oracles(params in arm(shape()), q in readings(shape())) {
                    kernels_match::<$n, $p>(&params, &q)?;
                }
            }

            proptest! {
                #![proptest_config(ProptestConfig::with_cases($hayati_cases))]

                #[test]
                fn hayati_kernels_match_oracles(params in hayati_arm(shape()), q in readings(shape())) {
                    kernels_match::<$n, $p>(&params, &q)?;
                }
            }
        }
    )*};
}

shape_tests! {
    // The shipped shapes (cases: D-H arms, arms with Hayati joints; the
    // measuring arms' as many as before the other shapes came).
    six_joints: "RRRRRR", 6, 27, 2000, 1000;
    seven_joints: "RRRRRRR", 7, 31, 2000, 1000;
    five_joints: "RRRRR", 5, 23, 300, 300;
    track_and_six: "PRRRRRR", 7, 31, 500, 500;
    lift_and_seven: "PRRRRRRR", 8, 35, 500, 500;
    scara: "RRPR", 4, 19, 500, 500;
    // Shapes without a generated kernel: the generic one alone.
    one_slide: "P", 1, 7, 200, 200;
    one_turn: "R", 1, 7, 200, 200;
    gantry: "PPPR", 4, 19, 200, 200;
    slide_second: "RPRRRRRR", 8, 35, 200, 200;
    nine: "RRRPRRRRR", 9, 39, 100, 100;
    twelve_turns: "RRRRRRRRRRRR", 12, 51, 50, 50;
    twelve_mixed: "RPRPRPRPRPRP", 12, 51, 50, 50;
}

/// The generated kernels and the generic one agree on every shipped shape
/// (each is checked against the oracles above; this compares them
/// directly, columns included, at nominal).
#[test]
fn generated_and_generic_kernels_agree() {
    for text in SHIPPED_SHAPES {
        let shape: ChainShape = text.parse().unwrap();
        let params = nominal_of(shape);
        let own = ArmKernel::new(&params).unwrap();
        assert_eq!(own.kind(), KernelKind::Generated);
        let generic = generic_kernel(&params);
        for q in spread_readings(shape, 9) {
            let (a, b) = (own.pose(&q).unwrap(), generic.pose(&q).unwrap());
            for r in 0..3 {
                assert!((a.position[r] - b.position[r]).abs() < 1e-9, "{text}");
            }
            let p = params.param_count();
            let (mut x, mut y) = (vec![[0.0; 6]; p], vec![[0.0; 6]; p]);
            own.pose_jacobian(&q, &mut x).unwrap();
            generic.pose_jacobian(&q, &mut y).unwrap();
            for (cx, cy) in x.iter().zip(&y) {
                for r in 0..6 {
                    assert!((cx[r] - cy[r]).abs() < 1e-9, "{text}: {cx:?} vs {cy:?}");
                }
            }
        }
    }
}

/// The generic kernel of an arm of any joint count.
fn generic_kernel(params: &DhParams) -> ArmKernel {
    macro_rules! by_count {
        ($($n:literal),*) => {
            match params.joint_count() {
                $($n => ArmKernel::with_chain::<Generic, $n>(params).unwrap(),)*
                n => panic!("{n} joints"),
            }
        };
    }
    by_count!(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12)
}

/// `len` poses of `shape`'s readings (±3 rad, ±300 mm), spread out.
fn spread_readings(shape: ChainShape, len: usize) -> Vec<Vec<f64>> {
    (0..len)
        .map(|i| {
            (0..shape.joints())
                .map(|j| {
                    let v = ((i * 7 + j * 3) as f64 * 0.37).sin();
                    if shape.is_prismatic(j) {
                        300.0 * v
                    } else {
                        3.0 * v
                    }
                })
                .collect()
        })
        .collect()
}

/// The arms the bit-identity tests run: every shipped shape and a few
/// unshipped ones, D-H and with Hayati joints (at the base, in the middle
/// and at the end).
fn lane_arms() -> Vec<DhParams> {
    let shapes = SHIPPED_SHAPES
        .iter()
        .copied()
        .chain(["RPRRRRRR", "PPPR", "R", "RPRPRPRPRPRP"]);
    let mut arms = Vec::new();
    for text in shapes {
        let params = nominal_of(text.parse().unwrap());
        let n = params.joint_count();
        let mut hayati = params.clone();
        for (j, beta) in [(0, 0.003), (n / 2, -0.2), (n - 1, 0.01)] {
            hayati.joints[j].model = JointModel::Hayati;
            hayati.joints[j].beta = beta;
        }
        arms.push(params);
        arms.push(hayati);
    }
    arms
}

/// The batch paths (SIMD lanes, pairs of batches, an odd batch and a scalar
/// tail) give the one-pose results bit for bit, for every batch length
/// around the lane width: positions, poses, parameter Jacobians (3-row in
/// both batch forms, 6-row), joint Jacobians.
#[test]
fn batches_equal_single_poses_bit_for_bit() {
    for params in lane_arms() {
        let arm = ArmKernel::new(&params).unwrap();
        let shape = arm.shape();
        let p = params.param_count();
        for len in [0usize, 1, 3, 4, 5, 8, 9, 13, 18] {
            let q = spread_readings(shape, len);
            let poses = PreparedPoses::for_shape(shape, &q).unwrap();
            let mut pos = vec![[0.0; 3]; len];
            arm.positions(&poses, 0..len, &mut pos).unwrap();
            let mut tools = vec![Pose::default(); len];
            arm.poses(&poses, 0..len, &mut tools).unwrap();
            let mut batch = Jacobians::new(len, p);
            arm.jacobians(&poses, &mut batch).unwrap();
            let mut seen = 0;
            arm.for_each_jacobian(&poses, 0..len, |i, pi, cols| {
                assert_eq!(i, seen);
                seen += 1;
                assert_eq!(*pi, batch.position(i));
                for (c, col) in cols.iter().enumerate() {
                    assert_eq!(*col, batch.column(i, c));
                }
            })
            .unwrap();
            assert_eq!(seen, len);
            let mut six = Vec::new();
            arm.for_each_pose_jacobian(&poses, 0..len, |i, t, cols| {
                assert_eq!(*t, tools[i]);
                six.push(cols.to_vec());
            })
            .unwrap();
            for i in 0..len {
                assert_eq!(pos[i], arm.position(&q[i]).unwrap(), "{shape} pose {i}");
                assert_eq!(tools[i], arm.pose(&q[i]).unwrap());
                let mut one = vec![[0.0; 3]; p];
                let pi = arm.position_jacobian(&q[i], &mut one).unwrap();
                assert_eq!(pi, batch.position(i));
                for (c, col) in one.iter().enumerate() {
                    assert_eq!(*col, batch.column(i, c), "{shape} pose {i} column {c}");
                }
                let mut one6 = vec![[0.0; 6]; p];
                assert_eq!(arm.pose_jacobian(&q[i], &mut one6).unwrap(), tools[i]);
                assert_eq!(one6, six[i]);
            }
        }
    }
}

/// The joint Jacobians in lanes are the one-pose ones bit for bit, ranges
/// that start mid-batch included; a range past the poses is an error.
#[test]
fn joint_jacobians_in_lanes_are_the_same_bits() {
    for params in lane_arms() {
        let k = ArmKernel::new(&params).unwrap();
        let n = params.joint_count();
        let q = spread_readings(k.shape(), 23);
        let poses = PreparedPoses::for_shape(k.shape(), &q).unwrap();
        for (start, end) in [(0, 0), (0, 3), (0, 4), (0, 9), (3, 23), (1, 18)] {
            let mut seen = start;
            k.for_each_joint_jacobian(&poses, start..end, |i, jq| {
                assert_eq!(i, seen);
                seen += 1;
                let mut one = vec![[0.0; 3]; n];
                k.joint_jacobian_at(&poses, i, &mut one).unwrap();
                assert_eq!(jq, &one[..], "{} pose {i}", k.shape());
                let mut two = vec![[0.0; 3]; n];
                k.joint_jacobian(&q[i], &mut two).unwrap();
                assert_eq!(one, two);
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

/// The extended chain with no Hayati joint is the D-H chain (it is only
/// picked when a joint is Hayati, but it must agree where both apply).
#[test]
fn extended_chain_without_hayati_joints_is_the_dh_chain() {
    for n in [6, 7] {
        let params = nominal(n);
        for q in spread_readings(ChainShape::revolute(n).unwrap(), 20) {
            let (pd, ph) = if n == 6 {
                let k = PreparedParams::<6>::new(&params).unwrap();
                let q: [f64; 6] = q.try_into().unwrap();
                (
                    kernel::position::<shipped::arm6::Kernel, 6>(&k, &q),
                    kernel::position::<shipped::arm6h::Kernel, 6>(&k, &q),
                )
            } else {
                let k = PreparedParams::<7>::new(&params).unwrap();
                let q: [f64; 7] = q.try_into().unwrap();
                let (cq, sq) = k.joint_inputs(&q);
                let (mut a, mut b) = (vec![[0.0; 3]; 31], vec![[0.0; 3]; 31]);
                let pd =
                    <shipped::arm7::Kernel as Chain<7>>::position_jacobian(&k, &cq, &sq, &mut a);
                let ph =
                    <shipped::arm7h::Kernel as Chain<7>>::position_jacobian(&k, &cq, &sq, &mut b);
                for (x, y) in a.iter().zip(&b) {
                    for r in 0..3 {
                        assert!((x[r] - y[r]).abs() < 1e-9);
                    }
                }
                (pd, ph)
            };
            for r in 0..3 {
                assert!((pd[r] - ph[r]).abs() < 1e-9);
            }
        }
    }
}

/// A prismatic joint at any place of a random chain moves the probe along
/// the previous joint's z axis by its reading: the kernel against a 4×4
/// product written here, independent of the library's reference model.
#[test]
fn random_mixed_chains_match_a_matrix_product() {
    let mut state = 0x39u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for trial in 0..200 {
        let n = 1 + trial % 12;
        let joints: Vec<DhJoint> = (0..n)
            .map(|_| {
                let kind = if next() > 0.0 {
                    JointKind::Prismatic
                } else {
                    JointKind::Revolute
                };
                DhJoint::dh(300.0 * next(), 300.0 * next(), PI * next(), PI * next())
                    .with_kind(kind)
            })
            .collect();
        let params = DhParams {
            joints,
            probe: [100.0 * next(), 100.0 * next(), 100.0 * next()],
        };
        let q: Vec<f64> = (params.joints.iter())
            .map(|j| match j.kind {
                JointKind::Prismatic => 400.0 * next(),
                JointKind::Revolute => PI * next(),
            })
            .collect();
        let mut t = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        for (j, qj) in params.joints.iter().zip(&q) {
            let (angle, d) = match j.kind {
                JointKind::Revolute => (j.theta + qj, j.d),
                JointKind::Prismatic => (j.theta, j.d + qj),
            };
            let (s, c) = angle.sin_cos();
            let (sa, ca) = j.alpha.sin_cos();
            let m = [
                [c, -ca * s, sa * s, j.a * c],
                [s, ca * c, -sa * c, j.a * s],
                [0.0, sa, ca, d],
            ];
            t = std::array::from_fn(|r| {
                std::array::from_fn(|col| {
                    let last = if col == 3 { t[r][3] } else { 0.0 };
                    (0..3).map(|k| t[r][k] * m[k][col]).sum::<f64>() + last
                })
            });
        }
        let b = params.probe;
        let want: [f64; 3] =
            std::array::from_fn(|r| (0..3).map(|k| t[r][k] * b[k]).sum::<f64>() + t[r][3]);
        let k = ArmKernel::new(&params).unwrap();
        let got = k.pose(&q).unwrap();
        let p = k.position(&q).unwrap();
        for (r, row) in t.iter().enumerate() {
            assert!(
                (got.position[r] - want[r]).abs() < 1e-9 && (p[r] - want[r]).abs() < 1e-9,
                "{}: {got:?} vs {want:?}",
                k.shape()
            );
            for (c, v) in row[..3].iter().enumerate() {
                assert!((got.rotation[r][c] - v).abs() < 1e-12);
            }
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
        ArmKernel::new(&DhParams::from_slice(&[0.0; 55]).unwrap()),
        Err(kernel::KernelError::Unsupported(13))
    );
    let mut sliding = six.clone();
    sliding.joints[0].kind = JointKind::Prismatic;
    let k = ArmKernel::new(&sliding).unwrap();
    assert_eq!(k.kind(), KernelKind::Generic);
    let revolute = PreparedPoses::new(6, &[[0.0; 6]]).unwrap();
    let e = k.positions(&revolute, 0..1, &mut [[0.0; 3]]).unwrap_err();
    assert_eq!(
        e.to_string(),
        "the arm's chain is PRRRRR but the data is RRRRRR"
    );
}
