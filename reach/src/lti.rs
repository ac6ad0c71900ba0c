//! Sound reachability of linear time-invariant systems `ẋ = A x + B u`, `u(t) ∈ U`, `x(0) ∈ X0`
//! (Girard 2005; Althoff 2010, §3.2). (Dynamic objects, double integrators, use the closed form of
//! this scheme in [`crate::object`].)
//!
//! All matrix series (`e^{Ar}`, `Γ(r) = ∫₀ʳ e^{As} ds`, the correction matrices `F`, `F_u`) are
//! evaluated in outward-rounded interval arithmetic ([`crate::interval::Interval`]), with the Taylor remainder after `η` terms bounded
//! elementwise by `E = rowsum(|A|^{η+1} r^{η+1}/(η+1)!) / (1 − ‖|A|r‖∞/(η+2))`. For nilpotent `|A|`
//! with `|A|^{η+1} = 0` (double integrator, `η ≥ 1`) the interval products are exactly zero, so
//! `E = 0` and the series is exact. Interval matrices act on zonotopes as `mid(M) Z ⊕ box(rad(M)|Z|)`.
//! See `docs/zonotopes.md` for the derivation.

mod interval_matrix;

pub use interval_matrix::IntervalMatrix;

pub use crate::error::ReachError;
use crate::interval::Interval;
use crate::rounding::{add_up, div_up, mul_up, sub_down};
use crate::zonotope::{Zonotope, ZonotopeError};
use interval_matrix::mat_vec_up;
use nalgebra::{DMatrix, DVector};

#[inline]
fn pt(x: f64) -> Interval {
    Interval::point(x)
}
const IZERO: Interval = Interval::ZERO;
/// `[κ, 0]` with `κ ≤ min_{s∈[0,1]} (sⁱ − s)`; `[−1, 0]` always qualifies (`sⁱ − s ∈ [−1, 0]`).
fn kappa_interval(i: usize) -> Interval {
    Interval::new(kappa(i), 0.0).unwrap_or(Interval::new(-1.0, 0.0).unwrap_or(Interval::ENTIRE))
}

/// Lower bound (≤ 0) of `min_{s ∈ [0,1]} (s^i − s)`, `i ≥ 2`: tangent of the convex function at an
/// approximate minimiser, evaluated in interval arithmetic.
fn kappa(i: usize) -> f64 {
    debug_assert!(i >= 2);
    let s0 = (i as f64).powf(-1.0 / (i as f64 - 1.0)).clamp(0.0, 1.0);
    let s = pt(s0);
    let mut p = pt(1.0);
    for _ in 0..i - 1 {
        p *= s;
    }
    let f = p * s - s; // s0^i − s0
    let df = pt(i as f64) * p - pt(1.0); // i s0^{i−1} − 1
    let at0 = f - df * s;
    let at1 = f + df * (pt(1.0) - s);
    at0.lo().min(at1.lo()).clamp(-1.0, 0.0)
}

/// A linear time-invariant system `ẋ = A x + B u`.
#[derive(Debug, Clone, PartialEq)]
pub struct LtiSystem {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
}

impl LtiSystem {
    /// `A` (n × n) and `B` (n × p), finite entries.
    pub fn new(a: DMatrix<f64>, b: DMatrix<f64>) -> Result<Self, ReachError> {
        if !a.is_square() || a.nrows() != b.nrows() {
            return Err(ZonotopeError::DimensionMismatch {
                what: "A/B rows",
                expected: a.nrows(),
                got: b.nrows(),
            }
            .into());
        }
        if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
            return Err(ZonotopeError::NonFinite("A/B").into());
        }
        Ok(Self { a, b })
    }
    /// `A`.
    pub fn a(&self) -> &DMatrix<f64> {
        &self.a
    }
    /// `B`.
    pub fn b(&self) -> &DMatrix<f64> {
        &self.b
    }
    /// The 3-D double integrator: state `(p, v)` ∈ R⁶, input acceleration ∈ R³.
    pub fn double_integrator_3d() -> Self {
        let mut a = DMatrix::zeros(6, 6);
        let mut b = DMatrix::zeros(6, 3);
        for i in 0..3 {
            a[(i, i + 3)] = 1.0;
            b[(i + 3, i)] = 1.0;
        }
        Self { a, b }
    }
}

