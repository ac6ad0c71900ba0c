//! A box of joint values (positions in rad or velocities in rad/s), valid by construction.
//!
//! Every reachability query over a set of configurations takes a [`JointBox`]: one
//! `[lo_j, hi_j]` per joint, each finite with `lo_j ≤ hi_j`, at most [`MAX_DOF`] joints. The
//! checks happen once, in the constructors; the occupancy and energy code trusts them and
//! allocates nothing (the bounds live on the stack).

use pacs_models::MAX_DOF;
use thiserror::Error;

/// Why a [`JointBox`] could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum JointBoxError {
    /// The lower and upper bounds have different lengths.
    #[error("joint box: {lo} lower bounds but {hi} upper bounds")]
    LengthMismatch {
        /// Number of lower bounds.
        lo: usize,
        /// Number of upper bounds.
        hi: usize,
    },
    /// More joints than any model may have.
    #[error("joint box: {0} joints, at most {MAX_DOF} supported")]
    TooManyJoints(usize),
    /// A bound is not finite or `lo > hi`.
    #[error("joint box: joint {joint}: need finite lo <= hi, got [{lo}, {hi}]")]
    Invalid {
        /// Joint index (0-based).
        joint: usize,
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
}

/// One check of [`JointBox::new`] and [`JointBox::assign`]: as many lower as upper bounds.
#[inline]
fn same_length(lo: &[f64], hi: &[f64]) -> Result<(), JointBoxError> {
    if lo.len() == hi.len() {
        Ok(())
    } else {
        Err(JointBoxError::LengthMismatch {
            lo: lo.len(),
            hi: hi.len(),
        })
    }
}

/// One check of every constructor: at most [`MAX_DOF`] joints.
#[inline]
fn joint_count(dof: usize) -> Result<(), JointBoxError> {
    if dof > MAX_DOF {
        Err(JointBoxError::TooManyJoints(dof))
    } else {
        Ok(())
    }
}

/// One check of every constructor, per joint: finite bounds with `lo ≤ hi`.
#[inline]
fn valid_joint(joint: usize, lo: f64, hi: f64) -> Result<(), JointBoxError> {
    if joint_ok(lo, hi) {
        Ok(())
    } else {
        Err(JointBoxError::Invalid { joint, lo, hi })
    }
}

/// The test itself: finite ends, `lo ≤ hi` (without branches, for [`JointBox::assign_lanes`]).
#[inline(always)]
fn joint_ok(lo: f64, hi: f64) -> bool {
    lo.is_finite() & hi.is_finite() & (lo <= hi)
}

/// `[lo_j, hi_j]` for each of `dof()` joints: finite, `lo_j ≤ hi_j`, `dof() ≤ MAX_DOF`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointBox {
    n: usize,
    lo: [f64; MAX_DOF],
    hi: [f64; MAX_DOF],
}

impl JointBox {
    /// The box `[lo_j, hi_j]` per joint.
    ///
    /// # Errors
    /// Different lengths, more than [`MAX_DOF`] joints, a non-finite bound or `lo_j > hi_j`.
    pub fn new(lo: &[f64], hi: &[f64]) -> Result<Self, JointBoxError> {
        same_length(lo, hi)?;
        Self::from_fn(lo.len(), |j| (lo[j], hi[j]))
    }

    /// The box whose joint `j` is `bounds(j) = (lo_j, hi_j)`.
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn from_fn(
        dof: usize,
        mut bounds: impl FnMut(usize) -> (f64, f64),
    ) -> Result<Self, JointBoxError> {
        joint_count(dof)?;
        let mut b = Self {
            n: dof,
            lo: [0.0; MAX_DOF],
            hi: [0.0; MAX_DOF],
        };
        for j in 0..dof {
            let (lo, hi) = bounds(j);
            valid_joint(j, lo, hi)?;
            b.lo[j] = lo;
            b.hi[j] = hi;
        }
        Ok(b)
    }

    /// The degenerate box `{q}`.
    ///
    /// # Errors
    /// As [`Self::new`] (a non-finite value).
    pub fn point(q: &[f64]) -> Result<Self, JointBoxError> {
        Self::new(q, q)
    }

    /// Number of joints.
    #[inline]
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Lower bounds, one per joint.
    #[inline]
    pub fn lo(&self) -> &[f64] {
        &self.lo[..self.n]
    }

    /// Upper bounds, one per joint.
    #[inline]
    pub fn hi(&self) -> &[f64] {
        &self.hi[..self.n]
    }

