//! Zonotopes `Z = {c + G β + diag(e) γ : β ∈ [-1,1]^m, γ ∈ [-1,1]^n}` in any dimension, with every
//! operation sound under floating point.
//!
//! The representation carries, besides centre `c` and generator matrix `G` (n × m), a non-negative
//! axis-aligned box radius `e` (the *error box*). Rounding errors of every operation, and small
//! remainder terms of the reachability code, are bounded rigorously and added to `e`, so every
//! returned zonotope contains the exact result of the operation on the exact input sets.
//!
//! Floating-point argument (see `docs/zonotopes.md`): a dot product of `k` terms evaluated with
//! plain IEEE operations in any order (FMA or not) differs from the exact value by at most
//! `γ_k Σ|a_j||b_j|` plus `k` half-subnormals, `γ_k = k u / (1 - k u)`, `u = 2^-53` (Higham, *Accuracy
//! and Stability*, §3.1). [`rnd_err`] turns a computed `Σ|a_j||b_j|` into an upper bound of that
//! error with a factor-two slack that also covers the rounding of the bound itself.
//!
//! [`Zonotope3`] is a fixed-capacity 3-D variant (no heap) for the hot path (support functions,
//! separating-direction distance bounds against capsules).

mod ball;
mod containment;
mod reduction;
mod zonotope3;

/// The Kani proofs of the outside certificates and the distance bound, also property tests
/// (`proofs/README.md`, claim C2).
#[cfg(any(test, kani))]
mod proofs;

pub use ball::{BallApprox, ball_zonotope, inradius_lower_3d};
pub use containment::Containment;
pub use zonotope3::{MAX_GENERATORS_3D, Zonotope3};

use crate::interval::Interval;
use crate::rounding::{add_up, mul_up, sub_down};
use nalgebra::{DMatrix, DVector};
use thiserror::Error;

/// Errors of zonotope construction and operations.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ZonotopeError {
    /// Operand dimensions do not agree.
    #[error("dimension mismatch in {what}: expected {expected}, got {got}")]
    DimensionMismatch {
        /// Which operand.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Actual size.
        got: usize,
    },
    /// A NaN or infinite value was given or produced.
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// An argument is outside its valid range.
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// Which argument.
        what: &'static str,
        /// Why it is invalid.
        reason: &'static str,
    },
    /// The LP solver failed.
    #[error("LP solver: {0}")]
    Solver(String),
}

/// Smallest positive subnormal, `2^-1074`.
const TINY: f64 = f64::from_bits(1);

/// Upper bound of the rounding error of `products` products summed with a recursion depth of at
/// most `depth` terms, given `s` = the plainly computed sum of the absolute values of the products.
///
/// Valid for `depth * u < 0.01`: `γ_depth · S_exact ≤ 1.01² · depth · u · s ≤ depth · ε · s`
/// (`ε = 2u`), plus one subnormal per product for underflow.
#[inline]
pub(crate) fn rnd_err(depth: usize, products: usize, s: f64) -> f64 {
    add_up(
        mul_up((depth as f64 + 1.0) * f64::EPSILON, s),
        (products as f64 + 1.0) * TINY,
    )
}

/// Upper bound of a plainly computed sum `s` of `k` non-negative terms.
#[inline]
pub(crate) fn nonneg_sum_up(k: usize, s: f64) -> f64 {
    add_up(s, rnd_err(k, k, s))
}

fn check_finite<'a>(
    what: &'static str,
    it: impl IntoIterator<Item = &'a f64>,
) -> Result<(), ZonotopeError> {
    if it.into_iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(ZonotopeError::NonFinite(what))
    }
}

/// A zonotope in `R^n`: `{c + G β + diag(e) γ : ‖β‖∞ ≤ 1, ‖γ‖∞ ≤ 1}` (units of the state).
#[derive(Debug, Clone, PartialEq)]
pub struct Zonotope {
    c: DVector<f64>,
    g: DMatrix<f64>,
    e: DVector<f64>,
}

impl Zonotope {
    /// A zonotope with centre `c` and generators as the columns of `g` (no error box).
    pub fn new(c: DVector<f64>, g: DMatrix<f64>) -> Result<Self, ZonotopeError> {
        if g.nrows() != c.len() {
            return Err(ZonotopeError::DimensionMismatch {
                what: "generator rows",
                expected: c.len(),
                got: g.nrows(),
            });
        }
        check_finite("centre", c.iter())?;
        check_finite("generators", g.iter())?;
        let n = c.len();
        Ok(Self {
            c,
            g,
            e: DVector::zeros(n),
        })
    }

