//! Constant-jerk polynomial pieces: exact evaluation and sound (outward-padded) extrema.
//!
//! Soundness of the extrema: a cubic piece q(d) = q + v d + a d²/2 + j d³/6 is evaluated in
//! Horner form; the floating-point error of each evaluation is below γ₆·Σ|terms| (γ₆ ≈ 6ε), so
//! every computed value is padded outward by `8ε·Σ|terms|` plus [`PAD_ABS`]. Interior extrema
//! (q at roots of q̇, q̇ at the root of q̈) are evaluated at a computed root d̃; at the true
//! root d* the first derivative vanishes, so |f(d̃) − f(d*)| ≤ max|f″|·|d̃ − d*|²/2, which for
//! the stable root formula (|d̃ − d*| ≲ 1e-14·(1 + |d*|) s) and |f″| ≤ 1e6 is far below [`PAD_ABS`].

/// Absolute outward padding of every computed bound (rad, rad/s or rad/s²).
pub const PAD_ABS: f64 = 1e-12;

/// Relative tolerance of the limit checks (a limit L holds if the padded bound ≤ L·(1 + tol)).
pub const LIMIT_REL_TOL: f64 = 1e-9;

const PAD_REL: f64 = 8.0 * f64::EPSILON;

/// One constant-jerk piece of one joint, valid from absolute time `t` (s) until the next piece.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Piece {
    /// Start time (s).
    pub t: f64,
    /// Position at `t` (rad).
    pub q: f64,
    /// Velocity at `t` (rad/s).
    pub v: f64,
    /// Acceleration at `t` (rad/s²).
    pub a: f64,
    /// Constant jerk (rad/s³).
    pub j: f64,
}

impl Piece {
    /// Exact polynomial state (q, q̇, q̈) at local time `d` = t − start (s).
    #[inline]
    pub fn eval(&self, d: f64) -> (f64, f64, f64) {
        (
            self.q + d * (self.v + d * (self.a * 0.5 + d * (self.j / 6.0))),
            self.v + d * (self.a + d * (self.j * 0.5)),
            self.a + d * self.j,
        )
    }

    /// Widen `r` (q, q̇, q̈ ranges) by the exact extrema of this piece over local `[d0, d1]`, padded outward.
    ///
    /// Guarantee (its Kani contract, claim C7: the chunk planner's output check
    /// [`crate::trajectory::Trajectory::check`] and the joint boxes of the monitored trajectory
    /// rest on it): for a piece and window [`piece_window_input`] admits and ranges without NaN
    /// ends, `r` is only widened, and afterwards holds the piece's evaluated state
    /// ([`Self::eval`], up to its own error bound) at every instant of the window
    /// ([`ranges_cover_piece_at`]; under Kani the postcondition takes any instant of
    /// `contract_instant`'s grid of 2⁻⁸ s, so its proof covers those; full-width instants are
    /// the twin's). Pieces beyond the precondition's ranges (faster than 8 rad/s, or windows
    /// longer than 64 s) are outside the contract. Proven on this function by `f5_extend_bounds_contract` and
    /// `f5_extend_bounds_contract_cubic` (pacs-proofs; Kani covers two constant pieces of the f5
    /// splits and any prior ranges); the twin `f5_extend_bounds_contract_holds` draws the whole
    /// input range and instants at full width. That the padding also covers the exact real
    /// values is the module doc's argument and `motion/tests/range_inari.rs`.
    #[cfg_attr(kani, kani::requires(piece_window_input(self, d0, d1) && ranges_input(r)))]
    #[cfg_attr(kani, kani::modifies(r))]
    #[cfg_attr(kani, kani::ensures(|_| ranges_cover_piece_at(self, d0, d1, &old(*r), &*r, contract_instant())))]
    #[inline]
    pub fn extend_bounds(&self, d0: f64, d1: f64, r: &mut [Range; 3]) {
        let [rq, rv, ra] = r;
        let mut at = |d: f64| {
            let (q, v, a) = self.eval(d);
            let (tq, _, _) = self.term_magnitudes(d);
            rq.include_padded(q, PAD_REL * tq + PAD_ABS);
            self.include_derivs(d, v, a, rv, ra);
        };
        self.for_derivative_points(d0, d1, &mut at);
        // q extrema where q̇ = 0: v + a d + j d²/2 = 0.
        let (c2, c1, c0) = (0.5 * self.j, self.a, self.v);
        if c2 == 0.0 {
            if c1 != 0.0 {
                let d = -c0 / c1;
                if d > d0 && d < d1 {
                    at(d);
                }
            }
        } else {
            let disc = c1 * c1 - 4.0 * c2 * c0;
            if disc >= 0.0 {
                let s = pacs_reach::ieee::sqrt(disc);
                let qq = -0.5 * (c1 + if c1 >= 0.0 { s } else { -s });
                let r1 = qq / c2;
                let r2 = if qq != 0.0 { c0 / qq } else { r1 };
                for d in [r1, r2] {
                    if d > d0 && d < d1 {
                        at(d);
                    }
                }
            }
        }
    }

