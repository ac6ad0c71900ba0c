//! Proofs of the zonotopes' outside certificates and distance bound, beside them (claim C2, the
//! parts a model checker can decide; the whole claims are `b3_zonotope_contains_conservative`
//! — a property test, and a Kani proof outside CI on a one-dimensional grid — and the property
//! test `b4_zonotope_capsule_conservative` in `pacs-proofs`).
//! Inputs on dyadic grids, so that every member point is a float computed without rounding and
//! the claims are checked against the exact set:
//!
//! - `b3_hull_excludes_member` (Kani and twin): a member `x = c + β₀g₀ + β₁g₁ + γe` of a
//!   zonotope with two generators and an error box is never excluded by the hull pre-test of
//!   [`Zonotope::contains`] ([`hull_excludes_of`], the arithmetic of
//!   [`Zonotope::hull_excludes`] over [`ZonotopeData`]). Under Kani one dimension, every number
//!   a multiple of 1/16 in `[−1, 1]` (`e ≥ 0`) and the coefficients `0, ±1/2, ±1`; the twin: one
//!   or two dimensions, multiples of 2⁻⁸ up to 256, coefficients multiples of 1/4. Mutant `x37b`
//!   (the hull without the error box) fails it.
//! - `b3_separates_member` (Kani and twin): no direction `d` separates a member of a zonotope
//!   with one generator and an error box ([`separates_of`]: `d·x` rounded down against the
//!   support function rounded up). Under Kani two dimensions, the constant zonotope of
//!   [`grid_plane`] and `d = λu` with `λ = 1` (`−1` adds no direction: each `u_i` takes both
//!   signs), `u_i ∈ {0, ±1, ±2⁻⁶⁰}`; the twins any direction. Mutant `x79` (`support_up_of` without rounding) fails it under Kani only.
//! - `b4_support_up_member` (Kani and twin): [`Zonotope3::support_up`]`(d) ≥ d·p` exactly for
//!   every member `p` of a zonotope with one generator and an error box and every direction
//!   `d = λu` with `u` a vector of `0, ±1, ±2^−SMALL_EXP` (components of very different
//!   magnitudes, so the support function's sums round). Under Kani `λ = 1`, `2⁻⁶⁰` and `d·p`
//!   an integer times `2⁻⁶⁶`; in the twin `λ` any float, `2⁻³⁰`, `u·p` exact on the grid and
//!   `λ·(u·p)` compared with integer significands ([`crate::exact::cmp_prod`]). Mutant `x78`
//!   (no outward rounding, no error term) fails both.
//! - `b4_distance_bound_shared_point` (Kani and twin): [`Zonotope3::distance_bound_along`] is 0
//!   for any such direction when `Z ⊕ B(inflate)` and the capsule share a point: `q = z + w`
//!   (`z` a member, `|w| ≤ inflate`) with `|q − p₁| ≤ r` (`p₁` the capsule's first end). Under
//!   Kani the constant zonotope, `w = 0` (the shared point a member), the capsule a ball
//!   (`p₂ = p₁`) whose centre is `r` off the member along an axis (so the gap along `n` may be
//!   positive and the norm and the division decide), `λ = 1`, and `√` by [`crate::ieee::root_not_below`] (any root whose
//!   rounded square is not below the radicand by more than 2⁻⁵⁰ relative: an over-approximation
//!   of IEEE `√`); in the twin any `w`, `v` in the balls, a second end, any `λ`. Mutant `x39b`
//!   (the bound without `inflate`) fails its twin.
//!
//! The generic functions are the library's own arithmetic ([`super::hull_axis`],
//! [`super::support_up_of`]): the dynamic [`Zonotope`] calls them on its heap vectors, the
//! proofs on plain fields (the model checker unrolls nalgebra's heap storage into thousands of
//! checks, and Bitwuzla's repairs reject float arrays passed by value). Each b3 twin also checks
//! that the dynamic zonotope's method gives the same answer.

// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]

use super::containment::{hull_excludes_of, separates_of};
use super::*;
use crate::exact::cmp_prod;
use nalgebra::Point3;
use pacs_models::shape::Capsule;
use pacs_proof_kit::{Source, harness, pinned3};
use std::cmp::Ordering;

