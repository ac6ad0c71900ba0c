//! A lightweight outward-rounded interval type for hot paths.
//!
//! Each bound of `+ − ×` is computed in round-to-nearest and stepped one ulp outward
//! (`next_down` / `next_up`), which encloses the exact result because IEEE 754 operations are
//! correctly rounded (see [`crate::rounding`]). This avoids switching the FPU rounding mode and is
//! an order of magnitude faster than `inari` here; property tests check every operation against
//! `inari` (the result must contain inari's rigorous result). A NaN anywhere yields the whole
//! real line, never a too-small set.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

use crate::rounding::{mul_down, mul_up, sqrt_down, sqrt_up};

/// A closed interval `[lo, hi]` of reals (`lo <= hi`, possibly infinite ends).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    lo: f64,
    hi: f64,
}

impl Interval {
    /// The whole real line.
    pub const ENTIRE: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };
    /// The point 0.
    pub const ZERO: Interval = Interval { lo: 0.0, hi: 0.0 };
    /// The point 1.
    pub const ONE: Interval = Interval { lo: 1.0, hi: 1.0 };

    /// `[lo, hi]`; `None` if `lo > hi` or either is NaN.
    #[inline]
    pub fn new(lo: f64, hi: f64) -> Option<Self> {
        (lo <= hi).then_some(Self { lo, hi })
    }

    /// The point interval `[x, x]` (NaN gives [`Self::ENTIRE`]).
    #[inline(always)]
    pub fn point(x: f64) -> Self {
        if x.is_nan() {
            Self::ENTIRE
        } else {
            Self { lo: x, hi: x }
        }
    }

    #[inline(always)]
    fn checked(lo: f64, hi: f64) -> Self {
        if lo <= hi {
            Self { lo, hi }
        } else {
            Self::ENTIRE
        }
    }

    /// Lower bound.
    #[inline(always)]
    pub fn lo(&self) -> f64 {
        self.lo
    }
    /// Upper bound.
    #[inline(always)]
    pub fn hi(&self) -> f64 {
        self.hi
    }
    /// A point inside the interval (the midpoint, rounded to nearest).
    ///
    /// # Soundness
    /// Claim C1: a member of the interval. Harness `a4_interval_mid_rad` (beside this module).
    #[inline(always)]
    pub fn mid(&self) -> f64 {
        if self.lo == self.hi {
            return self.lo;
        }
        let m = 0.5 * self.lo + 0.5 * self.hi;
        if m.is_finite() {
            m.clamp(self.lo, self.hi)
        } else {
            0.0f64.clamp(self.lo, self.hi)
        }
    }
    /// Upper bound of `max |x|` over the interval.
    #[inline(always)]
    pub fn mag(&self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }
    /// Upper bound of the distance from [`Self::mid`] to either end.
    ///
    /// # Soundness
    /// Claim C1: ≥ both exact distances. Harness `a4_interval_mid_rad`; mutant `x15` caught.
    #[inline(always)]
    pub fn rad_up(&self) -> f64 {
        let m = self.mid();
        (self.hi - m).next_up().max((m - self.lo).next_up())
    }
    /// Whether `x` lies in the interval.
    #[inline]
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }
    /// Whether `other` is a subset.
    #[inline]
    pub fn contains_interval(&self, other: &Interval) -> bool {
        self.lo <= other.lo && other.hi <= self.hi
    }
    /// Smallest interval containing both.
    #[inline]
    pub fn hull(&self, other: &Interval) -> Interval {
        Interval {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }
    /// Multiply by a scalar (outward rounded; a point times a scalar whose product is exactly a
    /// float stays a point).
    ///
    /// # Soundness
    /// Claim C1: contains `x·k` for every member `x`. Kani: `a4_interval_scale_sqr_enclose`
    /// (the whole claim on a grid where products round), `a4_interval_scale_ends` (the ends
    /// against `mul_down`/`mul_up`, which a2 proves exact bounds), `a4_interval_scale_point`;
    /// property test: the twin of `a4_interval_scale_sqr_enclose` (all beside this module).
    #[inline(always)]
    pub fn scale(self, x: f64) -> Interval {
        if self.lo == self.hi
            && let Some(p) = exact_prod(self.lo, x)
        {
            return Interval::point(p);
        }
        if (self.lo * x).is_nan() || (self.hi * x).is_nan() {
            return Self::ENTIRE;
        }
        // The outward-rounded products of the ends (claim C1 of `mul_down`/`mul_up`), the least
        // and the greatest: `x·k` is linear in `x`, so its extremes over the members are at the
        // ends. (Equal bit for bit to rounding the least/greatest nominal product: `next_down`
        // and `next_up` are monotone.)
        Self::checked(
            mul_down(self.lo, x).min(mul_down(self.hi, x)),
            mul_up(self.lo, x).max(mul_up(self.hi, x)),
        )
    }
    /// Lower bound of `min |x|` over the interval (the mignitude; 0 if the interval holds 0).
    #[inline(always)]
    pub fn mig(&self) -> f64 {
        if self.lo > 0.0 {
            self.lo
        } else if self.hi < 0.0 {
            -self.hi
        } else {
            0.0
        }
    }
    /// Enclosure of `√x` over the non-negative part of the interval (outward rounded; an
    /// interval entirely below 0 gives `[0, 0]`, like a negative rounding artefact).
    #[inline]
    pub fn sqrt(self) -> Interval {
        Self::checked(sqrt_down(self.lo), sqrt_up(self.hi.max(0.0)))
    }
    /// Square (tighter than `x * x` when the interval straddles 0).
    ///
    /// # Soundness
    /// Claim C1: contains `x²` for every member `x`. Kani: `a4_interval_sqr_cases` (the case
    /// logic, on exact squares), `a4_interval_scale_sqr_enclose` (the rounding, on a grid where
    /// squares round; mutant `x81`); its twin at full width.
    #[inline]
    pub fn sqr(self) -> Interval {
        if self.lo >= 0.0 {
            Self::checked(
                (self.lo * self.lo).next_down().max(0.0),
                (self.hi * self.hi).next_up(),
            )
        } else if self.hi <= 0.0 {
            Self::checked(
                (self.hi * self.hi).next_down().max(0.0),
                (self.lo * self.lo).next_up(),
            )
        } else {
            let m = self.mag();
            Self::checked(0.0, (m * m).next_up())
        }
    }
}

