//! Kani splits of claim C4 (the robot occupancy contains every link capsule over a joint box),
//! beside the building blocks of the interval forward kinematics ([`super::frames`]). The whole
//! claim — the FR3's 7-joint chain, the two enclosures of every capsule endpoint, the mean-value
//! sums, `occupancy_with`'s choice and padding — is the property test `d1_robot_link_enlargement`
//! (`pacs-proofs`); the split below proves one step every frame of the chain is built from,
//! two property tests check two more:
//!
//! - `d1_centre_trig_radii`: [`trig_radii`] (the arithmetic of [`centre_trig`] after libm) bounds
//!   the deviation of sin and cos over `[q_c − δ, q_c + δ]` from the libm values ŝ, ĉ at the
//!   centre: `w_s ≥ min(|ŝ|·h + |ĉ|·s_δ + T·(h + s_δ + 1), 1 + |ŝ|)` with h = min(δ²/2, 2),
//!   s_δ = min(δ, 1) and T ≥ `TRIG_PAD` (the libm contract |sin q_c − ŝ| ≤ `TRIG_PAD`), and
//!   likewise `w_c` with ŝ, ĉ swapped — exactly, in real numbers. The real-analysis step (module
//!   doc of [`super`]: sin(q_c + t) − ŝ = sin q_c·(cos t − 1) + cos q_c·sin t + (sin q_c − ŝ),
//!   0 ≤ 1 − cos t ≤ min(t²/2, 2), |sin t| ≤ min(|t|, 1), |sin q_c| ≤ |ŝ| + `TRIG_PAD`, and
//!   |sin q − ŝ| ≤ 1 + |ŝ|) makes that the claim of the doc; the twin also checks it against
//!   libm at points of the interval. Mutant `x35d` (w_s with the two terms' factors swapped)
//!   fails it.
//! - `d1_rotation_mul_mid`: one entry of [`RotationEnclosure::mul`]. Under Kani the γ term's
//!   claim (radii 0: the midpoint's rounding within `e` and `w`) on a grid of `0, ±1, ±2⁻³⁰,
//!   ±2⁻⁶⁰` ([`rotation_mul_grid`], an integer oracle); the twin also whole 3×3 enclosures and
//!   members at random vertices: |(A′·B′)ᵢⱼ − mᵢⱼ| ≤ eᵢⱼ and ≤ wᵢⱼ, exactly (TwoProduct,
//!   double-double sums). Mutant `x36d` (the γ term dropped) fails it, Kani and twin.
//! - `d1_affine_encloses`: one coordinate of [`RotationEnclosure::affine`] (A·v + t): under
//!   Kani the γ term's claim on the same grid ([`affine_grid`]); the twin also members
//!   A′ = Aₘ ± A_r, t′ = tₘ ± t_r: |A′·v + t′ − m| ≤ r for r = e, w. Mutant `x80` (the γ term
//!   dropped) fails it, Kani and twin; dropping the inflation of `w`, or `t.w`, fails the twin.
//!
//! Under Kani `d1_centre_trig_radii`'s inputs are ŝ, ĉ with 4-bit significands (0 or of
//! magnitude ≥ 2⁻¹⁶) and δ a power of two (0 or ≥ 2⁻¹⁰): every product and sum of the oracle is
//! then a float, and the claim is decided exactly ([`cmp_sum`]), while the code under test still
//! rounds (`TRIG_PAD`, `RAD_UP` have full significands). Its twin draws full-width ŝ, ĉ, δ
//! (and, half the time, libm's values at a centre q_c and a point q of the box, against libm's
//! sin q, cos q) and bounds the real bound from above with the outward-rounded helpers (claim
//! C1). `mul` and `affine` work on 3×3 matrices in four lanes ([`super::lanes`]); CBMC's
//! encoding of the by-value `[f64; 4]` lanes reaches Bitwuzla through
//! `bitwuzla_cli.py::repair_float_array_concats`. With 4-bit factors of any exponent (instead of
//! the grid) `d1_rotation_mul_mid` timed out at 240 s, also with a single symbolic product, and
//! the SAT back end at 300 s, also on the grid.
//!
//! Left to the twin of `d1_robot_link_enlargement`: the chain itself (frames composed by `mul`
//! over 7 joints, the Rodrigues and z-axis local transforms), the wide-box chain over
//! `sin_cos_interval` (a5), the mean-value sums (square roots; mutant `x5`), the norms of the
//! radius vectors and the capsule assembly; and to the twin of `d1_centre_trig_radii`:
//! full-width ŝ, ĉ and half-widths that are not powers of two.
// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]
use super::RobotReach;
use super::frames::*;
use super::lanes::*;
use crate::exact::{cmp_sum, sum_le_zero, tame, two_prod};
use crate::rounding::{TRIG_PAD, add_up, mul_up};
use pacs_proof_kit::{Source, harness};
use std::cmp::Ordering::Greater;