/// `n / 2^shift` for an integer `n` in `[−max, max]` (`signed`) or `[0, max]`.
fn grid<S: Source>(s: &mut S, max: usize, shift: i32, signed: bool) -> f64 {
    let n = s.index(max + 1) as f64;
    // 2^−shift from its bits (no `powi`: an LLVM intrinsic the model checker lacks).
    let x = n * f64::from_bits(((1023 - shift) as u64) << 52);
    if signed && s.bool() { -x } else { x }
}

/// A number of the zonotopes and balls, in `[0, hi]` or `[−hi, hi]`: under Kani a multiple of
/// 1/16 (`hi` ≤ 1, a multiple of 1/16), in the twins of 2⁻⁸ (`hi` ≤ 256).
fn number<S: Source>(s: &mut S, hi: f64, signed: bool) -> f64 {
    // Under Kani `hi ≤ 1`: 16 steps of 1/16 (the integer's conversion is cheaper for the solver
    // than a float of any exponent constrained to the grid, which timed out).
    let steps = if cfg!(kani) { 16.0 } else { 256.0 };
    let x = grid(
        s,
        (hi * steps) as usize,
        if cfg!(kani) { 4 } else { 8 },
        false,
    );
    if signed && s.bool() { -x } else { x }
}

/// The range of the zonotopes' numbers: under Kani `[−1, 1]`, in the twins `[−256, 256]`.
fn big() -> f64 {
    if cfg!(kani) { 1.0 } else { 256.0 }
}

/// A coefficient `β` of a member point: under Kani one of `0, ±1/2, ±1`, in the twins any
/// multiple of 1/4 in `[−1, 1]` (the boundary included).
#[derive(Debug, Clone, Copy)]
struct Coefficient {
    /// Under Kani the index of `β` in `0, 1, −1, 1/2, −1/2`; in the twins 4β + 4.
    k: usize,
}

impl Coefficient {
    fn any<S: Source>(s: &mut S) -> Self {
        Self {
            k: s.index(if cfg!(kani) { 5 } else { 9 }),
        }
    }
    /// `β·v`, exact for the grid values here. Under Kani selected, not multiplied (a product of
    /// two symbolic floats costs the solver most).
    fn times(self, v: f64) -> f64 {
        if cfg!(kani) {
            let half = v * 0.5;
            match self.k {
                0 => 0.0,
                1 => v,
                2 => -v,
                3 => half,
                _ => -half,
            }
        } else {
            (self.k as f64 - 4.0) * 0.25 * v
        }
    }
}

/// A two-dimensional zonotope with up to two generators in plain fields (no float arrays: the
/// solver's repairs of CBMC's output do not handle arrays of floats passed by value).
#[derive(Debug, Clone, Copy)]
struct Plane {
    c: (f64, f64),
    e: (f64, f64),
    /// Generators (columns), the second one used only if `m == 2`.
    g: ((f64, f64), (f64, f64)),
    m: usize,
    /// Dimension: 1 (the first coordinates only) or 2.
    n: usize,
}

impl ZonotopeData for Plane {
    fn dim(&self) -> usize {
        self.n
    }
    fn num_generators(&self) -> usize {
        self.m
    }
    fn c(&self, i: usize) -> f64 {
        if i == 0 { self.c.0 } else { self.c.1 }
    }
    fn g(&self, i: usize, j: usize) -> f64 {
        let col = if j == 0 { self.g.0 } else { self.g.1 };
        if i == 0 { col.0 } else { col.1 }
    }
    fn e(&self, i: usize) -> f64 {
        if i == 0 { self.e.0 } else { self.e.1 }
    }
}

/// A point or direction of the plane.
#[derive(Debug, Clone, Copy)]
struct Pair(f64, f64);

impl Coords for Pair {
    fn len(&self) -> usize {
        2
    }
    fn at(&self, i: usize) -> f64 {
        if i == 0 { self.0 } else { self.1 }
    }
}

impl Plane {
    /// The same set as a dynamic [`Zonotope`] (the twins check that its methods agree).
    #[cfg(not(kani))]
    fn dynamic(&self) -> Zonotope {
        Zonotope::with_error_box(
            DVector::from_fn(self.n, |i, _| self.c(i)),
            DMatrix::from_fn(self.n, self.m, |i, j| self.g(i, j)),
            DVector::from_fn(self.n, |i, _| self.e(i)),
        )
        .expect("valid")
    }
}