    /// Widen `r` (q̇, q̈ ranges) by the exact extrema of this piece over local `[d0, d1]`, padded
    /// outward: the derivative part of [`Self::extend_bounds`] (the same instants and pads,
    /// shared with it, without the position's extrema; so Kani's `f5_piece_velocity_acceleration`
    /// reaches this code through `extend_bounds`).
    #[inline]
    pub fn extend_deriv_bounds(&self, d0: f64, d1: f64, r: &mut [Range; 2]) {
        let [rv, ra] = r;
        self.for_derivative_points(d0, d1, &mut |d| {
            let (_, v, a) = self.eval(d);
            self.include_derivs(d, v, a, rv, ra);
        });
    }

    /// The instants of local `[d0, d1]` where q̇ or q̈ can be extreme: both ends (q̈ is linear),
    /// and where q̈ = 0 inside (q̇'s interior extremum).
    #[inline]
    fn for_derivative_points(&self, d0: f64, d1: f64, at: &mut impl FnMut(f64)) {
        at(d0);
        at(d1);
        if self.j != 0.0 {
            let d = -self.a / self.j;
            if d > d0 && d < d1 {
                at(d);
            }
        }
    }

    /// The sums of the magnitudes of the terms of q, q̇ and q̈ at local time `d` (s): the scale
    /// of each evaluation's rounding error (`PAD_REL` times it bounds that error, module doc).
    #[inline]
    pub fn term_magnitudes(&self, d: f64) -> (f64, f64, f64) {
        let ad = d.abs();
        (
            self.q.abs()
                + ad * (self.v.abs() + ad * (0.5 * self.a.abs() + ad * self.j.abs() / 6.0)),
            self.v.abs() + ad * (self.a.abs() + ad * 0.5 * self.j.abs()),
            self.a.abs() + ad * self.j.abs(),
        )
    }

    /// Include q̇ = `v` and q̈ = `a` at local instant `d`, each padded by its evaluation's
    /// rounding bound.
    #[inline]
    fn include_derivs(&self, d: f64, v: f64, a: f64, rv: &mut Range, ra: &mut Range) {
        let (_, tv, ta) = self.term_magnitudes(d);
        rv.include_padded(v, PAD_REL * tv + PAD_ABS);
        ra.include_padded(a, PAD_REL * ta + PAD_ABS);
    }
}

/// The pieces and windows [`Piece::extend_bounds`]' contract covers (claim C7): every field
/// finite with |q| ≤ 8 rad, |q̇| ≤ 8 rad/s, |q̈| ≤ 64 rad/s², |q⃛| ≤ 8192 rad/s³, and a local window
/// `0 ≤ d0 ≤ d1 ≤ 64` s — beyond the FR3's limits (2.62 rad/s, 10 rad/s², 5000 rad/s³), where the
/// module doc's error argument holds with a wide margin. The start time `t` is not read. NaN
/// fails every comparison, so it is never admitted.
pub fn piece_window_input(p: &Piece, d0: f64, d1: f64) -> bool {
    p.q.abs() <= 8.0
        && p.v.abs() <= 8.0
        && p.a.abs() <= 64.0
        && p.j.abs() <= 8192.0
        && 0.0 <= d0
        && d0 <= d1
        && d1 <= 64.0
}

