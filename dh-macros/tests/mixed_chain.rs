//! The macro expands and compiles for a mixed chain (`joints = "RRPR"`, a
//! SCARA), and its pose is what the textbook matrix product gives.

aacmm_dh_macros::dh_chain! {
    mod scara { joints = "RRPR" }
}

/// The 4×4 tool transform: links with the prismatic reading added to `d`,
/// then the probe's translation.
fn product(
    theta: &[f64],
    alpha: &[f64],
    a: &[f64],
    d: &[f64],
    b: [f64; 3],
    q: &[f64],
) -> [[f64; 4]; 4] {
    let mut t = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let slides = [false, false, true, false];
    for j in 0..q.len() {
        let (angle, dj) = if slides[j] {
            (theta[j], d[j] + q[j])
        } else {
            (theta[j] + q[j], d[j])
        };
        let (s, c) = angle.sin_cos();
        let (sa, ca) = alpha[j].sin_cos();
        let m = [
            [c, -ca * s, sa * s, a[j] * c],
            [s, ca * c, -sa * c, a[j] * s],
            [0.0, sa, ca, dj],
            [0.0, 0.0, 0.0, 1.0],
        ];
        t = [0, 1, 2, 3].map(|r| [0, 1, 2, 3].map(|c| (0..4).map(|k| t[r][k] * m[k][c]).sum()));
    }
    let p = [0, 1, 2].map(|r| t[r][0] * b[0] + t[r][1] * b[1] + t[r][2] * b[2] + t[r][3]);
    for r in 0..3 {
        t[r][3] = p[r];
    }
    t
}

#[test]
fn scara_pose_matches_the_matrix_product() {
    assert_eq!(
        (scara::JOINTS, scara::PARAMS, scara::SHAPE, scara::PRISMATIC),
        (4, 19, "RRPR", 0b0100)
    );
    let theta = [0.1, -0.2, 0.05, 0.3];
    let alpha = [0.0, 3.1, 0.0, 0.01];
    let a = [350.0, 300.0, 0.0, 0.0];
    let d = [400.0, 0.0, -20.0, 50.0];
    let b = [1.0, -2.0, 30.0];
    let q = [0.7, -1.2, 85.0, 2.0];
    let trig = |x: &[f64; 4]| (x.map(f64::cos), x.map(f64::sin));
    let (ct, st) = trig(&theta);
    let (ca, sa) = trig(&alpha);
    // Joint 3 slides: its reading itself travels in `cq`.
    let (mut cq, mut sq) = trig(&q);
    (cq[2], sq[2]) = (q[2], f64::NAN);
    let want = product(&theta, &alpha, &a, &d, b, &q);
    let got = scara::pose(&ct, &st, &ca, &sa, &a, &d, &b, &cq, &sq);
    for r in 0..3 {
        for c in 0..4 {
            assert!((got[r][c] - want[r][c]).abs() < 1e-9, "{got:?} vs {want:?}");
        }
    }
    let p = scara::position(&ct, &st, &ca, &sa, &a, &d, &b, &cq, &sq);
    for r in 0..3 {
        assert!((p[r] - want[r][3]).abs() < 1e-9);
    }
    // ∂/∂q3 of a slide: along the previous z axis, no rotation.
    let mut jac = [[0.0; 6]; 4];
    scara::joint_pose_jacobian(&ct, &st, &ca, &sa, &a, &d, &b, &cq, &sq, &mut jac);
    let h = 1e-4;
    let (mut qp, mut qm) = (q, q);
    qp[2] += h;
    qm[2] -= h;
    let (tp, tm) = (
        product(&theta, &alpha, &a, &d, b, &qp),
        product(&theta, &alpha, &a, &d, b, &qm),
    );
    for r in 0..3 {
        assert!((jac[2][r] - (tp[r][3] - tm[r][3]) / (2.0 * h)).abs() < 1e-8);
        assert_eq!(jac[2][3 + r], 0.0);
    }
}