/// `TRIG_PAD` rounded up to 8 significand bits (0x1.6ap-47 ≈ 1.0048e-14): under Kani the oracle
/// multiplies with it exactly; a larger pad only strengthens the claim.
const TRIG_PAD_8: f64 = f64::from_bits(0x3D06_A000_0000_0000);

/// Under Kani a value of at most 4 significand bits in `[lo, hi]` that is 0 or of magnitude
/// ≥ `min` (then products and short sums of such values are exact); any tame value in the twin.
fn short<S: Source>(s: &mut S, lo: f64, hi: f64, min: f64) -> Option<f64> {
    let x = s.f64_short(lo, hi, 4);
    let ok = if cfg!(kani) {
        x == 0.0 || x.abs() >= min
    } else {
        tame(x)
    };
    s.assume(ok).then_some(x)
}

/// `x·y` rounded up (twin) or exactly (Kani: short inputs, the product is a float).
fn mul_or_exact(x: f64, y: f64) -> f64 {
    if cfg!(kani) { x * y } else { mul_up(x, y) }
}

/// `x + y` rounded up (twin) or exactly (Kani: the sums of the oracle below are floats).
fn add_or_exact(x: f64, y: f64) -> f64 {
    if cfg!(kani) { x + y } else { add_up(x, y) }
}

/// `w` bounds the deviation of one of sin, cos over the box (see the module doc): with `a` the
/// libm value's magnitude of the function itself and `b` that of the other one,
/// `w ≥ min(a·h + b·s_δ + T·(h + s_δ + 1), 1 + a)` exactly.
fn assert_trig_radius(a: f64, b: f64, delta: f64, w: f64, what: &str) {
    let t = if cfg!(kani) { TRIG_PAD_8 } else { TRIG_PAD };
    // Exact under Kani (4-bit a, b ≥ 2⁻¹⁶ and δ ≥ 2⁻¹⁰ or 0: a·h is a multiple of 2⁻⁴⁶ below 2,
    // b·s_δ of 2⁻³² below 1, so their sum is a float; h + s_δ + 1 is a multiple of 2⁻²⁷ below 4
    // and its product with the 8-bit pad a float), above in the twin.
    let (main, pad) = trig_radius_terms(a, b, delta, t, mul_or_exact, add_or_exact);
    assert!(
        cmp_sum(main, pad, w) != Greater || cmp_sum(1.0, a, w) != Greater,
        "{what}: radius {w} below min({main} + {pad}, 1 + {a}) for δ = {delta}"
    );
}

/// The grid inputs of the Kani proofs of `trig_radii` (`d1_centre_trig_radii`,
/// `d1_trig_radii_contract`): ŝ, ĉ of 4 significand bits in `[−1, 1]`, 0 or of magnitude
/// ≥ 2⁻¹⁶ (any tame values in the twin).
fn grid_sin_cos<S: Source>(s: &mut S) -> Option<(f64, f64)> {
    Some((
        short(s, -1.0, 1.0, 1.0 / 65536.0)?,
        short(s, -1.0, 1.0, 1.0 / 65536.0)?,
    ))
}

/// A half-width δ in `[0, 8]`: under Kani a power of two (or 0), at least 2⁻¹⁰ — h and s_δ are
/// then powers of two, and the code's products by them exact scalings (4-bit half-widths timed
/// out at 300 s, Bitwuzla); any tame value in the twin.
fn grid_half_width<S: Source>(s: &mut S) -> Option<f64> {
    let delta = s.f64_short(0.0, 8.0, 0);
    s.assume(tame(delta) && (!cfg!(kani) || delta == 0.0 || delta >= 1.0 / 1024.0))
        .then_some(delta)
}

