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

use crate::interval::Interval;
use crate::rounding::{add_up, div_down, mul_up, norm3_up, sub_down};
use nalgebra::{DMatrix, DVector};
use pacs_models::shape::Capsule;
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

/// Result of a conservative point-containment query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Containment {
    /// The point is provably inside (a certified coefficient vector with `‖β‖∞ ≤ 1` exists).
    Inside,
    /// The point is provably outside (a direction `d` with `d·x > h_Z(d)` was verified).
    Outside,
    /// Neither could be proven (point within solver tolerance of the boundary, or degenerate `G`).
    Unknown,
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
        let m = self.num_generators();
        let mut lo = DVector::zeros(n);
        let mut hi = DVector::zeros(n);
        for i in 0..n {
            let mut r = self.e[i];
            for j in 0..m {
                r += self.g[(i, j)].abs();
            }
            let r = nonneg_sum_up(m + 1, r);
            lo[i] = sub_down(self.c[i], r);
            hi[i] = add_up(self.c[i], r);
        }
        (lo, hi)
    }

    /// Upper bound of `max_i |z_i|` over `Z`, per coordinate.
    pub fn abs_bound(&self) -> DVector<f64> {
        let (lo, hi) = self.interval_hull();
        DVector::from_fn(self.dim(), |i, _| lo[i].abs().max(hi[i].abs()))
    }

    /// Girard order reduction to at most `order · n` generators (result ⊇ input).
    ///
    /// Keeps the `n (order - 1)` generators with the largest `‖g‖₁ - ‖g‖∞` and replaces the others
    /// by their interval hull (axis-aligned generators, sums rounded up). `order ≥ 1`.
    pub fn reduce_girard(&self, order: usize) -> Result<Zonotope, ZonotopeError> {
        if order == 0 {
            return Err(ZonotopeError::Invalid {
                what: "order",
                reason: "must be >= 1",
            });
        }
        let n = self.dim();
        let m = self.num_generators();
        if m <= order * n {
            return Ok(self.clone());
        }
        let keep = n * (order - 1);
        let mut idx: Vec<(f64, usize)> = (0..m)
            .map(|j| {
                let col = self.g.column(j);
                let l1: f64 = col.iter().map(|v| v.abs()).sum();
                let linf = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                (l1 - linf, j)
            })
            .collect();
        idx.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
        let mut boxr = vec![0.0; n];
        for &(_, j) in &idx[keep..] {
            for (i, b) in boxr.iter_mut().enumerate() {
                *b += self.g[(i, j)].abs();
            }
        }
        let nb = m - keep;
        let box_axes: Vec<usize> = (0..n).filter(|&i| boxr[i] > 0.0).collect();
        let mut g = DMatrix::zeros(n, keep + box_axes.len());
        for (k, &(_, j)) in idx[..keep].iter().enumerate() {
            g.set_column(k, &self.g.column(j));
        }
        for (k, &i) in box_axes.iter().enumerate() {
            g[(i, keep + k)] = nonneg_sum_up(nb, boxr[i]);
        }
        Ok(Zonotope {
            c: self.c.clone(),
            g,
            e: self.e.clone(),
        })
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
        let m = self.num_generators();
        let (mut s, mut a) = (0.0, 0.0);
        for i in 0..n {
            s += d[i] * self.c[i];
            a += (d[i] * self.c[i]).abs();
            let t = d[i].abs() * self.e[i];
            s += t;
            a += t;
        }
        for j in 0..m {
            let (mut y, mut ya) = (0.0, 0.0);
            for i in 0..n {
                let t = d[i] * self.g[(i, j)];
                y += t;
                ya += t.abs();
            }
            s += y.abs();
            a += ya;
        }
        Ok(add_up(s, rnd_err(2 * n + m + 2, n * (m + 2), a)))
    }

    /// Approximate zonotope norm `min {‖β‖∞ : c + G' β = x}` of `x` (G' includes the error box) by LP
    /// (clarabel, tolerance ≈ 1e-8); `None` when `x - c` is outside the range of `G'`. Not rigorous:
    /// use [`Zonotope::contains`] for decisions.
    pub fn norm_lp(&self, x: &DVector<f64>) -> Result<Option<f64>, ZonotopeError> {
        Ok(self.solve_norm_lp(x)?.map(|(t, _, _)| t))
    }

    /// Whether the point `x` lies outside the interval hull (rounded outward).
    ///
    /// # Soundness
    /// Claim C2: never true for a point of `Z`. Harness `b3_zonotope_contains_conservative`.
    pub fn hull_excludes(&self, x: &DVector<f64>) -> bool {
        let (lo, hi) = self.interval_hull();
        (0..self.dim().min(x.len())).any(|i| x[i] < lo[i] || x[i] > hi[i])
    }

    /// Whether the direction `d` certifies that `x` is outside `Z`: `d·x > h_Z(d)`, with `d·x`
    /// rounded down and the support function rounded up. Any `d` may be tried (the LP's dual
    /// direction in [`Self::contains`]); a zero direction certifies nothing.
    ///
    /// # Soundness
    /// Claim C2: never true for a point of `Z`, whatever `d` (so the LP that proposes `d` need
    /// not be trusted). Harness `b3_zonotope_contains_conservative`.
    pub fn separates(&self, x: &DVector<f64>, d: &DVector<f64>) -> Result<bool, ZonotopeError> {
        if d.iter().all(|v| *v == 0.0) {
            return Ok(false);
        }
        let h = self.support_up(d)?;
        let mut dx = Interval::ZERO;
        for i in 0..self.dim().min(x.len()) {
            dx += pt(d[i]) * pt(x[i]);
        }
        Ok(dx.lo() > h)
    }

    /// Conservative point containment: `Inside` / `Outside` only when proven (see [`Containment`]).
    ///
    /// Inside: the LP coefficients `β*` leave a residual `x - c - G'β*` that is bounded in interval
    /// arithmetic and absorbed by `n` well-conditioned generators whose inverse is bounded rigorously
    /// (`‖I - K G_S‖∞ < 1`); requires `max|β*| + ‖G_S⁻¹‖∞ ‖res‖∞ ≤ 1`. Outside: the LP dual direction
    /// `y` satisfies `y·x > h_Z(y)` with both sides rounded against the claim.
    pub fn contains(&self, x: &DVector<f64>) -> Result<Containment, ZonotopeError> {
        let n = self.dim();
        if x.len() != n {
            return Err(ZonotopeError::DimensionMismatch {
                what: "point",
                expected: n,
                got: x.len(),
            });
        }
        check_finite("point", x.iter())?;
        // Cheap outside test: interval hull.
        if self.hull_excludes(x) {
            return Ok(Containment::Outside);
        }
        let zf = self.with_error_as_generators();
        let m = zf.num_generators();
        if m == 0 {
            return Ok(if (0..n).all(|i| x[i] == zf.c[i]) {
                Containment::Inside
            } else {
                Containment::Outside
            });
        }
        // Infeasible LP (x − c outside the range of G') or solver failure: no certificate either way.
        let Ok(Some((_t, beta, y))) = zf.solve_norm_lp(x) else {
            return Ok(Containment::Unknown);
        };
        if beta.iter().chain(y.iter()).any(|v| !v.is_finite()) {
            return Ok(Containment::Unknown);
        }
        // Outside certificate from the dual direction (either sign convention).
        for sgn in [1.0, -1.0] {
            if self.separates(x, &(&y * sgn))? {
                return Ok(Containment::Outside);
            }
        }
        // Inside certificate.
        let bmax = beta.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if bmax > 1.0 {
            return Ok(Containment::Unknown);
        }
        // Residual in interval arithmetic.
        let mut res = 0.0f64;
        for i in 0..n {
            let mut r = pt(x[i]) - pt(zf.c[i]);
            for j in 0..m {
                r -= pt(zf.g[(i, j)]) * pt(beta[j]);
            }
            res = res.max(r.mag());
        }
        if res == 0.0 {
            return Ok(Containment::Inside);
        }
        let Some(cols) = pick_columns(&zf.g) else {
            return Ok(Containment::Unknown);
        };
        let gs = DMatrix::from_fn(n, n, |i, k| zf.g[(i, cols[k])]);
        let Some(k) = gs.clone().try_inverse() else {
            return Ok(Containment::Unknown);
        };
        if k.iter().any(|v| !v.is_finite()) {
            return Ok(Containment::Unknown);
        }
        // q ≥ ‖I - K G_S‖∞, kn ≥ ‖K‖∞.
        let mut q = 0.0f64;
        let mut kn = 0.0f64;
        for i in 0..n {
            let mut row_q = 0.0;
            let mut row_k = 0.0;
            for j in 0..n {
                let mut acc = pt(if i == j { 1.0 } else { 0.0 });
                for l in 0..n {
                    acc -= pt(k[(i, l)]) * pt(gs[(l, j)]);
                }
                row_q = add_up(row_q, acc.mag());
                row_k = add_up(row_k, k[(i, j)].abs());
            }
            q = q.max(row_q);
            kn = kn.max(row_k);
        }
        if q >= 1.0 {
            return Ok(Containment::Unknown);
        }
        // ‖G_S⁻¹‖∞ ≤ ‖K‖∞ / (1 - q).
        let inv_norm = crate::rounding::div_up(kn, sub_down(1.0, q));
        let need = add_up(bmax, mul_up(inv_norm, res));
        Ok(if need <= 1.0 {
            Containment::Inside
        } else {
            Containment::Unknown
        })
    }

    /// LP `min t s.t. G β = x - c, |β_i| ≤ t`: returns `(t, β, dual of the equalities)`.
    fn solve_norm_lp(&self, x: &DVector<f64>) -> Result<Option<LpSolution>, ZonotopeError> {
        use clarabel::algebra::CscMatrix;
        use clarabel::solver::{
            DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
        };
        let zf = if self.e.iter().any(|&v| v > 0.0) {
            self.with_error_as_generators()
        } else {
            self.clone()
        };
        let n = zf.dim();
        let m = zf.num_generators();
        if x.len() != n {
            return Err(ZonotopeError::DimensionMismatch {
                what: "point",
                expected: n,
                got: x.len(),
            });
        }
        let nv = m + 1;
        let (mut ri, mut ci, mut vv) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            for j in 0..m {
                if zf.g[(i, j)] != 0.0 {
                    ri.push(i);
                    ci.push(j);
                    vv.push(zf.g[(i, j)]);
                }
            }
        }
        for j in 0..m {
            // β_j - t ≤ 0 ; -β_j - t ≤ 0
            ri.extend([n + 2 * j, n + 2 * j, n + 2 * j + 1, n + 2 * j + 1]);
            ci.extend([j, m, j, m]);
            vv.extend([1.0, -1.0, -1.0, -1.0]);
        }
        let a = CscMatrix::new_from_triplets(n + 2 * m, nv, ri, ci, vv);
        let p = CscMatrix::<f64>::zeros((nv, nv));
        let mut q = vec![0.0; nv];
        q[m] = 1.0;
        let mut b = vec![0.0; n + 2 * m];
        for i in 0..n {
            b[i] = x[i] - zf.c[i];
        }
        let cones = [
            SupportedConeT::ZeroConeT(n),
            SupportedConeT::NonnegativeConeT(2 * m),
        ];
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(100)
            .build()
            .map_err(|e| ZonotopeError::Solver(format!("{e:?}")))?;
        let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
            .map_err(|e| ZonotopeError::Solver(format!("{e:?}")))?;
        solver.solve();
        let sol = &solver.solution;
        match sol.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                let beta = DVector::from_fn(m, |j, _| sol.x[j]);
                let y = DVector::from_fn(n, |i, _| sol.z[i]);
                Ok(Some((sol.x[m], beta, y)))
            }
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => Ok(None),
            s => Err(ZonotopeError::Solver(format!("status {s:?}"))),
        }
    }
}