/// `x + y` when it is exactly a float (TwoSum's error is 0), else `None`.
#[inline]
fn exact_sum(x: f64, y: f64) -> Option<f64> {
    let (s, e) = crate::exact::two_sum(x, y);
    (e == 0.0 && s.is_finite()).then_some(s)
}

/// `x · y` when it is exactly a float, else `None` (decided on integer significands:
/// [`crate::exact::Dyadic`], exact at every magnitude, subnormals included).
#[inline]
fn exact_prod(x: f64, y: f64) -> Option<f64> {
    if x == 0.0 || y == 0.0 {
        return (x.is_finite() && y.is_finite()).then_some(0.0);
    }
    let p = x * y;
    (p.is_finite() && crate::exact::cmp_prod(x, y, p) == std::cmp::Ordering::Equal).then_some(p)
}

impl Add for Interval {
    type Output = Interval;
    /// Outward rounded; the sum of two points that is exactly a float stays a point.
    ///
    /// # Soundness
    /// Claim C1: contains `x + y` for all members. Kani: `a4_interval_add_lower`,
    /// `a4_interval_add_upper`, `a4_interval_add_sub_enclose` (the whole claim on a grid where
    /// sums round; mutant `x82`) and its twin.
    #[inline(always)]
    fn add(self, o: Interval) -> Interval {
        if self.lo == self.hi
            && o.lo == o.hi
            && let Some(s) = exact_sum(self.lo, o.lo)
        {
            return Interval::point(s);
        }
        Interval::checked((self.lo + o.lo).next_down(), (self.hi + o.hi).next_up())
    }
}