fn centre_trig_radii<S: Source>(s: &mut S) {
    let from_libm = !cfg!(kani) && s.bool();
    let (sh, ch, qc) = if from_libm {
        // The twin: also the libm values at a centre, and the claim at points of the box.
        let qc = s.f64_in(-7.0, 7.0);
        let (sh, ch) = qc.sin_cos();
        (sh, ch, qc)
    } else {
        let Some((sh, ch)) = grid_sin_cos(s) else {
            return;
        };
        (sh, ch, 0.0)
    };
    let Some(delta) = grid_half_width(s) else {
        return;
    };
    let (s_out, c_out, e, ws, wc) = trig_radii(sh, ch, delta);
    assert!(
        s_out.to_bits() == sh.to_bits() && c_out.to_bits() == ch.to_bits(),
        "the midpoints are not libm's values"
    );
    assert!(e >= TRIG_PAD, "centre radius {e} below TRIG_PAD");
    assert_trig_radius(sh.abs(), ch.abs(), delta, ws, "sin");
    assert_trig_radius(ch.abs(), sh.abs(), delta, wc, "cos");
    if from_libm {
        let q = s.f64_in(qc - delta, qc + delta);
        let (sq, cq) = q.sin_cos();
        // libm's own error at q (≤ 1 ulp) is far below the claim's slack (2·TRIG_PAD).
        assert!(
            (sq - sh).abs() <= ws,
            "|sin {q} − sin {qc}| > {ws} (δ = {delta})"
        );
        assert!(
            (cq - ch).abs() <= wc,
            "|cos {q} − cos {qc}| > {wc} (δ = {delta})"
        );
    }
}
harness!(
    d1_centre_trig_radii,
    unwind = 2,
    bits = 4,
    cases = pacs_proof_kit::DEFAULT_CASES,
    centre_trig_radii
);

/// `trig_radii`'s contract (`trig_radii_cover`, the bounds with every operation rounded up),
/// proven on the real function: ŝ, ĉ of 4 significand bits (0 or of magnitude ≥ 2⁻¹⁶) and δ a
/// power of two (0 or in `[2⁻¹⁰, 8]`), the domain of `d1_centre_trig_radii`, whose claim on it
/// is the exact bound.
#[cfg(kani)]
#[kani::proof_for_contract(trig_radii)]
#[kani::unwind(2)]
fn d1_trig_radii_contract() {
    let mut src = pacs_proof_kit::KaniSource { bits: 4 };
    let (Some((sh, ch)), Some(delta)) = (grid_sin_cos(&mut src), grid_half_width(&mut src)) else {
        return;
    };
    let _ = trig_radii(sh, ch, delta);
}

/// The twin of `d1_trig_radii_contract`: full-width ŝ, ĉ in `[−1, 1]` (half of them libm's
/// values at a random centre) and any admitted δ (0, any value up to 8, or a magnitude from
/// 1e-300 to 1e100), the postcondition checked.
#[cfg(test)]
#[test]
fn d1_trig_radii_contract_holds() {
    pacs_proof_kit::run_cases("d1_trig_radii_contract_holds", 20_000, |s| {
        let (sh, ch) = if s.bool() {
            s.f64_in(-7.0, 7.0).sin_cos()
        } else {
            (s.f64_in(-1.0, 1.0), s.f64_in(-1.0, 1.0))
        };
        let delta = match s.index(3) {
            0 => 0.0,
            1 => s.f64_in(0.0, 8.0),
            _ => 10f64.powi(s.index(401) as i32 - 300) * s.f64_in(1.0, 9.99),
        };
        if !trig_input(sh, ch, delta) {
            return;
        }
        let r = trig_radii(sh, ch, delta);
        assert!(
            trig_radii_cover(sh, ch, delta, r),
            "trig_radii({sh}, {ch}, {delta}) = {r:?} breaks its contract"
        );
    });
}