    /// A zonotope with an explicit non-negative error box radius `e` (exactly `c ⊕ G[-1,1]^m ⊕ box(e)`).
    pub fn with_error_box(
        c: DVector<f64>,
        g: DMatrix<f64>,
        e: DVector<f64>,
    ) -> Result<Self, ZonotopeError> {
        let mut z = Self::new(c, g)?;
        if e.len() != z.dim() {
            return Err(ZonotopeError::DimensionMismatch {
                what: "error box",
                expected: z.dim(),
                got: e.len(),
            });
        }
        check_finite("error box", e.iter())?;
        if e.iter().any(|&v| v < 0.0) {
            return Err(ZonotopeError::Invalid {
                what: "error box",
                reason: "radii must be >= 0",
            });
        }
        z.e = e;
        Ok(z)
    }

    /// The single point `x`.
    pub fn point(x: DVector<f64>) -> Result<Self, ZonotopeError> {
        let n = x.len();
        Self::new(x, DMatrix::zeros(n, 0))
    }

    /// A zonotope containing the box `[lo, hi]` (centre rounded, radii rounded up so the box is inside).
    pub fn from_interval(lo: &DVector<f64>, hi: &DVector<f64>) -> Result<Self, ZonotopeError> {
        if lo.len() != hi.len() {
            return Err(ZonotopeError::DimensionMismatch {
                what: "box bounds",
                expected: lo.len(),
                got: hi.len(),
            });
        }
        check_finite("box bounds", lo.iter().chain(hi.iter()))?;
        if lo.iter().zip(hi.iter()).any(|(a, b)| a > b) {
            return Err(ZonotopeError::Invalid {
                what: "box",
                reason: "lo > hi",
            });
        }
        let n = lo.len();
        let c = DVector::from_fn(n, |i, _| 0.5 * lo[i] + 0.5 * hi[i]);
        // [c - r, c + r] ⊇ [lo, hi] with r rounded up from both sides.
        let r = DVector::from_fn(n, |i, _| {
            crate::rounding::sub_up(hi[i], c[i])
                .max(crate::rounding::sub_up(c[i], lo[i]))
                .max(0.0)
        });
        Self::new(c, DMatrix::from_diagonal(&r))
    }

    /// Dimension `n`.
    #[inline]
    pub fn dim(&self) -> usize {
        self.c.len()
    }
    /// Number of generators `m` (the error box not counted).
    #[inline]
    pub fn num_generators(&self) -> usize {
        self.g.ncols()
    }
    /// Order `m / n`.
    pub fn order(&self) -> f64 {
        self.num_generators() as f64 / self.dim().max(1) as f64
    }
    /// Centre `c`.
    #[inline]
    pub fn center(&self) -> &DVector<f64> {
        &self.c
    }
    /// Generator matrix `G` (n × m).
    #[inline]
    pub fn generators(&self) -> &DMatrix<f64> {
        &self.g
    }
    /// Error box radius `e` (≥ 0).
    #[inline]
    pub fn error_box(&self) -> &DVector<f64> {
        &self.e
    }

    /// The same set with the error box turned into axis-aligned generators (non-zero ones only).
    pub fn with_error_as_generators(&self) -> Zonotope {
        let n = self.dim();
        let extra: Vec<usize> = (0..n).filter(|&i| self.e[i] > 0.0).collect();
        let m = self.num_generators();
        let mut g = DMatrix::zeros(n, m + extra.len());
        g.columns_mut(0, m).copy_from(&self.g);
        for (k, &i) in extra.iter().enumerate() {
            g[(i, m + k)] = self.e[i];
        }
        Zonotope {
            c: self.c.clone(),
            g,
            e: DVector::zeros(n),
        }
    }

    /// The same set without all-zero generators.
    pub fn compact(&self) -> Zonotope {
        let keep: Vec<usize> = (0..self.num_generators())
            .filter(|&j| self.g.column(j).iter().any(|&v| v != 0.0))
            .collect();
        let g = DMatrix::from_fn(self.dim(), keep.len(), |i, k| self.g[(i, keep[k])]);
        Zonotope {
            c: self.c.clone(),
            g,
            e: self.e.clone(),
        }
    }

    /// Exact projection onto the coordinates `rows` (in that order).
    pub fn project(&self, rows: &[usize]) -> Result<Zonotope, ZonotopeError> {
        if let Some(&bad) = rows.iter().find(|&&r| r >= self.dim()) {
            return Err(ZonotopeError::DimensionMismatch {
                what: "projection row",
                expected: self.dim(),
                got: bad,
            });
        }
        let c = DVector::from_fn(rows.len(), |i, _| self.c[rows[i]]);
        let g = DMatrix::from_fn(rows.len(), self.num_generators(), |i, j| {
            self.g[(rows[i], j)]
        });
        let e = DVector::from_fn(rows.len(), |i, _| self.e[rows[i]]);
        Ok(Zonotope { c, g, e })
    }