#[cfg(not(kani))]
fn dynamic(p: Pair, n: usize) -> DVector<f64> {
    DVector::from_column_slice(&[p.0, p.1][..n])
}

/// A plane zonotope with `m` generators on the grid and an exact member
/// `c + Σ β_j g_j + diag(e) γ`.
///
/// With `fixed`, under Kani the zonotope is the constant `c = (3/4, −1/2)`,
/// `g₀ = (−5/8, 7/8)`, `g₁ = (5/16, −3/16)`, `e = (1/8, 1/4)` (the member stays symbolic).
fn grid_plane<S: Source>(s: &mut S, n: usize, m: usize, fixed: bool) -> (Plane, Pair) {
    let k = big();
    let pair = |s: &mut S, signed| (number(s, k, signed), number(s, k, signed));
    let (c, e, g0, g1) = if cfg!(kani) && fixed {
        (
            (0.75, -0.5),
            (0.125, 0.25),
            (-0.625, 0.875),
            (0.3125, -0.1875),
        )
    } else {
        (pair(s, true), pair(s, false), pair(s, true), pair(s, true))
    };
    let g1 = if m == 2 { g1 } else { (0.0, 0.0) };
    let z = Plane {
        c,
        e,
        g: (g0, g1),
        m,
        n,
    };
    let (b0, b1) = (Coefficient::any(s), Coefficient::any(s));
    let (y0, y1) = (Coefficient::any(s), Coefficient::any(s));
    // Exact: multiples of 2⁻⁶ below 2¹¹ in magnitude.
    let x = Pair(
        c.0 + b0.times(g0.0) + b1.times(g1.0) + y0.times(e.0),
        c.1 + b0.times(g0.1) + b1.times(g1.1) + y1.times(e.1),
    );
    (z, x)
}

fn hull_member<S: Source>(s: &mut S) {
    // Kani: one dimension (the solver took 210 s for two); twins: one or two.
    let n = if cfg!(kani) { 1 } else { 1 + s.index(2) };
    let (z, x) = grid_plane(s, n, 2, false);
    let excluded = hull_excludes_of(&z, &x);
    assert!(!excluded, "{x:?} ∈ {z:?} excluded by the hull test");
    #[cfg(not(kani))]
    assert_eq!(z.dynamic().hull_excludes(&dynamic(x, z.n)), excluded);
}
harness!(
    b3_hull_excludes_member,
    unwind = 3,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    hull_member
);

fn separates_member<S: Source>(s: &mut S) {
    let n = if cfg!(kani) { 2 } else { 1 + s.index(2) };
    let (z, x) = grid_plane(s, n, 1, true);
    // Kani: directions λu with λ = 1 and u_i ∈ {0, ±1, ±2⁻⁶⁰} in two dimensions (the sums of
    // terms of such different magnitudes round); the twins: any direction of full width (its
    // products with the zonotope's numbers round) or λu with any λ.
    let d = if !cfg!(kani) && s.bool() {
        Pair(s.f64_full(-4.0, 4.0), s.f64_full(-4.0, 4.0))
    } else {
        let Some((lambda, u)) = direction(s) else {
            return;
        };
        Pair(factor(u[0], lambda), factor(u[1], lambda))
    };
    let separated = separates_of(&z, &x, &d);
    assert!(!separated, "direction {d:?} separates {x:?} from {z:?}");
    #[cfg(not(kani))]
    assert_eq!(
        z.dynamic()
            .separates(&dynamic(x, z.n), &dynamic(d, z.n))
            .expect("dimensions"),
        separated
    );
}
// Kani (two dimensions, a constant zonotope, λ = ±1: 22.6 s; mutant x79, which the twin misses,
// FAILED in 34.2 s) and twin. With one dimension and a full-width direction Kani timed out at
// 200–240 s (the exact-product test of `Interval::scale` in `d·x` the likely cost).
harness!(
    b3_separates_member,
    unwind = 4,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    separates_member
);