/// Settings of [`LtiReach`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachOptions {
    /// Taylor terms `η` (≥ 1) of the matrix series before the rigorous remainder.
    pub taylor_terms: usize,
    /// Girard order limit applied after each step (≥ 1).
    pub max_order: usize,
}

impl Default for ReachOptions {
    fn default() -> Self {
        Self {
            taylor_terms: 8,
            max_order: 20,
        }
    }
}

/// Precomputed enclosures for one time step `r` of an LTI system with input set `U`.
#[derive(Debug, Clone)]
pub struct LtiReach {
    n: usize,
    r: f64,
    opts: ReachOptions,
    phi_mid: DMatrix<f64>,
    phi_rad: DMatrix<f64>,
    f_mag: DMatrix<f64>,
    /// `mag(F_u) |ũ_c| + rad(Γ ũ_c)` (box for the constant-input correction).
    input_box: DVector<f64>,
    v_mid: DVector<f64>,
    /// `P̂₀(r)`, centred input solution (contains `P₀(t)` for all `t ∈ [0, r]`).
    p0: Zonotope,
    /// `P̂(r) = Γ ũ_c ⊕ P̂₀(r)`.
    p_full: Zonotope,
}

impl LtiReach {
    /// Precompute `e^{Ar}`, `Γ(r)`, `F`, `F_u` and the input solutions for step `r ≥ 0` (s).
    pub fn new(
        sys: &LtiSystem,
        u: &Zonotope,
        r: f64,
        opts: ReachOptions,
    ) -> Result<Self, ReachError> {
        let n = sys.a.nrows();
        check_arguments(sys, u, r, opts)?;
        let eta = opts.taylor_terms;
        let ri = pt(r);
        let ar = IntervalMatrix::from_matrix(&sys.a).scale(ri);
        let abs_ar = IntervalMatrix::from_matrix(&sys.a.abs()).scale(ri);
        // Powers P_i = (Ar)^i, i = 0..=η.
        let mut pw = vec![IntervalMatrix::identity(n)];
        for i in 1..=eta {
            pw.push(pw[i - 1].mul(&ar));
        }
        // Factorials as intervals.
        let mut fact = vec![pt(1.0)];
        for i in 1..=eta + 2 {
            fact.push(fact[i - 1] * pt(i as f64));
        }
        let e_row = remainder_rows(&abs_ar, &fact, n, eta, r)?;
        let r_e: Vec<f64> = e_row.iter().map(|&e| mul_up(r, e)).collect();
        let series = Series {
            pw: &pw,
            fact: &fact,
            n,
            ri,
            e_row: &e_row,
            r_e: &r_e,
        };
        let (phi, gam) = phi_and_gamma(&series);
        let (f, fu) = correction_matrices(&series);
        let (phi_mid, phi_rad) = phi.mid_rad();
        if phi_mid
            .iter()
            .chain(phi_rad.iter())
            .chain(f.mag().iter())
            .chain(fu.mag().iter())
            .chain(gam.mag().iter())
            .any(|v| !v.is_finite())
        {
            return Err(ZonotopeError::NonFinite("matrix series").into());
        }
        // Input: Ũ = B U = ũ_c ⊕ Ũ₀.
        let ut = u.linear_map(&sys.b)?;
        let uc = ut.center().clone();
        let u0 = Zonotope::with_error_box(
            DVector::zeros(n),
            ut.generators().clone(),
            ut.error_box().clone(),
        )?;
        let p0 = centred_input_solution(&series, &u0)?;
        let (v_mid, v_rad) = gamma_times_centre(&gam, &uc, n);
        let ucabs = uc.abs();
        let mut input_box = mat_vec_up(&fu.mag(), &ucabs);
        for i in 0..n {
            input_box[i] = add_up(input_box[i], v_rad[i]);
        }
        let mut p_full = p0.translate(&v_mid)?;
        p_full.add_box(&v_rad);
        let p0 = p0.reduce_girard(opts.max_order)?;
        let p_full = p_full.reduce_girard(opts.max_order)?;
        Ok(Self {
            n,
            r,
            opts,
            phi_mid,
            phi_rad,
            f_mag: f.mag(),
            input_box,
            v_mid,
            p0,
            p_full,
        })
    }