/// `(t*, β*, equality duals)` of the zonotope-norm LP.
type LpSolution = (f64, DVector<f64>, DVector<f64>);

#[inline]
fn pt(x: f64) -> Interval {
    Interval::point(x)
}

/// Greedy choice of `n` columns of `g` (n × m) with large Gram–Schmidt residuals; `None` if rank < n.
fn pick_columns(g: &DMatrix<f64>) -> Option<Vec<usize>> {
    let (n, m) = g.shape();
    let mut basis: Vec<DVector<f64>> = Vec::with_capacity(n);
    let mut cols = Vec::with_capacity(n);
    let scale = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for _ in 0..n {
        let mut best: Option<(f64, usize, DVector<f64>)> = None;
        for j in 0..m {
            if cols.contains(&j) {
                continue;
            }
            let mut r: DVector<f64> = g.column(j).into_owned();
            for bv in &basis {
                let d = r.dot(bv);
                r -= bv * d;
            }
            let nr = r.norm();
            if best.as_ref().is_none_or(|b| nr > b.0) {
                best = Some((nr, j, r));
            }
        }
        let (nr, j, r) = best?;
        if nr <= 1e-12 * scale || nr == 0.0 {
            return None;
        }
        basis.push(r / nr);
        cols.push(j);
    }
    Some(cols)
}

