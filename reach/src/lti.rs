//! Sound reachability of linear time-invariant systems `ẋ = A x + B u`, `u(t) ∈ U`, `x(0) ∈ X0`
//! (Girard 2005; Althoff 2010, §3.2), and a dynamic-object occupancy model built on it.
//!
//! All matrix series (`e^{Ar}`, `Γ(r) = ∫₀ʳ e^{As} ds`, the correction matrices `F`, `F_u`) are
//! evaluated in outward-rounded interval arithmetic ([`crate::interval::Interval`]), with the Taylor remainder after `η` terms bounded
//! elementwise by `E = rowsum(|A|^{η+1} r^{η+1}/(η+1)!) / (1 − ‖|A|r‖∞/(η+2))`. For nilpotent `|A|`
//! with `|A|^{η+1} = 0` (double integrator, `η ≥ 1`) the interval products are exactly zero, so
//! `E = 0` and the series is exact. Interval matrices act on zonotopes as `mid(M) Z ⊕ box(rad(M)|Z|)`.
//! See `docs/zonotopes.md` for the derivation.

pub use crate::error::ReachError;
use crate::interval::Interval;
use crate::rounding::{add_down, add_up, div_up, mul_up, sub_down, sub_up};
use crate::zonotope::{BallApprox, Zonotope, Zonotope3, ZonotopeError, ball_zonotope};
use nalgebra::{DMatrix, DVector};
use pacs_models::shape::Capsule;

#[inline]
fn pt(x: f64) -> Interval {
    Interval::point(x)
}
const IZERO: Interval = Interval::ZERO;
/// `[κ, 0]` with `κ ≤ min_{s∈[0,1]} (sⁱ − s)`; `[−1, 0]` always qualifies (`sⁱ − s ∈ [−1, 0]`).
fn kappa_interval(i: usize) -> Interval {
    Interval::new(kappa(i), 0.0).unwrap_or(Interval::new(-1.0, 0.0).unwrap_or(Interval::ENTIRE))
}

#[inline]
fn is_zero(x: Interval) -> bool {
    x.lo() == 0.0 && x.hi() == 0.0
}

/// A dense interval matrix (row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct IntervalMatrix {
    rows: usize,
    cols: usize,
    v: Vec<Interval>,
}