    /// `(lo_j, hi_j)`.
    #[inline]
    pub fn bounds(&self, j: usize) -> (f64, f64) {
        (self.lo[j], self.hi[j])
    }

    /// The box with no joints (a placeholder to [`Self::assign`] into). A function, not a
    /// constant: Kani lays a constant out as bytes, whose floats CBMC's SMT encoding cannot give
    /// Bitwuzla.
    #[inline]
    pub fn empty() -> JointBox {
        JointBox {
            n: 0,
            lo: [0.0; MAX_DOF],
            hi: [0.0; MAX_DOF],
        }
    }

    /// Replace the bounds in place with `[lo_j, hi_j]`: [`Self::new`] without building and moving
    /// a new box (for loops that fill one box per step). The same checks; on error `self` is
    /// unchanged. Entries beyond the new count are zero, as after [`Self::new`], so equal boxes
    /// compare equal however they were built.
    ///
    /// # Errors
    /// As [`Self::new`].
    #[inline]
    // Element by element on purpose (below).
    #[allow(clippy::manual_memcpy)]
    pub fn assign(&mut self, lo: &[f64], hi: &[f64]) -> Result<(), JointBoxError> {
        same_length(lo, hi)?;
        let n = lo.len();
        joint_count(n)?;
        for j in 0..n {
            valid_joint(j, lo[j], hi[j])?;
        }
        // Element by element, not `copy_from_slice`/`fill`: their memcpy/memset of float arrays
        // is what CBMC's SMT encoding cannot give Bitwuzla (the audit's h2 harnesses run
        // through here).
        for j in 0..n {
            self.lo[j] = lo[j];
            self.hi[j] = hi[j];
        }
        for j in n..self.n {
            self.lo[j] = 0.0;
            self.hi[j] = 0.0;
        }
        self.n = n;
        Ok(())
    }

    /// [`Self::assign`] from bounds in arrays of [`MAX_DOF`] lanes whose first `n` are the
    /// joints: the same box where `assign` succeeds, and `false` with `self` unchanged where it
    /// fails (the error is not built). The lanes beyond the joints are taken as 0 (whatever
    /// `lo` and `hi` hold there), selected lane by lane in the same loop that tests them, so
    /// that every lane is tested and copied alike, without early exit or a separate fill: four
    /// lanes per vector instruction (the audit fills two boxes per logged span). Test
    /// `assign_lanes_is_assign`.
    #[inline]
    pub fn assign_lanes(&mut self, lo: &[f64; MAX_DOF], hi: &[f64; MAX_DOF], n: usize) -> bool {
        if n > MAX_DOF {
            return false;
        }
        let mut l = [0.0; MAX_DOF];
        let mut h = [0.0; MAX_DOF];
        let mut ok = true;
        for j in 0..MAX_DOF {
            let joint = j < n;
            l[j] = if joint { lo[j] } else { 0.0 };
            h[j] = if joint { hi[j] } else { 0.0 };
            ok &= joint_ok(l[j], h[j]);
        }
        if ok {
            self.lo = l;
            self.hi = h;
            self.n = n;
        }
        ok
    }

    /// The smallest box containing both (same number of joints; `self`'s count otherwise).
    pub fn hull(&self, o: &JointBox) -> JointBox {
        let mut h = *self;
        h.hull_in_place(o);
        h
    }

    /// Grow `self` in place to [`Self::hull`] of both (no copy of the box).
    #[inline]
    pub fn hull_in_place(&mut self, o: &JointBox) {
        // Lanes beyond the joints are 0 in every box (each constructor and `assign*` keeps
        // them so), so with equal counts the hull over every lane is the hull of the joints:
        // a fixed-length loop, four lanes per vector instruction.
        if self.n == o.n {
            for j in 0..MAX_DOF {
                self.lo[j] = self.lo[j].min(o.lo[j]);
                self.hi[j] = self.hi[j].max(o.hi[j]);
            }
        } else {
            for j in 0..self.n.min(o.n) {
                self.lo[j] = self.lo[j].min(o.lo[j]);
                self.hi[j] = self.hi[j].max(o.hi[j]);
            }
        }
    }