/// Over-approximating zonotopes of a Euclidean ball in 3-D.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BallApprox {
    /// 3 axis generators (a cube; volume ratio ≈ 1.91, support overshoot ≤ √3).
    Box,
    /// 3 axes + 4 body diagonals (7 generators).
    Seven,
    /// 3 axes + 6 face diagonals + 4 body diagonals (13 generators, support overshoot ≈ 1.1).
    Thirteen,
}

impl BallApprox {
    fn directions(self) -> &'static [[f64; 3]] {
        const D13: [[f64; 3]; 13] = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, -1.0],
            [-1.0, 1.0, 1.0],
            [1.0, 1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 0.0, 1.0],
            [1.0, 0.0, -1.0],
            [0.0, 1.0, 1.0],
            [0.0, 1.0, -1.0],
        ];
        match self {
            BallApprox::Box => &D13[..3],
            BallApprox::Seven => &D13[..7],
            BallApprox::Thirteen => &D13[..],
        }
    }
}

/// Rigorous lower bound of the inradius (about the centre) of the 3-D zonotope `Σ [-1,1] g_k`.
///
/// The zonotope is the intersection of its facet half-spaces; every facet normal is `g_i × g_j`
/// for some pair, so the inradius is `min_{i<j} h(n_ij)/‖n_ij‖`; `n_ij` is enclosed in intervals.
pub fn inradius_lower_3d(gens: &[[f64; 3]]) -> f64 {
    let mut best = f64::INFINITY;
    let iv: Vec<[Interval; 3]> = gens
        .iter()
        .map(|g| [pt(g[0]), pt(g[1]), pt(g[2])])
        .collect();
    for i in 0..gens.len() {
        for j in (i + 1)..gens.len() {
            let (a, b) = (&iv[i], &iv[j]);
            let n = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let nn = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if nn.lo() <= 0.0 {
                if nn.hi() > 0.0 {
                    // Possibly degenerate pair: cannot certify, give up on a positive bound.
                    return 0.0;
                }
                continue; // exactly parallel pair: not a facet normal
            }
            let mut h = 0.0f64;
            for g in &iv {
                let d = n[0] * g[0] + n[1] * g[1] + n[2] * g[2];
                h = crate::rounding::add_down(h, d.mig());
            }
            best = best.min(div_down(h, nn.hi()));
        }
    }
    if best.is_finite() { best.max(0.0) } else { 0.0 }
}