/// A 3×3 matrix from its rows (lane 3 unused).
fn mat(rows: [[f64; 3]; 3]) -> Mat3Lanes {
    let c = |j: usize| Lanes3(simd::new([rows[0][j], rows[1][j], rows[2][j], 0.0]));
    Mat3Lanes([c(0), c(1), c(2)])
}

/// The enclosure with midpoint `m` and radii `e`, `w` (rows).
fn enclosure(m: [[f64; 3]; 3], e: [[f64; 3]; 3], w: [[f64; 3]; 3]) -> RotationEnclosure {
    RotationEnclosure {
        m: mat(m),
        e: mat(e),
        w: mat(w),
    }
}

/// The grid harnesses' integer oracle: `|S − m| ≤ r` for the exact `S·2⁻¹²⁰` (an integer `S`),
/// the midpoint `m` and radius `r` the code computed. `m·2¹²⁰` must be an integer (it is on the
/// grid: asserted, not assumed); then `|S − m·2¹²⁰| ≤ r·2¹²⁰ ⟺ |S − m·2¹²⁰| ≤ ⌊r·2¹²⁰⌋`.
fn within_grid_units(exact: i128, mid: f64, rad: f64) -> bool {
    let mid_s = mid * SCALE_120;
    assert!(mid_s == mid_s.floor(), "midpoint {mid} off the 2⁻¹²⁰ grid");
    (exact - mid_s as i128).abs() <= (rad * SCALE_120).floor() as i128
}

/// Entry `(i, j)` of a matrix.
fn entry(m: &Mat3Lanes, i: usize, j: usize) -> f64 {
    m.0[j].arr()[i]
}

/// True only if `|Σ parts − mid| ≤ r` is proven (exactly, by double-double sums).
fn within(parts: &[f64], mid: f64, r: f64) -> bool {
    let mut above = [0.0; 32];
    let mut below = [0.0; 32];
    let n = parts.len();
    for k in 0..n {
        above[k] = parts[k];
        below[k] = -parts[k];
    }
    above[n] = -mid;
    below[n] = mid;
    above[n + 1] = -r;
    below[n + 1] = -r;
    sum_le_zero(&above[..n + 2]) && sum_le_zero(&below[..n + 2])
}

/// One entry of [`RotationEnclosure::mul`]: for whole 3×3 enclosures A, B (any midpoints in
/// [−4, 4], radii `e ≤ w` up to 1/4 or 0) and members A′ = Aₘ ± A_r, B′ = Bₘ ± B_r at a random
/// vertex (the worst points of the bilinear product), |(A′·B′)ᵢⱼ − mᵢⱼ| ≤ rᵢⱼ for r = e and
/// r = w, decided exactly (TwoProduct and double-double sums). With radii 0 it is the γ term's
/// claim (the midpoint's rounding); mutant `x36d` (γ dropped) fails it.
fn rotation_mul_mid<S: Source>(s: &mut S) {
    // Under Kani the grid form below; the twin draws it a quarter of the time.
    if cfg!(kani) || s.index(4) == 0 {
        rotation_mul_grid(s);
        return;
    }
    let mut am = [[0.0; 3]; 3];
    let mut bm = [[0.0; 3]; 3];
    let (mut ae, mut aw, mut be, mut bw) =
        ([[0.0; 3]; 3], [[0.0; 3]; 3], [[0.0; 3]; 3], [[0.0; 3]; 3]);
    for i in 0..3 {
        for k in 0..3 {
            am[i][k] = s.f64_in(-4.0, 4.0);
            bm[i][k] = s.f64_in(-4.0, 4.0);
            if s.bool() {
                ae[i][k] = s.f64_in(0.0, 0.25);
                aw[i][k] = s.f64_in(ae[i][k], 0.25);
                be[i][k] = s.f64_in(0.0, 0.25);
                bw[i][k] = s.f64_in(be[i][k], 0.25);
            }
        }
    }
    let all = [am, bm, ae, aw, be, bw];
    if !s.assume(all.iter().flatten().flatten().all(|&x| tame(x))) {
        return;
    }
    let (a, b) = (enclosure(am, ae, aw), enclosure(bm, be, bw));
    let p = a.mul(&b);
    let (i, j) = (s.index(3), s.index(3));
    let mid = entry(&p.m, i, j);
    for (ar, br, r, what) in [(&ae, &be, &p.e, "e"), (&aw, &bw, &p.w, "w")] {
        // A member (a + σ·a_r)(b + τ·b_r) summed over k: four exact products each.
        let mut parts = [0.0; 24];
        let mut n = 0;
        for k in 0..3 {
            let sa = if s.bool() { -1.0 } else { 1.0 };
            let sb = if s.bool() { -1.0 } else { 1.0 };
            let (x, xr, y, yr) = (am[i][k], sa * ar[i][k], bm[k][j], sb * br[k][j]);
            for (u, v) in [(x, y), (x, yr), (xr, y), (xr, yr)] {
                if u != 0.0 && v != 0.0 {
                    let (h, l) = two_prod(u, v);
                    parts[n] = h;
                    parts[n + 1] = l;
                    n += 2;
                }
            }
        }
        let rad = entry(r, i, j);
        assert!(
            within(&parts[..n], mid, rad),
            "entry ({i}, {j}): a member of A·B is farther than {what} = {rad} from {mid}"
        );
    }
}
// Kani on the grid (47.8 s at load 3; x36d FAILED in 56.8 s) and twin.
harness!(
    d1_rotation_mul_mid,
    unwind = 4,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    rotation_mul_mid
);

