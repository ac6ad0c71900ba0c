//! Proofs of the energy bound's arithmetic, beside it (claim C5). The whole claim — the bound
//! dominates ½ q̇ᵀ M(q) q̇ over the boxes of the FR3 — is the property test
//! `g1_energy_bound_dominates` (pacs-proofs): its interval kinematics with sin/cos are beyond a
//! model checker. The Kani proofs here decide the steps that turn velocity bounds into energy.

// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]
use super::energy_iv::link_energy;
use crate::exact::{sum_le_zero, tame, two_prod, two_sum};
use crate::interval::proofs::{SCALE_104, grid_value};
use pacs_proof_kit::{Source, harness};

/// A tame float in `[0, m]` (0 or magnitude ≥ 1e-100: see [`crate::exact`]).
fn non_negative<S: Source>(s: &mut S, m: f64) -> Option<f64> {
    let x = s.f64_in(0.0, m);
    s.assume(tame(x)).then_some(x)
}

/// One link's energy bound `link_energy(m, λ̄, v2, w2)` is at least the exact ½·m·v2 + ½·λ̄·w2.
/// Kani checks it on the rounding grid (`grid_value` of the interval proofs: values `N·2⁻⁵²`
/// whose products round, `|N|` below 2⁶¹; the exact ½·m·v2 + ½·λ̄·w2 is the integer
/// `N_m·N_v2 + N_λ·N_w2` times 2⁻¹⁰⁵, and `e ≥ E·2⁻¹⁰⁵ ⟺ ⌊e·2¹⁰⁵⌋ ≥ E`: decided on integers);
/// the twin draws that grid with full-width significands, and any masses up to 10³ kg, moments
/// up to 10² kg·m² and squared speeds up to 10⁶, decided exactly (TwoProduct splits each
/// product into an exact pair, the double-double sum decides the sign). Catches mutant
/// `x29_link_energy_without_inflate` (the sum not inflated: it rounds down).
fn link_energy_rounds_up<S: Source>(s: &mut S) {
    if !cfg!(kani) {
        link_energy_any_range(s);
    }
    let [(m, nm), (l, nl), (v2, nv), (w2, nw)] = [(); 4].map(|()| {
        let (x, n) = grid_value(s);
        (x.abs(), n.abs())
    });
    let e = link_energy(m, l, v2, w2);
    // Values below 2⁹, so e < 2¹⁹: scaled by 2¹⁰⁵ below 2¹²⁴, exact in `i128`.
    let exact = nm * nv + nl * nw;
    assert!(
        !e.is_nan() && (e * SCALE_105).floor() as i128 >= exact,
        "link_energy({m}, {l}, {v2}, {w2}) = {e} below ½·m·v2 + ½·λ̄·w2 = {exact}·2⁻¹⁰⁵"
    );
}

/// `2¹⁰⁵`: the scale of [`link_energy_rounds_up`]'s integer oracle.
const SCALE_105: f64 = 2.0 * SCALE_104;

/// The twin's part of [`link_energy_rounds_up`] over the whole ranges.
fn link_energy_any_range<S: Source>(s: &mut S) {
    let (Some(m), Some(l), Some(v2), Some(w2)) = (
        non_negative(s, 1e3),
        non_negative(s, 1e2),
        non_negative(s, 1e6),
        non_negative(s, 1e6),
    ) else {
        return;
    };
    let e = link_energy(m, l, v2, w2);
    // ½·m and ½·λ̄ are exact (no underflow: tame).
    let (a, ae) = two_prod(0.5 * m, v2);
    let (b, be) = two_prod(0.5 * l, w2);
    // An exact 0 needs no oracle (the double-double sum's error bound, ≥ 2⁻¹⁰²², exceeds the
    // slack TINY_E there); a non-zero product of tame values is ≥ 1e-200.
    let holds = if a == 0.0 && b == 0.0 {
        e >= 0.0
    } else if ae == 0.0 && be == 0.0 {
        // a + b = s + t exactly (TwoSum); e − s is exact for s/2 ≤ e ≤ 2s (Sterbenz), so
        // e ≥ s + t is decided without rounding.
        let (s, t) = two_sum(a, b);
        e >= s && e <= 2.0 * s && e - s >= t
    } else {
        sum_le_zero(&[a, ae, b, be, -e])
    };
    assert!(
        holds,
        "link_energy({m}, {l}, {v2}, {w2}) = {e} below ½·m·v2 + ½·λ̄·w2"
    );
}
harness!(
    g1_link_energy_rounds_up,
    unwind = 5,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    link_energy_rounds_up
);

/// (g1, Kani) [`link_energy_rounds_up`] for significands short enough that both products are
/// exact (3 bits: products of ≤ 6 bits; 4 bits took 212 s): the sum's rounding, the inflation and `TINY_E` are
/// what is checked. `a + b = s + t` exactly (TwoSum); `e − s` is exact for `s ≤ e ≤ 2s`
/// (Sterbenz), so `e ≥ s + t` is decided without rounding.
fn link_energy_exact_products<S: Source>(s: &mut S) {
    // Truncated to 3 significant bits (under Kani they have no more): the products are exact.
    let short = |x: f64| f64::from_bits(x.to_bits() & !((1u64 << 49) - 1));
    let m = short(s.f64_in(1e-3, 1e3));
    let l = short(s.f64_in(1e-3, 1e2));
    let v2 = short(s.f64_in(1e-6, 1e6));
    let w2 = short(s.f64_in(1e-6, 1e6));
    let (a, b) = (0.5 * m * v2, 0.5 * l * w2);
    let e = link_energy(m, l, v2, w2);
    let (sum, t) = two_sum(a, b);
    assert!(
        e >= sum && e <= 2.0 * sum && e - sum >= t,
        "link_energy({m}, {l}, {v2}, {w2}) = {e} below ½·m·v2 + ½·λ̄·w2"
    );
}
harness!(
    g1_link_energy_exact_products,
    unwind = 2,
    bits = 3,
    cases = pacs_proof_kit::DEFAULT_CASES,
    link_energy_exact_products
);
