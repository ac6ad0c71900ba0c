//! Directed rounding for f64 without changing the FPU mode.
//!
//! IEEE 754 `+ - * / sqrt` are correctly rounded to nearest, so the exact result lies within half
//! an ulp of the computed one; stepping one ulp outward (`next_up` / `next_down`) therefore gives a
//! guaranteed upper / lower bound. These helpers are the only place where that argument is made;
//! everything that needs a sound scalar bound goes through them (or through [`crate::interval::Interval`]).
//!
//! `sin`/`cos` are not correctly rounded in libm; [`sin_cos_interval`] pads libm's results by
//! [`TRIG_PAD`], which exceeds the documented error of glibc and of Rust's libm (≤ 1 ulp on
//! [-1, 1], i.e. ≤ 1.12e-16) by a factor of about a hundred (1e-14 m is far below any geometric tolerance here). A test compares libm against a rigorous
//! Taylor enclosure on 10⁵ arguments.

use crate::interval::Interval;

/// Absolute padding applied to libm `sin`/`cos` values (see module docs).
pub const TRIG_PAD: f64 = 1e-14;

/// `x + y` rounded up.
///
/// # Soundness
/// Claim C1: ≥ the exact sum (IEEE round-to-nearest, one step up). Harness `a1_add_enclose`
/// (beside this module, `proofs.rs`); mutant `m1` caught.
#[inline(always)]
pub fn add_up(x: f64, y: f64) -> f64 {
    (x + y).next_up()
}
/// `x + y` rounded down.
///
/// # Soundness
/// Claim C1: ≤ the exact sum. Harness `a1_add_enclose`.
#[inline(always)]
pub fn add_down(x: f64, y: f64) -> f64 {
    (x + y).next_down()
}
/// `x - y` rounded up.
///
/// # Soundness
/// Claim C1: ≥ the exact difference. Harness `a1_sub_enclose`.
#[inline(always)]
pub fn sub_up(x: f64, y: f64) -> f64 {
    (x - y).next_up()
}
/// `x - y` rounded down.
///
/// # Soundness
/// Claim C1: ≤ the exact difference. Harness `a1_sub_enclose`.
#[inline(always)]
pub fn sub_down(x: f64, y: f64) -> f64 {
    (x - y).next_down()
}
/// `x * y` rounded up.
///
/// # Soundness
/// Claim C1: ≥ the exact product. Harnesses `a2_mul_up_pp`, `_pn`, `_np`, `_nn` (Kani, beside
/// this module: one per sign quadrant of the operands, together every pair; the whole end is
/// `a2_mul_up_enclose`, heavy-tailed under Kani; the twin `a2_mul_enclose` draws any pair);
/// mutant `x14` caught by all.
#[inline(always)]
pub fn mul_up(x: f64, y: f64) -> f64 {
    (x * y).next_up()
}
/// `x * y` rounded down.
///
/// # Soundness
/// Claim C1: ≤ the exact product. Harnesses `a2_mul_down_pp`, `_pn`, `_np`, `_nn` (Kani, one
/// per sign quadrant; the whole end `a2_mul_down_enclose`; twin `a2_mul_enclose`); mutant
/// `x14b` caught.
#[inline(always)]
pub fn mul_down(x: f64, y: f64) -> f64 {
    (x * y).next_down()
}
/// `x / y` rounded up.
///
/// # Soundness
/// Claim C1: ≥ the exact quotient. Harness `a2_div_enclose`; mutant `x16` caught.
#[inline(always)]
pub fn div_up(x: f64, y: f64) -> f64 {
    (x / y).next_up()
}
/// `x / y` rounded down.
///
/// # Soundness
/// Claim C1: ≤ the exact quotient. Harness `a2_div_enclose`.
#[inline(always)]
pub fn div_down(x: f64, y: f64) -> f64 {
    (x / y).next_down()
}
/// `sqrt(x)` rounded up (`x >= 0`; a negative rounding artefact is treated as 0).
///
/// # Soundness
/// Claim C1: ≥ the exact √x, given `ieee::sqrt`'s contract (`prev(r)² ≤ x ≤ next(r)²`, tested
/// against the library). Harness `a2_sqrt_root_step` (Kani: the result is `next(r)` of the root
/// `r` of `x` itself; mutant `x42`) and `a2_sqrt_enclose` (the whole claim; Kani on a grid of
/// values with irrational roots, its twin any `x` against the exact oracle).
#[inline(always)]
pub fn sqrt_up(x: f64) -> f64 {
    crate::ieee::sqrt(x.max(0.0)).next_up()
}
/// `sqrt(x)` rounded down, never below 0.
///
/// # Soundness
/// Claim C1: ≤ the exact √x, given `ieee::sqrt`'s contract. Harness `a2_sqrt_root_step` (Kani:
/// at most `prev(r)`, never below 0; mutant `x30`) and `a2_sqrt_enclose` (Kani on a grid, and
/// its twin).
#[inline(always)]
pub fn sqrt_down(x: f64) -> f64 {
    crate::ieee::sqrt(x.max(0.0)).next_down().max(0.0)
}