impl Sub for Interval {
    type Output = Interval;
    /// `a − b = a + (−b)`: negation is exact, so this is the same outward-rounded (or exact
    /// point) result bit for bit.
    #[inline(always)]
    fn sub(self, o: Interval) -> Interval {
        self + (-o)
    }
}

impl Neg for Interval {
    type Output = Interval;
    #[inline(always)]
    fn neg(self) -> Interval {
        Interval {
            lo: -self.hi,
            hi: -self.lo,
        }
    }
}

impl Mul for Interval {
    type Output = Interval;
    /// Outward rounded; a point operand uses [`Interval::scale`].
    ///
    /// # Soundness
    /// Claim C1: contains `x·y` for all members. Kani: `a4_interval_mul_corners` (the ends
    /// against `mul_down`/`mul_up` of every corner, which a2 proves exact bounds),
    /// `a4_interval_mul_enclose` (the whole claim on a grid where products round) and its twin;
    /// mutant `x3` caught.
    #[inline(always)]
    fn mul(self, o: Interval) -> Interval {
        if self.lo == self.hi {
            return o.scale(self.lo);
        }
        if o.lo == o.hi {
            return self.scale(o.lo);
        }
        let (a, b, c, d) = (self.lo, self.hi, o.lo, o.hi);
        if (a * c).is_nan() || (a * d).is_nan() || (b * c).is_nan() || (b * d).is_nan() {
            return Interval::ENTIRE;
        }
        // The outward-rounded products of the four corners (claim C1 of `mul_down`/`mul_up`),
        // the least and the greatest: `x·y` is bilinear, so its extremes over a box of members
        // are at the corners. (Equal bit for bit to rounding the least/greatest nominal product:
        // `next_down` and `next_up` are monotone.)
        Interval::checked(
            mul_down(a, c)
                .min(mul_down(a, d))
                .min(mul_down(b, c).min(mul_down(b, d))),
            mul_up(a, c)
                .max(mul_up(a, d))
                .max(mul_up(b, c).max(mul_up(b, d))),
        )
    }
}

impl Div for Interval {
    type Output = Interval;
    /// Enclosure of `x / y`; a divisor that may be 0 gives [`Interval::ENTIRE`].
    #[inline]
    fn div(self, o: Interval) -> Interval {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return Interval::ENTIRE;
        }
        // A quotient of points that is exactly a float (q·y = x exactly) stays a point.
        if self.lo == self.hi && o.lo == o.hi {
            let q = self.lo / o.lo;
            if exact_prod(q, o.lo) == Some(self.lo) {
                return Interval::point(q);
            }
        }
        let a = self.lo / o.lo;
        let b = self.lo / o.hi;
        let c = self.hi / o.lo;
        let d = self.hi / o.hi;
        if a.is_nan() || b.is_nan() || c.is_nan() || d.is_nan() {
            return Interval::ENTIRE;
        }
        Interval::checked(
            a.min(b).min(c.min(d)).next_down(),
            a.max(b).max(c.max(d)).next_up(),
        )
    }
}

impl AddAssign for Interval {
    #[inline(always)]
    fn add_assign(&mut self, o: Interval) {
        *self = *self + o;
    }
}

impl SubAssign for Interval {
    #[inline(always)]
    fn sub_assign(&mut self, o: Interval) {
        *self = *self - o;
    }
}

impl MulAssign for Interval {
    #[inline(always)]
    fn mul_assign(&mut self, o: Interval) {
        *self = *self * o;
    }
}

/// The Kani proofs of this module, each also a property test (`proofs/README.md`).
#[cfg(any(test, kani))]
pub(crate) mod proofs;

#[cfg(test)]
mod tests {
    use super::*;
    use inari::interval;
    use proptest::prelude::*;

