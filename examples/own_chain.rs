//! A chain shape of your own, generated in your crate and handed to the
//! library: a cylindrical robot with a wrist, `RPPRRR` (a turning column, a
//! lift and a radial slide, then three revolute wrist joints), which the
//! library ships no generated kernel for.
//!
//! ```text
//! cargo run --release --example own_chain
//! ```
//!
//! `aacmm_core::dh_kernel!` expands the chain at compile time into the
//! same closed-form code the library's shipped shapes have (position, tool
//! pose and their Jacobians, generic over the scalar so it runs in SIMD
//! lanes), with a marker type `Kernel` that `ArmKernel::with_chain` takes.
//! The program checks that it computes what the library's own kernel for
//! this shape (the generic, closed-form per-joint one) computes — position,
//! pose and every Jacobian column — and prints how long each takes per
//! pose.

use std::f64::consts::FRAC_PI_2;
use std::time::Instant;

use aacmm_core::kernel::{ArmKernel, Jacobians, KernelKind, PreparedPoses};
use aacmm_core::params::{DhJoint, DhParams, JointKind};

aacmm_core::dh_kernel! {
    /// A cylindrical robot with a spherical wrist: column, lift, radial
    /// slide, three wrist joints.
    pub mod cylindrical { joints = "RPPRRR" }
}

/// The robot's nominal geometry (mm, rad): the lift along the column's
/// axis, the radial slide perpendicular to it, a wrist of ∓90° twists.
fn robot() -> DhParams {
    let slide = |d: f64, alpha: f64, theta: f64| {
        DhJoint::dh(0.0, d, alpha, theta).with_kind(JointKind::Prismatic)
    };
    DhParams {
        joints: vec![
            DhJoint::dh(0.0, 350.0, 0.0, 0.0),
            slide(200.0, -FRAC_PI_2, 0.0),
            slide(150.0, 0.0, 0.0),
            DhJoint::dh(0.0, 0.0, -FRAC_PI_2, 0.0),
            DhJoint::dh(0.0, 0.0, FRAC_PI_2, 0.0),
            DhJoint::dh(0.0, 80.0, 0.0, 0.0),
        ],
        probe: [0.0, 0.0, 120.0],
    }
}

/// Readings of pose `i`: angles (rad) for the turning joints, strokes
/// (mm) for the slides.
fn readings(i: usize) -> [f64; 6] {
    let s = |k: usize| ((i * 7 + k * 3) as f64 * 0.37).sin();
    [
        3.0 * s(0),
        300.0 * s(1),
        250.0 * s(2),
        3.0 * s(3),
        1.5 * s(4),
        3.0 * s(5),
    ]
}

fn main() {
    let arm = robot();
    let mine = ArmKernel::with_chain::<cylindrical::Kernel, 6>(&arm).expect("the robot's shape");
    let library = ArmKernel::new(&arm).expect("a chain of 6 joints");
    assert_eq!(mine.kind(), KernelKind::User);
    assert_eq!(library.kind(), KernelKind::Generic, "RPPRRR is not shipped");
    println!(
        "{} joints, shape {}: your generated kernel against the library's generic one",
        arm.joint_count(),
        mine.shape()
    );

    // One pose at a time: position, pose, every Jacobian column.
    let p = arm.param_count();
    let mut worst = 0.0f64;
    for i in 0..200 {
        let q = readings(i);
        let (a, b) = (mine.pose(&q).unwrap(), library.pose(&q).unwrap());
        let rows = a.rotation.iter().flatten().zip(b.rotation.iter().flatten());
        let pos = a.position.iter().zip(&b.position);
        for (x, y) in rows.chain(pos) {
            worst = worst.max((x - y).abs());
        }
        let (mut ja, mut jb) = (vec![[0.0; 6]; p], vec![[0.0; 6]; p]);
        mine.pose_jacobian(&q, &mut ja).unwrap();
        library.pose_jacobian(&q, &mut jb).unwrap();
        let (mut qa, mut qb) = (vec![[0.0; 6]; 6], vec![[0.0; 6]; 6]);
        mine.joint_pose_jacobian(&q, &mut qa).unwrap();
        library.joint_pose_jacobian(&q, &mut qb).unwrap();
        for (x, y) in ja.iter().chain(&qa).zip(jb.iter().chain(&qb)) {
            for r in 0..6 {
                worst = worst.max((x[r] - y[r]).abs());
            }
        }
    }
    println!("largest difference over 200 poses (mm, rad, their ratios): {worst:.2e}");
    assert!(worst < 1e-9, "the two kernels disagree by {worst}");

    // A batch: positions and parameter Jacobians in SIMD lanes.
    let q: Vec<[f64; 6]> = (0..100_000).map(readings).collect();
    let poses = PreparedPoses::for_shape(mine.shape(), &q).unwrap();
    for (name, k) in [
        ("yours (generated)", &mine),
        ("library (generic)", &library),
    ] {
        let mut out = Jacobians::new(q.len(), p);
        let start = Instant::now();
        for _ in 0..5 {
            k.jacobians(&poses, &mut out).unwrap();
        }
        let per_pose = start.elapsed().as_secs_f64() / (5.0 * q.len() as f64);
        println!(
            "{name}: position and Jacobian {:.0} ns a pose",
            per_pose * 1e9
        );
    }
}
