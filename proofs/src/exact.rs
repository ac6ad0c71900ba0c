//! Exact comparisons of real-number expressions of f64 values, from error-free transformations
//! (TwoSum) and the fused multiply-add (one rounding of the exact `a·b + c`). They need no
//! interval library, so they also run under Kani.
//!
//! Preconditions (checked by the harnesses with `assume`): all inputs finite, no overflow, and
//! inputs either 0 or of magnitude ≥ [`NORMAL_MIN`] (so no partial result underflows and a
//! rounded non-zero value cannot become 0).

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

/// Exact error of `p = fl(x · y)`: `x·y = p + e` exactly (via FMA).
pub fn two_prod(x: f64, y: f64) -> (f64, f64) {
    let p = x * y;
    (p, x.mul_add(y, -p))
}

/// Order of the exact `x + y` relative to `r`.
///
/// Rounding to nearest is monotone, so `fl(x + y) > r` implies `x + y > r`'s negation cannot
/// hold; when `fl(x + y) == r` the sign of the exact error decides.
pub fn cmp_sum(x: f64, y: f64, r: f64) -> Ordering {
    let (s, e) = two_sum(x, y);
    if s != r {
        s.partial_cmp(&r).expect("finite")
    } else {
        e.partial_cmp(&0.0).expect("finite")
    }
}

/// Order of the exact `x · y` relative to `r`: the sign of `fl(x·y − r)` (one rounding of the
/// exact difference preserves its sign; no underflow under the module's preconditions).
pub fn cmp_prod(x: f64, y: f64, r: f64) -> Ordering {
    x.mul_add(y, -r).partial_cmp(&0.0).expect("finite")
}

/// Order of the exact `x / y` relative to `q` (`y ≠ 0`): `x/y − q = (x − q·y)/y`.
pub fn cmp_quot(x: f64, y: f64, q: f64) -> Ordering {
    let d = (-q).mul_add(y, x).partial_cmp(&0.0).expect("finite");
    if y > 0.0 { d } else { d.reverse() }
}

/// Order of the exact `√x` relative to `r` (`x ≥ 0`, `r ≥ 0`): `√x` vs `r` ⟺ `x` vs `r²`.
pub fn cmp_sqrt(x: f64, r: f64) -> Ordering {
    if r < 0.0 {
        return Ordering::Greater;
    }
    r.mul_add(r, -x)
        .partial_cmp(&0.0)
        .expect("finite")
        .reverse()
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
    let n = terms.len() as f64;
    let err = (n * n + 2.0) * mag * 2f64.powi(-100) + f64::MIN_POSITIVE;
    (hi + lo, err + (hi + lo).abs() * 2f64.powi(-52))
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
/// (TwoSum), so `(a_i − b_i)² = d² + 2de + e²`, each product split exactly by FMA.
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
}
