//! The macro's input: `[#[attrs]] [vis] mod NAME { joints = N | "SHAPE"[, probe = bool][, hayati = bool][, core = PATH] }`.

use proc_macro2::TokenStream;
use quote::{ToTokens, quote};
use syn::parse::{Parse, ParseStream};
use syn::punctuated::Punctuated;
use syn::{Attribute, Ident, Lit, Token, Visibility, braced};

use crate::chain::{ChainSpec, expand_chain, parse_shape};
use crate::emit::{chain_impl, kernel_items};

pub use crate::chain::MAX_JOINTS;

/// A parsed invocation.
pub struct ChainMacroInput {
    attrs: Vec<Attribute>,
    vis: Visibility,
    name: Ident,
    /// The chain to generate.
    pub spec: ChainSpec,
    /// The path of the library whose `kernel::Chain` trait the module's
    /// marker type `Kernel` implements (`core = aacmm_core`); none without.
    core: Option<TokenStream>,
}

/// A setting's value: a literal, or a path (`core = ...`).
enum Value {
    Lit(Lit),
    Path(TokenStream),
}

impl ToTokens for Value {
    fn to_tokens(&self, tokens: &mut TokenStream) {
        match self {
            Value::Lit(l) => l.to_tokens(tokens),
            Value::Path(p) => p.to_tokens(tokens),
        }
    }
}

struct Setting {
    key: Ident,
    value: Value,
}

impl Parse for Setting {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let key: Ident = input.parse()?;
        input.parse::<Token![=]>()?;
        let value = if input.peek(Lit) {
            Value::Lit(input.parse()?)
        } else {
            // A path, `$crate` included, up to the next comma.
            let mut path = TokenStream::new();
            while !input.is_empty() && !input.peek(Token![,]) {
                let tt: proc_macro2::TokenTree = input.parse()?;
                path.extend([tt]);
            }
            Value::Path(path)
        };
        Ok(Setting { key, value })
    }
}

/// The settings as given, each at most once.
#[derive(Default)]
struct Settings {
    joints: Option<(usize, u16)>,
    probe: Option<bool>,
    hayati: Option<bool>,
    core: Option<TokenStream>,
}

impl Settings {
    fn set(&mut self, s: Setting) -> syn::Result<()> {
        let key = s.key.to_string();
        let duplicate = || syn::Error::new(s.key.span(), format!("`{key}` is given twice"));
        let taken = match key.as_str() {
            "joints" => self.joints.is_some(),
            "probe" => self.probe.is_some(),
            "hayati" => self.hayati.is_some(),
            "core" => self.core.is_some(),
            _ => {
                return Err(syn::Error::new(
                    s.key.span(),
                    format!(
                        "unknown setting `{key}`; expected `joints`, `probe`, `hayati` or `core`"
                    ),
                ));
            }
        };
        if taken {
            return Err(duplicate());
        }
        match key.as_str() {
            "joints" => self.joints = Some(joints(&s.value)?),
            "probe" => self.probe = Some(flag(&s.value, "probe")?),
            "hayati" => self.hayati = Some(flag(&s.value, "hayati")?),
            _ => match s.value {
                Value::Path(p) if !p.is_empty() => self.core = Some(p),
                other => {
                    return Err(syn::Error::new_spanned(
                        other,
                        "`core` takes the path of aacmm-core (`core = aacmm_core`)",
                    ));
                }
            },
        }
        Ok(())
    }
}

/// `joints = N` (all revolute) or `joints = "PRRR"` (one letter per joint).
fn joints(value: &Value) -> syn::Result<(usize, u16)> {
    match value {
        Value::Lit(Lit::Int(lit)) => {
            let n: usize = lit.base10_parse()?;
            if !(1..=MAX_JOINTS).contains(&n) {
                return Err(syn::Error::new_spanned(
                    lit,
                    format!("`joints` must be 1 to {MAX_JOINTS}, got {n}"),
                ));
            }
            Ok((n, 0))
        }
        Value::Lit(Lit::Str(lit)) => parse_shape(&lit.value())
            .map_err(|e| syn::Error::new_spanned(lit, format!("`joints`: {e}"))),
        other => Err(syn::Error::new_spanned(
            other,
            "`joints` takes an integer (that many revolute joints) or a shape such as \"PRRRRRR\"",
        )),
    }
}

fn flag(value: &Value, key: &str) -> syn::Result<bool> {
    match value {
        Value::Lit(Lit::Bool(lit)) => Ok(lit.value),
        other => Err(syn::Error::new_spanned(
            other,
            format!("`{key}` takes `true` or `false`"),
        )),
    }
}

