//! Correctly rounded conversion of a scanned decimal `w·10^q` (`w` of at most 19 digits) to
//! `f64` by one wide integer product, for the numbers outside the exact fast path (Clinger's)
//! that logs are full of: 16–19 significant digits with a small exponent.
//!
//! # Method
//! `5^q` is kept as a 128-bit integer `T` with its top bit set and a binary exponent: exactly for
//! `0 ≤ q ≤ 55` (`5^55 < 2^128`), and as `T = ⌊2^(127+L) / 5^|q|⌋` for `−54 ≤ q < 0` (`L` the bit
//! length of `5^|q|`), so that `T ≤ T* < T + 1` for the exact `T* = 2^(127+L) / 5^|q|`. With `w`
//! shifted left until its top bit is set (`w′`), the value is `w′·T*·2^E` for a known `E`, and
//! `P = w′·T` (a 192-bit integer) bounds it: `P ≤ w′·T* < P + w′`. Round-to-nearest-even is
//! monotone, so if `P` and `P + w′` round to the same double, so does the exact value (for
//! `q ≥ 0`, `T* = T` and `P` is exact). Otherwise, or outside the normal exponent range, or for
//! `q` outside `[−54, 55]`, [`to_f64`] returns `None` and the caller uses the standard library's
//! parse. No tables from elsewhere: `T` is computed here (`const`), by integer arithmetic.
//!
//! Agreement with the standard library's parse, bit for bit: `tests/jsonl_fast.rs`
//! (`the_wide_product_agrees_with_the_standard_parse`, 1,000,000 literals of 16–19 digits, and
//! the scanner's other number tests).

/// Smallest and largest decimal exponent with a table entry.
const Q_MIN: i32 = -54;
const Q_MAX: i32 = 55;
const ENTRIES: usize = (Q_MAX - Q_MIN + 1) as usize;

/// `(T, s)` per `q` in `Q_MIN..=Q_MAX`: `5^q ≈ T·2^(−s)` with `2^127 ≤ T < 2^128` (exact for
/// `q ≥ 0`, rounded down for `q < 0`, module docs).
const POW5: [(u128, i32); ENTRIES] = pow5_table();

const fn pow5_table() -> [(u128, i32); ENTRIES] {
    let mut t = [(0u128, 0i32); ENTRIES];
    let mut i = 0;
    while i < ENTRIES {
        let q = Q_MIN + i as i32;
        let mut p: u128 = 1; // 5^|q|
        let mut k = 0;
        while k < q.unsigned_abs() {
            p *= 5;
            k += 1;
        }
        let bits = 128 - p.leading_zeros() as i32; // L, the bit length of 5^|q|
        t[i] = if q >= 0 {
            // 5^q = (p << lz)·2^(−lz).
            let lz = p.leading_zeros();
            (p << lz, lz as i32)
        } else {
            // ⌊2^(127+L) / p⌋ by binary long division (p < 2^126: 2r never overflows), the
            // quotient lies in (2^127, 2^128): 5^q = 2^(127+L)/p · 2^(−(127+L)).
            let n = 127 + bits;
            let mut r: u128 = 1; // 2^0 mod p, as the dividend's bits are brought down
            let mut quo: u128 = 0;
            let mut j = 0;
            while j < n {
                r <<= 1;
                quo <<= 1;
                if r >= p {
                    r -= p;
                    quo |= 1;
                }
                j += 1;
            }
            (quo, n)
        };
        i += 1;
    }
    t
}

