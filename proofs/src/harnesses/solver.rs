//! (z) The model checker's own arithmetic: checked integer operations and float bit access give
//! the values Rust defines, under every solver `proofs/kani.sh` uses.
//!
//! Every proof above rests on the solver back end encoding the program faithfully. CBMC 6.4's
//! SMT back end (the `bitwuzla` solver here) once did not: it built the `(result, overflowed)`
//! pair of signed `+`/`−` and of `×` with the two members swapped, so every checked integer
//! operation of a debug build had a wrong result and a wrong overflow flag
//! (`proofs/smt/bitwuzla_cli.py` repairs it; `proofs/README.md`, "Solvers"). These proofs fail
//! on such an encoding; CI runs them with each solver before trusting any other result.
//! `z1_real_overflow_is_found` checks the other direction: a real overflow is still reported.

/// `x` as (unbiased exponent, significand) of its IEEE 754 bits (finite `x`).
fn exponent_significand(x: f64) -> (i32, u64) {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    if biased == 0 {
        (-1074, frac)
    } else {
        (biased - 1075, frac | (1u64 << 52))
    }
}

/// Checked `+ − ×` against the same operation one width up; the float fields in range.
fn arithmetic(a32: i32, b32: i32, a16: i16, b16: i16, c16: u16, d16: u16, x: f64) {
    let w = i64::from(a32) + i64::from(b32);
    assert!(a32.overflowing_add(b32) == (w as i32, w != i64::from(w as i32)));
    let w = i64::from(a32) - i64::from(b32);
    assert!(a32.overflowing_sub(b32) == (w as i32, w != i64::from(w as i32)));
    let w = i32::from(a16) * i32::from(b16);
    assert!(a16.overflowing_mul(b16) == (w as i16, w != i32::from(w as i16)));
    let w = u32::from(c16) * u32::from(d16);
    assert!(c16.overflowing_mul(d16) == (w as u16, w > u32::from(u16::MAX)));
    let w = u32::from(c16) + u32::from(d16);
    assert!(c16.overflowing_add(d16) == (w as u16, w > u32::from(u16::MAX)));
    if x.is_finite() {
        let (e, m) = exponent_significand(x);
        assert!((-1074..=971).contains(&e) && m < (1u64 << 53));
        // Plain (overflow-checked) operations whose values matter.
        let small = (a16 % 100, b16 % 100);
        assert!(i32::from(small.0 - small.1) == i32::from(small.0) - i32::from(small.1));
        assert!(i32::from(small.0 * small.1) == i32::from(small.0) * i32::from(small.1));
    }
}

#[cfg(kani)]
#[kani::proof]
fn z0_solver_integer_semantics() {
    arithmetic(
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
    );
}

/// A real overflow in a checked operation is reported (the harness must panic).
#[cfg(kani)]
#[kani::proof]
#[kani::should_panic]
fn z1_real_overflow_is_found() {
    let a: i32 = kani::any();
    kani::assume(a > 0);
    let _ = std::hint::black_box(a + i32::MAX);
}

#[cfg(test)]
mod tests {
    /// The same identities on seeded random values (the twin).
    #[test]
    fn z0_solver_integer_semantics_twin() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..10_000 {
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                state
            };
            let (r1, r2, r3) = (next(), next(), next());
            super::arithmetic(
                r1 as i32,
                (r1 >> 32) as i32,
                r2 as i16,
                (r2 >> 16) as i16,
                (r2 >> 32) as u16,
                (r2 >> 48) as u16,
                f64::from_bits(r3),
            );
        }
    }
}