    /// Step length `r` (s).
    pub fn step(&self) -> f64 {
        self.r
    }

    /// `⊇ R(t + r)` given `R(t) ⊆ x` (also valid for time-interval sets: shifts them by `r`).
    pub fn point_set(&self, x: &Zonotope) -> Result<Zonotope, ReachError> {
        self.check_dim(x)?;
        let mut z = x.linear_map(&self.phi_mid)?;
        z.add_box(&mat_vec_up(&self.phi_rad, &x.abs_bound()));
        let z = z.minkowski_sum(&self.p_full)?;
        Ok(z.reduce_girard(self.opts.max_order)?)
    }

    /// `⊇ R([0, r])` from `R(0) ⊆ x0`:
    /// `CH(x0, Φ x0 + Γ ũ_c) ⊕ F x0 ⊕ F_u ũ_c ⊕ P̂₀(r)` with all rounding absorbed.
    pub fn first_interval(&self, x0: &Zonotope) -> Result<Zonotope, ReachError> {
        self.check_dim(x0)?;
        let n = self.n;
        let r0 = x0.with_error_as_generators();
        let z2 = r0.linear_map(&self.phi_mid)?; // same generator order as r0
        let m = r0.num_generators();
        let c1 = r0.center();
        let g1 = r0.generators();
        let g2 = z2.generators();
        let mut err = DVector::zeros(n);
        let mut c = DVector::zeros(n);
        let mut g = DMatrix::zeros(n, 2 * m + 1);
        for i in 0..n {
            // c2 = Φ c + v (rounded), |error| ≤ ε|c2|.
            let c2 = z2.center()[i] + self.v_mid[i];
            let mut e = add_up(z2.error_box()[i], mul_up(f64::EPSILON, c2.abs()));
            let mut acc = 0.0; // Σ |rounded entries|: each (a ± b)/2 has error ≤ ε|fl| + tiny
            c[i] = 0.5 * (c1[i] + c2);
            acc += c[i].abs();
            g[(i, m)] = 0.5 * (c1[i] - c2);
            acc += g[(i, m)].abs();
            for j in 0..m {
                g[(i, j)] = 0.5 * (g1[(i, j)] + g2[(i, j)]);
                g[(i, m + 1 + j)] = 0.5 * (g1[(i, j)] - g2[(i, j)]);
                acc += g[(i, j)].abs() + g[(i, m + 1 + j)].abs();
            }
            let acc_up = crate::zonotope::nonneg_sum_up(2 * m + 2, acc);
            e = add_up(
                e,
                add_up(
                    mul_up(f64::EPSILON, acc_up),
                    (2 * m + 2) as f64 * f64::from_bits(1),
                ),
            );
            err[i] = e;
        }
        let mut h = Zonotope::with_error_box(c, g, err)?;
        let xabs = x0.abs_bound();
        let b1 = mat_vec_up(&self.phi_rad, &xabs);
        let b2 = mat_vec_up(&self.f_mag, &xabs);
        h.add_box(&DVector::from_fn(n, |i, _| {
            add_up(add_up(b1[i], b2[i]), self.input_box[i])
        }));
        let h = h.minkowski_sum(&self.p0)?;
        Ok(h.reduce_girard(self.opts.max_order)?)
    }