/// A grid vector (multiples of 1/16, up to [`big`]/16 in magnitude).
fn grid3<S: Source>(s: &mut S, signed: bool) -> [f64; 3] {
    let k = big();
    [
        number(s, k, signed),
        number(s, k, signed),
        number(s, k, signed),
    ]
}

/// A zonotope `c ⊕ [−1, 1] g ⊕ box(e)` on the grid and an exact member `c + βg + diag(e)γ`.
///
/// Under Kani the zonotope is the constant `c = (3/4, −1/2, 5/16)`, `g = (−5/8, 7/8, 1/4)`,
/// `e = (1/8, 1/16, 1/4)` (the member stays symbolic).
fn grid_zonotope3<S: Source>(s: &mut S) -> (Zonotope3<1>, [f64; 3]) {
    let (c, g, e) = if cfg!(kani) {
        (
            [0.75, -0.5, 0.3125],
            [-0.625, 0.875, 0.25],
            [0.125, 0.0625, 0.25],
        )
    } else {
        (grid3(s, true), grid3(s, true), grid3(s, false))
    };
    let b = Coefficient::any(s);
    let mut p = [0.0; 3];
    for i in 0..3 {
        // Exact: multiples of 2⁻⁶ below 2¹⁰.
        p[i] = c[i] + b.times(g[i]) + Coefficient::any(s).times(e[i]);
    }
    // `from_parts` is `check_parts` then `assemble`.
    assert!(
        Zonotope3::<1>::check_parts(c, &[g], e).is_ok(),
        "valid zonotope"
    );
    (Zonotope3::<1>::assemble(c, &[g], e), p)
}

/// The small factor's exponent: `2⁻³⁰` in the twins (with any `λ`, the sums round), `2⁻⁶⁰`
/// under Kani (`λ = 1` there, so the spread of magnitudes is what makes the sums round: with
/// `2⁻³⁰` every sum of the constant zonotope's terms was exact and mutant `x78` survived).
const SMALL_EXP: u64 = if cfg!(kani) { 60 } else { 30 };

/// `u·v` for the factor `u` of index `k` of a direction (see [`direction`]): one of `0, ±1,
/// ±2^−SMALL_EXP`, selected rather than multiplied (exact for the grid values and `λ` here).
fn factor(k: usize, v: f64) -> f64 {
    let small = f64::from_bits((1023 - SMALL_EXP) << 52);
    match k {
        0 => 0.0,
        1 => v,
        2 => -v,
        3 => v * small,
        _ => -(v * small),
    }
}

/// A direction `λu`: `λ` any float in `[−4, 4]` (the harness's significand width under Kani,
/// no underflow), each `u_i` one of `0, ±1, ±2⁻³⁰` ([`factor`]), so that `λu_i` is exact and
/// `u·p` is exact on the grid, while sums of terms of such different magnitudes round.
/// Returns `(λ, indices of u)`.
fn direction<S: Source>(s: &mut S) -> Option<(f64, [usize; 3])> {
    let lambda = if cfg!(kani) {
        // λ = −1 adds no direction: each `u_i` takes both signs.
        1.0
    } else {
        s.f64_in(-4.0, 4.0)
    };
    if !s.assume(lambda == 0.0 || lambda.abs() >= 1e-200) {
        return None;
    }
    Some((lambda, [s.index(5), s.index(5), s.index(5)]))
}

