//! `dh_chain!`: generates the closed-form kernel of a Denavit–Hartenberg chain
//! at compile time. All the work is in `aacmm-codegen`; this crate parses,
//! calls it, and turns its errors into `compile_error!` at the offending span.
//!
//! ```
//! aacmm_dh_macros::dh_chain! {
//!     /// A planar-free 2-joint test chain.
//!     pub mod two { joints = 2, probe = true }
//! }
//! // Zero geometry except a probe 10 mm along the last z axis.
//! let z = [0.0f64; 2];
//! let one = [1.0f64; 2];
//! let p = two::position(&one, &z, &one, &z, &z, &z, &[0.0, 0.0, 10.0], &one, &z);
//! assert_eq!(p, [0.0, 0.0, 10.0]);
//! ```

use proc_macro::TokenStream;

/// `dh_chain! { [attrs] [vis] mod NAME { joints = N | "SHAPE"[, probe = true|false][, hayati = true|false][, core = PATH] } }`
/// expands to a module with `JOINTS`, `PARAMS`, `SHAPE`, `PRISMATIC`,
/// `EXTENDED` and the generic functions `position`, `position_jacobian`,
/// `joint_jacobian` (the probe's position, 3-row Jacobians), `pose`,
/// `pose_jacobian` and `joint_pose_jacobian` (the tool frame, 6-row
/// Jacobians). `joints = 6` is six revolute joints; `joints = "PRRRRRR"`
/// names each joint, base first, `R` revolute or `P` prismatic (its
/// reading, mm, goes in `cq` and adds to `d`). With `hayati = true` every
/// link ends in `Ry(β)` (inputs `cb`, `sb`), and the parameter Jacobians
/// take `hayati: &[bool; N]` choosing per joint whether the d-slot's column
/// is `∂/∂d` or `∂/∂β` (see `aacmm_codegen::chain`). With `core = PATH`
/// (the path of aacmm-core) the module also holds a marker type `Kernel`
/// implementing `PATH::kernel::Chain<N>`; aacmm-core's `dh_kernel!` passes
/// it for you.
#[proc_macro]
pub fn dh_chain(input: TokenStream) -> TokenStream {
    aacmm_codegen::expand(input.into())
        .unwrap_or_else(syn::Error::into_compile_error)
        .into()
}
