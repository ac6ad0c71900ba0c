//! Conservative point containment: the zonotope-norm LP (clarabel) proposes coefficients and a
//! separating direction; only their rigorous checks decide `Inside` / `Outside`.

use super::{
    Coords, Zonotope, ZonotopeData, ZonotopeError, check_finite, hull_axis, pt, support_up_of,
};
use crate::interval::Interval;
use crate::rounding::{add_up, mul_up, sub_down};
use nalgebra::{DMatrix, DVector};

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

impl Zonotope {
    /// Approximate zonotope norm `min {‖β‖∞ : c + G' β = x}` of `x` (G' includes the error box) by LP
    /// (clarabel, tolerance ≈ 1e-8); `None` when `x - c` is outside the range of `G'`. Not rigorous:
    /// use [`Zonotope::contains`] for decisions.
    pub fn norm_lp(&self, x: &DVector<f64>) -> Result<Option<f64>, ZonotopeError> {
        Ok(self.solve_norm_lp(x)?.map(|(t, _, _)| t))
    }

    /// Whether the point `x` lies outside the interval hull (rounded outward).
    ///
    /// # Soundness
    /// Claim C2: never true for a point of `Z`. Harness `b3_zonotope_contains_conservative`
    /// (twin; Kani outside CI on a one-dimensional grid); Kani: `b3_hull_excludes_member`
    /// (beside this module, `proofs.rs`).
    pub fn hull_excludes(&self, x: &DVector<f64>) -> bool {
        hull_excludes_of(self, x)
    }

    /// Whether the direction `d` certifies that `x` is outside `Z`: `d·x > h_Z(d)`, with `d·x`
    /// rounded down and the support function rounded up. Any `d` may be tried (the LP's dual
    /// direction in [`Self::contains`]); a zero direction certifies nothing.
    ///
    /// # Soundness
    /// Claim C2: never true for a point of `Z`, whatever `d` (so the LP that proposes `d` need
    /// not be trusted). Harness `b3_zonotope_contains_conservative` (twin; Kani outside CI on a
    /// one-dimensional grid); Kani: `b3_separates_member` (`proofs.rs`).
    pub fn separates(&self, x: &DVector<f64>, d: &DVector<f64>) -> Result<bool, ZonotopeError> {
        if d.iter().all(|v| *v == 0.0) {
            return Ok(false);
        }
        if d.len() != self.dim() {
            return Err(ZonotopeError::DimensionMismatch {
                what: "direction",
                expected: self.dim(),
                got: d.len(),
            });
        }
        Ok(separates_of(self, x, d))
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

/// [`Zonotope::hull_excludes`] on any storage (see [`ZonotopeData`]): whether `x` lies outside
/// the interval hull (rounded outward) in one of the first `min(n, len x)` coordinates.
#[inline]
pub(crate) fn hull_excludes_of(z: &impl ZonotopeData, x: &impl Coords) -> bool {
    for i in 0..z.dim().min(x.len()) {
        let (lo, hi) = hull_axis(z, i);
        if x.at(i) < lo || x.at(i) > hi {
            return true;
        }
    }
    false
}

/// [`Zonotope::separates`] on any storage, for a non-zero `d` of the zonotope's dimension:
/// `d·x` rounded down (interval arithmetic) above [`support_up_of`].
#[inline]
pub(crate) fn separates_of(z: &impl ZonotopeData, x: &impl Coords, d: &impl Coords) -> bool {
    let h = support_up_of(z, d);
    let mut dx = Interval::ZERO;
    for i in 0..z.dim().min(x.len()) {
        dx += pt(d.at(i)) * pt(x.at(i));
    }
    dx.lo() > h
}

/// `(t*, β*, equality duals)` of the zonotope-norm LP.
type LpSolution = (f64, DVector<f64>, DVector<f64>);

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
