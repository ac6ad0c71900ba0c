//! Exact comparisons of real-number expressions of f64 values. Products, quotients and square
//! roots are decided on integer significands ([`Dyadic`]: exact for every finite float, no
//! overflow or underflow); sums with error-free transformations (Knuth's TwoSum, Dekker's
//! TwoProduct with Veltkamp splitting), which use only correctly rounded `+ − ×`. No fused
//! multiply-add, no interval library, no libm: the same code is the oracle of the property tests,
//! of the Kani harnesses (CBMC models `+ − ×` and integers bit-exactly but over-approximates
//! `fma`) and of the IEEE 754 contracts in [`crate::ieee`].
//!
//! Preconditions of the TwoSum/TwoProduct-based functions ([`two_prod`], [`dd_sum`] and the norm
//! and distance tests; checked by the harnesses with `assume`): all inputs finite, no overflow,
//! and inputs either 0 or of magnitude ≥ [`NORMAL_MIN`] (so no partial result underflows and a
//! rounded non-zero value cannot become 0). [`cmp_prod`], [`cmp_quot`] and [`cmp_sqrt`] need
//! finite arguments only.

use std::cmp::Ordering;

/// Smallest magnitude of non-zero harness inputs (keeps every product far from underflow).
pub const NORMAL_MIN: f64 = 1e-100;

/// `x` is 0 or finite with magnitude in `[NORMAL_MIN, 1e100]`.
pub fn tame(x: f64) -> bool {
    x == 0.0 || (x.abs() >= NORMAL_MIN && x.abs() <= 1e100)
}

/// Exact error of `s = fl(x + y)`: `x + y = s + e` exactly (Knuth's TwoSum).
pub fn two_sum(x: f64, y: f64) -> (f64, f64) {
    let s = x + y;
    let bb = s - x;
    let e = (x - (s - bb)) + (y - bb);
    (s, e)
}

/// Veltkamp's constant `2²⁷ + 1`.
const SPLITTER: f64 = 134_217_729.0;

/// `x = hi + lo` exactly, each half with at most 26 significant bits (Veltkamp; no overflow for
/// `|x| < 2⁹⁹⁵`).
#[inline]
pub fn split(x: f64) -> (f64, f64) {
    let c = SPLITTER * x;
    let hi = c - (c - x);
    (hi, x - hi)
}

/// Exact error of `p = fl(x · y)`: `x·y = p + e` exactly (Dekker's TwoProduct: the four partial
/// products of the 26-bit halves are exact). Preconditions as in the module doc (no overflow, no
/// underflow of the partial products).
#[inline]
pub fn two_prod(x: f64, y: f64) -> (f64, f64) {
    let p = x * y;
    let (xh, xl) = split(x);
    let (yh, yl) = split(y);
    let e = ((xh * yh - p) + xh * yl + xl * yh) + xl * yl;
    (p, e)
}

/// A finite float as an exact dyadic rational `(−1)^neg · m · 2^e` with an integer significand
/// (`m < 2⁵³` for a float, `< 2¹⁰⁶` for a product of two). Integer arithmetic on the significands
/// is exact and has no overflow or underflow, whatever the exponents, so the comparisons below
/// need no precondition beyond finiteness; a model checker sees them as bit-vector arithmetic
/// (one integer multiplier per product instead of Dekker's seven floating-point ones).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dyadic {
    /// Sign (true: negative; ignored when `m = 0`).
    pub neg: bool,
    /// Integer significand.
    pub m: u128,
    /// Binary exponent.
    pub e: i32,
}

impl Dyadic {
    /// The exact value of a finite `x` (`None` for ±∞ and NaN); subnormals included.
    #[inline]
    pub fn of(x: f64) -> Option<Self> {
        if !x.is_finite() {
            return None;
        }
        let bits = x.to_bits();
        let biased = ((bits >> 52) & 0x7ff) as i32;
        let frac = u128::from(bits & ((1u64 << 52) - 1));
        let (m, e) = if biased == 0 {
            (frac, -1074)
        } else {
            (frac | (1u128 << 52), biased - 1075)
        };
        Some(Self {
            neg: bits >> 63 == 1,
            m,
            e,
        })
    }