/// A 3-D zonotope (centre `centre`) ⊇ the Euclidean ball of `radius` (m), with rigorously
/// certified inradius ≥ `radius`.
pub fn ball_zonotope(
    centre: [f64; 3],
    radius: f64,
    approx: BallApprox,
) -> Result<Zonotope, ZonotopeError> {
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(ZonotopeError::Invalid {
            what: "ball radius",
            reason: "must be finite and >= 0",
        });
    }
    let c = DVector::from_column_slice(&centre);
    check_finite("ball centre", c.iter())?;
    if radius == 0.0 {
        return Zonotope::new(c, DMatrix::zeros(3, 0));
    }
    let (unit, gsum) = unit_ball_generators(approx);
    // Generators fl(R'·g_k) with R' ≥ R(1 + 1e-12): the exact R'·Z_unit has inradius ≥ R', and
    // rounding moves each generator by ≤ u‖R' g_k‖, which lowers the inradius by at most
    // u R' Σ‖g_k‖ = u R' gsum ≪ 1e-12 R'. Tiny radii are raised to 1e-280 (no underflow).
    debug_assert!(gsum * f64::EPSILON < 1e-13);
    let rp = mul_up(radius.max(1e-280), 1.0 + 1e-12);
    let g = DMatrix::from_fn(3, unit.len(), |i, j| unit[j][i] * rp);
    Zonotope::new(c, g)
}