/// `(x, x·2⁶⁰)` for `x` one of `0, ±1, ±2⁻³⁰, ±2⁻⁶⁰`.
fn spread<S: Source>(s: &mut S) -> (f64, i128) {
    let k = s.index(7);
    let e: u32 = [0, 0, 0, 30, 30, 60, 60][k];
    let sign = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    if k == 0 {
        return (0.0, 0);
    }
    let x = sign * f64::from_bits(u64::from(1023 - e) << 52);
    let units = 1i128 << (60 - e);
    (x, if sign < 0.0 { -units } else { units })
}

/// `2¹²⁰`: the scale of [`rotation_mul_grid`]'s integer oracle.
const SCALE_120: f64 = 1_329_227_995_784_915_872_903_807_060_280_344_576.0;

/// Under Kani, the γ term's claim of [`rotation_mul_mid`] (radii 0: the midpoint's rounding)
/// on a grid: row 0 of A and column 0 of B of `0, ±1, ±2⁻³⁰, ±2⁻⁶⁰`, the other entries 0, so
/// the products are exact and their sum rounds; `(A·B)₀₀` is an integer times 2⁻¹²⁰ (exact in
/// `i128`), `m₀₀·2¹²⁰` an integer (every partial sum is a multiple of 2⁻¹²⁰ below 4), and
/// `|S − m| ≤ r ⟺ |S − m·2¹²⁰| ≤ ⌊r·2¹²⁰⌋`.
fn rotation_mul_grid<S: Source>(s: &mut S) {
    let (mut am, mut bm) = ([[0.0; 3]; 3], [[0.0; 3]; 3]);
    let mut exact = 0i128;
    for k in 0..3 {
        let (a, au) = spread(s);
        let (b, bu) = spread(s);
        am[0][k] = a;
        bm[k][0] = b;
        exact += au * bu;
    }
    let zero = [[0.0; 3]; 3];
    let p = enclosure(am, zero, zero).mul(&enclosure(bm, zero, zero));
    let mid = entry(&p.m, 0, 0);
    for (r, what) in [(&p.e, "e"), (&p.w, "w")] {
        assert!(
            within_grid_units(exact, mid, entry(r, 0, 0)),
            "entry (0, 0): A·B = {exact}·2⁻¹²⁰ farther than {what} from the midpoint"
        );
    }
}

