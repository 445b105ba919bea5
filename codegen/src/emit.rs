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
                // A prismatic joint's reading travels where a revolute
                // joint's cos does; its `sq` slot is not read.
                Input::Q(j) => ("cq", j),
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

/// An array literal of the values `v`.
fn vector(g: &Graph, v: &[Id]) -> TokenStream {
    let items = v.iter().map(|&id| operand(g, id));
    quote!([#(#items),*])
}

fn vec3(g: &Graph, v: &[Id; 3]) -> TokenStream {
    vector(g, v)
}

/// The top three rows of the tool's homogeneous transform, `[R | p]`.
fn transform(g: &Graph, rotation: &[[Id; 3]; 3], p: &[Id; 3]) -> TokenStream {
    let rows = (0..3).map(|r| vector(g, &[rotation[r][0], rotation[r][1], rotation[r][2], p[r]]));
    quote!([#(#rows),*])
}

/// The ids of the tool's transform.
fn transform_ids(k: &KernelExprs) -> Vec<Id> {
    k.rotation
        .iter()
        .flatten()
        .chain(&k.frame_position)
        .copied()
        .collect()
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

/// The `let`s for `cols` and `returned`, with the stores `jac[i] = [..];`
/// among them.
fn columns<const R: usize>(g: &Graph, cols: &[[Id; R]], returned: &[Id]) -> TokenStream {
    columns_with(g, cols, &[], 0, returned)
}

/// [`columns`] where, for each `j` of `alternatives`, column `offset + j` is
/// `alternatives[j]` when `hayati[j]` (a per-parameter-set flag, the same in
/// every SIMD lane) and `cols[offset + j]` otherwise.
fn columns_with<const R: usize>(
    g: &Graph,
    cols: &[[Id; R]],
    alternatives: &[[Id; R]],
    offset: usize,
    returned: &[Id],
) -> TokenStream {
    let outputs: Vec<Id> = cols
        .iter()
        .chain(alternatives)
        .flatten()
        .chain(returned)
        .copied()
        .collect();
    let stores = cols.iter().enumerate().map(|(i, col)| {
        let v = vector(g, col);
        let store = Literal::usize_unsuffixed(i);
        match i
            .checked_sub(offset)
            .and_then(|j| alternatives.get(j).map(|alt| (j, alt)))
        {
            Some((j, alt)) => {
                let ready = last_operation(g, &[*col, *alt].concat());
                let alt = vector(g, alt);
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

/// What every generated function shares: its arguments, bounds and
/// attributes, and the documentation of the arguments.
struct Signature {
    args: TokenStream,
    select_arg: TokenStream,
    bounds: TokenStream,
    attrs: TokenStream,
    args_doc: String,
    select_doc: &'static str,
    order: &'static str,
}

impl Signature {
    fn of(k: &KernelExprs) -> Signature {
        let n = Literal::usize_unsuffixed(k.spec.joints);
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
        let per_pose = if k.spec.prismatic == 0 {
            "per pose `cq, sq` (cos, sin of the encoder readings)."
        } else {
            "per pose `cq, sq`: for a revolute joint the cos and sin of its reading, for a \
             prismatic joint its reading itself (mm, added to `d`) in `cq` (its `sq` is not read)."
        };
        let args_doc = if k.spec.hayati {
            format!(
                "Arguments: per parameter set `ct, st` (cos, sin of the zero offsets θ), \
                `ca, sa` (cos, sin of the twists α), `a`, `d` (mm), `cb, sb` (cos, sin of the \
                Hayati rotations β about the link's y axis; β = 0 for a D-H joint) and the probe \
                offset `b` (mm); {per_pose}"
            )
        } else {
            format!(
                "Arguments: per parameter set `ct, st` (cos, sin of the zero offsets θ), \
                `ca, sa` (cos, sin of the twists α), `a`, `d` (mm) and the probe offset `b` (mm); \
                {per_pose}"
            )
        };
        Signature {
            args: quote! {
                ct: &[S; #n], st: &[S; #n], ca: &[S; #n], sa: &[S; #n],
                a: &[S; #n], d: &[S; #n], #beta_arg #probe_arg
                cq: &[S; #n], sq: &[S; #n]
            },
            // Only the parameter Jacobians depend on which joints are Hayati.
            select_arg: if k.spec.hayati {
                quote!(hayati: &[bool; #n],)
            } else {
                quote!()
            },
            bounds: quote! {
                S: ::core::marker::Copy
                    + ::core::ops::Add<Output = S>
                    + ::core::ops::Sub<Output = S>
                    + ::core::ops::Mul<Output = S>
                    + ::core::ops::Neg<Output = S>
                    + ::core::convert::From<f64>
            },
            attrs: quote! {
                #[inline(always)]
                #[allow(clippy::all, clippy::pedantic, clippy::too_many_arguments, unused_variables)]
            },
            args_doc,
            select_doc: if k.spec.hayati {
                " `hayati[i]` puts joint `i`'s β column in its d-slot instead of its d column."
            } else {
                ""
            },
            order: if k.spec.probe {
                "`a1..an, d1..dn, α1..αn, θ1..θn, Bx, By, Bz`"
            } else {
                "`a1..an, d1..dn, α1..αn, θ1..θn`"
            },
        }
    }
}

/// The items of a generated kernel module (without the `mod` around them).
pub fn kernel_items(k: &KernelExprs) -> TokenStream {
    let consts = constants(k);
    let position = position_items(k);
    let pose = pose_items(k);
    quote! {
        #consts
        #position
        #pose
    }
}

/// `JOINTS`, `PARAMS`, `SHAPE`, `PRISMATIC` and `EXTENDED`.
fn constants(k: &KernelExprs) -> TokenStream {
    let n = Literal::usize_unsuffixed(k.spec.joints);
    let p = Literal::usize_unsuffixed(k.spec.param_count());
    let shape = k.spec.shape();
    let prismatic = Literal::u16_unsuffixed(k.spec.prismatic);
    let extended = k.spec.hayati;
    quote! {
        /// Number of joints of this chain.
        pub const JOINTS: usize = #n;
        /// Number of geometric parameters of this chain.
        pub const PARAMS: usize = #p;
        /// The chain's shape, base first: `R` revolute, `P` prismatic.
        pub const SHAPE: &str = #shape;
        /// The prismatic joints: bit `i` for joint `i`.
        pub const PRISMATIC: u16 = #prismatic;
        /// Whether every link ends in `Ry(β)` (the extended chain, which
        /// computes Hayati joints too).
        pub const EXTENDED: bool = #extended;
    }
}

/// One output's three functions — its value, its parameter Jacobian, its
/// joint Jacobian — with `R`-row columns: the probe's position (3), the
/// tool's pose (6).
struct Family<'a, const R: usize> {
    names: [&'static str; 3],
    /// Each function's documentation, a `#[doc]` per entry.
    docs: [Vec<String>; 3],
    /// What the value function computes and returns.
    value: (&'a [Id], TokenStream),
    /// What the Jacobian functions return besides their columns.
    returned: (&'a [Id], TokenStream),
    /// The return type.
    ret: TokenStream,
    params: &'a [[Id; R]],
    betas: &'a [[Id; R]],
    joints: &'a [[Id; R]],
}

/// The three functions of `f`.
fn family<const R: usize>(k: &KernelExprs, sig: &Signature, f: Family<'_, R>) -> TokenStream {
    let g = &k.graph;
    let Signature {
        args,
        select_arg,
        bounds,
        attrs,
        ..
    } = sig;
    let n = Literal::usize_unsuffixed(k.spec.joints);
    let p = Literal::usize_unsuffixed(k.spec.param_count());
    let rows = Literal::usize_unsuffixed(R);
    let [value_name, jac_name, joint_name] = f.names.map(|s| Ident::new(s, Span::call_site()));
    let [value_doc, jac_doc, joint_doc] = &f.docs;
    let (value_ids, value) = f.value;
    let value_body = body(g, value_ids);
    let (returned_ids, returned) = f.returned;
    let jac_body = columns_with(g, f.params, f.betas, k.spec.joints, returned_ids);
    let joint_body = columns(g, f.joints, returned_ids);
    let ret = f.ret;
    quote! {
        #(#[doc = #value_doc])*
        #attrs
        pub fn #value_name<S>(#args) -> #ret where #bounds {
            #value_body
            #value
        }

        #(#[doc = #jac_doc])*
        #attrs
        pub fn #jac_name<S>(#args, #select_arg jac: &mut [[S; #rows]; #p]) -> #ret where #bounds {
            #jac_body
            #returned
        }

        #(#[doc = #joint_doc])*
        #attrs
        pub fn #joint_name<S>(#args, jac: &mut [[S; #rows]; #n]) -> #ret where #bounds {
            #joint_body
            #returned
        }
    }
}

/// `position`, `position_jacobian` and `joint_jacobian`: the probe's
/// position and its 3-row Jacobians.
fn position_items(k: &KernelExprs) -> TokenStream {
    let g = &k.graph;
    let sig = Signature::of(k);
    let (order, select_doc, args_doc) = (sig.order, sig.select_doc, sig.args_doc.clone());
    let jac_doc = format!(
        "Probe position and `∂p/∂parameter` into `jac`, one column per parameter in the order {order}.{select_doc} {args_doc}"
    );
    let joint_doc = "Probe position and `∂p/∂q_i` (mm/rad for a revolute joint, mm/mm for a \
        prismatic one) into `jac`, one column per joint.";
    let f = Family {
        names: ["position", "position_jacobian", "joint_jacobian"],
        docs: [
            vec![
                "Probe position (mm) by the right-to-left product.".into(),
                args_doc.clone(),
            ],
            vec![jac_doc],
            vec![joint_doc.into(), args_doc],
        ],
        value: (&k.position, vec3(g, &k.position)),
        returned: (&k.frame_position, vec3(g, &k.frame_position)),
        ret: quote!([S; 3]),
        params: &k.param_jacobian,
        betas: &k.beta_jacobian,
        joints: &k.joint_jacobian,
    };
    family(k, &sig, f)
}

/// `pose`, `pose_jacobian` and `joint_pose_jacobian`: the tool frame and
/// its 6-row Jacobians.
fn pose_items(k: &KernelExprs) -> TokenStream {
    let g = &k.graph;
    let sig = Signature::of(k);
    let (order, select_doc, args_doc) = (sig.order, sig.select_doc, sig.args_doc.clone());
    let ids = transform_ids(k);
    let pose = transform(g, &k.rotation, &k.frame_position);
    let returns = "Returns the top three rows of the tool's homogeneous transform, `[R | p]`: \
        `R` the last frame's axes as columns, `p` the probe (mm).";
    let six = "Each column is 6 rows: the position's derivative (3), then the small rotation \
        `ω` with `δR = [ω]× R` in the base frame (3).";
    let jac_doc = format!(
        "The tool pose and its Jacobian into `jac`, one column per parameter in the order {order}. {six}{select_doc} {returns} {args_doc}"
    );
    let joint_doc = format!(
        "The tool pose and `∂/∂q_i` into `jac`, one column per joint: `[z × (p − o); z]` for a revolute joint, `[z; 0]` for a prismatic one. {six} {returns} {args_doc}"
    );
    let f = Family {
        names: ["pose", "pose_jacobian", "joint_pose_jacobian"],
        docs: [
            vec![
                "The tool pose by the frames.".into(),
                returns.into(),
                args_doc,
            ],
            vec![jac_doc],
            vec![joint_doc],
        ],
        value: (&ids, pose.clone()),
        returned: (&ids, pose),
        ret: quote!([[S; 4]; 3]),
        params: &k.pose_jacobian,
        betas: &k.beta_pose_jacobian,
        joints: &k.joint_pose_jacobian,
    };
    family(k, &sig, f)
}

/// A marker type `Kernel` implementing `#core::kernel::Chain<N>` over the
/// module's functions: what a library built on them (aacmm-core, at the
/// path `core`) accepts as a chain.
pub fn chain_impl(k: &KernelExprs, core: &TokenStream) -> TokenStream {
    let n = Literal::usize_unsuffixed(k.spec.joints);
    let (geo, select) = if k.spec.hayati {
        (
            quote!(&k.ct, &k.st, &k.ca, &k.sa, &k.a, &k.d, &k.cb, &k.sb, &k.b,),
            quote!(&k.hayati,),
        )
    } else {
        (
            quote!(&k.ct, &k.st, &k.ca, &k.sa, &k.a, &k.d, &k.b,),
            quote!(),
        )
    };
    let consts = quote!(#core::kernel::Consts<S, #n>);
    let scalar = quote!(S: #core::kernel::Scalar);
    let sized = |rows: usize, what: &str| {
        let rows = Literal::usize_unsuffixed(rows);
        let message = format!("the Jacobian buffer holds {what} columns");
        quote! {
            // Invariant: every caller sizes `jac` from the chain's
            // PARAMS (the public entry points check the length first).
            let jac: &mut [[S; #rows]; PARAMS] = jac.try_into().expect(#message);
        }
    };
    let (three, six) = (sized(3, "4n + 3"), sized(6, "4n + 3"));
    quote! {
        /// This chain as a type: what `ArmKernel::with_chain` takes.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub struct Kernel;

        impl #core::kernel::Chain<#n> for Kernel {
            const PRISMATIC: ::core::option::Option<u16> = ::core::option::Option::Some(PRISMATIC);
            const EXTENDED: bool = EXTENDED;

            #[inline(always)]
            fn position<#scalar>(k: &#consts, cq: &[S; #n], sq: &[S; #n]) -> [S; 3] {
                position(#geo cq, sq)
            }

            #[inline(always)]
            fn position_jacobian<#scalar>(k: &#consts, cq: &[S; #n], sq: &[S; #n], jac: &mut [[S; 3]]) -> [S; 3] {
                #three
                position_jacobian(#geo cq, sq, #select jac)
            }

            #[inline(always)]
            fn joint_jacobian<#scalar>(k: &#consts, cq: &[S; #n], sq: &[S; #n], jac: &mut [[S; 3]; #n]) -> [S; 3] {
                joint_jacobian(#geo cq, sq, jac)
            }

            #[inline(always)]
            fn pose<#scalar>(k: &#consts, cq: &[S; #n], sq: &[S; #n]) -> [[S; 4]; 3] {
                pose(#geo cq, sq)
            }

            #[inline(always)]
            fn pose_jacobian<#scalar>(k: &#consts, cq: &[S; #n], sq: &[S; #n], jac: &mut [[S; 6]]) -> [[S; 4]; 3] {
                #six
                pose_jacobian(#geo cq, sq, #select jac)
            }

            #[inline(always)]
            fn joint_pose_jacobian<#scalar>(k: &#consts, cq: &[S; #n], sq: &[S; #n], jac: &mut [[S; 6]; #n]) -> [[S; 4]; 3] {
                joint_pose_jacobian(#geo cq, sq, jac)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::{ChainSpec, expand_chain};

    fn items(joints: usize) -> (KernelExprs, syn::File) {
        items_of(ChainSpec::revolute(joints))
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
        let mut pose = pose_jacobian_outputs(&k);
        assert_eq!(lets("pose_jacobian"), k.graph.op_count(&pose).total());
        pose.truncate(12);
        assert_eq!(lets("pose"), k.graph.op_count(&pose).total());
    }

    /// Everything `pose_jacobian` computes, the transform first.
    fn pose_jacobian_outputs(k: &KernelExprs) -> Vec<Id> {
        let mut out = transform_ids(k);
        out.extend(k.pose_jacobian.iter().flatten());
        out
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
        // The pose's columns add no product: its rotation rows are axes
        // the frames computed already.
        let pose = k.graph.op_count(&pose_jacobian_outputs(&k));
        assert_eq!(pose, jac, "pose + jacobian");
    }

    /// A prismatic joint costs less than a revolute one: no angle sum.
    #[test]
    fn a_prismatic_joint_is_cheaper() {
        let (r, _) = items_of(ChainSpec::revolute(8));
        let (p, _) = items_of(ChainSpec::of_shape("PRRRRRRR").unwrap());
        for k in [&r, &p] {
            assert_eq!(k.pose_jacobian.len(), 35);
        }
        let count = |k: &KernelExprs| k.graph.op_count(&pose_jacobian_outputs(k)).total();
        assert!(count(&p) < count(&r), "{} vs {}", count(&p), count(&r));
        let pos = |k: &KernelExprs| k.graph.op_count(&k.position).total();
        assert!(pos(&p) < pos(&r));
    }

    /// The extended chain costs more than the D-H one (it computes both the
    /// d and the β column of every joint), but stays straight-line code of
    /// the same order: a guard against an accidental blow-up.
    #[test]
    fn extended_chain_stays_small() {
        let (k, file) = items_of(ChainSpec {
            hayati: true,
            ..ChainSpec::revolute(6)
        });
        let mut outputs = jacobian_outputs(&k);
        outputs.extend(k.beta_jacobian.iter().flatten());
        let jac = k.graph.op_count(&outputs);
        let pos = k.graph.op_count(&k.position);
        println!("extended chain, 6 joints: position {pos:?}, position + jacobian {jac:?}");
        assert!(pos.total() <= 160, "position: {pos:?}");
        assert!(jac.total() <= 620, "position + jacobian: {jac:?}");
        let text = quote!(#file).to_string();
        // The d-slot's choice in both parameter Jacobians.
        assert_eq!(text.matches("if hayati [").count(), 12);
    }

    #[test]
    fn no_matrix_products_or_calls_in_the_per_pose_code() {
        for shape in ["RRRRRRR", "PRRRRRRR", "RRPR"] {
            for hayati in [false, true] {
                let (_, file) = items_of(ChainSpec {
                    hayati,
                    ..ChainSpec::of_shape(shape).unwrap()
                });
                calls_free(&file);
            }
        }
    }

    /// The marker type's impl parses and forwards to every function.
    #[test]
    fn the_chain_impl_forwards_to_the_functions() {
        for hayati in [false, true] {
            let k = expand_chain(ChainSpec {
                hayati,
                ..ChainSpec::of_shape("RRPR").unwrap()
            });
            let items = chain_impl(&k, &quote!(::aacmm_core));
            let file: syn::File = syn::parse2(items).expect("the impl parses");
            let text = quote!(#file).to_string();
            assert!(text.contains("impl :: aacmm_core :: kernel :: Chain < 4 > for Kernel"));
            for f in [
                "position",
                "position_jacobian",
                "joint_jacobian",
                "pose",
                "pose_jacobian",
                "joint_pose_jacobian",
            ] {
                // The trait's fn and the call of the module's.
                assert_eq!(text.matches(&format!("fn {f} <")).count(), 1, "{f}");
                assert_eq!(text.matches(&format!(" {f} (")).count(), 1, "{f}");
            }
            assert_eq!(text.contains("& k . hayati"), hayati);
        }
    }

    fn calls_free(file: &syn::File) {
        let names = [
            "position",
            "position_jacobian",
            "joint_jacobian",
            "pose",
            "pose_jacobian",
            "joint_pose_jacobian",
        ];
        for name in names {
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