/// Relative inflation that bounds the rounding error of a short expression of non-negative terms:
/// an expression of k ≤ 16 correctly rounded `+ × √` operations on non-negative floats is at most
/// a factor (1 − u)^−k < 1 + 2e-15 below its exact value (u = 2⁻⁵³, no overflow), so multiplying
/// by 1 + 1e-14 (itself rounded, losing < u) and adding [`TINY`] for underflow bounds it from above.
pub const INFLATE: f64 = 1.0 + 1e-14;
/// Absolute slack covering underflow in [`INFLATE`]-bounded expressions.
pub const TINY: f64 = 1e-300;

/// Absolute slack after a square root of an [`INFLATE`]-bounded sum: squares that underflow lose
/// up to 2⁻¹⁰⁷⁴ each, and √ turns an absolute error ε of the radicand into up to √ε ≈ 4e-162 (for
/// three terms), far above [`TINY`].
pub const SQRT_TINY: f64 = 1e-150;

/// Upper bound of the Euclidean norm of `(x, y, z)` (see [`INFLATE`], [`SQRT_TINY`]).
///
/// # Soundness
/// Claim C1: ≥ the exact norm, given `ieee::sqrt`'s contract. Harness `a3_norm_up_encloses`
/// (Kani on a grid where squares and sums round, an integer oracle; its twin any coordinates);
/// Kani proves the `√`-and-inflation step at 8 bits (`a3_norm_up_sqrt_inflate`); mutant `x1`
/// caught.
#[inline]
pub fn norm3_up(x: f64, y: f64, z: f64) -> f64 {
    crate::ieee::sqrt(x * x + y * y + z * z) * INFLATE + SQRT_TINY
}

/// Lower bound of the Euclidean norm of `(x, y, z)`.
///
/// # Soundness
/// Claim C1: ≤ the exact norm, given `ieee::sqrt`'s contract. Harness `a3_norm_down_encloses`
/// (Kani on a grid where squares and sums round; its twin any coordinates); Kani proves the `√`
/// step at 8 bits (`a3_norm_down_sqrt`); mutant `x30`.
#[inline]
pub fn norm3_down(x: f64, y: f64, z: f64) -> f64 {
    sqrt_down(add_down(
        add_down(mul_down(x, x), mul_down(y, y)),
        mul_down(z, z),
    ))
}

/// Upper bound of the distance between two points.
///
/// # Soundness
/// Claim C1: ≥ the exact distance, given `ieee::sqrt`'s contract. Harness `a3_dist_up_encloses`
/// (Kani on a grid where differences, squares and sums round; its twin any points); Kani proves
/// the coordinate bounds and the `√`-and-inflation step at 6 bits (`a3_dist_up_sqrt_inflate`).
#[inline]
pub fn dist3_up(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    // |fl(a-b)| may be below |a-b| by half an ulp per coordinate; bound it from both sides.
    let d = |i: usize| {
        let lo = sub_down(a[i], b[i]);
        let hi = sub_up(a[i], b[i]);
        lo.abs().max(hi.abs())
    };
    norm3_up(d(0), d(1), d(2))
}