    /// `⊇ R([k r, (k+1) r])` for `k = 0..steps`.
    pub fn reach(&self, x0: &Zonotope, steps: usize) -> Result<Vec<Zonotope>, ReachError> {
        let mut out = Vec::with_capacity(steps);
        if steps == 0 {
            return Ok(out);
        }
        out.push(self.first_interval(x0)?);
        for k in 1..steps {
            let next = self.point_set(&out[k - 1])?;
            out.push(next);
        }
        Ok(out)
    }

    fn check_dim(&self, x: &Zonotope) -> Result<(), ReachError> {
        if x.dim() != self.n {
            return Err(ZonotopeError::DimensionMismatch {
                what: "state set",
                expected: self.n,
                got: x.dim(),
            }
            .into());
        }
        Ok(())
    }
}

/// The errors [`LtiReach::new`] reports before computing anything: an input set `u` of the wrong
/// dimension, a step `r` (s) not finite and ≥ 0, zero Taylor terms or order limit.
fn check_arguments(
    sys: &LtiSystem,
    u: &Zonotope,
    r: f64,
    opts: ReachOptions,
) -> Result<(), ReachError> {
    if u.dim() != sys.b.ncols() {
        return Err(ZonotopeError::DimensionMismatch {
            what: "input set",
            expected: sys.b.ncols(),
            got: u.dim(),
        }
        .into());
    }
    if !(r.is_finite() && r >= 0.0) {
        return Err(ReachError::Invalid {
            what: "time step",
            reason: "must be finite and >= 0",
        });
    }
    if opts.taylor_terms == 0 || opts.max_order == 0 {
        return Err(ReachError::Invalid {
            what: "options",
            reason: "taylor_terms and max_order must be >= 1",
        });
    }
    Ok(())
}

/// The Taylor remainder `E` after `eta` terms, row by row (rounded up; every entry of row `j` is
/// within `[−E_j, E_j]`), from `abs_ar = |A| r` (n × n) and the factorials `fact`; all zero if
/// the interval power `(|A| r)^{η+1}` is. Refuses a step `r` (s) with `‖|A|r‖∞/(η+2) ≥ 1`.
fn remainder_rows(
    abs_ar: &IntervalMatrix,
    fact: &[Interval],
    n: usize,
    eta: usize,
    r: f64,
) -> Result<Vec<f64>, ReachError> {
    let mut abs_pow = abs_ar.clone();
    for _ in 1..=eta {
        abs_pow = abs_pow.mul(abs_ar);
    }
    let mut e_row = vec![0.0; n];
    if !abs_pow.is_zero() {
        let mut eps_num = 0.0f64;
        for i in 0..n {
            let mut s = 0.0;
            for j in 0..n {
                s = add_up(s, abs_ar.get(i, j).hi());
            }
            eps_num = eps_num.max(s);
        }
        let eps = div_up(eps_num, eta as f64 + 2.0);
        if eps >= 1.0 {
            return Err(ReachError::StepTooLarge {
                step: r,
                terms: eta,
                norm: eps_num,
            });
        }
        let w = abs_pow.scale(pt(1.0) / fact[eta + 1]);
        for (i, er) in e_row.iter_mut().enumerate() {
            let mut s = 0.0;
            for j in 0..n {
                s = add_up(s, w.get(i, j).hi());
            }
            *er = div_up(s, sub_down(1.0, eps));
        }
    }
    Ok(e_row)
}

/// The truncated Taylor series of `e^{Ar}` the discretisation sums: the powers `pw[i] = (Ar)^i`
/// (i = 0..=η), the factorials `fact` (as intervals, up to (η+2)!), the dimension `n`, the step
/// `ri = [r, r]` (s) and the remainder rows `E` (`e_row`) and `r E` (`r_e`), rounded up.
#[derive(Clone, Copy)]
struct Series<'a> {
    pw: &'a [IntervalMatrix],
    fact: &'a [Interval],
    n: usize,
    ri: Interval,
    e_row: &'a [f64],
    r_e: &'a [f64],
}