impl Parse for ChainMacroInput {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let attrs = input.call(Attribute::parse_outer)?;
        let vis: Visibility = input.parse()?;
        input.parse::<Token![mod]>()?;
        let name: Ident = input.parse()?;
        let content;
        let brace = braced!(content in input);
        let given = Punctuated::<Setting, Token![,]>::parse_terminated(&content)?;
        if !input.is_empty() {
            return Err(input.error("unexpected tokens after the chain module"));
        }
        let mut settings = Settings::default();
        for s in given {
            settings.set(s)?;
        }
        let (joints, prismatic) = settings.joints.ok_or_else(|| {
            syn::Error::new(
                brace.span.join(),
                "missing `joints = N` (the number of revolute joints) or `joints = \"SHAPE\"`",
            )
        })?;
        Ok(ChainMacroInput {
            attrs,
            vis,
            name,
            spec: ChainSpec {
                joints,
                prismatic,
                probe: settings.probe.unwrap_or(true),
                hayati: settings.hayati.unwrap_or(false),
            },
            core: settings.core,
        })
    }
}

impl ChainMacroInput {
    /// The generated module.
    pub fn generate(&self) -> TokenStream {
        let ChainMacroInput {
            attrs, vis, name, ..
        } = self;
        let k = expand_chain(self.spec);
        let items = kernel_items(&k);
        let marker = match &self.core {
            Some(core) if self.spec.probe => chain_impl(&k, core),
            Some(core) => syn::Error::new_spanned(
                core,
                "`core` needs a chain with a probe (the library's parameters end in Bx, By, Bz)",
            )
            .into_compile_error(),
            None => TokenStream::new(),
        };
        quote! {
            #(#attrs)*
            #vis mod #name {
                #items
                #marker
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expand;

    fn error(tokens: TokenStream) -> String {
        match expand(tokens) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn defaults_to_a_probe() {
        let input: ChainMacroInput = syn::parse2(quote!(mod arm7 { joints = 7 })).unwrap();
        assert_eq!(input.spec, ChainSpec::revolute(7));
    }

    #[test]
    fn a_shape_names_the_prismatic_joints() {
        let input: ChainMacroInput =
            syn::parse2(quote!(mod lift { joints = "PRRRRRRR", hayati = true })).unwrap();
        assert_eq!(
            input.spec,
            ChainSpec {
                hayati: true,
                ..ChainSpec::of_shape("PRRRRRRR").unwrap()
            }
        );
        assert!(error(quote!(mod m { joints = "RRXR" })).contains("`X` at joint 3"));
        assert!(error(quote!(mod m { joints = "" })).contains("this shape has 0"));
    }

    #[test]
    fn core_adds_the_marker_type() {
        let with = expand(quote!(pub mod scara { joints = "RRPR", core = ::aacmm_core }))
            .unwrap()
            .to_string();
        assert!(with.contains("pub struct Kernel"));
        assert!(with.contains("impl :: aacmm_core :: kernel :: Chain < 4 > for Kernel"));
        let without = expand(quote!(mod scara { joints = "RRPR" }))
            .unwrap()
            .to_string();
        assert!(!without.contains("struct Kernel"));
        let bare = expand(quote!(mod m { joints = 3, probe = false, core = crate }))
            .unwrap()
            .to_string();
        assert!(bare.contains("compile_error"));
        assert!(error(quote!(mod m { joints = 3, core = 1 })).contains("`core` takes the path"));
    }

    #[test]
    fn user_errors_say_what_is_wrong() {
        assert!(error(quote!(mod m { joints = 0 })).contains("must be 1 to 12, got 0"));
        assert!(
            error(quote!(mod m { joints = 6, jionts = 6 })).contains("unknown setting `jionts`")
        );
        assert!(error(quote!(mod m { joints = 6, joints = 7 })).contains("given twice"));
        assert!(error(quote!(mod m { probe = true })).contains("missing `joints = N`"));
        assert!(error(quote!(mod m { joints = "6" })).contains("`6` at joint 1"));
        assert!(error(quote!(mod m { joints = 6.0 })).contains("takes an integer"));
        assert!(error(quote!(mod m { joints = 6, probe = 1 })).contains("`true` or `false`"));
        assert!(error(quote!(mod m { joints = 6 } extra)).contains("unexpected tokens"));
    }

    #[test]
    fn keeps_attributes_and_visibility() {
        let out = expand(quote! {
            /// The arm.
            pub(crate) mod arm6 { joints = 6 }
        })
        .unwrap()
        .to_string();
        let doc = out.find("The arm.").expect("doc kept");
        let module = out.find("pub (crate) mod arm6").expect("visibility kept");
        assert!(doc < module);
    }
}