/// Under Kani, the γ term's claim of [`affine_encloses`] (radii 0: the midpoint's rounding) on
/// a grid: row 0 of A, `v` and `t₀` of `0, ±1, ±2⁻³⁰, ±2⁻⁶⁰` (the other entries 0), so the
/// products are exact and the sum rounds; `(A·v + t)₀` is an integer times 2⁻¹²⁰, decided as in
/// [`rotation_mul_grid`].
fn affine_grid<S: Source>(s: &mut S) {
    let mut am = [[0.0; 3]; 3];
    let (mut v, mut tm) = ([0.0; 3], [0.0; 3]);
    let mut exact = 0i128;
    for k in 0..3 {
        let (a, au) = spread(s);
        let (x, xu) = spread(s);
        am[0][k] = a;
        v[k] = x;
        exact += au * xu;
    }
    let (t, tu) = spread(s);
    tm[0] = t;
    exact += tu << 60;
    let a = enclosure(am, [[0.0; 3]; 3], [[0.0; 3]; 3]);
    let lanes = |x: [f64; 3]| Lanes3(simd::new([x[0], x[1], x[2], 0.0]));
    let t = VecEnc {
        m: lanes(tm),
        e: lanes([0.0; 3]),
        w: lanes([0.0; 3]),
    };
    let out = a.affine(&t, lanes(v));
    let mid = out.m.arr()[0];
    for (r, what) in [(out.e, "e"), (out.w, "w")] {
        assert!(
            within_grid_units(exact, mid, r.arr()[0]),
            "coordinate 0: A·v + t = {exact}·2⁻¹²⁰ farther than {what} from the midpoint"
        );
    }
}

/// Offsets with integer norms (5, 1, 3, 7): a point this far from a joint origin has an exact
/// distance, whose square root the `√` contract pins to within an ulp.
const PYTHAGOREAN: [([f64; 3], f64); 4] = [
    ([3.0, 4.0, 0.0], 5.0),
    ([0.0, 0.0, 1.0], 1.0),
    ([1.0, 2.0, 2.0], 3.0),
    ([2.0, 3.0, 6.0], 7.0),
];

/// `1 − 2⁻⁴⁰`: the slack of [`mean_value_one_joint`] for the roots (within an ulp each) and the
/// round-to-nearest sums (the code's pad, applied after, covers them in the whole claim).
const MEAN_VALUE_SLACK: f64 = 1.0 - 1.0 / 1_099_511_627_776.0;

/// One joint's term of [`RobotReach::mean_value_sums`] (the mean-value bound
/// `Σ_{j<k} δ_j·sup‖p − o_j‖`), for both points: with one joint (`k = 1`), its origin at a
/// fixed point with radius 0, each point at `o + offset/8` for an offset of integer norm
/// ([`PYTHAGOREAN`], radius 0) and `δ` any multiple of 1/16 in [0, 1], each sum is at least
/// `δ·‖p − o‖·(1 − 2⁻⁴⁰)` — every term counted in full (the distances and products are exact
/// here; `√` is the IEEE contract under Kani, any root within an ulp). A thin split whose
/// strength is mutant `x5` (δ halved in the sum), which the whole-claim twin
/// `d1_robot_link_enlargement` and this split's twin both catch.
fn mean_value_one_joint<S: Source>(s: &mut S) {
    let mut f = Frames::default();
    let o = [0.5, -0.25, 0.125];
    // Every lane holds the origin (lanes ≥ k are masked out of the sum; with the same origin
    // their radicands are the same exact square).
    for (i, &x) in o.iter().enumerate() {
        f.om[i][0] = Lanes3(simd::new([x; 4]));
    }
    let delta_j = s.index(17) as f64 * 0.0625;
    let mut delta = [Lanes3::default(); JCH];
    delta[0] = Lanes3(simd::new([delta_j, 0.0, 0.0, 0.0]));
    let point = |s: &mut S| {
        // Under Kani the offset (3, 4, 0) (every radicand (5/8)², see `sqrt_of_square`).
        let (off, norm) = PYTHAGOREAN[if cfg!(kani) { 0 } else { s.index(4) }];
        let sign = |b: bool| if b { -0.125 } else { 0.125 };
        let m = [
            o[0] + sign(s.bool()) * off[0],
            o[1] + sign(s.bool()) * off[1],
            o[2] + sign(s.bool()) * off[2],
        ];
        let enc = VecEnc {
            m: Lanes3(simd::new([m[0], m[1], m[2], 0.0])),
            ..VecEnc::default()
        };
        (enc, norm * 0.125)
    };
    let ((p0, d0), (p1, d1)) = (point(s), point(s));
    let sums = RobotReach::mean_value_sums(&f, &delta, [&p0, &p1], 1);
    for (sum, d) in [(sums[0], d0), (sums[1], d1)] {
        let need = delta_j * d * MEAN_VALUE_SLACK;
        assert!(
            sum >= need,
            "mean-value sum {sum} below δ·‖p − o‖ = {delta_j}·{d} (less the slack)"
        );
    }
}
harness!(
    d1_mean_value_one_joint,
    unwind = 5,
    bits = 52,
    stub = (crate::ieee::sqrt => sqrt_of_square),
    cases = pacs_proof_kit::DEFAULT_CASES,
    mean_value_one_joint
);

