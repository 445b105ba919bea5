//! The macro expands and compiles for a 7-axis chain, and its code computes
//! what the textbook matrix product computes.

aacmm_dh_macros::dh_chain! {
    mod arm7 { joints = 7 }
}

aacmm_dh_macros::dh_chain! {
    mod bare3 { joints = 3, probe = false }
}

fn product(theta: &[f64], alpha: &[f64], a: &[f64], d: &[f64], b: [f64; 3], q: &[f64]) -> [f64; 3] {
    // Right to left on the homogeneous point, each link as a full 4×4.
    let mut v = [b[0], b[1], b[2], 1.0];
    for j in (0..q.len()).rev() {
        let (s, c) = (q[j] + theta[j]).sin_cos();
        let (sa, ca) = alpha[j].sin_cos();
        let m = [
            [c, -ca * s, sa * s, a[j] * c],
            [s, ca * c, -sa * c, a[j] * s],
            [0.0, sa, ca, d[j]],
            [0.0, 0.0, 0.0, 1.0],
        ];
        v = [0, 1, 2, 3].map(|r| (0..4).map(|k| m[r][k] * v[k]).sum());
    }
    [v[0], v[1], v[2]]
}

#[test]
fn seven_joint_kernel_matches_the_matrix_product() {
    assert_eq!((arm7::JOINTS, arm7::PARAMS), (7, 31));
    let theta = [0.1, -0.2, 0.3, 0.05, -0.4, 0.2, 0.7];
    let alpha = [-1.5, 1.6, -1.57, 1.5, -1.6, 1.57, 0.3];
    let a = [50.0, -55.0, 35.0, -35.0, 35.0, -35.0, 12.0];
    let d = [375.0, 0.0, 250.0, 0.0, 270.0, 0.0, 40.0];
    let b = [1.0, -2.0, 100.0];
    let q = [0.3, 1.2, -0.7, 2.0, -1.1, 0.4, -2.5];
    let trig = |x: &[f64; 7]| (x.map(f64::cos), x.map(f64::sin));
    let (ct, st) = trig(&theta);
    let (ca, sa) = trig(&alpha);
    let (cq, sq) = trig(&q);
    let want = product(&theta, &alpha, &a, &d, b, &q);
    let got = arm7::position(&ct, &st, &ca, &sa, &a, &d, &b, &cq, &sq);
    let mut jac = [[0.0; 3]; 31];
    let got_frames = arm7::position_jacobian(&ct, &st, &ca, &sa, &a, &d, &b, &cq, &sq, &mut jac);
    for k in 0..3 {
        assert!((got[k] - want[k]).abs() < 1e-9, "{got:?} vs {want:?}");
        assert!((got_frames[k] - want[k]).abs() < 1e-9);
    }
    // ∂p/∂q7 by central differences.
    let mut joint = [[0.0; 3]; 7];
    arm7::joint_jacobian(&ct, &st, &ca, &sa, &a, &d, &b, &cq, &sq, &mut joint);
    let h = 1e-6;
    let mut qp = q;
    qp[6] += h;
    let mut qm = q;
    qm[6] -= h;
    let (pp, pm) = (
        product(&theta, &alpha, &a, &d, b, &qp),
        product(&theta, &alpha, &a, &d, b, &qm),
    );
    for k in 0..3 {
        assert!((joint[6][k] - (pp[k] - pm[k]) / (2.0 * h)).abs() < 1e-6);
    }
}

#[test]
fn chain_without_probe_takes_no_offset() {
    assert_eq!(bare3::PARAMS, 12);
    let z = [0.0f64; 3];
    let one = [1.0f64; 3];
    let a = [10.0, 20.0, 30.0];
    // All angles zero, no twist: the links line up along x.
    let p = bare3::position(&one, &z, &one, &z, &a, &z, &one, &z);
    assert_eq!(p, [60.0, 0.0, 0.0]);
}
