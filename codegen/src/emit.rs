//! Kernel expressions → Rust tokens: one `let` per live operation, in
//! evaluation order, generic over the scalar type so the same code runs on
//! `f64`, on SIMD lanes and on dual numbers.

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote};

use crate::chain::KernelExprs;
use crate::graph::{Graph, Id, Input, Node};

fn operand(g: &Graph, id: Id) -> TokenStream {
    match g.node(id) {
        Node::Input(input) => {
            let (array, index) = match input {
                Input::CosQ(j) => ("cq", j),
                Input::SinQ(j) => ("sq", j),
                Input::CosTheta(j) => ("ct", j),
                Input::SinTheta(j) => ("st", j),
                Input::CosAlpha(j) => ("ca", j),
                Input::SinAlpha(j) => ("sa", j),
                Input::A(j) => ("a", j),
                Input::D(j) => ("d", j),
                Input::CosBeta(j) => ("cb", j),
                Input::SinBeta(j) => ("sb", j),
                Input::Probe(k) => ("b", k),
            };
            let array = Ident::new(array, Span::call_site());
            let index = Literal::usize_unsuffixed(index);
            quote!(#array[#index])
        }
        Node::Const(bits) => {
            let value = Literal::f64_suffixed(f64::from_bits(bits));
            quote!(S::from(#value))
        }
        _ => {
            let t = temp(id);
            quote!(#t)
        }
    }
}

fn temp(id: Id) -> Ident {
    format_ident!("t{}", id.index())
}

/// The `let` statement of operation `id` (`None` for an input or constant).
fn let_of(g: &Graph, id: Id) -> Option<TokenStream> {
    let value = match g.node(id) {
        Node::Add(a, b) => {
            let (a, b) = (operand(g, a), operand(g, b));
            quote!(#a + #b)
        }
        Node::Sub(a, b) => {
            let (a, b) = (operand(g, a), operand(g, b));
            quote!(#a - #b)
        }
        Node::Mul(a, b) => {
            let (a, b) = (operand(g, a), operand(g, b));
            quote!(#a * #b)
        }
        Node::Neg(a) => {
            let a = operand(g, a);
            quote!(-#a)
        }
        Node::Input(_) | Node::Const(_) => return None,
    };
    let t = temp(id);
    Some(quote!(let #t: S = #value;))
}

/// The `let` statements that compute `outputs`.
fn body(g: &Graph, outputs: &[Id]) -> TokenStream {
    let lets = g
        .reachable(outputs)
        .into_iter()
        .filter_map(|id| let_of(g, id));
    quote!(#(#lets)*)
}

fn vec3(g: &Graph, v: &[Id; 3]) -> TokenStream {
    let [x, y, z] = v.map(|id| operand(g, id));
    quote!([#x, #y, #z])
}

/// The last operation among `ids` in evaluation order (`None` when all are
/// inputs or constants, available from the start).
fn last_operation(g: &Graph, ids: &[Id]) -> Option<Id> {
    ids.iter()
        .copied()
        .filter(|&id| !matches!(g.node(id), Node::Input(_) | Node::Const(_)))
        .max()
}

/// The `let`s that compute `outputs`, each of `stores` placed right after
/// the `let` of the last value it reads (before the first `let` when it
/// reads only inputs): a column leaves the registers as soon as it is
/// computed instead of waiting, spilled, for the end of the function.
/// The operations are those of [`body`] in the same order, so the values
/// are the same bits.
fn body_with_stores(
    g: &Graph,
    outputs: &[Id],
    mut stores: Vec<(Option<Id>, TokenStream)>,
) -> TokenStream {
    stores.sort_by_key(|(ready, _)| *ready);
    let mut pending = stores.into_iter().peekable();
    let mut code = TokenStream::new();
    while let Some((_, store)) = pending.next_if(|(ready, _)| ready.is_none()) {
        code.extend(store);
    }
    for id in g.reachable(outputs) {
        code.extend(let_of(g, id));
        while let Some((_, store)) = pending.next_if(|(ready, _)| *ready == Some(id)) {
            code.extend(store);
        }
    }
    assert!(pending.next().is_none(), "every store placed");
    code
}

/// The `let`s for `cols` and `position`, with the stores `jac[i] = [..];`
/// among them.
fn columns(g: &Graph, cols: &[[Id; 3]], position: &[Id; 3]) -> TokenStream {
    columns_with(g, cols, &[], 0, position)
}

/// [`columns`] where, for each `j` of `alternatives`, column `offset + j` is
/// `alternatives[j]` when `hayati[j]` (a per-parameter-set flag, the same in
/// every SIMD lane) and `cols[offset + j]` otherwise.
fn columns_with(
    g: &Graph,
    cols: &[[Id; 3]],
    alternatives: &[[Id; 3]],
    offset: usize,
    position: &[Id; 3],
) -> TokenStream {
    let outputs: Vec<Id> = cols
        .iter()
        .chain(alternatives)
        .flatten()
        .chain(position)
        .copied()
        .collect();
    let stores = cols.iter().enumerate().map(|(i, col)| {
        let v = vec3(g, col);
        let store = Literal::usize_unsuffixed(i);
        match i
            .checked_sub(offset)
            .and_then(|j| alternatives.get(j).map(|alt| (j, alt)))
        {
            Some((j, alt)) => {
                let ready = last_operation(g, &[*col, *alt].concat());
                let alt = vec3(g, alt);
                let j = Literal::usize_unsuffixed(j);
                (
                    ready,
                    quote!(jac[#store] = if hayati[#j] { #alt } else { #v };),
                )
            }
            None => (last_operation(g, col), quote!(jac[#store] = #v;)),
        }
    });
    body_with_stores(g, &outputs, stores.collect())
}

/// The items of a generated kernel module (without the `mod` around them).
pub fn kernel_items(k: &KernelExprs) -> TokenStream {
    let g = &k.graph;
    let n = Literal::usize_unsuffixed(k.spec.joints);
    let p = Literal::usize_unsuffixed(k.spec.param_count());
    let probe_arg = if k.spec.probe {
        quote!(b: &[S; 3],)
    } else {
        quote!()
    };
    let beta_arg = if k.spec.hayati {
        quote!(cb: &[S; #n], sb: &[S; #n],)
    } else {
        quote!()
    };
    let args = quote! {
        ct: &[S; #n], st: &[S; #n], ca: &[S; #n], sa: &[S; #n],
        a: &[S; #n], d: &[S; #n], #beta_arg #probe_arg
        cq: &[S; #n], sq: &[S; #n]
    };
    // Only the parameter Jacobian depends on which joints are Hayati.
    let select_arg = if k.spec.hayati {
        quote!(hayati: &[bool; #n],)
    } else {
        quote!()
    };
    let bounds = quote! {
        S: ::core::marker::Copy
            + ::core::ops::Add<Output = S>
            + ::core::ops::Sub<Output = S>
            + ::core::ops::Mul<Output = S>
            + ::core::ops::Neg<Output = S>
            + ::core::convert::From<f64>
    };
    let attrs = quote! {
        #[inline(always)]
        #[allow(clippy::all, clippy::pedantic, clippy::too_many_arguments, unused_variables)]
    };

    let position_body = body(g, &k.position);
    let position = vec3(g, &k.position);

    let jac_body = columns_with(
        g,
        &k.param_jacobian,
        &k.beta_jacobian,
        k.spec.joints,
        &k.frame_position,
    );
    let joint_body = columns(g, &k.joint_jacobian, &k.frame_position);
    let frame_position = vec3(g, &k.frame_position);

    let order = if k.spec.probe {
        "`a1..an, d1..dn, α1..αn, θ1..θn, Bx, By, Bz`"
    } else {
        "`a1..an, d1..dn, α1..αn, θ1..θn`"
    };
    let args_doc = if k.spec.hayati {
        "Arguments: per parameter set `ct, st` (cos, sin of the zero offsets θ), \
        `ca, sa` (cos, sin of the twists α), `a`, `d` (mm), `cb, sb` (cos, sin of the \
        Hayati rotations β about the link's y axis; β = 0 for a D-H joint) and the probe \
        offset `b` (mm); per pose `cq, sq` (cos, sin of the encoder readings)."
    } else {
        "Arguments: per parameter set `ct, st` (cos, sin of the zero offsets θ), \
        `ca, sa` (cos, sin of the twists α), `a`, `d` (mm) and the probe offset `b` (mm); \
        per pose `cq, sq` (cos, sin of the encoder readings)."
    };
    let select_doc = if k.spec.hayati {
        " `hayati[i]` puts `∂p/∂β_i` in joint `i`'s d-slot instead of `∂p/∂d_i`."
    } else {
        ""
    };
    let jac_doc = format!(
        "Probe position and `∂p/∂parameter` into `jac`, one column per parameter in the order {order}.{select_doc} {args_doc}"
    );
    quote! {
        /// Number of joints of this chain.
        pub const JOINTS: usize = #n;
        /// Number of geometric parameters of this chain.
        pub const PARAMS: usize = #p;

        #[doc = "Probe position (mm) by the right-to-left product."]
        #[doc = #args_doc]
        #attrs
        pub fn position<S>(#args) -> [S; 3] where #bounds {
            #position_body
            #position
        }

        #[doc = #jac_doc]
        #attrs
        pub fn position_jacobian<S>(#args, #select_arg jac: &mut [[S; 3]; #p]) -> [S; 3] where #bounds {
            #jac_body
            #frame_position
        }

        #[doc = "Probe position and `∂p/∂q_i` (mm/rad) into `jac`, one column per joint."]
        #[doc = #args_doc]
        #attrs
        pub fn joint_jacobian<S>(#args, jac: &mut [[S; 3]; #n]) -> [S; 3] where #bounds {
            #joint_body
            #frame_position
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::{ChainSpec, expand_chain};

    fn items(joints: usize) -> (KernelExprs, syn::File) {
        items_of(ChainSpec {
            joints,
            probe: true,
            hayati: false,
        })
    }

    fn items_of(spec: ChainSpec) -> (KernelExprs, syn::File) {
        let k = expand_chain(spec);
        let file = syn::parse2(kernel_items(&k)).expect("generated code parses as Rust items");
        (k, file)
    }

    /// Everything `position_jacobian` computes.
    fn jacobian_outputs(k: &KernelExprs) -> Vec<Id> {
        k.param_jacobian
            .iter()
            .flatten()
            .chain(&k.frame_position)
            .copied()
            .collect()
    }

    fn function<'a>(file: &'a syn::File, name: &str) -> &'a syn::ItemFn {
        file.items
            .iter()
            .find_map(|item| match item {
                syn::Item::Fn(f) if f.sig.ident == name => Some(f),
                _ => None,
            })
            .expect("function generated")
    }

    /// One `let` per live operation: nothing is computed twice, nothing dead.
    #[test]
    fn one_let_per_live_operation() {
        let (k, file) = items(6);
        let lets = |name: &str| {
            function(&file, name)
                .block
                .stmts
                .iter()
                .filter(|s| matches!(s, syn::Stmt::Local(_)))
                .count()
        };
        assert_eq!(lets("position"), k.graph.op_count(&k.position).total());
        assert_eq!(
            lets("position_jacobian"),
            k.graph.op_count(&jacobian_outputs(&k)).total()
        );
    }

    /// The straight-line code stays small: a regression guard on the folding
    /// and sharing (the counts are those of the current generator; a change
    /// that grows them should be looked at, not waved through).
    #[test]
    fn operation_counts_stay_small() {
        let (k, _) = items(6);
        let pos = k.graph.op_count(&k.position);
        let jac = k.graph.op_count(&jacobian_outputs(&k));
        // Position: 6 links × (6 angle addition + 14 link update) = 120.
        assert!(pos.total() <= 120, "position: {pos:?}");
        // Frames, then two cross products per joint: 422 today.
        assert!(jac.total() <= 425, "position + jacobian: {jac:?}");
    }

    /// The extended chain costs more than the D-H one (it computes both the
    /// d and the β column of every joint), but stays straight-line code of
    /// the same order: a guard against an accidental blow-up.
    #[test]
    fn extended_chain_stays_small() {
        let (k, file) = items_of(ChainSpec {
            joints: 6,
            probe: true,
            hayati: true,
        });
        let mut outputs = jacobian_outputs(&k);
        outputs.extend(k.beta_jacobian.iter().flatten());
        let jac = k.graph.op_count(&outputs);
        let pos = k.graph.op_count(&k.position);
        println!("extended chain, 6 joints: position {pos:?}, position + jacobian {jac:?}");
        assert!(pos.total() <= 160, "position: {pos:?}");
        assert!(jac.total() <= 620, "position + jacobian: {jac:?}");
        let text = quote!(#file).to_string();
        assert_eq!(text.matches("if hayati [").count(), 6);
    }

    #[test]
    fn no_matrix_products_or_calls_in_the_per_pose_code() {
        for hayati in [false, true] {
            let (_, file) = items_of(ChainSpec {
                joints: 7,
                probe: true,
                hayati,
            });
            calls_free(&file);
        }
    }

    fn calls_free(file: &syn::File) {
        for name in ["position", "position_jacobian", "joint_jacobian"] {
            let text = quote!(#file).to_string();
            assert!(!text.contains("sin ("), "{name}");
            assert!(!text.contains("cos ("), "{name}");
            let block = &function(file, name).block;
            let body = quote!(#block).to_string();
            // Only operators, indexing and `S::from` constants: no calls.
            let calls = body.matches('(').count() - body.matches("S :: from (").count();
            assert_eq!(calls, 0, "{name} has a call: {body}");
        }
    }
}