/// Stub of [`crate::ieee::sqrt`] for [`mean_value_one_joint`]: IEEE `√` of the exact square
/// `(5/8)²` is `5/8` (a correctly rounded root of an exact square is exact); any other radicand
/// gets the IEEE contract of `ieee::sqrt` (any root within an ulp).
#[cfg(kani)]
fn sqrt_of_square(x: f64) -> f64 {
    if x == 0.390625 {
        return 0.625;
    }
    crate::ieee::any_root(x)
}

/// One coordinate of [`RotationEnclosure::affine`] (A·v + t for an exact v): for an enclosure A
/// and a vector enclosure t (midpoints in [−4, 4], radii `e ≤ w` up to 1/4 or 0), any v in
/// [−4, 4]³ and members A′ = Aₘ ± A_r, t′ = tₘ ± t_r at a random vertex,
/// |(A′·v + t′)ᵢ − mᵢ| ≤ rᵢ for r = e and r = w, decided exactly.
fn affine_encloses<S: Source>(s: &mut S) {
    // Under Kani the grid form below; the twin draws it a quarter of the time.
    if cfg!(kani) || s.index(4) == 0 {
        affine_grid(s);
        return;
    }
    let mut am = [[0.0; 3]; 3];
    let (mut ae, mut aw) = ([[0.0; 3]; 3], [[0.0; 3]; 3]);
    let (mut tm, mut te, mut tw, mut v) = ([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
    for i in 0..3 {
        for k in 0..3 {
            am[i][k] = s.f64_in(-4.0, 4.0);
            if s.bool() {
                ae[i][k] = s.f64_in(0.0, 0.25);
                aw[i][k] = s.f64_in(ae[i][k], 0.25);
            }
        }
        tm[i] = s.f64_in(-4.0, 4.0);
        if s.bool() {
            te[i] = s.f64_in(0.0, 0.25);
            tw[i] = s.f64_in(te[i], 0.25);
        }
        v[i] = s.f64_in(-4.0, 4.0);
    }
    let flat = [am, ae, aw, [tm, te, tw], [v, v, v]];
    if !s.assume(flat.iter().flatten().flatten().all(|&x| tame(x))) {
        return;
    }
    let a = enclosure(am, ae, aw);
    let lanes = |x: [f64; 3]| Lanes3(simd::new([x[0], x[1], x[2], 0.0]));
    let t = VecEnc {
        m: lanes(tm),
        e: lanes(te),
        w: lanes(tw),
    };
    let out = a.affine(&t, lanes(v));
    let i = s.index(3);
    let mid = out.m.arr()[i];
    for (ar, tr, r, what) in [(&ae, te[i], out.e, "e"), (&aw, tw[i], out.w, "w")] {
        // A member Σ_k (a_k + σ_k·a_r,k)·v_k + t + τ·t_r: two exact products per k.
        let mut parts = [0.0; 14];
        let mut n = 0;
        for k in 0..3 {
            let sa = if s.bool() { -1.0 } else { 1.0 };
            for u in [am[i][k], sa * ar[i][k]] {
                let (h, l) = two_prod(u, v[k]);
                parts[n] = h;
                parts[n + 1] = l;
                n += 2;
            }
        }
        let st = if s.bool() { -1.0 } else { 1.0 };
        parts[n] = tm[i];
        parts[n + 1] = st * tr;
        n += 2;
        let rad = r.arr()[i];
        assert!(
            within(&parts[..n], mid, rad),
            "coordinate {i}: a member of A·v + t is farther than {what} = {rad} from {mid}"
        );
    }
}
// Kani on the grid (42.3 s at load 3; x80 FAILED in 23.0 s) and twin.
harness!(
    d1_affine_encloses,
    unwind = 4,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    affine_encloses
);
