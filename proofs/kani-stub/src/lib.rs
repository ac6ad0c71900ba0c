//! Type-checking stand-in for the Kani verifier's `kani` crate.
//!
//! Only the API used by `pacs-proofs` is provided, with Kani's signatures. It is selected by
//! `--cfg kani_stub` and exists so that CI compiles the `#[cfg(kani)]` harnesses; nothing here is
//! meant to run (calling [`any`] panics). Under real `cargo kani` this crate is not used.

pub use kani_stub_macros::{
    ensures, modifies, proof, proof_for_contract, requires, should_panic, solver, stub,
    stub_verified, unwind,
};

/// Types with a nondeterministic value (Kani: `kani::Arbitrary`).
pub trait Arbitrary: Sized {
    /// A nondeterministic value.
    fn any() -> Self;
}

macro_rules! arbitrary {
    ($($t:ty),*) => {$(
        impl Arbitrary for $t {
            fn any() -> Self {
                unimplemented!("kani stand-in: type-checking only, run `cargo kani`")
            }
        }
    )*};
}
arbitrary!(bool, u8, u16, u32, u64, usize, i16, i32, i64, f32, f64);

/// Arrays of nondeterministic values (Kani implements `Arbitrary` for `[T; N]` too).
impl<T: Arbitrary, const N: usize> Arbitrary for [T; N] {
    fn any() -> Self {
        std::array::from_fn(|_| T::any())
    }
}

/// A nondeterministic value of type `T` (Kani: `kani::any`).
pub fn any<T: Arbitrary>() -> T {
    T::any()
}

/// Restrict the verification to executions where `cond` holds (Kani: `kani::assume`).
pub fn assume(cond: bool) {
    let _ = cond;
}
