//! The macro's input: `[#[attrs]] [vis] mod NAME { joints = N[, probe = bool][, hayati = bool] }`.

use proc_macro2::TokenStream;
use quote::quote;
use syn::parse::{Parse, ParseStream};
use syn::punctuated::Punctuated;
use syn::{Attribute, Ident, Lit, Token, Visibility, braced};

use crate::chain::{ChainSpec, expand_chain};
use crate::emit::kernel_items;

/// Most joints a chain may have; serial arms have 6 or 7, and the expression
/// size grows with the square of the count.
pub const MAX_JOINTS: usize = 12;

/// A parsed invocation.
pub struct ChainMacroInput {
    attrs: Vec<Attribute>,
    vis: Visibility,
    name: Ident,
    /// The chain to generate.
    pub spec: ChainSpec,
}

struct Setting {
    key: Ident,
    value: Lit,
}

impl Parse for Setting {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let key: Ident = input.parse()?;
        input.parse::<Token![=]>()?;
        let value: Lit = input.parse()?;
        Ok(Setting { key, value })
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
        let settings = Punctuated::<Setting, Token![,]>::parse_terminated(&content)?;
        if !input.is_empty() {
            return Err(input.error("unexpected tokens after the chain module"));
        }
        let mut joints: Option<usize> = None;
        let mut probe: Option<bool> = None;
        let mut hayati: Option<bool> = None;
        for s in settings {
            let key = s.key.to_string();
            let duplicate = || syn::Error::new(s.key.span(), format!("`{key}` is given twice"));
            match key.as_str() {
                "joints" => {
                    if joints.is_some() {
                        return Err(duplicate());
                    }
                    let Lit::Int(lit) = &s.value else {
                        return Err(syn::Error::new_spanned(
                            &s.value,
                            "`joints` takes an integer",
                        ));
                    };
                    let n: usize = lit.base10_parse()?;
                    if !(1..=MAX_JOINTS).contains(&n) {
                        return Err(syn::Error::new_spanned(
                            lit,
                            format!("`joints` must be 1 to {MAX_JOINTS}, got {n}"),
                        ));
                    }
                    joints = Some(n);
                }
                "probe" => {
                    if probe.is_some() {
                        return Err(duplicate());
                    }
                    let Lit::Bool(lit) = &s.value else {
                        return Err(syn::Error::new_spanned(
                            &s.value,
                            "`probe` takes `true` or `false`",
                        ));
                    };
                    probe = Some(lit.value);
                }
                "hayati" => {
                    if hayati.is_some() {
                        return Err(duplicate());
                    }
                    let Lit::Bool(lit) = &s.value else {
                        return Err(syn::Error::new_spanned(
                            &s.value,
                            "`hayati` takes `true` or `false`",
                        ));
                    };
                    hayati = Some(lit.value);
                }
                _ => {
                    return Err(syn::Error::new(
                        s.key.span(),
                        format!("unknown setting `{key}`; expected `joints`, `probe` or `hayati`"),
                    ));
                }
            }
        }
        let joints = joints.ok_or_else(|| {
            syn::Error::new(
                brace.span.join(),
                "missing `joints = N` (the number of revolute joints)",
            )
        })?;
        Ok(ChainMacroInput {
            attrs,
            vis,
            name,
            spec: ChainSpec {
                joints,
                probe: probe.unwrap_or(true),
                hayati: hayati.unwrap_or(false),
            },
        })
    }
}

impl ChainMacroInput {
    /// The generated module.
    pub fn generate(&self) -> TokenStream {
        let ChainMacroInput {
            attrs, vis, name, ..
        } = self;
        let items = kernel_items(&expand_chain(self.spec));
        quote! {
            #(#attrs)*
            #vis mod #name {
                #items
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
        assert_eq!(
            input.spec,
            ChainSpec {
                joints: 7,
                probe: true,
                hayati: false,
            }
        );
    }

    #[test]
    fn user_errors_say_what_is_wrong() {
        assert!(error(quote!(mod m { joints = 0 })).contains("must be 1 to 12, got 0"));
        assert!(
            error(quote!(mod m { joints = 6, jionts = 6 })).contains("unknown setting `jionts`")
        );
        assert!(error(quote!(mod m { joints = 6, joints = 7 })).contains("given twice"));
        assert!(error(quote!(mod m { probe = true })).contains("missing `joints = N`"));
        assert!(error(quote!(mod m { joints = "6" })).contains("takes an integer"));
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