impl IntervalMatrix {
    /// The zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            v: vec![IZERO; rows * cols],
        }
    }
    /// Point intervals of `m`.
    pub fn from_matrix(m: &DMatrix<f64>) -> Self {
        Self {
            rows: m.nrows(),
            cols: m.ncols(),
            v: (0..m.nrows() * m.ncols())
                .map(|k| pt(m[(k / m.ncols(), k % m.ncols())]))
                .collect(),
        }
    }
    /// The identity.
    pub fn identity(n: usize) -> Self {
        let mut s = Self::zeros(n, n);
        for i in 0..n {
            s.v[i * n + i] = pt(1.0);
        }
        s
    }
    /// Entry `(i, j)`.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> Interval {
        self.v[i * self.cols + j]
    }
    #[inline]
    fn set(&mut self, i: usize, j: usize, x: Interval) {
        self.v[i * self.cols + j] = x;
    }
    /// Enclosure of the product `self · rhs`.
    pub fn mul(&self, rhs: &IntervalMatrix) -> IntervalMatrix {
        assert_eq!(self.cols, rhs.rows);
        let mut out = Self::zeros(self.rows, rhs.cols);
        for i in 0..self.rows {
            for j in 0..rhs.cols {
                let mut acc = IZERO;
                for k in 0..self.cols {
                    let (a, b) = (self.get(i, k), rhs.get(k, j));
                    // [0,0]·x = [0,0] exactly: skipping it changes nothing (sparse A is common).
                    if is_zero(a) || is_zero(b) {
                        continue;
                    }
                    acc += a * b;
                }
                out.set(i, j, acc);
            }
        }
        out
    }
    /// Enclosure of `self · s` for the interval scalar `s`.
    pub fn scale(&self, s: Interval) -> IntervalMatrix {
        Self {
            rows: self.rows,
            cols: self.cols,
            v: self.v.iter().map(|&x| x * s).collect(),
        }
    }
    /// `self += rhs · s` (enclosure; exact-zero entries of `rhs` are skipped, which is exact).
    pub fn add_scaled(&mut self, rhs: &IntervalMatrix, s: Interval) {
        assert_eq!((self.rows, self.cols), (rhs.rows, rhs.cols));
        for (a, &b) in self.v.iter_mut().zip(&rhs.v) {
            if !is_zero(b) {
                *a += b * s;
            }
        }
    }
    /// Enclosure of the sum.
    pub fn add(&self, rhs: &IntervalMatrix) -> IntervalMatrix {
        assert_eq!((self.rows, self.cols), (rhs.rows, rhs.cols));
        Self {
            rows: self.rows,
            cols: self.cols,
            v: self.v.iter().zip(&rhs.v).map(|(&a, &b)| a + b).collect(),
        }
    }
    /// Adds `[-w_i, w_i]` to every entry of row `i`.
    fn widen_rows(&mut self, w: &[f64]) {
        for (i, &wi) in w.iter().enumerate().take(self.rows) {
            if wi > 0.0 {
                let iv = Interval::new(-wi, wi).unwrap_or(Interval::ENTIRE);
                for j in 0..self.cols {
                    self.v[i * self.cols + j] += iv;
                }
            }
        }
    }
    /// `true` if every entry is exactly `[0, 0]`.
    pub fn is_zero(&self) -> bool {
        self.v.iter().all(|&x| is_zero(x))
    }
    /// `(mid, rad)` with `[mid − rad, mid + rad] ⊇` each entry (rad rounded up).
    pub fn mid_rad(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        let mut mid = DMatrix::zeros(self.rows, self.cols);
        let mut rad = DMatrix::zeros(self.rows, self.cols);
        for i in 0..self.rows {
            for j in 0..self.cols {
                let x = self.get(i, j);
                let (lo, hi) = (x.lo(), x.hi());
                if lo == hi {
                    mid[(i, j)] = lo; // point interval: exact, radius 0
                } else {
                    let m = x.mid();
                    mid[(i, j)] = m;
                    // [m − r, m + r] ⊇ [lo, hi] with both differences rounded up.
                    rad[(i, j)] = sub_up(hi, m).max(sub_up(m, lo));
                }
            }
        }
        (mid, rad)
    }
    /// Entrywise magnitude `max |x|` (exact upper bounds).
    pub fn mag(&self) -> DMatrix<f64> {
        DMatrix::from_fn(self.rows, self.cols, |i, j| self.get(i, j).mag())
    }
    /// Zonotope ⊇ `{M z : M ∈ self, z ∈ Z}`: `mid Z ⊕ box(rad |Z|)`.
    pub fn map_zonotope(&self, z: &Zonotope) -> Result<Zonotope, ZonotopeError> {
        let (mid, rad) = self.mid_rad();
        let mut out = z.linear_map(&mid)?;
        let b = mat_vec_up(&rad, &z.abs_bound());
        out.add_box(&b);
        Ok(out)
    }
}

