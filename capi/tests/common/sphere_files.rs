//! The files of a sphere campaign for the C API's tests: the paper's arm
//! with a 6 mm probe ball, and the points it probes on simulated spheres.

use std::ffi::CString;
use std::path::{Path, PathBuf};

use aacmm_core::domain::Arm;
use aacmm_core::io::{AngleUnit, LengthUnit, arm_to_toml, spheres::write_spheres};
use aacmm_core::params::DhParams;
use aacmm_core::simulate::{SphereSettings, simulate_spheres};

/// The paper's nominal arm with a 6 mm probe ball.
pub fn arm() -> Arm {
    Arm {
        ball_diameter_mm: Some(6.0),
        ..Arm::without_limits("paper", DhParams::paper_nominal())
    }
}

/// [`arm`]'s file and the spheres it probes as `settings` say, written
/// into a directory of their own named by `name`: the two paths, and the
/// directory (for the caller to remove).
pub fn files(name: &str, settings: &SphereSettings) -> (CString, CString, PathBuf) {
    let dir = std::env::temp_dir().join(format!("aacmm-capi-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let arm_path = dir.join("arm.toml");
    std::fs::write(
        &arm_path,
        arm_to_toml(&arm(), LengthUnit::Mm, AngleUnit::Deg),
    )
    .unwrap();
    let c = simulate_spheres(&arm(), settings).unwrap();
    let mut text = Vec::new();
    write_spheres(&mut text, &c.spheres, AngleUnit::Deg).unwrap();
    let spheres = dir.join("spheres.csv");
    std::fs::write(&spheres, text).unwrap();
    let cs = |p: &Path| CString::new(p.to_str().unwrap()).unwrap();
    (cs(&arm_path), cs(&spheres), dir)
}