fn support_member<S: Source>(s: &mut S) {
    let (z, p) = grid_zonotope3(s);
    let Some((lambda, u)) = direction(s) else {
        return;
    };
    let d = pinned3([
        factor(u[0], lambda),
        factor(u[1], lambda),
        factor(u[2], lambda),
    ]);
    let h = z.support_up(d);
    if cfg!(kani) {
        // λ = 1 and u_i ∈ {0, ±1, ±2⁻⁶⁰}: d·p is an integer times 2⁻⁶⁶ (p a multiple of 2⁻⁶
        // below 2¹⁰), exact in i128; h·2⁶⁶ is exact (a power of two, no overflow) and
        // `d·p ≤ h ⟺ d·p·2⁶⁶ ≤ ⌈h·2⁶⁶⌉`. A float `u·p` would round here.
        let mut exact = 0i128;
        for i in 0..3 {
            let scaled = p[i] * 64.0;
            assert!(scaled == scaled.floor(), "member {p:?} off the 2⁻⁶ grid");
            let units = scaled as i128;
            exact += match u[i] {
                0 => 0,
                1 => units << 60,
                2 => -(units << 60),
                3 => units,
                _ => -units,
            };
        }
        if lambda < 0.0 {
            exact = -exact;
        }
        const SCALE: f64 = 73_786_976_294_838_206_464.0; // 2⁶⁶
        assert!(
            ((h * SCALE).ceil() as i128) >= exact,
            "support_up({d:?}) = {h} < d·p = {exact}·2⁻⁶⁶ for p = {p:?} ∈ {z:?}"
        );
    } else {
        // u·p exactly: multiples of 2⁻³⁶ below 2¹², a float.
        let up = factor(u[0], p[0]) + factor(u[1], p[1]) + factor(u[2], p[2]);
        assert!(
            cmp_prod(lambda, up, h) != Ordering::Greater,
            "support_up({d:?}) = {h} < d·p for p = {p:?} ∈ {z:?}"
        );
    }
}
// Kani (λ = ±1, the integer oracle: 9.0 s) and twin (any λ).
harness!(
    b4_support_up_member,
    unwind = 4,
    bits = 52,
    cases = pacs_proof_kit::DEFAULT_CASES,
    support_member
);

/// A grid vector `v` with `|v| ≤ r` exactly (`r` on the grid too): squares of multiples of 1/16
/// are exact, so is their sum.
fn in_ball<S: Source>(s: &mut S, r: f64) -> Option<[f64; 3]> {
    let v = [number(s, r, true), number(s, r, true), number(s, r, true)];
    s.assume(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] <= r * r)
        .then_some(v)
}

/// `±len` along one axis, or 0 (Kani's offsets in [`distance_shared_point`]: no ball constraint).
fn along_an_axis<S: Source>(s: &mut S, len: f64) -> [f64; 3] {
    let mut v = [0.0; 3];
    let k = s.index(4);
    if k < 3 {
        v[k] = if s.bool() { len } else { -len };
    }
    v
}

fn distance_shared_point<S: Source>(s: &mut S) {
    let (z, p) = grid_zonotope3(s);
    let inflate = number(s, big(), false);
    // Under Kani the shared point is the member itself (`w = 0`), the capsule a ball (`p₂ = p₁`) whose centre is `r` off the member along
    // an axis: the gap along `n` may be positive, and the bound's division and norm decide.
    let w = if cfg!(kani) {
        [0.0; 3]
    } else {
        let Some(w) = in_ball(s, inflate) else {
            return;
        };
        w
    };
    let r = number(s, big(), false);
    let v = if cfg!(kani) {
        along_an_axis(s, r)
    } else {
        let Some(v) = in_ball(s, r) else {
            return;
        };
        v
    };
    // q = p + w ∈ Z ⊕ B(inflate), and |q − p1| = |v| ≤ r: q lies in the capsule.
    let p1 = [p[0] + w[0] + v[0], p[1] + w[1] + v[1], p[2] + w[2] + v[2]];
    let p2 = if cfg!(kani) || s.bool() {
        p1
    } else {
        grid3(s, true)
    };
    let cap = Capsule::new_unchecked(Point3::from(pinned3(p1)), Point3::from(pinned3(p2)), r);
    let Some((lambda, u)) = direction(s) else {
        return;
    };
    let n = pinned3([
        factor(u[0], lambda),
        factor(u[1], lambda),
        factor(u[2], lambda),
    ]);
    let lb = z.distance_bound_along(inflate, &cap, n);
    assert!(
        lb == 0.0,
        "{z:?} ⊕ B({inflate}) separated by {lb} along {n:?} from {cap:?} sharing {:?}",
        [p[0] + w[0], p[1] + w[1], p[2] + w[2]]
    );
}
// Kani on the restricted domain of the module doc (why restricted: proofs/README.md); its twin
// also catches mutant `x39b` (the bound without `inflate`).
harness!(
    b4_distance_bound_shared_point,
    unwind = 4,
    bits = 52,
    stub = (crate::ieee::sqrt => crate::ieee::root_not_below),
    cases = pacs_proof_kit::DEFAULT_CASES,
    distance_shared_point
);