    /// The exact product of two values of at most 64-bit significands (floats, not products).
    #[inline]
    pub fn times(self, o: Self) -> Self {
        debug_assert!(self.m >> 64 == 0 && o.m >> 64 == 0);
        Self {
            neg: self.neg != o.neg,
            m: self.m * o.m,
            e: self.e + o.e,
        }
    }

    fn signum(&self) -> i8 {
        match (self.m == 0, self.neg) {
            (true, _) => 0,
            (false, true) => -1,
            (false, false) => 1,
        }
    }

    /// The exact order of two dyadics: by sign, then by the position of the leading bit, then by
    /// the significands aligned at that bit (exact: both shifted left until bit 127 is set).
    pub fn cmp_exact(&self, o: &Self) -> Ordering {
        let (sa, sb) = (self.signum(), o.signum());
        if sa != sb || sa == 0 {
            return sa.cmp(&sb);
        }
        let (za, zb) = (self.m.leading_zeros(), o.m.leading_zeros());
        // Leading bit at 2^(e + 127 − z); compare e − z.
        let (la, lb) = (
            i64::from(self.e) - i64::from(za),
            i64::from(o.e) - i64::from(zb),
        );
        let mag = if la != lb {
            la.cmp(&lb)
        } else {
            (self.m << za).cmp(&(o.m << zb))
        };
        if sa < 0 { mag.reverse() } else { mag }
    }
}

/// Exact order of `x·y` against `r` for finite `x`, `y` and any non-NaN `r` (a finite product is
/// below `+∞` and above `−∞`); `Equal` only if an argument is NaN or `x`, `y` are not finite.
fn cmp_prod_dyadic(x: f64, y: f64, r: f64) -> Ordering {
    match (Dyadic::of(x), Dyadic::of(y), Dyadic::of(r)) {
        (Some(x), Some(y), Some(r)) => x.times(y).cmp_exact(&r),
        (Some(_), Some(_), None) => against_infinity(r).unwrap_or(Ordering::Equal),
        _ => Ordering::Equal,
    }
}

/// The order of any finite value against `r = ±∞` (`None` for other `r`).
fn against_infinity(r: f64) -> Option<Ordering> {
    if r == f64::INFINITY {
        Some(Ordering::Less)
    } else if r == f64::NEG_INFINITY {
        Some(Ordering::Greater)
    } else {
        None
    }
}

/// Order of the exact `x + y` relative to `r`.
///
/// Rounding to nearest is monotone, so `fl(x + y) > r` implies `x + y > r`'s negation cannot
/// hold; when `fl(x + y) == r` the sign of the exact error decides.
pub fn cmp_sum(x: f64, y: f64, r: f64) -> Ordering {
    let (s, e) = two_sum(x, y);
    if s != r {
        s.partial_cmp(&r).unwrap_or(Ordering::Equal)
    } else {
        e.partial_cmp(&0.0).unwrap_or(Ordering::Equal)
    }
}

/// Order of the exact `x · y` relative to `r` (finite arguments, any magnitude: integer
/// significands, [`Dyadic`]).
pub fn cmp_prod(x: f64, y: f64, r: f64) -> Ordering {
    cmp_prod_dyadic(x, y, r)
}

/// Order of the exact `x / y` relative to `q` (`y ≠ 0`, all finite): `x/y − q` has the sign of
/// `(x − q·y)·sign(y)`.
pub fn cmp_quot(x: f64, y: f64, q: f64) -> Ordering {
    if let Some(o) = against_infinity(q) {
        return o;
    }
    // x − q·y vs 0  ⟺  x vs q·y.
    let d = cmp_prod_dyadic(q, y, x).reverse();
    if y > 0.0 { d } else { d.reverse() }
}

/// Order of the exact `√x` relative to `r` (`x ≥ 0`, both finite): `√x` vs `r` ⟺ `x` vs `r²`
/// (`r ≥ 0`).
pub fn cmp_sqrt(x: f64, r: f64) -> Ordering {
    if r < 0.0 {
        return Ordering::Greater;
    }
    if let Some(o) = against_infinity(r) {
        return o;
    }
    cmp_prod_dyadic(r, r, x).reverse()
}