    /// Whether `q` (one value per joint) lies in the box.
    pub fn contains(&self, q: &[f64]) -> bool {
        q.len() == self.n && (0..self.n).all(|j| self.lo[j] <= q[j] && q[j] <= self.hi[j])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn construction_validates_each_joint() {
        let b = JointBox::new(&[0.0, -1.0], &[0.5, -1.0]).expect("valid");
        assert_eq!(b.dof(), 2);
        assert_eq!(b.lo(), &[0.0, -1.0]);
        assert_eq!(b.hi(), &[0.5, -1.0]);
        assert!(b.contains(&[0.25, -1.0]) && !b.contains(&[0.6, -1.0]) && !b.contains(&[0.1]));
        assert_eq!(
            JointBox::new(&[0.0], &[0.0, 1.0]),
            Err(JointBoxError::LengthMismatch { lo: 1, hi: 2 })
        );
        assert_eq!(
            JointBox::new(&[0.0, 2.0], &[1.0, 1.0]),
            Err(JointBoxError::Invalid {
                joint: 1,
                lo: 2.0,
                hi: 1.0
            })
        );
        assert!(matches!(
            JointBox::point(&[f64::NAN]),
            Err(JointBoxError::Invalid { joint: 0, .. })
        ));
        assert!(matches!(
            JointBox::new(&[0.0; MAX_DOF + 1], &[0.0; MAX_DOF + 1]),
            Err(JointBoxError::TooManyJoints(n)) if n == MAX_DOF + 1
        ));
        assert_eq!(
            JointBox::new(&[0.0, 2.0], &[1.0, 1.0])
                .unwrap_err()
                .to_string(),
            "joint box: joint 1: need finite lo <= hi, got [2, 1]"
        );
    }

    /// `assign_lanes` is `assign` on the first `n` lanes, whatever the others hold: over
    /// 20,000 random bound arrays (finite, infinite, NaN, inverted), counts 0..=MAX_DOF + 1.
    #[test]
    fn assign_lanes_is_assign() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let pick = |r: u64| match r % 16 {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            k => (k as f64 - 9.0) * 0.25,
        };
        let mut base = JointBox::new(&[0.5, -1.0], &[0.75, 1.0]).unwrap();
        for _ in 0..20_000 {
            let mut lo = [0.0; MAX_DOF];
            let mut hi = [0.0; MAX_DOF];
            for j in 0..MAX_DOF {
                lo[j] = pick(next());
                // Mostly valid joints, so that whole boxes pass too.
                hi[j] = if next() % 4 == 0 {
                    pick(next())
                } else if lo[j].is_finite() {
                    lo[j] + 0.5
                } else {
                    1.0
                };
                if next() % 8 != 0 && !lo[j].is_finite() {
                    lo[j] = -1.0;
                }
            }
            let n = (next() % (MAX_DOF as u64 + 2)) as usize;
            let (mut a, mut b) = (base, base);
            let expected = if n <= MAX_DOF {
                a.assign(&lo[..n], &hi[..n]).is_ok()
            } else {
                false
            };
            assert_eq!(b.assign_lanes(&lo, &hi, n), expected, "{lo:?} {hi:?} {n}");
            assert_eq!(a, b);
            base = b;
        }
    }

    #[test]
    fn assign_equals_new_and_leaves_the_box_alone_on_error() {
        let mut b = JointBox::new(&[0.0, -1.0, 2.0], &[0.5, -1.0, 3.0]).unwrap();
        let before = b;
        let bad: [(&[f64], &[f64]); 4] = [
            (&[0.0], &[0.0, 1.0]),
            (&[0.0, 2.0], &[1.0, 1.0]),
            (&[f64::INFINITY], &[f64::INFINITY]),
            (&[0.0; MAX_DOF + 1], &[0.0; MAX_DOF + 1]),
        ];
        for (lo, hi) in bad {
            assert_eq!(b.assign(lo, hi), JointBox::new(lo, hi).map(|_| ()));
            assert_eq!(b, before);
        }
        // Fewer joints than before: the same box (entries beyond the count zeroed) as `new`.
        b.assign(&[-0.25, 0.0], &[0.25, 1.0]).unwrap();
        assert_eq!(b, JointBox::new(&[-0.25, 0.0], &[0.25, 1.0]).unwrap());
        let mut e = JointBox::empty();
        assert_eq!(e.dof(), 0);
        e.assign(&[1.0; 7], &[2.0; 7]).unwrap();
        assert_eq!(e, JointBox::new(&[1.0; 7], &[2.0; 7]).unwrap());
    }

    #[test]
    fn hull_in_place_is_the_hull() {
        let a = JointBox::new(&[0.0, -1.0], &[0.5, -1.0]).unwrap();
        let c = JointBox::new(&[-0.5, -0.5], &[0.25, 2.0]).unwrap();
        let mut h = a;
        h.hull_in_place(&c);
        assert_eq!(h, JointBox::new(&[-0.5, -1.0], &[0.5, 2.0]).unwrap());
        assert_eq!(h, a.hull(&c));
    }
}