    /// Minkowski sum `self ⊕ other` (⊇ the exact sum; centre rounding absorbed in the error box).
    pub fn minkowski_sum(&self, other: &Zonotope) -> Result<Zonotope, ZonotopeError> {
        let n = self.dim();
        if other.dim() != n {
            return Err(ZonotopeError::DimensionMismatch {
                what: "Minkowski sum operand",
                expected: n,
                got: other.dim(),
            });
        }
        let (m1, m2) = (self.num_generators(), other.num_generators());
        let mut g = DMatrix::zeros(n, m1 + m2);
        g.columns_mut(0, m1).copy_from(&self.g);
        g.columns_mut(m1, m2).copy_from(&other.g);
        let mut c = DVector::zeros(n);
        let mut e = DVector::zeros(n);
        for i in 0..n {
            c[i] = self.c[i] + other.c[i];
            // |fl(a+b) - (a+b)| ≤ u|a+b| ≤ ε|fl(a+b)| (addition never underflows inexactly).
            e[i] = add_up(
                add_up(self.e[i], other.e[i]),
                mul_up(f64::EPSILON, c[i].abs()),
            );
        }
        check_finite("Minkowski sum", c.iter())?;
        Ok(Zonotope { c, g, e })
    }

    /// Translation by `v` (⊇ exact, rounding absorbed).
    pub fn translate(&self, v: &DVector<f64>) -> Result<Zonotope, ZonotopeError> {
        self.minkowski_sum(&Zonotope::point(v.clone())?)
    }

    /// Add the box `[-b, b]` (b ≥ 0, rounded up into the error box).
    pub fn add_box(&mut self, b: &DVector<f64>) {
        for i in 0..self.dim() {
            debug_assert!(b[i] >= 0.0);
            self.e[i] = add_up(self.e[i], b[i]);
        }
    }

    /// Linear map `M Z` for `M` (p × n): ⊇ `{M z : z ∈ Z}` (product rounding and `|M| e` in the error box).
    pub fn linear_map(&self, m: &DMatrix<f64>) -> Result<Zonotope, ZonotopeError> {
        let n = self.dim();
        if m.ncols() != n {
            return Err(ZonotopeError::DimensionMismatch {
                what: "linear map columns",
                expected: n,
                got: m.ncols(),
            });
        }
        check_finite("linear map", m.iter())?;
        let p = m.nrows();
        let k = self.num_generators();
        let mut c = DVector::zeros(p);
        let mut g = DMatrix::zeros(p, k);
        let mut e = DVector::zeros(p);
        for i in 0..p {
            let mut s_abs = 0.0; // Σ over all columns of Σ_j |M_ij||x_j|
            let (mut y, mut a) = (0.0, 0.0);
            for j in 0..n {
                y += m[(i, j)] * self.c[j];
                a += (m[(i, j)] * self.c[j]).abs();
            }
            c[i] = y;
            s_abs += a;
            for col in 0..k {
                let (mut y, mut a) = (0.0, 0.0);
                for j in 0..n {
                    let t = m[(i, j)] * self.g[(j, col)];
                    y += t;
                    a += t.abs();
                }
                g[(i, col)] = y;
                s_abs += a;
            }
            // |M| e, rounded up.
            let mut me = 0.0;
            for j in 0..n {
                me += m[(i, j)].abs() * self.e[j];
            }
            let me_up = nonneg_sum_up(n, me);
            // Per-column errors are ≤ γ_n Σ_j|M_ij||x_j|; their sum over columns is bounded by the
            // error of the total with depth n + k + 1 (covers the plain summation of `s_abs`).
            e[i] = add_up(me_up, rnd_err(n + k + 1, n * (k + 1), s_abs));
        }
        check_finite(
            "linear map result",
            c.iter().chain(g.iter()).chain(e.iter()),
        )?;
        Ok(Zonotope { c, g, e })
    }

    /// Interval hull: `(lo, hi)` with `Z ⊆ [lo, hi]` (rounded outward).
    pub fn interval_hull(&self) -> (DVector<f64>, DVector<f64>) {
        let n = self.dim();
        let mut lo = DVector::zeros(n);
        let mut hi = DVector::zeros(n);
        for i in 0..n {
            (lo[i], hi[i]) = hull_axis(self, i);
        }
        (lo, hi)
    }

