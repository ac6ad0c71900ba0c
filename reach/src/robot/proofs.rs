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
//! - `d1_rotation_mul_mid` (property test only): one entry of [`RotationEnclosure::mul`] for
//!   whole 3×3 enclosures and members at random vertices: |(A′·B′)ᵢⱼ − mᵢⱼ| ≤ eᵢⱼ and ≤ wᵢⱼ,
//!   exactly (TwoProduct, double-double sums); with radii 0 the γ term's claim. Mutant `x36d`
//!   (the γ term dropped) fails it.
//! - `d1_affine_encloses` (property test only): one coordinate of [`RotationEnclosure::affine`]
//!   (A·v + t) for members A′ = Aₘ ± A_r, t′ = tₘ ± t_r: |A′·v + t′ − m| ≤ r for r = e, w.
//!   Dropping the inflation of `w`, or `t.w`, fails it.
//!
//! Under Kani `d1_centre_trig_radii`'s inputs are ŝ, ĉ with 4-bit significands (0 or of
//! magnitude ≥ 2⁻¹⁶) and δ a power of two (0 or ≥ 2⁻¹⁰): every product and sum of the oracle is
//! then a float, and the claim is decided exactly ([`cmp_sum`]), while the code under test still
//! rounds (`TRIG_PAD`, `RAD_UP` have full significands). Its twin draws full-width ŝ, ĉ, δ
//! (and, half the time, libm's values at a centre q_c and a point q of the box, against libm's
//! sin q, cos q) and bounds the real bound from above with the outward-rounded helpers (claim
//! C1). `mul` and `affine` work on 3×3 matrices in four lanes ([`super::lanes`]); under Kani
//! `d1_rotation_mul_mid` timed out (one entry, 4-bit factors: Bitwuzla could not parse CBMC's
//! encoding of the by-value `[f64; 4]` arguments, and the SAT back end timed out at 300 s; with
//! a local repair of that encoding Bitwuzla timed out at 240 s, also with a single symbolic
//! product), so they are property tests.
//!
//! Left to the twin of `d1_robot_link_enlargement`: the chain itself (frames composed by `mul`
//! over 7 joints, the Rodrigues and z-axis local transforms), the wide-box chain over
//! `sin_cos_interval` (a5), the mean-value sums (square roots; mutant `x5`), the norms of the
//! radius vectors and the capsule assembly; and to the twin of `d1_centre_trig_radii`:
//! full-width ŝ, ĉ and half-widths that are not powers of two.
// Proof functions are entry points of the model checker, not called from the crate.
#![cfg_attr(kani, allow(dead_code))]
use super::frames::*;
use super::lanes::*;
use super::{NORM_PAD, RAD_UP, RobotReach};
use crate::exact::{cmp_sum, sum_le_zero, tame, two_prod};
use crate::rounding::{TRIG_PAD, add_up, dist3_up, mul_up};
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
    // h = min(δ²/2, 2) (δ ≥ 2 ⟺ δ²/2 ≥ 2) and s_δ = min(δ, 1), exact under Kani, above in the
    // twin.
    let h = if delta >= 2.0 {
        2.0
    } else {
        mul_or_exact(mul_or_exact(0.5, delta), delta)
    };
    let sd = delta.min(1.0);
    // Under Kani (4-bit a, b ≥ 2⁻¹⁶ and δ ≥ 2⁻¹⁰ or 0): a·h is a multiple of 2⁻⁴⁶ below 2, b·s_δ
    // of 2⁻³² below 1, so their sum is a float; h + s_δ + 1 is a multiple of 2⁻²⁷ below 4 and its
    // product with the 8-bit pad a float.
    let main = add_or_exact(mul_or_exact(a, h), mul_or_exact(b, sd));
    let pad = mul_or_exact(add_or_exact(add_or_exact(h, sd), 1.0), t);
    assert!(
        cmp_sum(main, pad, w) != Greater || cmp_sum(1.0, a, w) != Greater,
        "{what}: radius {w} below min({main} + {pad}, 1 + {a}) for δ = {delta}"
    );
}