/// Ranges whose ends are not NaN (`EMPTY` included): the prior ranges [`Piece::extend_bounds`]'
/// contract widens. Written without a loop (a contract's precondition is evaluated wherever a
/// harness calls the function).
pub fn ranges_input(r: &[Range; 3]) -> bool {
    let ok = |x: &Range| !x.lo.is_nan() && !x.hi.is_nan();
    ok(&r[0]) && ok(&r[1]) && ok(&r[2])
}

/// The instant at which Kani checks [`Piece::extend_bounds`]' postcondition: any multiple of
/// 2⁻⁸ s from 0 to 256 s (a 16-bit integer scaled exactly; with any full-width float the proof
/// times out, proofs/README.md); the twin takes instants at full width.
#[cfg(kani)]
#[cfg_attr(kani_stub, allow(dead_code))] // the stand-in drops the contract that calls it
fn contract_instant() -> f64 {
    f64::from(kani::any::<u16>()) * (1.0 / 256.0)
}

/// The postcondition of [`Piece::extend_bounds`] at one local instant `d`: `after` widens
/// `before` (no end moved inwards), and if `d` lies in `[d0, d1]`, the piece's evaluated state
/// `(q, q̇, q̈)` at `d` ([`Piece::eval`]) lies in `after`'s three ranges up to its own
/// evaluation error bound (`PAD_REL` times [`Piece::term_magnitudes`]: the real state lies in
/// the ranges by the module doc's argument, and the evaluated one is that close to it). The contract takes one
/// arbitrary `d` (`contract_instant`), so its proof covers every such instant; the twin checks
/// many.
pub fn ranges_cover_piece_at(
    p: &Piece,
    d0: f64,
    d1: f64,
    before: &[Range; 3],
    after: &[Range; 3],
    d: f64,
) -> bool {
    let widened = |k: usize| after[k].lo <= before[k].lo && after[k].hi >= before[k].hi;
    // Within the evaluation's own error bound of the range: the real state lies in it (module
    // doc), and the evaluated one within `PAD_REL·t` of the real one.
    let inside =
        |k: usize, x: f64, t: f64| after[k].lo - PAD_REL * t <= x && x <= after[k].hi + PAD_REL * t;
    let (q, v, a) = p.eval(d);
    let (tq, tv, ta) = p.term_magnitudes(d);
    widened(0)
        && widened(1)
        && widened(2)
        && (!(d0 <= d && d <= d1) || (inside(0, q, tq) && inside(1, v, tv) && inside(2, a, ta)))
}

/// A closed interval [lo, hi] that accumulates the padded extrema of constant-jerk pieces;
/// `EMPTY` has lo = +∞, hi = −∞.
///
/// Guarantee: it only ever widens (`include_padded`, `union`), never narrows, and after
/// [`Piece::extend_bounds`] / [`Piece::extend_deriv_bounds`] it contains the exact real value of
/// the piece at every instant of the span (property test against `inari` in
/// `motion/tests/range_inari.rs`). It is not [`pacs_reach::Interval`]: it must start empty and
/// its ends are padded once per evaluation by the rounding bound of the module docs instead of
/// being rounded outward per operation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl Range {
    /// The empty interval.
    pub const EMPTY: Range = Range {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
    };

    /// The interval [x, x].
    #[inline]
    pub fn point(x: f64) -> Self {
        Range { lo: x, hi: x }
    }
    /// Widen to contain [x − pad, x + pad].
    #[inline]
    pub fn include_padded(&mut self, x: f64, pad: f64) {
        self.lo = self.lo.min(x - pad);
        self.hi = self.hi.max(x + pad);
    }
    /// Widen to contain `o`.
    #[inline]
    pub fn union(&mut self, o: Range) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
    }
    /// Largest absolute value in the interval.
    #[inline]
    pub fn abs_max(&self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }
}