/// Unit-ball generator sets with certified inradius ≥ 1, and `Σ_k ‖g_k‖` (upper bound), cached.
fn unit_ball_generators(approx: BallApprox) -> (&'static [[f64; 3]], f64) {
    use std::sync::OnceLock;
    static CACHE: [OnceLock<(Vec<[f64; 3]>, f64)>; 3] =
        [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    let k = match approx {
        BallApprox::Box => 0,
        BallApprox::Seven => 1,
        BallApprox::Thirteen => 2,
    };
    let (g, s) = CACHE[k].get_or_init(|| {
        let units: Vec<[f64; 3]> = approx
            .directions()
            .iter()
            .map(|d| {
                let nrm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                [d[0] / nrm, d[1] / nrm, d[2] / nrm]
            })
            .collect();
        let mut s = 1.0 / inradius_lower_3d(&units) * (1.0 + 1e-12);
        loop {
            let gens: Vec<[f64; 3]> = units
                .iter()
                .map(|u| [u[0] * s, u[1] * s, u[2] * s])
                .collect();
            if inradius_lower_3d(&gens) >= 1.0 {
                let sum = gens
                    .iter()
                    .fold(0.0, |a, g| add_up(a, norm3_up(g[0], g[1], g[2])));
                return (gens, sum);
            }
            s *= 1.0 + 1e-9;
        }
    });
    (g.as_slice(), *s)
}

/// Capacity of [`Zonotope3`] generator storage.
pub const MAX_GENERATORS_3D: usize = 48;

/// A 3-D zonotope with inline storage (no heap): `{c + Σ β_k g_k + diag(e) γ}` (m).
#[derive(Debug, Clone, PartialEq)]
pub struct Zonotope3 {
    c: [f64; 3],
    g: [[f64; 3]; MAX_GENERATORS_3D],
    len: usize,
    e: [f64; 3],
    /// Plain `Σ_k |g_k| + e` per axis (for the rounding-error bound of the support function).
    abs_sum: [f64; 3],
}

impl Zonotope3 {
    /// Build from centre, generators (at most [`MAX_GENERATORS_3D`]) and error box radius `e ≥ 0`.
    pub fn new(c: [f64; 3], gens: &[[f64; 3]], e: [f64; 3]) -> Result<Self, ZonotopeError> {
        if gens.len() > MAX_GENERATORS_3D {
            return Err(ZonotopeError::DimensionMismatch {
                what: "Zonotope3 generators",
                expected: MAX_GENERATORS_3D,
                got: gens.len(),
            });
        }
        check_finite(
            "Zonotope3",
            c.iter().chain(gens.iter().flatten()).chain(e.iter()),
        )?;
        if e.iter().any(|&v| v < 0.0) {
            return Err(ZonotopeError::Invalid {
                what: "error box",
                reason: "radii must be >= 0",
            });
        }
        let mut g = [[0.0; 3]; MAX_GENERATORS_3D];
        g[..gens.len()].copy_from_slice(gens);
        let mut abs_sum = e;
        for gk in gens {
            for i in 0..3 {
                abs_sum[i] += gk[i].abs();
            }
        }
        Ok(Self {
            c,
            g,
            len: gens.len(),
            e,
            abs_sum,
        })
    }

    /// Convert a 3-D [`Zonotope`], Girard-reducing first if it has too many generators (⊇ input).
    pub fn from_zonotope(z: &Zonotope) -> Result<Self, ZonotopeError> {
        if z.dim() != 3 {
            return Err(ZonotopeError::DimensionMismatch {
                what: "Zonotope3 dimension",
                expected: 3,
                got: z.dim(),
            });
        }
        let z = z.compact();
        let z = if z.num_generators() > MAX_GENERATORS_3D {
            z.reduce_girard(MAX_GENERATORS_3D / 3)?
        } else {
            z
        };
        let gens: Vec<[f64; 3]> = (0..z.num_generators())
            .map(|j| [z.g[(0, j)], z.g[(1, j)], z.g[(2, j)]])
            .collect();
        Self::new([z.c[0], z.c[1], z.c[2]], &gens, [z.e[0], z.e[1], z.e[2]])
    }

    /// The general-dimension form (same set).
    pub fn to_zonotope(&self) -> Zonotope {
        let c = DVector::from_column_slice(&self.c);
        let g = DMatrix::from_fn(3, self.len, |i, j| self.g[j][i]);
        Zonotope {
            c,
            g,
            e: DVector::from_column_slice(&self.e),
        }
    }

    /// Centre (m).
    #[inline]
    pub fn center(&self) -> [f64; 3] {
        self.c
    }
    /// Generators (m).
    #[inline]
    pub fn generators(&self) -> &[[f64; 3]] {
        &self.g[..self.len]
    }
    /// Error box radius (m).
    #[inline]
    pub fn error_box(&self) -> [f64; 3] {
        self.e
    }

    /// Support function upper bound `≥ max_{z ∈ Z} d·z` (rigorous; `d` need not be unit).
    #[inline]
    pub fn support_up(&self, d: [f64; 3]) -> f64 {
        let mut s = d[0] * self.c[0] + d[1] * self.c[1] + d[2] * self.c[2];
        s += d[0].abs() * self.e[0] + d[1].abs() * self.e[1] + d[2].abs() * self.e[2];
        for gk in self.generators() {
            s += (d[0] * gk[0] + d[1] * gk[1] + d[2] * gk[2]).abs();
        }
        let a = d[0].abs() * (self.c[0].abs() + self.abs_sum[0])
            + d[1].abs() * (self.c[1].abs() + self.abs_sum[1])
            + d[2].abs() * (self.c[2].abs() + self.abs_sum[2]);
        // depth: 3-term dots inside a sum of len + 6 terms; a itself is a plain sum of ≤ len + 3
        // terms per axis, whose relative error is covered by the factor-two slack of rnd_err.
        add_up(s, rnd_err(self.len + 12, 3 * self.len + 12, a))
    }

    /// A point of `Z` (approximately) maximising `d·z`, ignoring the error box (for GJK).
    #[inline]
    fn support_point(&self, d: [f64; 3]) -> [f64; 3] {
        let mut p = self.c;
        for gk in self.generators() {
            let s = d[0] * gk[0] + d[1] * gk[1] + d[2] * gk[2];
            let sg = if s >= 0.0 { 1.0 } else { -1.0 };
            p[0] += sg * gk[0];
            p[1] += sg * gk[1];
            p[2] += sg * gk[2];
        }
        p
    }

    /// Interval hull `(lo, hi)` ⊇ Z (m, rounded outward).
    pub fn interval_hull(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for i in 0..3 {
            let r = nonneg_sum_up(self.len + 1, self.abs_sum[i]);
            lo[i] = sub_down(self.c[i], r);
            hi[i] = add_up(self.c[i], r);
        }
        (lo, hi)
    }

    /// Rigorous lower bound of the distance between `Z ⊕ B(inflate)` and `capsule`, from the
    /// separating direction `n` (any non-zero `n` gives a valid bound; 0 if `n` separates nothing).
    ///
    /// `(min_Z n·z − max_segment n·p) / ‖n‖ − inflate − capsule radius`, each step rounded down.
    pub fn distance_bound_along(&self, inflate: f64, capsule: &Capsule, n: [f64; 3]) -> f64 {
        let nn = norm3_up(n[0], n[1], n[2]);
        if !(nn > 0.0 && nn.is_finite()) {
            return 0.0;
        }
        let zmin = -self.support_up([-n[0], -n[1], -n[2]]);
        let p1 = capsule.p1();
        let p2 = capsule.p2();
        let smax = dot3_up(n, [p1.x, p1.y, p1.z]).max(dot3_up(n, [p2.x, p2.y, p2.z]));
        let gap = sub_down(zmin, smax);
        if gap.is_nan() || gap <= 0.0 {
            return 0.0;
        }
        let d = sub_down(sub_down(div_down(gap, nn), inflate), capsule.radius());
        if d > 0.0 { d } else { 0.0 }
    }

    /// Rigorous lower bound `L` with `0 ≤ L ≤ dist(Z ⊕ B(inflate), capsule)` (m); `L > 0` proves
    /// the sets disjoint. The direction comes from a small GJK on `Z − segment`; only its rigorous
    /// evaluation ([`Self::distance_bound_along`]) matters for soundness.
    ///
    /// # Soundness
    /// Claim C2: never above the exact distance, whatever direction the GJK proposes. Harness
    /// `b4_zonotope_capsule_conservative` (twin; Kani times out).
    pub fn distance_lower_bound(&self, inflate: f64, capsule: &Capsule) -> f64 {
        match self.gjk_direction(capsule) {
            Some(n) => self.distance_bound_along(inflate, capsule, n),
            None => 0.0,
        }
    }

    /// `true` only if `Z ⊕ B(inflate)` and `capsule` are proven disjoint.
    #[inline]
    pub fn is_disjoint(&self, inflate: f64, capsule: &Capsule) -> bool {
        self.distance_lower_bound(inflate, capsule) > 0.0
    }

    /// GJK on the Minkowski difference `Z − S` (S the capsule axis segment): approximate closest
    /// point `v` to the origin; `None` if the sets (approximately) overlap.
    fn gjk_direction(&self, capsule: &Capsule) -> Option<[f64; 3]> {
        let a = capsule.p1();
        let b = capsule.p2();
        let (a, b) = ([a.x, a.y, a.z], [b.x, b.y, b.z]);
        let sup = |d: [f64; 3]| -> [f64; 3] {
            let pz = self.support_point(d);
            // segment support in direction -d
            let ps = if dot3(d, a) <= dot3(d, b) { a } else { b };
            sub3(pz, ps)
        };
        let mid = [
            0.5 * (a[0] + b[0]),
            0.5 * (a[1] + b[1]),
            0.5 * (a[2] + b[2]),
        ];
        let mut v = sub3(self.c, mid);
        if dot3(v, v) == 0.0 {
            v = [1.0, 0.0, 0.0];
        }
        let mut simplex = Simplex {
            p: [[0.0; 3]; 4],
            len: 0,
        };
        let w0 = sup(neg3(v));
        simplex.p[0] = w0;
        simplex.len = 1;
        v = w0;
        let scale = dot3(self.abs_sum, [1.0; 3])
            + crate::ieee::sqrt(dot3(sub3(a, b), sub3(a, b)))
            + crate::ieee::sqrt(dot3(v, v));
        for _ in 0..64 {
            let vv = dot3(v, v);
            if vv <= (1e-14 * scale) * (1e-14 * scale) {
                return None;
            }
            let w = sup(neg3(v));
            // Convergence: v·v − v·w ≤ tol · v·v.
            if vv - dot3(v, w) <= 1e-10 * vv {
                break;
            }
            if simplex.p[..simplex.len].contains(&w) {
                break;
            }
            simplex.p[simplex.len] = w;
            simplex.len += 1;
            match simplex.closest() {
                Some(nv) => v = nv,
                None => return None,
            }
        }
        Some(v)
    }
}

/// Rigorous upper bound of `a·b` (3 terms).
#[inline]
fn dot3_up(a: [f64; 3], b: [f64; 3]) -> f64 {
    let s = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let t = (a[0] * b[0]).abs() + (a[1] * b[1]).abs() + (a[2] * b[2]).abs();
    add_up(s, rnd_err(3, 3, t))
}

#[inline]
fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn neg3(a: [f64; 3]) -> [f64; 3] {
    [-a[0], -a[1], -a[2]]
}
#[inline]
fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
#[inline]
fn add_scaled(a: [f64; 3], s: f64, d: [f64; 3]) -> [f64; 3] {
    [a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]]
}