/// `Φ = Σ P_i / i! + [−E, E]` and `Γ = Σ P_i r/(i+1)! + r[−E, E]` from the series `s`.
fn phi_and_gamma(s: &Series<'_>) -> (IntervalMatrix, IntervalMatrix) {
    let Series {
        pw,
        fact,
        n,
        ri,
        e_row,
        r_e,
    } = *s;
    let eta = pw.len() - 1; // pw holds P_0..=P_η
    let mut phi = IntervalMatrix::zeros(n, n);
    let mut gam = IntervalMatrix::zeros(n, n);
    for i in 0..=eta {
        phi.add_scaled(&pw[i], pt(1.0) / fact[i]);
        gam.add_scaled(&pw[i], ri / fact[i + 1]);
    }
    phi.widen_rows(e_row);
    gam.widen_rows(r_e);
    (phi, gam)
}

/// The correction matrices `F = Σ_{i=2}^{η} [κ_i, 0] P_i / i! + [−E, E]` and
/// `F_u = Σ_{i=1}^{η} [κ_{i+1}, 0] r P_i/(i+1)! + r[−E, E]` (from the series `s`).
fn correction_matrices(s: &Series<'_>) -> (IntervalMatrix, IntervalMatrix) {
    let Series {
        pw,
        fact,
        n,
        ri,
        e_row,
        r_e,
    } = *s;
    let eta = pw.len() - 1; // pw holds P_0..=P_η
    let mut f = IntervalMatrix::zeros(n, n);
    let mut fu = IntervalMatrix::zeros(n, n);
    for i in 1..=eta {
        if pw[i].is_zero() {
            continue;
        }
        if i >= 2 {
            let k = kappa_interval(i);
            f.add_scaled(&pw[i], k / fact[i]);
        }
        let k1 = kappa_interval(i + 1);
        fu.add_scaled(&pw[i], k1 * ri / fact[i + 1]);
    }
    f.widen_rows(e_row);
    fu.widen_rows(r_e);
    (f, fu)
}

/// `P̂₀(r) = ⊕_{i=0}^{η} (r P_i/(i+1)!) Ũ₀ ⊕ box(r E |Ũ₀|)`, the centred input solution, from the
/// series `s` and `Ũ₀`.
fn centred_input_solution(s: &Series<'_>, u0: &Zonotope) -> Result<Zonotope, ReachError> {
    let Series {
        pw,
        fact,
        n,
        ri,
        r_e,
        ..
    } = *s;
    let mut p0 = Zonotope::point(DVector::zeros(n))?;
    for (i, p) in pw.iter().enumerate() {
        if p.is_zero() {
            continue;
        }
        let m = p.scale(ri / fact[i + 1]);
        p0 = p0.minkowski_sum(&m.map_zonotope(u0)?)?;
    }
    let u0abs = u0.abs_bound();
    let u0sum = u0abs.iter().fold(0.0, |a, &b| add_up(a, b));
    p0.add_box(&DVector::from_fn(n, |i, _| mul_up(r_e[i], u0sum)));
    Ok(p0)
}

/// `v = Γ ũ_c` as an interval vector: its midpoints and radii (rounded up).
fn gamma_times_centre(
    gam: &IntervalMatrix,
    uc: &DVector<f64>,
    n: usize,
) -> (DVector<f64>, DVector<f64>) {
    let mut v_mid = DVector::zeros(n);
    let mut v_rad = DVector::zeros(n);
    for i in 0..n {
        let mut acc = IZERO;
        for j in 0..n {
            acc += gam.get(i, j) * pt(uc[j]);
        }
        v_mid[i] = acc.mid();
        v_rad[i] = acc.rad_up();
    }
    (v_mid, v_rad)
}