/// The double nearest to `mant·10^q` (ties to even), `mant < 2^64`, or `None` where this method
/// does not decide it (module docs). `mant = 0` is `None` (the caller's exact path covers it).
#[inline]
pub(super) fn to_f64(mant: u64, q: i64) -> Option<f64> {
    if mant == 0 || q < i64::from(Q_MIN) || q > i64::from(Q_MAX) {
        return None;
    }
    let (t, s) = POW5[(q - i64::from(Q_MIN)) as usize];
    let lz = mant.leading_zeros();
    let w = mant << lz;
    // P = w·T as (top, bottom): top = bits 64..192, bottom = bits 0..64.
    let lo = u128::from(w) * (t & u128::from(u64::MAX));
    let hi = u128::from(w) * (t >> 64);
    let top = hi + (lo >> 64); // < 2^128: hi ≤ (2^64 − 1)², lo >> 64 < 2^64
    let bottom = lo as u64;
    // The value is (w·T*)·2^E, E = q − s − lz (10^q = 5^q·2^q, w = w′·2^(−lz)).
    let e = q as i32 - s - lz as i32;
    let lower = Split::of(top, bottom);
    let x = lower.round(e)?;
    if q >= 0 {
        return Some(x); // T exact: P is the exact value.
    }
    // P + w′ (a carry out of `bottom` goes into `top`; P + w′ < 2^192).
    let (b2, carry) = bottom.overflowing_add(w);
    if lower.same_rounding_above(carry) {
        return Some(x);
    }
    let upper = Split::of(top + u128::from(carry), b2).round(e)?;
    (x.to_bits() == upper.to_bits()).then_some(x)
}

/// A 192-bit integer `top·2^64 + bottom` (`top ≥ 2^126`) cut where a double's 53 significant
/// bits end: the kept bits `m`, the first bit below them (`half`), and what lies below that.
struct Split {
    /// The leading 53 bits, in [2^52, 2^53).
    m: u64,
    /// The bit just below `m`'s last.
    half: bool,
    /// Any bit below `half` set (in `top` or in `bottom`).
    sticky: bool,
    /// Every bit of `top` below `half` set (adding 1 to `top` carries into `half`).
    top_rest_full: bool,
    /// Bit position of the leading one within the 192-bit integer: 190 or 191.
    hb: i32,
}

impl Split {
    /// The cut, in 64-bit words: `top ≥ 2^126` puts its leading one in bit 62 or 63 of its high
    /// word `th`, so the 53 kept bits and `half` lie in `th` (a shift of 10 or 11) and the bits
    /// below `half` are the rest of `th`, `top`'s low word and `bottom`.
    #[inline]
    fn of(top: u128, bottom: u64) -> Split {
        let th = (top >> 64) as u64;
        let tl = top as u64;
        let lz = th.leading_zeros(); // 0 or 1
        let shift = 11 - lz;
        let rest_mask = (1u64 << (shift - 1)) - 1;
        let rest = th & rest_mask;
        Split {
            m: th >> shift,
            half: (th >> (shift - 1)) & 1 == 1,
            sticky: rest != 0 || tl != 0 || bottom != 0,
            top_rest_full: rest == rest_mask && tl == u64::MAX,
            hb: 191 - lz as i32,
        }
    }

    /// Whether `P + w′` rounds as `P` (this split), where `0 < w′ < 2^64` was added to `P`'s
    /// `bottom` with `carry` out of it, without splitting `P + w′`. Let `R` be the bits below
    /// `half`. If `R ≠ 0` (`sticky`), adding `w′` changes neither `m` nor `half` unless it carries
    /// through every bit of `top` below `half`, and both stay sticky: the same rounding. If
    /// `R = 0`, there is no carry (`bottom = 0`), `m` and `half` stay, and `P + w′` is sticky:
    /// it rounds up exactly where `half` is set, as `P` does unless `P` is a tie that rounds down
    /// to an even `m`. (False is always safe: the caller then rounds `P + w′` itself.)
    #[inline]
    fn same_rounding_above(&self, carry: bool) -> bool {
        if self.sticky {
            !(carry && self.top_rest_full)
        } else {
            !self.half || self.m & 1 == 1
        }
    }

