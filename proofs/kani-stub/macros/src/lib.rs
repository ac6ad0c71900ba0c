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