/// GJK simplex (≤ 4 points of the Minkowski difference).
struct Simplex {
    p: [[f64; 3]; 4],
    len: usize,
}

impl Simplex {
    /// Replace the simplex by the smallest sub-simplex containing its point closest to the origin
    /// and return that point; `None` if the origin is inside the tetrahedron.
    fn closest(&mut self) -> Option<[f64; 3]> {
        match self.len {
            1 => Some(self.p[0]),
            2 => {
                let (v, keep) = closest_segment(self.p[0], self.p[1]);
                self.keep(&keep);
                Some(v)
            }
            3 => {
                let (v, keep) = closest_triangle(self.p[0], self.p[1], self.p[2]);
                self.keep(&keep);
                Some(v)
            }
            _ => {
                let [a, b, c, d] = self.p;
                let faces = [
                    ([0, 1, 2], 3),
                    ([0, 2, 3], 1),
                    ([0, 3, 1], 2),
                    ([1, 3, 2], 0),
                ];
                let mut best: Option<([f64; 3], [usize; 3], usize)> = None;
                let pts = [a, b, c, d];
                for (f, opp) in faces {
                    let (x, y, z) = (pts[f[0]], pts[f[1]], pts[f[2]]);
                    let nrm = cross3(sub3(y, x), sub3(z, x));
                    let sp = -dot3(x, nrm);
                    let sd = dot3(sub3(pts[opp], x), nrm);
                    if sp * sd < 0.0 || sd == 0.0 {
                        let (v, keep) = closest_triangle(x, y, z);
                        let map = [f[keep[0]], f[keep[1]], f[keep[2]]];
                        let nk = keep[3];
                        if best
                            .as_ref()
                            .is_none_or(|bst| dot3(v, v) < dot3(bst.0, bst.0))
                        {
                            best = Some((v, map, nk));
                        }
                    }
                }
                let (v, map, nk) = best?;
                let old = self.p;
                for k in 0..nk {
                    self.p[k] = old[map[k]];
                }
                self.len = nk;
                Some(v)
            }
        }
    }