    /// The value `·2^e`, rounded to the nearest double (ties to even); `None` outside the
    /// normal range (subnormal results and overflow are left to the caller).
    #[inline]
    fn round(&self, e: i32) -> Option<f64> {
        let mut m = self.m;
        if self.half && (self.sticky || m & 1 == 1) {
            m += 1;
        }
        // value = m·2^(hb − 52 + e); the unbiased exponent of a double m·2^k with m in
        // [2^52, 2^53) is k + 52.
        let mut exp = self.hb + e;
        if m == 1 << 53 {
            m >>= 1;
            exp += 1;
        }
        if !(-1022..=1023).contains(&exp) {
            return None;
        }
        let bits = (((exp + 1023) as u64) << 52) | (m & ((1 << 52) - 1));
        Some(f64::from_bits(bits))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_five_to_the_q() {
        // q ≥ 0: T·2^(−s) is 5^q exactly.
        for q in 0..=Q_MAX {
            let (t, s) = POW5[(q - Q_MIN) as usize];
            assert!(t >> 127 == 1);
            assert_eq!(t >> s, 5u128.pow(q as u32), "q = {q}");
            assert_eq!((t >> s) << s, t, "q = {q}");
        }
        // q < 0: T·5^|q| ≤ 2^s < (T + 1)·5^|q| exactly (256-bit products), T's top bit set.
        for q in Q_MIN..0 {
            let (t, s) = POW5[(q - Q_MIN) as usize];
            assert!(t >> 127 == 1, "q = {q}");
            let p = 5u128.pow(q.unsigned_abs());
            let two_s = shl256(s as u32);
            assert!(le256(mul256(t, p), two_s), "T·5^|q| > 2^s at q = {q}");
            assert!(
                lt256(two_s, mul256(t + 1, p)),
                "(T + 1)·5^|q| ≤ 2^s at q = {q}"
            );
        }
        // Spot values: 5^-1 = 0.2 = 0xCCCC…·2^(−130).
        let (t, s) = POW5[(-1 - Q_MIN) as usize];
        assert_eq!(t, 0xCCCC_CCCC_CCCC_CCCC_CCCC_CCCC_CCCC_CCCC);
        assert_eq!(s, 130);
    }

    /// `a·b` as four 64-bit limbs, least significant first.
    fn mul256(a: u128, b: u128) -> [u64; 4] {
        let (a, b) = ([a as u64, (a >> 64) as u64], [b as u64, (b >> 64) as u64]);
        let mut r = [0u64; 4];
        for i in 0..2 {
            let mut carry = 0u128;
            for j in 0..2 {
                let cur = u128::from(r[i + j]) + u128::from(a[i]) * u128::from(b[j]) + carry;
                r[i + j] = cur as u64;
                carry = cur >> 64;
            }
            let mut k = i + 2;
            while carry != 0 {
                let cur = u128::from(r[k]) + carry;
                r[k] = cur as u64;
                carry = cur >> 64;
                k += 1;
            }
        }
        r
    }

    fn shl256(s: u32) -> [u64; 4] {
        let mut r = [0u64; 4];
        r[(s / 64) as usize] = 1 << (s % 64);
        r
    }

    fn lt256(a: [u64; 4], b: [u64; 4]) -> bool {
        a.iter().rev().cmp(b.iter().rev()) == std::cmp::Ordering::Less
    }

    fn le256(a: [u64; 4], b: [u64; 4]) -> bool {
        a.iter().rev().cmp(b.iter().rev()) != std::cmp::Ordering::Greater
    }

    #[test]
    fn known_values() {
        for (m, q, want) in [
            (1u64, 0i64, 1.0f64),
            (15_707_963_267_948_966, -16, std::f64::consts::FRAC_PI_2),
            (10_874_044_514_468_606, -18, 0.010874044514468606),
            (9_999_999_999_999_999_999, -19, 0.9999999999999999999),
            (17_976_931_348_623_157, 292, 1.7976931348623157e308),
            (22_250_738_585_072_014, -324, 2.2250738585072014e-308),
        ] {
            let want_bits = want.to_bits();
            if let Some(x) = to_f64(m, q) {
                assert_eq!(x.to_bits(), want_bits, "{m}e{q}");
            }
        }
        assert_eq!(
            to_f64(15_707_963_267_948_966, -16),
            Some(std::f64::consts::FRAC_PI_2)
        );
        assert_eq!(to_f64(0, 0), None);
        assert_eq!(to_f64(1, 400), None);
    }

    /// On random 17-digit mantissas with exponents −30..30 the product decides nearly always,
    /// and each decided value is the standard library's parse. Undecided: exact ties with
    /// `q < 0` (e.g. `67678315102150075e-1` = 6767831510215007.5, halfway between two doubles:
    /// the bracket `[P, P + w′)` holds the tie and a value on either side), ≈ 0.09 % here; a
    /// bracket straddling a rounding point otherwise needs the ≈ 75 bits below it to be within
    /// w′ < 2⁶⁴ of it.
    #[test]
    fn the_product_decides_and_agrees() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut decided = 0;
        for i in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let m = 10_000_000_000_000_000 + x % 90_000_000_000_000_000;
            let q = (i % 61) as i64 - 30;
            let want: f64 = format!("{m}e{q}").parse().unwrap();
            let r = to_f64(m, q);
            if let Some(got) = r {
                decided += 1;
                assert_eq!(got.to_bits(), want.to_bits(), "{m}e{q}");
            }
        }
        assert!(decided >= 99_800, "{decided}");
    }
}