/// Sum of floats in double-double: `(value, err)` with `|Σ terms − value| ≤ err`.
///
/// Each TwoSum is exact; the only error is the final addition of the accumulated low parts,
/// bounded generously by `2⁻⁹⁰ · Σ|terms|`-scale terms.
pub fn dd_sum(terms: &[f64]) -> (f64, f64) {
    let mut hi = 0.0;
    let mut lo = 0.0;
    let mut mag = 0.0;
    for &t in terms {
        let (s, e) = two_sum(hi, t);
        hi = s;
        lo += e;
        mag += t.abs();
    }
    // lo accumulates ≤ n errors each ≤ u·|partial| ≤ u·mag; its own rounding ≤ n·u·|lo|.
    // 2⁻¹⁰⁰ and 2⁻⁵² as constants (no `powi`: CBMC's SMT back end cannot flatten its model).
    const TWO_M100: f64 = f64::from_bits((1023 - 100) << 52);
    const TWO_M52: f64 = f64::from_bits((1023 - 52) << 52);
    let n = terms.len() as f64;
    let err = (n * n + 2.0) * mag * TWO_M100 + f64::MIN_POSITIVE;
    (hi + lo, err + (hi + lo).abs() * TWO_M52)
}

/// The smallest float `≥ x + y` (exact upward rounding; finite `x`, `y` whose sum does not
/// overflow): the rounded sum, moved up when [`cmp_sum`] finds the exact sum above it.
pub fn ceil_sum(x: f64, y: f64) -> f64 {
    let s = x + y;
    if cmp_sum(x, y, s) == Ordering::Greater {
        s.next_up()
    } else {
        s
    }
}

/// The largest float `≤ x + y` (exact downward rounding; as [`ceil_sum`]).
pub fn floor_sum(x: f64, y: f64) -> f64 {
    let s = x + y;
    if cmp_sum(x, y, s) == Ordering::Less {
        s.next_down()
    } else {
        s
    }
}

/// The smallest float `≥ x · y` (exact upward rounding; finite `x`, `y` whose product does not
/// overflow): the rounded product, moved up when [`cmp_prod`] finds the exact product above it.
pub fn ceil_prod(x: f64, y: f64) -> f64 {
    let p = x * y;
    if cmp_prod(x, y, p) == Ordering::Greater {
        p.next_up()
    } else {
        p
    }
}

/// True only if the exact `Σ terms ≤ 0` is proven by [`dd_sum`].
pub fn sum_le_zero(terms: &[f64]) -> bool {
    let (v, e) = dd_sum(terms);
    v + e <= 0.0 && v <= -e
}

/// The exact `x² + y² + z² − r²` as 8 floats summing to it exactly.
pub fn sq_terms(x: f64, y: f64, z: f64, r: f64) -> [f64; 8] {
    let (a, ae) = two_prod(x, x);
    let (b, be) = two_prod(y, y);
    let (c, ce) = two_prod(z, z);
    let (d, de) = two_prod(r, r);
    [a, ae, b, be, c, ce, -d, -de]
}

/// True only if the exact Euclidean norm of `(x, y, z)` is `≤ r` (proven).
pub fn norm3_le(x: f64, y: f64, z: f64, r: f64) -> bool {
    if x == 0.0 && y == 0.0 && z == 0.0 {
        return r >= 0.0;
    }
    r >= 0.0 && sum_le_zero(&sq_terms(x, y, z, r))
}

/// True only if the exact Euclidean norm of `(x, y, z)` is `≥ r` (proven).
pub fn norm3_ge(x: f64, y: f64, z: f64, r: f64) -> bool {
    if r <= 0.0 {
        return true;
    }
    let t = sq_terms(x, y, z, r);
    sum_le_zero(&t.map(|v| -v))
}