    fn keep(&mut self, keep: &[usize; 4]) {
        let old = self.p;
        for k in 0..keep[3] {
            self.p[k] = old[keep[k]];
        }
        self.len = keep[3];
    }
}

/// Closest point of segment `ab` to the origin; `keep[..keep[3]]` are the used vertex indices.
fn closest_segment(a: [f64; 3], b: [f64; 3]) -> ([f64; 3], [usize; 4]) {
    let ab = sub3(b, a);
    let t = -dot3(a, ab);
    if t <= 0.0 {
        return (a, [0, 0, 0, 1]);
    }
    let den = dot3(ab, ab);
    if t >= den {
        return (b, [1, 0, 0, 1]);
    }
    (add_scaled(a, t / den, ab), [0, 1, 0, 2])
}

/// Closest point of triangle `abc` to the origin (Ericson, RTCD §5.1.5); used vertex indices in
/// `keep[..keep[3]]`.
fn closest_triangle(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> ([f64; 3], [usize; 4]) {
    let ab = sub3(b, a);
    let ac = sub3(c, a);
    let ap = neg3(a);
    let d1 = dot3(ab, ap);
    let d2 = dot3(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [0, 0, 0, 1]);
    }
    let bp = neg3(b);
    let d3 = dot3(ab, bp);
    let d4 = dot3(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [1, 0, 0, 1]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (add_scaled(a, v, ab), [0, 1, 0, 2]);
    }
    let cp = neg3(c);
    let d5 = dot3(ab, cp);
    let d6 = dot3(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [2, 0, 0, 1]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (add_scaled(a, w, ac), [0, 2, 0, 2]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (add_scaled(b, w, sub3(c, b)), [1, 2, 0, 2]);
    }
    let den = va + vb + vc;
    if den == 0.0 || !den.is_finite() {
        // Degenerate triangle: fall back to the best edge.
        let cands = [
            closest_segment(a, b),
            closest_segment(a, c),
            closest_segment(b, c),
        ];
        let maps = [[0, 1], [0, 2], [1, 2]];
        let mut bi = 0;
        for i in 1..3 {
            if dot3(cands[i].0, cands[i].0) < dot3(cands[bi].0, cands[bi].0) {
                bi = i;
            }
        }
        let (v, k) = cands[bi];
        let mut keep = [0, 0, 0, k[3]];
        for j in 0..k[3] {
            keep[j] = maps[bi][k[j]];
        }
        return (v, keep);
    }
    let v = vb / den;
    let w = vc / den;
    (
        [
            a[0] + ab[0] * v + ac[0] * w,
            a[1] + ab[1] * v + ac[1] * w,
            a[2] + ab[2] * v + ac[2] * w,
        ],
        [0, 1, 2, 3],
    )
}