    fn iv() -> impl Strategy<Value = Interval> {
        prop_oneof![
            (-1e3f64..1e3).prop_map(Interval::point),
            (-1e3f64..1e3, 0.0f64..10.0).prop_map(|(a, w)| Interval::new(a, a + w).unwrap()),
            (-1e-3f64..1e-3, 0.0f64..1e-3).prop_map(|(a, w)| Interval::new(a, a + w).unwrap()),
        ]
    }

    fn inari_of(x: Interval) -> inari::Interval {
        interval!(x.lo(), x.hi()).unwrap()
    }

    fn encloses(ours: Interval, exact: inari::Interval) -> bool {
        ours.lo() <= exact.inf() && exact.sup() <= ours.hi()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(10_000))]
        #[test]
        fn ops_enclose_inari(a in iv(), b in iv(), s in -1e3f64..1e3) {
            let (ia, ib) = (inari_of(a), inari_of(b));
            prop_assert!(encloses(a + b, ia + ib));
            prop_assert!(encloses(a - b, ia - ib));
            prop_assert!(encloses(a * b, ia * ib));
            prop_assert!(encloses(-a, -ia));
            prop_assert!(encloses(a.scale(s), ia * interval!(s, s).unwrap()));
            prop_assert!(encloses(a.sqr(), ia.sqr()));
            if !(b.lo() <= 0.0 && b.hi() >= 0.0) {
                prop_assert!(encloses(a / b, ia / ib));
            }
            if a.hi() >= 0.0 {
                prop_assert!(encloses(a.sqrt(), ia.sqrt()));
            }
            prop_assert!(a.mig() <= ia.mig());
            let (mut c, mut d, mut e) = (a, a, a);
            c += b;
            d -= b;
            e *= b;
            prop_assert!(c == a + b && d == a - b && e == a * b);
            prop_assert!(a.contains(a.mid()));
            prop_assert!(a.hi() - a.mid() <= a.rad_up() && a.mid() - a.lo() <= a.rad_up());
        }
    }

    #[test]
    fn exact_point_results_stay_points() {
        let p = Interval::point;
        assert_eq!(p(1.0) + p(2.0), p(3.0));
        assert_eq!(p(1.0) - p(0.25), p(0.75));
        assert_eq!(p(0.5) * p(3.0), p(1.5));
        assert_eq!(p(0.1).scale(2.0), p(0.2));
        assert_eq!(p(1.0) / p(4.0), p(0.25));
        let q = p(1.0) / p(3.0);
        assert!(q.lo() < q.hi());
        // Inexact results are widened.
        let third = p(1.0) * p(1.0 / 3.0).scale(3.0);
        assert!(third.lo() <= 1.0 && third.hi() >= 1.0);
        let s = p(0.1) + p(0.2);
        assert!(s.lo() < s.hi() && s.lo() <= 0.3 && 0.3 <= s.hi());
        let m = p(0.1) * p(0.1);
        assert!(m.lo() < m.hi());
        // Extreme magnitudes fall back to outward rounding.
        let t = p(1e-300).scale(1e-20);
        assert!(t.lo() < t.hi() && t.hi() > 0.0);
    }

    #[test]
    fn division_by_an_interval_holding_zero_is_entire() {
        let one = Interval::ONE;
        assert_eq!(one / Interval::new(-1.0, 1.0).unwrap(), Interval::ENTIRE);
        assert_eq!(one / Interval::new(0.0, 1.0).unwrap(), Interval::ENTIRE);
        let q = one / Interval::point(3.0);
        assert!(q.lo() < 1.0 / 3.0 && 1.0 / 3.0 < q.hi());
        assert_eq!(Interval::new(-3.0, -2.0).unwrap().mig(), 2.0);
        assert_eq!(Interval::new(-3.0, 2.0).unwrap().mig(), 0.0);
    }

    #[test]
    fn nan_gives_entire() {
        let inf = Interval::new(0.0, f64::INFINITY).unwrap();
        assert_eq!(inf * Interval::ZERO, Interval::ENTIRE);
        assert_eq!(Interval::point(f64::NAN), Interval::ENTIRE);
    }
}