fn centre_trig_radii<S: Source>(s: &mut S) {
    let from_libm = !cfg!(kani) && s.bool();
    let (sh, ch, qc) = if from_libm {
        // The twin: also the libm values at a centre, and the claim at points of the box.
        let qc = s.f64_in(-7.0, 7.0);
        let (sh, ch) = qc.sin_cos();
        (sh, ch, qc)
    } else {
        let (Some(sh), Some(ch)) = (
            short(s, -1.0, 1.0, 1.0 / 65536.0),
            short(s, -1.0, 1.0, 1.0 / 65536.0),
        ) else {
            return;
        };
        (sh, ch, 0.0)
    };
    // Under Kani a power of two (or 0): h and s_δ are then powers of two, and the code's
    // products by them exact scalings (4-bit half-widths timed out at 300 s, Bitwuzla).
    let delta = s.f64_short(0.0, 8.0, 0);
    if !s.assume(tame(delta) && (!cfg!(kani) || delta == 0.0 || delta >= 1.0 / 1024.0)) {
        return;
    }
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

/// A 3×3 matrix from its rows (lane 3 unused).
fn mat(rows: [[f64; 3]; 3]) -> Mat3Lanes {
    let c = |j: usize| Lanes3(simd::new([rows[0][j], rows[1][j], rows[2][j], 0.0]));
    Mat3Lanes([c(0), c(1), c(2)])
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
    let a = RotationEnclosure {
        m: mat(am),
        e: mat(ae),
        w: mat(aw),
    };
    let b = RotationEnclosure {
        m: mat(bm),
        e: mat(be),
        w: mat(bw),
    };
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
// Property test only: under Kani `mul` on 3×3 enclosures in four lanes timed out (below and
// `proofs/README.md`), even with one symbolic product.
harness!(
    d1_rotation_mul_mid,
    twin_only,
    cases = pacs_proof_kit::DEFAULT_CASES,
    rotation_mul_mid
);

/// One coordinate of [`RotationEnclosure::affine`] (A·v + t for an exact v): for an enclosure A
/// and a vector enclosure t (midpoints in [−4, 4], radii `e ≤ w` up to 1/4 or 0), any v in
/// [−4, 4]³ and members A′ = Aₘ ± A_r, t′ = tₘ ± t_r at a random vertex,
/// |(A′·v + t′)ᵢ − mᵢ| ≤ rᵢ for r = e and r = w, decided exactly.
fn affine_encloses<S: Source>(s: &mut S) {
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
    let a = RotationEnclosure {
        m: mat(am),
        e: mat(ae),
        w: mat(aw),
    };
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
// Property test only, as `d1_rotation_mul_mid` (the same four-lane operations under Kani).
harness!(
    d1_affine_encloses,
    twin_only,
    cases = pacs_proof_kit::DEFAULT_CASES,
    affine_encloses
);

/// The roots a proof with [`any_root_logged`] saw: up to eight calls of `ieee::sqrt`, each with
/// its radicand's and its result's bit patterns. Scalar statics: CBMC's SMT encoding of arrays
/// in statics is rejected by Bitwuzla ("expected bit-vector term … to 'concat'").
#[cfg(kani)]
mod root_log {
    use std::sync::atomic::AtomicU64;
    macro_rules! slots {
        ($($name:ident),*) => { $(pub static $name: AtomicU64 = AtomicU64::new(0);)* };
    }
    slots!(
        COUNT, X0, X1, X2, X3, X4, X5, X6, X7, R0, R1, R2, R3, R4, R5, R6, R7
    );
    /// `(radicand, root)` of call `k` (< 8).
    pub fn slot(k: u64) -> (&'static AtomicU64, &'static AtomicU64) {
        match k {
            0 => (&X0, &R0),
            1 => (&X1, &R1),
            2 => (&X2, &R2),
            3 => (&X3, &R3),
            4 => (&X4, &R4),
            5 => (&X5, &R5),
            6 => (&X6, &R6),
            _ => (&X7, &R7),
        }
    }
}

/// Stub of [`crate::ieee::sqrt`] for `d1_mean_value_sums`: for a positive finite `x` any `r` in
/// `[0, 1e160)`, logged with `x` (the first eight calls); IEEE results otherwise. As
/// `any_root_recorded` (a3): over-approximates IEEE `√`; the root's accuracy (the contract of
/// `ieee::sqrt`) enters only in the composition written in the harness's doc.
#[cfg(kani)]
pub(crate) fn any_root_logged(x: f64) -> f64 {
    use std::sync::atomic::Ordering::Relaxed;
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 || x == f64::INFINITY {
        return x;
    }
    let r: f64 = kani::any();
    kani::assume((0.0..1.0e160).contains(&r));
    let k = root_log::COUNT.load(Relaxed);
    if k < 8 {
        let (xs, rs) = root_log::slot(k);
        xs.store(x.to_bits(), Relaxed);
        rs.store(r.to_bits(), Relaxed);
        root_log::COUNT.store(k + 1, Relaxed);
    }
    r
}

/// The root the code took of call `k`, checked to be of the radicand `expected` (bitwise): under
/// Kani the logged one (a call with another radicand, or none, fails the claim), in the twin
/// the library root of `expected` (`√` is deterministic). A radicand of 0 takes no root under
/// Kani's stub (it returns 0 without logging), so calls are counted over positive radicands.
fn root_taken(k: u64, expected: f64) -> f64 {
    #[cfg(kani)]
    {
        use std::sync::atomic::Ordering::Relaxed;
        let (xs, rs) = root_log::slot(k);
        assert!(
            k < root_log::COUNT.load(Relaxed) && xs.load(Relaxed) == expected.to_bits(),
            "root {k}: not of the radicand {expected}"
        );
        f64::from_bits(rs.load(Relaxed))
    }
    #[cfg(not(kani))]
    {
        let _ = k;
        crate::ieee::sqrt(expected)
    }
}

/// A value on the grid `n / 2^shift`, `n` in `[−max, max]` (`signed`) or `[0, max]`, under Kani;
/// any value in that range in the twin.
fn grid_or_any<S: Source>(s: &mut S, max: usize, shift: i32, signed: bool) -> f64 {
    let scale = f64::from_bits(((1023 - shift) as u64) << 52);
    if cfg!(kani) {
        let x = s.index(max + 1) as f64 * scale;
        if signed && s.bool() { -x } else { x }
    } else {
        let m = max as f64 * scale;
        s.f64_in(if signed { -m } else { 0.0 }, m)
    }
}

/// The mean-value sums of the robot occupancy's second enclosure
/// ([`RobotReach::mean_value_sums`], claim C4), for the first `k ≤ 4` joints (one chunk of lanes)
/// and two points `p_e` given as box enclosures (midpoint ± radius per coordinate) against the
/// joint origins `o_j` (likewise):
///
/// - the radicand of joint j's root is `D_j = Σ_i d_ji²`, with `d_ji = |p_i − o_ji| + p_w,i +
///   o_w,ji` (midpoints and radii), the sup of `|p_i − o_i|` over the two boxes: for members at
///   any vertex `|p_i − o_i| ≤ d_ji`, so `D_j ≥ ‖p − o_j‖²`;
/// - the result is the round-to-nearest evaluation of `Σ_{j<k} δ_j·r_j` (lanes added pairwise)
///   with `r_j` the root of `D_j`, bit for bit.
///
/// Under Kani on grids of dyadic values (midpoints of 1/16 in [−4, 4], radii of 1/64 up to 1/4,
/// half-widths δ of 1/64 up to 1), where every `d_ji` and `D_j` is exact, with `√` by
/// [`any_root_logged`] (any root, logged with its radicand). Composition (module doc of
/// [`super`]): with the contract of `ieee::sqrt` each `r_j ≥ √D_j·(1 − 2⁻⁵²)`, and the rounded
/// sum of `k ≤ 16` products is within a relative `γ` of the exact one, which `RAD_UP` and the
/// pad of `occupancy_into` cover; so `(e_centre + mv)·RAD_UP + pad ≥ Σ_j δ_j·‖p − o_j‖` (the
/// mean-value bound of the displacement). The twin checks that final inequality at full width
/// (members at random vertices, distances rounded up). Mutant `x5` (δ/2 for the half-width)
/// fails both.
fn mean_value<S: Source>(s: &mut S) {
    let k = s.index(LANES + 1);
    let mut f = Frames::default();
    let (mut om, mut ow) = ([[0.0; LANES]; 3], [[0.0; LANES]; 3]);
    let mut delta = [0.0; LANES];
    for j in 0..LANES {
        for i in 0..3 {
            om[i][j] = grid_or_any(s, 64, 4, true);
            ow[i][j] = grid_or_any(s, 16, 6, false);
        }
        delta[j] = grid_or_any(s, 64, 6, false);
    }
    let (mut pm, mut pw) = ([[0.0; 3]; 2], [[0.0; 3]; 2]);
    for e in 0..2 {
        for i in 0..3 {
            pm[e][i] = grid_or_any(s, 64, 4, true);
            pw[e][i] = grid_or_any(s, 16, 6, false);
        }
    }
    for i in 0..3 {
        f.om[i][0] = Lanes3(simd::new(om[i]));
        f.ow[i][0] = Lanes3(simd::new(ow[i]));
    }
    let mut dl = [Lanes3::default(); JCH];
    dl[0] = Lanes3(simd::new(delta));
    let lanes = |x: [f64; 3]| Lanes3(simd::new([x[0], x[1], x[2], 0.0]));
    let p = [0, 1].map(|e| VecEnc {
        m: lanes(pm[e]),
        e: Lanes3::default(),
        w: lanes(pw[e]),
    });
    let mv = RobotReach::mean_value_sums(&f, &dl, [&p[0], &p[1]], k);
    let mut call = 0;
    for e in 0..2 {
        let mut terms = [0.0; LANES];
        let mut truth = 0.0;
        for j in 0..LANES {
            // The sup distance per coordinate, and a member pair at a vertex within it.
            let mut d2 = 0.0;
            let (mut pp, mut op) = ([0.0; 3], [0.0; 3]);
            for i in 0..3 {
                let d = ((pm[e][i] - om[i][j]).abs() + pw[e][i]) + ow[i][j];
                d2 += d * d;
                let sp = if s.bool() { 1.0 } else { -1.0 };
                let so = if s.bool() { 1.0 } else { -1.0 };
                pp[i] = pm[e][i] + sp * pw[e][i];
                op[i] = om[i][j] + so * ow[i][j];
                if cfg!(kani) {
                    let gap = pp[i] - op[i];
                    assert!(gap.abs() <= d, "coordinate {i}: |{gap}| above the sup {d}");
                }
            }
            // The code takes no root at all for k = 0 (no chunk).
            let r = if k > 0 && d2 > 0.0 {
                let r = root_taken(call, d2);
                call += 1;
                r
            } else {
                0.0
            };
            let mask = if j < k { 1.0 } else { 0.0 };
            terms[j] = 0.0 + r * (delta[j] * mask);
            if j < k {
                // An upper bound of δ_j·‖p − o_j‖ for the member pair (twin only).
                truth = add_up(truth, mul_up(delta[j], dist3_up(&pp, &op)));
            }
        }
        let sum = (terms[0] + terms[1]) + (terms[2] + terms[3]);
        if cfg!(kani) {
            assert!(
                mv[e].to_bits() == sum.to_bits(),
                "point {e}: the sum {} is not Σ δ_j·r_j = {sum} (k = {k})",
                mv[e]
            );
        } else if k > 0 {
            // The mean-value bound as `occupancy_into` pads it (e_centre = 0 here).
            let w: f64 = delta[..k].iter().fold(1.0, |a, &d| add_up(a, d));
            let bound = mv[e] * RAD_UP + mul_up(NORM_PAD, w);
            assert!(
                truth <= bound,
                "point {e}: Σ δ_j·‖p − o_j‖ ≤ {truth} above the padded sum {bound} (k = {k})"
            );
        }
    }
}
harness!(
    d1_mean_value_sums,
    unwind = 5,
    bits = 52,
    stub = (crate::ieee::sqrt => any_root_logged),
    cases = pacs_proof_kit::DEFAULT_CASES,
    mean_value
);