/// A rigorous enclosure of `[sin x, cos x]` for every `x` in `[lo, hi]` (`lo <= hi`, finite).
///
/// Uses libm at the endpoints padded by [`TRIG_PAD`], plus the extrema ±1 when a critical point
/// `kπ/2` may lie inside (decided with an interval enclosure of π, so borderline cases include it).
///
/// # Soundness
/// Claim C1: contains sin x and cos x for every x in `[lo, hi]`, assuming libm's sin/cos within
/// 1 ulp on the reduced range. Harness `a5_sin_cos_interval_encloses` (the Kani proof: the
/// critical points, for `lo < hi`; the twin: the whole claim against libm); mutant `x4` caught.
pub fn sin_cos_interval(lo: f64, hi: f64) -> (Interval, Interval) {
    debug_assert!(lo <= hi, "sin_cos_interval({lo}, {hi})");
    let full = Interval::new(-1.0, 1.0).expect("valid");
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) || hi - lo >= 6.0 {
        return (full, full);
    }
    let (s_lo, c_lo) = crate::ieee::sin_cos(lo);
    if lo == hi {
        let s =
            Interval::new((s_lo - TRIG_PAD).max(-1.0), (s_lo + TRIG_PAD).min(1.0)).unwrap_or(full);
        let c =
            Interval::new((c_lo - TRIG_PAD).max(-1.0), (c_lo + TRIG_PAD).min(1.0)).unwrap_or(full);
        return (s, c);
    }
    let (s_hi, c_hi) = crate::ieee::sin_cos(hi);
    let mut s_min = s_lo.min(s_hi) - TRIG_PAD;
    let mut s_max = s_lo.max(s_hi) + TRIG_PAD;
    let mut c_min = c_lo.min(c_hi) - TRIG_PAD;
    let mut c_max = c_lo.max(c_hi) + TRIG_PAD;
    // Critical points x = kπ/2 (k ≡ 0 mod 4: cos max; 1: sin max; 2: cos min; 3: sin min).
    // Candidates k are taken one wider than the nominal range; each is then tested against an
    // enclosure of kπ/2 (π/2 lies between the neighbours of its correctly rounded f64 value).
    let half_pi = Interval::new(
        std::f64::consts::FRAC_PI_2.next_down(),
        std::f64::consts::FRAC_PI_2.next_up(),
    )
    .expect("valid");
    let k_lo = (lo / std::f64::consts::FRAC_PI_2).floor() as i64 - 1;
    let k_hi = (hi / std::f64::consts::FRAC_PI_2).ceil() as i64 + 1;
    for kk in k_lo..=k_hi {
        let p = half_pi.scale(kk as f64);
        if p.hi() < lo || p.lo() > hi {
            continue;
        }
        match kk.rem_euclid(4) {
            0 => c_max = 1.0,
            1 => s_max = 1.0,
            2 => c_min = -1.0,
            _ => s_min = -1.0,
        }
    }
    let clamp = |a: f64, b: f64| Interval::new(a.max(-1.0), b.min(1.0)).unwrap_or(full);
    (clamp(s_min, s_max), clamp(c_min, c_max))
}

/// The Kani proofs of this module, each also a property test (`proofs/README.md`).
#[cfg(any(test, kani))]
pub(crate) mod proofs;

#[cfg(test)]
mod tests {
    use super::*;
    use inari::{Interval as IInterval, interval};
    use proptest::prelude::*;