#[cfg(test)]
mod bracket_tests {
    use super::Split;

    /// xorshift64*.
    fn next(state: &mut u64) -> u64 {
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        state.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Where `same_rounding_above` says `P + w′` rounds as `P`, splitting and rounding `P + w′`
    /// gives the same double: on random 192-bit `P` and `w′ ≥ 2^63` (a shifted mantissa), and
    /// on the edges — `P` a tie (`R = 0`, `half` set, `m` even and odd), `P` exact, and the bits
    /// of `top` below `half` all set so that the carry reaches `half`. The mutant that always
    /// answers true fails here (the tie that rounds down).
    #[test]
    fn the_shortcut_agrees_with_rounding_the_upper_end() {
        let mut state = 0x0DEC_1A55_5EED_0042u64;
        let mut shortcut = 0;
        let mut edge_disagreements = 0;
        for case in 0..200_000u32 {
            let r = |st: &mut u64| next(st);
            // top in [2^126, 2^128).
            let mut top = (u128::from(r(&mut state)) << 64 | u128::from(r(&mut state))) >> 1;
            top |= 1 << 126;
            if case % 2 == 0 {
                top |= 1 << 127;
            }
            let hb = 64 + 127 - top.leading_zeros() as i32;
            let sh = (hb - 52 - 64) as u32;
            let rest_mask = (1u128 << (sh - 1)) - 1;
            let mut bottom = r(&mut state);
            match case % 8 {
                // A tie: half set, nothing below.
                1 => {
                    top = (top & !rest_mask) | (1 << (sh - 1));
                    bottom = 0;
                }
                // Exact: nothing from half down.
                2 => {
                    top &= !((1u128 << sh) - 1);
                    bottom = 0;
                }
                // Every bit of top below half set.
                3 => top |= rest_mask,
                // Every bit of top from half down set.
                4 => top |= (1u128 << sh) - 1,
                _ => {}
            }
            let w = r(&mut state) | 1 << 63;
            let (b2, carry) = bottom.overflowing_add(w);
            let lower = Split::of(top, bottom);
            let e = -1100 + (r(&mut state) % 2000) as i32;
            let (Some(x), Some(y)) = (
                lower.round(e),
                Split::of(top + u128::from(carry), b2).round(e),
            ) else {
                continue;
            };
            if lower.same_rounding_above(carry) {
                shortcut += 1;
                assert_eq!(
                    x.to_bits(),
                    y.to_bits(),
                    "top {top:#x} bottom {bottom:#x} w {w:#x}"
                );
            } else if x.to_bits() != y.to_bits() {
                edge_disagreements += 1;
            }
        }
        // The shortcut decides most cases, and the cases it leaves include real disagreements
        // (the ties and the carries into half are reached).
        assert!(shortcut > 100_000, "{shortcut}");
        assert!(edge_disagreements > 1_000, "{edge_disagreements}");
    }
}
