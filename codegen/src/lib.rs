//! The code generator behind `aacmm-dh-macros`: a D-H chain description is
//! expanded symbolically ([`chain`]) into a folded, shared expression DAG
//! ([`graph`]) and emitted as straight-line Rust ([`emit`]). An ordinary
//! library, so all of it is tested without a compiler in the loop; the
//! proc-macro only parses and reports.

pub mod chain;
pub mod emit;
pub mod graph;
pub mod input;

pub use chain::{ChainSpec, KernelExprs, expand_chain};

use proc_macro2::TokenStream;

/// Parses a `dh_chain!` invocation and returns the generated module.
///
/// ```
/// let out = aacmm_codegen::expand(quote::quote! {
///     pub mod arm6 { joints = 6, probe = true }
/// })
/// .unwrap()
/// .to_string();
/// assert!(out.contains("pub mod arm6"));
/// assert!(out.contains("pub const PARAMS : usize = 27"));
/// // No trig calls: the per-pose code only combines prepared sin/cos.
/// assert!(!out.contains("sin (") && !out.contains("cos (") && !out.contains("sin_cos"));
/// ```
pub fn expand(tokens: TokenStream) -> syn::Result<TokenStream> {
    let input: input::ChainMacroInput = syn::parse2(tokens)?;
    Ok(input.generate())
}