    /// Rigorous sin/cos enclosure: argument reduction by kπ/2 with an interval π, then a Taylor
    /// series in interval arithmetic on the reduced argument (|r| <= 0.8).
    fn taylor_sin_cos(x: f64) -> (IInterval, IInterval) {
        let one = interval!(1.0, 1.0).unwrap();
        // Cody–Waite split of π/2: HI has 33 significant bits (k·HI exact), TAIL = π/2 − HI
        // correctly rounded (fdlibm's pio2_1, pio2_1t), enclosed by one ulp either side.
        const HI: f64 = f64::from_bits(0x3ff9_21fb_5440_0000); // 1.5707963267341256
        const TAIL: f64 = f64::from_bits(0x3dd0_b461_1a62_6331); // 6.077100506506192e-11
        let tail = interval!(TAIL.next_down(), TAIL.next_up()).unwrap();
        assert!(
            (IInterval::PI / interval!(2.0, 2.0).unwrap())
                .subset(interval!(HI, HI).unwrap() + tail)
        );
        let k = (x / std::f64::consts::FRAC_PI_2).round();
        let ki = interval!(k, k).unwrap();
        let r = interval!(x, x).unwrap() - ki * interval!(HI, HI).unwrap() - ki * tail;
        // Horner: sin r = r(1 − r²/(2·3)(1 − r²/(4·5)(…))), cos r = 1 − r²/(1·2)(1 − r²/(3·4)(…)).
        let r2 = r * r;
        let mut s = one;
        let mut c = one;
        for n in (1..15u32).rev() {
            let ds = interval!((2 * n * (2 * n + 1)) as f64, (2 * n * (2 * n + 1)) as f64).unwrap();
            let dc = interval!((2 * n * (2 * n - 1)) as f64, (2 * n * (2 * n - 1)) as f64).unwrap();
            s = one - r2 / ds * s;
            c = one - r2 / dc * c;
        }
        let s = r * s;
        let rem = interval!(-1e-30, 1e-30).unwrap(); // |r|^30/30! < 1e-30
        let (s, c) = (s + rem, c + rem);
        match (k as i64).rem_euclid(4) {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }

    #[test]
    fn libm_within_pad_of_rigorous_taylor() {
        let mut rng = 0x2545F4914F6CDD1Du64;
        for _ in 0..100_000 {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            let x = ((rng >> 11) as f64 / (1u64 << 53) as f64) * 14.0 - 7.0;
            let (s, c) = taylor_sin_cos(x);
            let (sl, cl) = x.sin_cos();
            // The enclosure is tight enough for the check to mean something...
            assert!(
                s.wid() < 4e-15 && c.wid() < 4e-15,
                "taylor enclosure too wide at {x}"
            );
            // ...and every exact value in it is within TRIG_PAD of libm.
            assert!(
                s.sup() - TRIG_PAD <= sl && sl <= s.inf() + TRIG_PAD,
                "sin({x}) = {sl} vs {s:?}"
            );
            assert!(
                c.sup() - TRIG_PAD <= cl && cl <= c.inf() + TRIG_PAD,
                "cos({x}) = {cl} vs {c:?}"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(10_000))]
        #[test]
        fn sin_cos_interval_encloses_samples(a in -7.0f64..7.0, w in 0.0f64..7.0, t in 0.0f64..=1.0) {
            let hi = a + w;
            let (s, c) = sin_cos_interval(a, hi);
            let x = a + t * (hi - a);
            let x = x.clamp(a, hi);
            let (ts, tc) = taylor_sin_cos(x);
            prop_assert!(s.lo() <= ts.inf() && ts.sup() <= s.hi(), "sin {x} in [{a},{hi}]: {s:?} vs {ts:?}");
            prop_assert!(c.lo() <= tc.inf() && tc.sup() <= c.hi(), "cos {x} in [{a},{hi}]: {c:?} vs {tc:?}");
        }

        #[test]
        fn norm3_up_bounds_exact(x in -1e6f64..1e6, y in -1e-3f64..1e3, z in -1e3f64..1e3) {
            let (xi, yi, zi) = (interval!(x, x).unwrap(), interval!(y, y).unwrap(), interval!(z, z).unwrap());
            let exact = (xi.sqr() + yi.sqr() + zi.sqr()).sqrt();
            prop_assert!(exact.sup() <= norm3_up(x, y, z));
            prop_assert!(norm3_down(x, y, z) <= exact.inf());
        }

        #[test]
        fn directed_ops_bound_exact(x in -1e6f64..1e6, y in -1e6f64..1e6) {
            // Exact results via inari (rigorous) must lie between the down and up variants.
            let xi = interval!(x, x).unwrap();
            let yi = interval!(y, y).unwrap();
            for (lo, hi, e) in [
                (add_down(x, y), add_up(x, y), xi + yi),
                (sub_down(x, y), sub_up(x, y), xi - yi),
                (mul_down(x, y), mul_up(x, y), xi * yi),
            ] {
                prop_assert!(lo <= e.inf() && e.sup() <= hi);
            }
            if y != 0.0 {
                let e = xi / yi;
                prop_assert!(div_down(x, y) <= e.inf() && e.sup() <= div_up(x, y));
            }
            let ax = x.abs();
            let e = interval!(ax, ax).unwrap().sqrt();
            prop_assert!(sqrt_down(ax) <= e.inf() && e.sup() <= sqrt_up(ax));
        }
    }
}