/// Upper bound of `M v` for `M, v ≥ 0`.
fn mat_vec_up(m: &DMatrix<f64>, v: &DVector<f64>) -> DVector<f64> {
    DVector::from_fn(m.nrows(), |i, _| {
        let mut s = 0.0;
        for j in 0..m.ncols() {
            s = add_up(s, mul_up(m[(i, j)], v[j]));
        }
        s
    })
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
        // Remainder E (row-wise bound; every entry of row j is within [-E_j, E_j]).
        let mut abs_pow = abs_ar.clone();
        for _ in 1..=eta {
            abs_pow = abs_pow.mul(&abs_ar);
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
        let r_e: Vec<f64> = e_row.iter().map(|&e| mul_up(r, e)).collect();
        // Φ = Σ P_i / i! + [−E, E]; Γ = Σ P_i r/(i+1)! + r[−E, E].
        let mut phi = IntervalMatrix::zeros(n, n);
        let mut gam = IntervalMatrix::zeros(n, n);
        for i in 0..=eta {
            phi.add_scaled(&pw[i], pt(1.0) / fact[i]);
            gam.add_scaled(&pw[i], ri / fact[i + 1]);
        }
        phi.widen_rows(&e_row);
        gam.widen_rows(&r_e);
        // F = Σ_{i=2}^{η} [κ_i, 0] P_i / i! + [−E, E];  F_u = Σ_{i=1}^{η} [κ_{i+1}, 0] r P_i/(i+1)! + r[−E, E].
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
        f.widen_rows(&e_row);
        fu.widen_rows(&r_e);
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
        // P̂₀ = ⊕_{i=0}^{η} (r P_i/(i+1)!) Ũ₀ ⊕ box(r E |Ũ₀|).
        let mut p0 = Zonotope::point(DVector::zeros(n))?;
        for (i, p) in pw.iter().enumerate() {
            if p.is_zero() {
                continue;
            }
            let m = p.scale(ri / fact[i + 1]);
            p0 = p0.minkowski_sum(&m.map_zonotope(&u0)?)?;
        }
        let u0abs = u0.abs_bound();
        let u0sum = u0abs.iter().fold(0.0, |a, &b| add_up(a, b));
        p0.add_box(&DVector::from_fn(n, |i, _| mul_up(r_e[i], u0sum)));
        // v = Γ ũ_c (interval vector).
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

/// A sphere of radius `radius` (m) whose centre moves as a 3-D double integrator with
/// `‖acceleration‖ ≤ max_acc` (m/s²) and optionally `‖velocity‖ ≤ max_speed` (m/s), observed with
/// delay `delay` (s) and Euclidean position / velocity errors `pos_error` (m), `vel_error` (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicObject {
    radius: f64,
    max_acc: f64,
    max_speed: Option<f64>,
    delay: f64,
    pos_error: f64,
    vel_error: f64,
    approx: BallApprox,
}

/// A measurement of a dynamic object stamped `time` (s): the true state at `time − delay` is within
/// the errors of `position` (m) and `velocity` (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectMeasurement {
    /// Time stamp `t_m` (s).
    pub time: f64,
    /// Measured centre position (m).
    pub position: [f64; 3],
    /// Measured velocity (m/s).
    pub velocity: [f64; 3],
}

impl DynamicObject {
    /// Validate and build (all values finite and ≥ 0); `approx` selects the ball over-approximation.
    pub fn new(
        radius: f64,
        max_acc: f64,
        max_speed: Option<f64>,
        delay: f64,
        pos_error: f64,
        vel_error: f64,
        approx: BallApprox,
    ) -> Result<Self, ReachError> {
        for v in [radius, max_acc, delay, pos_error, vel_error]
            .into_iter()
            .chain(max_speed)
        {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ReachError::Invalid {
                    what: "object parameter",
                    reason: "must be finite and >= 0",
                });
            }
        }
        Ok(Self {
            radius,
            max_acc,
            max_speed,
            delay,
            pos_error,
            vel_error,
            approx,
        })
    }

    /// Occupancy over `[t_a, t_b]` (s) after measurement `meas`: contains every point of the sphere
    /// for every admissible motion consistent with the measurement. Requires `t_m − δ ≤ t_a ≤ t_b`.
    ///
    /// # Soundness
    /// Claim C4′: as stated, for the double-integrator model with the measurement errors and the
    /// delay of the spec. Harness `j1_object_occupancy_contains_motion` (property test: the
    /// occupancy uses the LP-based zonotope code, beyond the model checker); mutant `x13` caught.
    pub fn occupancy(
        &self,
        meas: &ObjectMeasurement,
        t_a: f64,
        t_b: f64,
    ) -> Result<ObjectOccupancy, ReachError> {
        if !(t_a.is_finite() && t_b.is_finite() && meas.time.is_finite() && t_a <= t_b) {
            return Err(ReachError::Invalid {
                what: "time interval",
                reason: "need finite t_a <= t_b",
            });
        }
        // Elapsed time since the true state, enclosed outward.
        let tau_a = add_down(sub_down(t_a, meas.time), self.delay);
        let tau_b = add_up(sub_up(t_b, meas.time), self.delay);
        if t_a - meas.time + self.delay < 0.0 {
            return Err(ReachError::Invalid {
                what: "t_a",
                reason: "before the measured state (t_m - delay)",
            });
        }
        let tau_a = tau_a.max(0.0);
        let sys = LtiSystem::double_integrator_3d();
        let opts = ReachOptions {
            taylor_terms: 2,
            max_order: 12,
        };
        let u = ball_zonotope([0.0; 3], self.max_acc, self.approx)?;
        let bp = ball_zonotope([0.0; 3], self.pos_error, self.approx)?;
        let bv = ball_zonotope([0.0; 3], self.vel_error, self.approx)?;
        let (mp, mv) = (bp.num_generators(), bv.num_generators());
        let mut c = DVector::zeros(6);
        let mut g = DMatrix::zeros(6, mp + mv);
        for i in 0..3 {
            c[i] = meas.position[i];
            c[i + 3] = meas.velocity[i];
            for j in 0..mp {
                g[(i, j)] = bp.generators()[(i, j)];
            }
            for j in 0..mv {
                g[(i + 3, mp + j)] = bv.generators()[(i, j)];
            }
        }
        let x0 = Zonotope::new(c, g)?;
        let xa = if tau_a > 0.0 {
            LtiReach::new(&sys, &u, tau_a, opts)?.point_set(&x0)?
        } else {
            x0
        };
        let r = sub_up(tau_b, tau_a).max(0.0);
        let xi = LtiReach::new(&sys, &u, r, opts)?.first_interval(&xa)?;
        let pos = xi.project(&[0, 1, 2])?;
        let centres = Zonotope3::from_zonotope(&pos)?;
        let speed_ball = match self.max_speed {
            Some(vm) => {
                let rad = add_up(self.pos_error, mul_up(vm, tau_b));
                Some(Zonotope3::new(meas.position, &[], [0.0; 3]).map(|z| (z, rad))?)
            }
            None => None,
        };
        Ok(ObjectOccupancy {
            centres,
            radius: self.radius,
            speed_ball,
            t_a,
            t_b,
        })
    }
}