    /// Upper bound of `max_i |z_i|` over `Z`, per coordinate.
    pub fn abs_bound(&self) -> DVector<f64> {
        let (lo, hi) = self.interval_hull();
        DVector::from_fn(self.dim(), |i, _| lo[i].abs().max(hi[i].abs()))
    }

    /// Support function upper bound: `≥ max_{z ∈ Z} d·z` (rigorous).
    pub fn support_up(&self, d: &DVector<f64>) -> Result<f64, ZonotopeError> {
        let n = self.dim();
        if d.len() != n {
            return Err(ZonotopeError::DimensionMismatch {
                what: "direction",
                expected: n,
                got: d.len(),
            });
        }
        Ok(support_up_of(self, d))
    }
}

/// Read access to the numbers of `c ⊕ G[−1, 1]^m ⊕ box(e)`: the dynamic [`Zonotope`]'s heap
/// storage, or plain fields in the proofs beside this module (which the model checker handles
/// without a heap or float arrays). The arithmetic of [`Zonotope::interval_hull`],
/// [`Zonotope::support_up`], [`Zonotope::hull_excludes`] and [`Zonotope::separates`] is written
/// once over it ([`hull_axis`], [`support_up_of`], `containment::{hull_excludes_of,
/// separates_of}`), so the proofs check the library's own operations.
pub(crate) trait ZonotopeData {
    /// Dimension `n`.
    fn dim(&self) -> usize;
    /// Number of generators `m`.
    fn num_generators(&self) -> usize;
    /// Centre coordinate `c_i`.
    fn c(&self, i: usize) -> f64;
    /// Generator entry `G_ij`.
    fn g(&self, i: usize, j: usize) -> f64;
    /// Error box radius `e_i`.
    fn e(&self, i: usize) -> f64;
}

impl ZonotopeData for Zonotope {
    #[inline]
    fn dim(&self) -> usize {
        self.c.len()
    }
    #[inline]
    fn num_generators(&self) -> usize {
        self.g.ncols()
    }
    #[inline]
    fn c(&self, i: usize) -> f64 {
        self.c[i]
    }
    #[inline]
    fn g(&self, i: usize, j: usize) -> f64 {
        self.g[(i, j)]
    }
    #[inline]
    fn e(&self, i: usize) -> f64 {
        self.e[i]
    }
}

/// Read access to the coordinates of a point or direction (see [`ZonotopeData`]).
pub(crate) trait Coords {
    /// Number of coordinates.
    fn len(&self) -> usize;
    /// Coordinate `i`.
    fn at(&self, i: usize) -> f64;
}

impl Coords for DVector<f64> {
    #[inline]
    fn len(&self) -> usize {
        self.nrows()
    }
    #[inline]
    fn at(&self, i: usize) -> f64 {
        self[i]
    }
}

/// The interval hull of `c ⊕ G[−1, 1]^m ⊕ box(e)` along axis `i` (rounded outward): the
/// arithmetic of [`Zonotope::interval_hull`] (see [`ZonotopeData`]).
#[inline]
pub(crate) fn hull_axis(z: &impl ZonotopeData, i: usize) -> (f64, f64) {
    let m = z.num_generators();
    let mut r = z.e(i);
    for j in 0..m {
        r += z.g(i, j).abs();
    }
    let r = nonneg_sum_up(m + 1, r);
    (sub_down(z.c(i), r), add_up(z.c(i), r))
}

/// Support function upper bound `≥ max_{z ∈ Z} d·z` (`d` of the zonotope's dimension): the
/// arithmetic of [`Zonotope::support_up`] (see [`ZonotopeData`]).
#[inline]
pub(crate) fn support_up_of(z: &impl ZonotopeData, d: &impl Coords) -> f64 {
    let n = z.dim();
    let m = z.num_generators();
    let (mut s, mut a) = (0.0, 0.0);
    for i in 0..n {
        s += d.at(i) * z.c(i);
        a += (d.at(i) * z.c(i)).abs();
        let t = d.at(i).abs() * z.e(i);
        s += t;
        a += t;
    }
    for j in 0..m {
        let (mut y, mut ya) = (0.0, 0.0);
        for i in 0..n {
            let t = d.at(i) * z.g(i, j);
            y += t;
            ya += t.abs();
        }
        s += y.abs();
        a += ya;
    }
    add_up(s, rnd_err(2 * n + m + 2, n * (m + 2), a))
}

#[inline]
fn pt(x: f64) -> Interval {
    Interval::point(x)
}
