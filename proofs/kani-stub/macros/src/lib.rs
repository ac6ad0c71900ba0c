//! Identity attribute macros standing in for `#[kani::proof]` and `#[kani::unwind(N)]`.

use proc_macro::TokenStream;

/// `#[kani::proof]`: the item is returned unchanged (type-checking only).
#[proc_macro_attribute]
pub fn proof(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::unwind(N)]`: the item is returned unchanged (type-checking only).
#[proc_macro_attribute]
pub fn unwind(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::solver(NAME)]`: the item is returned unchanged (type-checking only).
#[proc_macro_attribute]
pub fn solver(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::should_panic]`: the item is returned unchanged (type-checking only).
#[proc_macro_attribute]
pub fn should_panic(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::stub(ORIGINAL, REPLACEMENT)]`: the item is returned unchanged (type-checking only;
/// the stand-in does not check that the two paths resolve).
#[proc_macro_attribute]
pub fn stub(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::requires(COND)]` (function contracts): the item is returned unchanged (type-checking
/// only; the condition is not compiled).
#[proc_macro_attribute]
pub fn requires(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::ensures(|result| COND)]` (function contracts): the item is returned unchanged.
#[proc_macro_attribute]
pub fn ensures(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::modifies(PLACES)]` (function contracts): the item is returned unchanged.
#[proc_macro_attribute]
pub fn modifies(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::proof_for_contract(FUNCTION)]`: the item is returned unchanged.
#[proc_macro_attribute]
pub fn proof_for_contract(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}

/// `#[kani::stub_verified(FUNCTION)]`: the item is returned unchanged.
#[proc_macro_attribute]
pub fn stub_verified(_attr: TokenStream, item: TokenStream) -> TokenStream {
    item
}