impl DynamicObject {
    /// Occupancies over the consecutive intervals `[times[k], times[k+1]]` (s, non-decreasing),
    /// each as in [`DynamicObject::occupancy`].
    pub fn occupancy_sequence(
        &self,
        meas: &ObjectMeasurement,
        times: &[f64],
    ) -> Result<Vec<ObjectOccupancy>, ReachError> {
        times
            .windows(2)
            .map(|w| self.occupancy(meas, w[0], w[1]))
            .collect()
    }
}

/// Occupancy of a dynamic object over `[t_a, t_b]`: `(centres ⊕ B(radius)) ∩ (speed ball ⊕ B(radius))`
/// (the second set only with a speed bound). Both sets contain every possible sphere point.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectOccupancy {
    centres: Zonotope3,
    radius: f64,
    speed_ball: Option<(Zonotope3, f64)>,
    t_a: f64,
    t_b: f64,
}

impl ObjectOccupancy {
    /// Zonotope containing every possible centre position (m).
    pub fn centres(&self) -> &Zonotope3 {
        &self.centres
    }
    /// Sphere radius (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// `(centre, radius)` of the speed-bound ball of centre positions, if any (m).
    pub fn speed_ball(&self) -> Option<([f64; 3], f64)> {
        self.speed_ball.as_ref().map(|(z, r)| (z.center(), *r))
    }
    /// Time interval `[t_a, t_b]` (s).
    pub fn interval(&self) -> (f64, f64) {
        (self.t_a, self.t_b)
    }
    /// Rigorous lower bound `L`, `0 ≤ L ≤` distance between the occupancy and `capsule` (m).
    pub fn distance_lower_bound(&self, capsule: &Capsule) -> f64 {
        let mut best = self.centres.distance_lower_bound(self.radius, capsule);
        if let Some((ball, r)) = &self.speed_ball {
            best = best.max(ball.distance_lower_bound(add_up(*r, self.radius), capsule));
        }
        best
    }
    /// `true` only if the occupancy and `capsule` are proven disjoint.
    pub fn is_disjoint(&self, capsule: &Capsule) -> bool {
        self.distance_lower_bound(capsule) > 0.0
    }
}