/// True only if the exact distance `|a − b|` is `≤ r` (proven): each `a_i − b_i = d + e` exactly
/// (TwoSum), so `(a_i − b_i)² = d² + 2de + e²`, each product split exactly by [`two_prod`].
pub fn dist3_le(a: &[f64; 3], b: &[f64; 3], r: f64) -> bool {
    if r < 0.0 {
        return false;
    }
    if a == b {
        return true;
    }
    let mut terms = [0.0; 20];
    for i in 0..3 {
        let (d, e) = two_sum(a[i], -b[i]);
        let (p0, e0) = two_prod(d, d);
        let (p1, e1) = two_prod(2.0 * d, e);
        let (p2, e2) = two_prod(e, e);
        terms[6 * i..6 * i + 6].copy_from_slice(&[p0, e0, p1, e1, p2, e2]);
    }
    let (rr, re) = two_prod(r, r);
    terms[18] = -rr;
    terms[19] = -re;
    sum_le_zero(&terms)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The directed roundings against exact integer arithmetic: terms `N·2^(e − 60)` (`|N| <
    /// 2⁴⁰`, `e ∈ [0, 60]`), whose exact sums and products are integers times `2⁻⁶⁰` and
    /// `2⁻¹²⁰`; the result must be the float next to the exact value on its side (compared as
    /// integers), and at the exact value where that is a float.
    #[test]
    fn the_directed_roundings_are_exact() {
        let mut src = pacs_proof_kit::RandomSource::new("the_directed_roundings_are_exact", 0);
        let mut next = || src.next_u64();
        let two60 = f64::from_bits((1023 + 60) << 52);
        let scaled = |v: f64, k: f64| -> i128 { (v * k) as i128 };
        for case in 0..200_000 {
            let mut term = || {
                let big = (next() % (1 << 40)) as i128 - (1 << 39);
                let e = (next() % 61) as i32;
                ((big << e) as f64) * f64::from_bits((1023 - 60) << 52)
            };
            let (a, b) = (term(), term());
            // Sums: exact value (a + b)·2⁶⁰ as an integer; the results bracket it tightly.
            let exact = scaled(a, two60) + scaled(b, two60);
            let (up, down) = (ceil_sum(a, b), floor_sum(a, b));
            assert!(
                scaled(up, two60) >= exact && scaled(up.next_down(), two60) < exact
                    || scaled(up, two60) == exact,
                "case {case}: ceil_sum({a}, {b}) = {up}"
            );
            assert!(
                scaled(down, two60) <= exact && scaled(down.next_up(), two60) > exact
                    || scaled(down, two60) == exact,
                "case {case}: floor_sum({a}, {b}) = {down}"
            );
            // Products: `c = C·2^−i`, `d = D·2^−j` (`|C|, |D| < 2⁴⁰`): the exact product is the
            // integer `C·D` (below 2⁸⁰, so it rounds) times `2^−(i+j)`; scaling the result by
            // `2^(i+j)` is exact and gives an integer (53 bits of a value ≥ 2⁵³ or the exact one).
            let (cc, dd) = (
                (next() % (1 << 40)) as i128 - (1 << 39),
                (next() % (1 << 40)) as i128 - (1 << 39),
            );
            let (i, j) = ((next() % 400) as i32, (next() % 400) as i32);
            let pow2 = |k: i32| f64::from_bits(((1023 + k) as u64) << 52);
            let (c, d) = (cc as f64 * pow2(-i), dd as f64 * pow2(-j));
            let exact = cc * dd;
            let up = ceil_prod(c, d);
            let scale = |v: f64| (v * pow2(i) * pow2(j)) as i128;
            assert!(
                scale(up) >= exact && (scale(up) == exact || scale(up.next_down()) < exact),
                "case {case}: ceil_prod({c}, {d}) = {up}"
            );
        }
        let tiny = f64::from_bits(1);
        assert_eq!(ceil_sum(1.0, tiny), 1.0f64.next_up());
        assert_eq!(floor_sum(1.0, tiny), 1.0);
        assert_eq!(floor_sum(1.0, -tiny), 1.0f64.next_down());
        assert_eq!(ceil_prod(tiny, 0.5), tiny);
        // fl(0.1·0.1) lies above the exact square of the float 0.1: it is the ceiling.
        assert_eq!(ceil_prod(0.1, 0.1), 0.1f64 * 0.1);
        assert_eq!(cmp_prod(0.1, 0.1, 0.1f64 * 0.1), Ordering::Less);
        assert_eq!(ceil_prod(3.0, -2.0), -6.0);
    }

    #[test]
    fn dyadic_comparisons_at_the_extremes() {
        // Products that underflow or overflow in floating point are still ordered exactly.
        assert_eq!(cmp_prod(1e-300, 1e-300, 0.0), Ordering::Greater);
        assert_eq!(cmp_prod(-1e-300, 1e-300, 0.0), Ordering::Less);
        assert_eq!(cmp_prod(1e300, 1e300, f64::MAX), Ordering::Greater);
        let tiny = f64::from_bits(1); // 2^-1074
        assert_eq!(cmp_prod(tiny, 0.5, 0.0), Ordering::Greater);
        assert_eq!(cmp_prod(tiny, 1.0, tiny), Ordering::Equal);
        assert_eq!(cmp_prod(tiny, 2.0, tiny.next_up()), Ordering::Equal);
        assert_eq!(cmp_prod(f64::MAX, 0.5, f64::MAX / 2.0), Ordering::Equal);
        assert_eq!(cmp_prod(0.0, -5.0, -0.0), Ordering::Equal);
        assert_eq!(cmp_prod(3.0, -2.0, -6.0), Ordering::Equal);
        assert_eq!(
            cmp_prod(3.0, -2.0, (-6.0f64).next_down()),
            Ordering::Greater
        );
        assert_eq!(cmp_prod(3.0, -2.0, (-6.0f64).next_up()), Ordering::Less);
        assert_eq!(cmp_quot(1.0, -3.0, -1.0 / 3.0), Ordering::Less);
        assert_eq!(cmp_sqrt(f64::MAX, 1.5e154), Ordering::Less);
        assert_eq!(cmp_sqrt(4.0, 2.0), Ordering::Equal);
        assert_eq!(cmp_prod(f64::NAN, 1.0, 1.0), Ordering::Equal);
        // A finite product against an infinite bound (e.g. a rounding helper that overflowed).
        assert_eq!(cmp_prod(1e300, 1e300, f64::INFINITY), Ordering::Less);
        assert_eq!(
            cmp_prod(-1e300, 1e300, f64::NEG_INFINITY),
            Ordering::Greater
        );
        assert_eq!(cmp_quot(1.0, 3.0, f64::INFINITY), Ordering::Less);
        assert_eq!(cmp_sqrt(4.0, f64::INFINITY), Ordering::Less);
    }

    #[test]
    fn oracles_on_known_values() {
        assert_eq!(cmp_sum(0.1, 0.2, 0.30000000000000004), Ordering::Less);
        assert_eq!(cmp_sum(1.0, 2.0, 3.0), Ordering::Equal);
        assert_eq!(cmp_prod(0.1, 0.1, 0.010000000000000002), Ordering::Less);
        assert_eq!(cmp_quot(1.0, 3.0, 1.0 / 3.0), Ordering::Greater);
        assert_eq!(cmp_sqrt(2.0, 2f64.sqrt()), Ordering::Less);
        assert!(norm3_le(3.0, 4.0, 0.0, 5.000001) && norm3_ge(3.0, 4.0, 0.0, 4.999999));
        assert!(!norm3_le(3.0, 4.0, 0.0, 5f64.next_down()));
        assert!(dist3_le(&[0.0; 3], &[3.0, 4.0, 0.0], 5.000001));
        assert!(!dist3_le(
            &[0.1, 0.0, 0.0],
            &[0.0, 0.0, 0.0],
            0.1f64.next_down()
        ));
    }

    /// Dekker's product agrees with the fused multiply-add (the exact error rounded once is the
    /// exact error itself when it is representable, which TwoProduct guarantees).
    #[test]
    fn two_prod_matches_fma() {
        let mut state = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let e = ((state >> 40) % 200) as i32 - 100;
            let m = 1.0 + (state >> 11) as f64 / (1u64 << 53) as f64;
            let v = m * 2f64.powi(e);
            if state & 1 == 0 { v } else { -v }
        };
        for _ in 0..100_000 {
            let (x, y) = (next(), next());
            let (p, e) = two_prod(x, y);
            assert_eq!(p, x * y);
            assert_eq!(e, x.mul_add(y, -p), "{x} * {y}");
            let r = next();
            let want = x.mul_add(y, -r).partial_cmp(&0.0).unwrap();
            assert_eq!(cmp_prod(x, y, r), want);
            assert_eq!(cmp_prod(x, y, p), e.partial_cmp(&0.0).unwrap());
        }
    }
}
