//! (h2) The audit's span enclosures and consistency check (claim C9, `verify::audit::enclosure`).
//!
//! The whole claim (`h2_span_enclosure_sound`; Kani outside CI on one corner, [`enclosure_sound`]): one joint with random limits
//! moves admissibly over a span of random length: either piecewise-constant acceleration in
//! `[−A, A]` with one switch (bang-bang included; the samples carry `q` and `q̇`), or
//! piecewise-constant jerk in `[−J, J]` over three pieces with `|q̈| ≤ A` (the samples also carry
//! `q̈`). Every such motion must be judged consistent, and its exact position and velocity at
//! sampled instants must lie in the span's boxes (tolerance 1e-12 relative for the generator's
//! own rounding). Then the same samples with the end position moved beyond the displacement
//! reachable between the logged velocities (the "`dq` contradicts Δq" case) must be
//! judged inconsistent.
//!
//! The splits, one mode and one claim each (Kani proofs; each twin draws the whole ranges):
//! - `h2_bang_bang_enclosed`: constant acceleration with one switch, samples with `q`, `q̇`:
//!   consistent, and `(q, q̇)` at any instant in the boxes;
//! - `h2_jerk_enclosed`: constant jerk over two pieces (three in the twin), samples with `q`,
//!   `q̇`, `q̈`: consistent, and `(q, q̇)` at any instant in the boxes;
//! - `h2_contradiction_inconsistent`: any samples whose displacement lies beyond the band
//!   reachable between their logged velocities are judged inconsistent.
//!
//! Under Kani each split takes one corner of the twin's limit ranges (`v_max ∈ [0.5, 3]`,
//! `a_max ∈ [1, 20]`, `j_max ∈ [100, 10 000]`) as constants (the accessors of `JointLimits`
//! stubbed, [`kani_limits`]), the span `Δ = 0.01` s from `t₀ = 10` s ([`span`]), 4-bit inputs
//! and one symbolic instant; `h2_bang_bang_enclosed` and `h2_jerk_enclosed` one motion each
//! (start `q₀ = 1`, `q̇₀ = 0.3`; bang-bang `+A` then `−A` from `Δ/2`; jerk `+J` then `−J` from
//! `Δ/2` with `q̈₀ = −A`) at any instant (a symbolic `q̇₀` as well timed out at 120 s),
//! `h2_contradiction_inconsistent` three velocity pairs with any positions, side and excess.
//! Each twin draws the whole ranges.

use crate::{Source, harness};
use pacs_audit::enclosure::{Sample, SpanBoxes, span_boxes};
use pacs_models::JointLimits;
use pacs_models::robot::MAX_DOF;

/// State (q, v, a) after time `t` of constant jerk `j` from (q, v, a).
fn advance(q: f64, v: f64, a: f64, j: f64, t: f64) -> (f64, f64, f64) {
    (
        q + v * t + a * t * t / 2.0 + j * t * t * t / 6.0,
        v + a * t + j * t * t / 2.0,
        a + j * t,
    )
}

/// Up to 3 constant-jerk (or, with `jerk = None`, constant-acceleration) pieces.
struct Motion {
    q0: f64,
    v0: f64,
    a0: f64,
    dur: [f64; 3],
    /// Per piece: jerk (jerk-limited mode) or acceleration (bang-bang mode).
    u: [f64; 3],
    jerk_mode: bool,
}

impl Motion {
    fn at(&self, t: f64) -> (f64, f64, f64) {
        let (mut q, mut v, mut a) = (self.q0, self.v0, self.a0);
        let mut left = t;
        for k in 0..3 {
            let d = self.dur[k].min(left.max(0.0));
            if self.jerk_mode {
                (q, v, a) = advance(q, v, a, self.u[k], d);
            } else {
                (q, v, a) = advance(q, v, self.u[k], 0.0, d);
            }
            left -= self.dur[k];
        }
        (q, v, a)
    }
}

fn sample(t: f64, s: (f64, f64, f64), ddq: bool) -> Sample {
    let mut out = Sample {
        t,
        q: [0.0; MAX_DOF],
        dq: [0.0; MAX_DOF],
        ddq: [0.0; MAX_DOF],
        has_dq: true,
        has_ddq: ddq,
    };
    out.q[0] = s.0;
    out.dq[0] = s.1;
    out.ddq[0] = s.2;
    out
}

/// The corners of the twin's limit ranges that the Kani proofs take (one per split), as the
/// one-element slices the accessors of `JointLimits` return (see [`kani_limits`]).
const V_HALF: [f64; 1] = [0.5];
const A_ONE: [f64; 1] = [1.0];
const A_TWENTY: [f64; 1] = [20.0];
const J_HUNDRED: [f64; 1] = [100.0];
const J_TEN_THOUSAND: [f64; 1] = [10_000.0];

/// Under Kani, `JointLimits` keeps its values in heap vectors, whose contents symbolic
/// execution does not propagate as constants: `dof()` became symbolic, so `span_boxes` unrolled
/// its joint loop (and `JointBox::new` its loop) up to the unwind bound, 17 copies (20 000
/// checks), and the limits entered every product as unknowns. The splits therefore replace the
/// accessors `span_boxes` reads by these functions (`#[kani::stub]`), which return exactly what
/// the accessors return for the one limits object each split builds (`joint(corner)`, one
/// joint; checked by `tests::kani_limits_match_the_accessors`): the same values as constants.
#[cfg(any(kani, test))]
mod kani_limits {
    use super::{A_ONE, A_TWENTY, J_HUNDRED, J_TEN_THOUSAND, V_HALF};
    use pacs_models::JointLimits;

    pub fn one_joint(_: &JointLimits) -> usize {
        1
    }
    pub fn v_half(_: &JointLimits) -> &[f64] {
        &V_HALF
    }
    pub fn a_one(_: &JointLimits) -> &[f64] {
        &A_ONE
    }
    pub fn a_twenty(_: &JointLimits) -> &[f64] {
        &A_TWENTY
    }
    pub fn j_hundred(_: &JointLimits) -> &[f64] {
        &J_HUNDRED
    }
    pub fn j_ten_thousand(_: &JointLimits) -> &[f64] {
        &J_TEN_THOUSAND
    }
}

/// `(v_max, a_max, j_max)`: under Kani the given corner of the twin's ranges (the limits'
/// validation then runs on constants), in the twin drawn from the whole ranges.
fn limits<S: Source>(s: &mut S, corner: (f64, f64, f64)) -> (f64, f64, f64) {
    if cfg!(kani) {
        corner
    } else {
        (
            s.f64_in(0.5, 3.0),
            s.f64_in(1.0, 20.0),
            s.f64_in(100.0, 10_000.0),
        )
    }
}

/// The span's length and start `(Δ, t₀)`: under Kani the constants `(0.01, 10)` (the time
/// stamps `10` and `fl(10.01)`, whose difference is not exactly `Δ`: the rounding of the time
/// stamps is exercised, on constants the model checker folds); the twin draws `Δ ∈ [1e-4,
/// 0.05]`, `t₀ ∈ [0, 10]`.
fn span<S: Source>(s: &mut S) -> (f64, f64) {
    if cfg!(kani) {
        (0.01, 10.0)
    } else {
        (s.f64_in(1e-4, 0.05), s.f64_in(0.0, 10.0))
    }
}

/// One joint with positions in `[−10, 10]` and the given limits.
///
/// Under Kani a placeholder instead (`JointLimits::placeholder_for_kani`, no joints):
/// `JointLimits::new` validates values it reads back from the heap, which symbolic execution does
/// not fold to constants, so its error paths (`format!`, `String` growth, the allocator) stayed
/// in the formula — 38 000 of the 225 000 steps of `h2_contradiction_inconsistent`, and most of
/// its 5 000 checks. The Kani proofs read the limits only through the stubbed accessors
/// ([`kani_limits`]), which return the corner's values; the placeholder itself is never read.
fn joint(v_max: f64, a_max: f64, j_max: f64) -> JointLimits {
    #[cfg(kani)]
    {
        let _ = (v_max, a_max, j_max);
        return JointLimits::placeholder_for_kani();
    }
    #[cfg(not(kani))]
    JointLimits::new(
        vec![-10.0],
        vec![10.0],
        vec![v_max],
        vec![a_max],
        vec![j_max],
    )
    .expect("valid limits")
}

/// The boxes of a span between samples of an admissible motion: it must be judged consistent.
fn consistent_boxes(lim: &JointLimits, s0: &Sample, s1: &Sample) -> SpanBoxes {
    let enc = span_boxes(lim, s0, s1, 1e-9);
    match enc.boxes {
        Some(b) if enc.consistent => b,
        _ => panic!("an admissible motion was judged inconsistent"),
    }
}

/// The true `(q, q̇)` at `tau` (the generator's value, tolerance 1e-12 relative for its own
/// rounding) lies in the boxes.
fn assert_inside(b: &SpanBoxes, tau: f64, (q, v): (f64, f64)) {
    let ((q_lo, q_hi), (dq_lo, dq_hi)) = (b.q.bounds(0), b.dq.bounds(0));
    let tol_q = 1e-12 * (1.0 + q.abs());
    let tol_v = 1e-12 * (1.0 + v.abs());
    assert!(
        q_lo - tol_q <= q && q <= q_hi + tol_q,
        "q({tau}) = {q} outside [{q_lo}, {q_hi}]"
    );
    assert!(
        dq_lo - tol_v <= v && v <= dq_hi + tol_v,
        "q̇({tau}) = {v} outside [{dq_lo}, {dq_hi}]"
    );
}

/// Checks `inside(τ)` at any instant `τ` of a span of length `dt` (one symbolic instant under
/// Kani), and in the twin also at the ends and 7 evenly spaced instants between.
fn at_instants<S: Source>(s: &mut S, dt: f64, mut inside: impl FnMut(f64)) {
    inside(s.f64_in(0.0, dt));
    if !cfg!(kani) {
        for i in 0..=8 {
            inside(dt * f64::from(i) / 8.0);
        }
    }
}

/// `s1` with its position moved beyond the displacement reachable between the two logged
/// velocities under `|q̈| ≤ A` (by at least 1 % of the reachable band plus 1e-9 rad), to either
/// side: samples no admissible motion matches (the "`dq` contradicts Δq" case).
fn contradicting<S: Source>(s: &mut S, a_max: f64, s0: &Sample, s1: &Sample) -> Sample {
    let dt = s1.t - s0.t;
    let (c, d) = (s0.dq[0], s1.dq[0]);
    let reach = (a_max * a_max * dt * dt - (d - c) * (d - c)) / (4.0 * a_max);
    let sign = if s.bool() { 1.0 } else { -1.0 };
    let extra = s.f64_in(0.01, 1.0) * reach.max(0.0) + 1e-9;
    let mut bad = *s1;
    bad.q[0] = s0.q[0] + dt * (c + d) / 2.0 + sign * (reach.max(0.0) + extra);
    bad
}

/// The whole claim: random limits, random mode, both claims. Under Kani one corner of the
/// limits (`v = 0.5`, `A = 1`, `J = 100`: the accessors stubbed, [`kani_limits`]), the span of
/// [`span`], either mode and in each the splits' extreme motion from `q₀ = 1`, `q̇₀ = 0.3`
/// (bang-bang `+A` then `−A` from `Δ/2`; jerk `+J` then `−J` from `Δ/2` with `q̈₀ = −A`), any
/// instant, and the contradiction of the same samples to either side by any excess (4-bit); the
/// twin draws the whole ranges.
fn enclosure_sound<S: Source>(s: &mut S) {
    let (v_max, a_max, j_max) = limits(s, (V_HALF[0], A_ONE[0], J_HUNDRED[0]));
    let lim = joint(v_max, a_max, j_max);
    let (dt, t0) = span(s);
    let jerk_mode = s.bool();
    let dur = if cfg!(kani) {
        [dt / 2.0, dt / 2.0, 0.0]
    } else {
        let f1 = s.f64_in(0.0, 1.0);
        let f2 = s.f64_in(0.0, 1.0 - f1);
        [dt * f1, dt * f2, dt * (1.0 - f1 - f2).max(0.0)]
    };
    let (q0, v0) = if cfg!(kani) {
        (1.0, 0.3)
    } else {
        (s.f64_in(-2.0, 2.0), s.f64_in(-v_max, v_max))
    };
    let mut m = Motion {
        q0,
        v0,
        a0: 0.0,
        dur,
        u: [0.0; 3],
        jerk_mode,
    };
    if jerk_mode {
        let j_eff = j_max.min(4.0 * a_max / dt);
        if cfg!(kani) {
            m.a0 = -a_max;
            m.u = [j_eff, -j_eff, 0.0];
        } else {
            m.a0 = s.f64_in(-a_max, a_max);
            for k in 0..3 {
                m.u[k] = s.f64_in(-j_eff, j_eff);
            }
        }
    } else if cfg!(kani) {
        m.u = [a_max, -a_max, -a_max];
    } else {
        m.u[0] = s.f64_in(-a_max, a_max);
        m.u[1] = s.f64_in(-a_max, a_max);
        m.u[2] = m.u[1];
    }
    // Admissible, decided exactly: |q̈| ≤ A at the knots (q̈ is linear on each piece) and
    // |q̇| ≤ v_max (margin 0.1 %) at the knots and, in jerk mode, where q̈ = 0 inside a piece
    // (q̇ is linear on bang-bang pieces, quadratic with its extremum there on jerk pieces).
    let mut t_knot = 0.0;
    for k in 0..=3 {
        let (_, v, a) = m.at(t_knot);
        let a = if jerk_mode { a } else { m.u[k.min(2)] };
        if !s.assume(a.abs() <= a_max && v.abs() <= v_max * 0.999) {
            return;
        }
        if k < 3 {
            if jerk_mode && m.u[k] != 0.0 {
                let tz = -a / m.u[k];
                if tz > 0.0 && tz < m.dur[k] {
                    let (_, vz, _) = m.at(t_knot + tz);
                    if !s.assume(vz.abs() <= v_max * 0.999) {
                        return;
                    }
                }
            }
            t_knot += m.dur[k];
        }
    }
    let s0 = sample(t0, m.at(0.0), jerk_mode);
    let s1 = sample(t0 + dt, m.at(dt), jerk_mode);
    // Bang-bang samples have no meaningful acceleration at the ends: not logged.
    let b = consistent_boxes(&lim, &s0, &s1);
    at_instants(s, dt, |tau| {
        let (q, v, _) = m.at(tau);
        assert_inside(&b, tau, (q, v));
    });
    let bad = contradicting(s, a_max, &s0, &s1);
    assert!(
        !span_boxes(&lim, &s0, &bad, 1e-9).consistent,
        "positions contradicting the logged velocities were judged consistent"
    );
}

// The Kani proof (one corner, the splits' two motions and the contradiction of their samples;
// [`enclosure_sound`]) and the twin (the whole ranges).
harness!(
    h2_span_enclosure_sound,
    unwind = 6,
    bits = 4,
    stubs = [
        (pacs_models::JointLimits::dof => kani_limits::one_joint),
        (pacs_models::JointLimits::v_max => kani_limits::v_half),
        (pacs_models::JointLimits::a_max => kani_limits::a_one),
        (pacs_models::JointLimits::j_max => kani_limits::j_hundred),
    ],
    cases = crate::DEFAULT_CASES,
    enclosure_sound
);

/// Constant acceleration `u0` on `[0, d0]`, then `u1` (bang-bang when both are ±A).
struct OneSwitch {
    q0: f64,
    v0: f64,
    u0: f64,
    d0: f64,
    u1: f64,
    /// State at the switch.
    q1: f64,
    v1: f64,
}

impl OneSwitch {
    fn new(q0: f64, v0: f64, u0: f64, d0: f64, u1: f64) -> Self {
        Self {
            q0,
            v0,
            u0,
            d0,
            u1,
            q1: q0 + v0 * d0 + u0 * d0 * d0 / 2.0,
            v1: v0 + u0 * d0,
        }
    }

    /// `(q, q̇)` at `t ≥ 0`.
    fn at(&self, t: f64) -> (f64, f64) {
        if t <= self.d0 {
            (
                self.q0 + self.v0 * t + self.u0 * t * t / 2.0,
                self.v0 + self.u0 * t,
            )
        } else {
            let e = t - self.d0;
            (
                self.q1 + self.v1 * e + self.u1 * e * e / 2.0,
                self.v1 + self.u1 * e,
            )
        }
    }
}

/// Split: acceleration in `[−A, A]` with one switch anywhere in the span (bang-bang included),
/// samples with `q` and `q̇`: judged consistent, and `(q, q̇)` at any instant in the boxes.
fn bang_bang_enclosed<S: Source>(s: &mut S) {
    let (v_max, a_max, j_max) = limits(s, (V_HALF[0], A_TWENTY[0], J_TEN_THOUSAND[0]));
    let lim = joint(v_max, a_max, j_max);
    let (dt, t0) = span(s);
    // Under Kani one start (the instant stays symbolic); the twin draws any.
    let (q0, v0) = if cfg!(kani) {
        (1.0, 0.3)
    } else {
        (s.f64_in(-2.0, 2.0), s.f64_in(-v_max, v_max))
    };
    // Under Kani the extreme motion (full acceleration, switch to full deceleration halfway:
    // it attains the upper envelope of the position); the twin draws any accelerations and
    // switch time.
    let (u0, d0, u1) = if cfg!(kani) {
        (a_max, dt / 2.0, -a_max)
    } else {
        (
            s.f64_in(-a_max, a_max),
            s.f64_in(0.0, dt),
            s.f64_in(-a_max, a_max),
        )
    };
    let m = OneSwitch::new(q0, v0, u0, d0, u1);
    // Admissible: |q̇| ≤ v_max (margin 0.1 %) at the start, the switch and the end (q̇ is linear
    // on each piece); |q̈| ≤ A by construction.
    let (q_end, v_end) = m.at(dt);
    let w = v_max * 0.999;
    if !s.assume(v0.abs() <= w && m.v1.abs() <= w && v_end.abs() <= w) {
        return;
    }
    let s0 = sample(t0, (q0, v0, 0.0), false);
    let s1 = sample(t0 + dt, (q_end, v_end, 0.0), false);
    let b = consistent_boxes(&lim, &s0, &s1);
    at_instants(s, dt, |tau| assert_inside(&b, tau, m.at(tau)));
}

// The Kani proof (4-bit inputs, the limits' accessors stubbed by the split's corner,
// [`kani_limits`]) and the twin.
harness!(
    h2_bang_bang_enclosed,
    unwind = 6,
    bits = 4,
    stubs = [
        (pacs_models::JointLimits::dof => kani_limits::one_joint),
        (pacs_models::JointLimits::v_max => kani_limits::v_half),
        (pacs_models::JointLimits::a_max => kani_limits::a_twenty),
        (pacs_models::JointLimits::j_max => kani_limits::j_ten_thousand),
    ],
    cases = crate::DEFAULT_CASES,
    bang_bang_enclosed
);

/// A piece of constant jerk `j` from state `(q, v, a)` at time `t`.
#[derive(Clone, Copy)]
struct Piece {
    t: f64,
    q: f64,
    v: f64,
    a: f64,
    j: f64,
}

impl Piece {
    /// `(q, q̇, q̈)` at time `t` (on this piece's polynomial).
    fn at(&self, t: f64) -> (f64, f64, f64) {
        advance(self.q, self.v, self.a, self.j, t - self.t)
    }

    /// The piece that starts at `t` with jerk `j`.
    fn then(&self, t: f64, j: f64) -> Piece {
        let (q, v, a) = self.at(t);
        Piece { t, q, v, a, j }
    }

    /// Admissible up to time `end`, given that the state at `end` was checked: `|q̈| ≤ A`
    /// and `|q̇| ≤ w` at the start (`q̈` is linear), and `|q̇| ≤ w` at the extremum of `q̇`
    /// where `q̈ = 0` inside the piece (at `τ = −a/j`, value `v − a²/(2j)`), decided without a
    /// division: the extremum lies inside when `a·j < 0` and `|a| < |j|·(end − t)`, and then it
    /// is a minimum (`j > 0`, bound `−w`) or a maximum (`j < 0`, bound `w`):
    /// `2|j|(w ± v) ≥ a²`.
    fn admissible(&self, end: f64, a_max: f64, w: f64) -> bool {
        let (v, a, j) = (self.v, self.a, self.j);
        if !(a.abs() <= a_max && v.abs() <= w) {
            return false;
        }
        if a * j < 0.0 && a.abs() < j.abs() * (end - self.t) {
            let room = if j > 0.0 { w + v } else { w - v };
            return 2.0 * j.abs() * room >= a * a;
        }
        true
    }
}

/// Split: jerk in `[−J, J]` over two pieces (three in the twin) with `|q̈| ≤ A` and
/// `|q̇| ≤ v_max`, samples with `q`, `q̇` and `q̈`: judged consistent, and `(q, q̇)` at any
/// instant in the boxes.
fn jerk_enclosed<S: Source>(s: &mut S) {
    let (v_max, a_max, j_max) = limits(s, (V_HALF[0], A_ONE[0], J_HUNDRED[0]));
    let lim = joint(v_max, a_max, j_max);
    let (dt, t0) = span(s);
    // The twin keeps the jerks where `|q̈| ≤ A` is likely to hold over the span.
    let j_eff = if cfg!(kani) {
        j_max
    } else {
        j_max.min(4.0 * a_max / dt)
    };
    // Under Kani one motion (q̈ from −A up by JΔ/2, then back to −A; the instant stays
    // symbolic); the twin draws any start, jerks and switch times.
    let p0 = if cfg!(kani) {
        Piece {
            t: 0.0,
            q: 1.0,
            v: 0.3,
            a: -a_max,
            j: j_max,
        }
    } else {
        Piece {
            t: 0.0,
            q: s.f64_in(-2.0, 2.0),
            v: s.f64_in(-v_max, v_max),
            a: s.f64_in(-a_max, a_max),
            j: s.f64_in(-j_eff, j_eff),
        }
    };
    let t1 = if cfg!(kani) {
        dt / 2.0
    } else {
        s.f64_in(0.0, dt)
    };
    let j1 = if cfg!(kani) {
        -j_max
    } else {
        s.f64_in(-j_eff, j_eff)
    };
    let p1 = p0.then(t1, j1);
    // A third piece in the twin only.
    let t2 = if cfg!(kani) { dt } else { s.f64_in(t1, dt) };
    let p2 = if cfg!(kani) {
        p1
    } else {
        p1.then(t2, s.f64_in(-j_eff, j_eff))
    };
    let at = |t: f64| {
        if t <= t1 {
            p0.at(t)
        } else if cfg!(kani) || t <= t2 {
            p1.at(t)
        } else {
            p2.at(t)
        }
    };
    let end = at(dt);
    let w = v_max * 0.999;
    let ok = p0.admissible(t1, a_max, w)
        && p1.admissible(t2, a_max, w)
        && (cfg!(kani) || p2.admissible(dt, a_max, w))
        && end.2.abs() <= a_max
        && end.1.abs() <= w;
    if !s.assume(ok) {
        return;
    }
    let s0 = sample(t0, (p0.q, p0.v, p0.a), true);
    let s1 = sample(t0 + dt, end, true);
    let b = consistent_boxes(&lim, &s0, &s1);
    at_instants(s, dt, |tau| {
        let (q, v, _) = at(tau);
        assert_inside(&b, tau, (q, v));
    });
}

// The Kani proof (4-bit inputs, the limits' accessors stubbed by the split's corner,
// [`kani_limits`]) and the twin.
harness!(
    h2_jerk_enclosed,
    unwind = 6,
    bits = 4,
    stubs = [
        (pacs_models::JointLimits::dof => kani_limits::one_joint),
        (pacs_models::JointLimits::v_max => kani_limits::v_half),
        (pacs_models::JointLimits::a_max => kani_limits::a_one),
        (pacs_models::JointLimits::j_max => kani_limits::j_hundred),
    ],
    cases = crate::DEFAULT_CASES,
    jerk_enclosed
);

/// Split: any two samples with velocities (in the limits, no accelerations) whose displacement
/// lies beyond the band reachable between the logged velocities under `|q̈| ≤ A` (by 1 % of the
/// band plus 1e-9 rad, to either side) are judged inconsistent. Under Kani the velocities are
/// any pair in `[−v_max, v_max]`; the twin draws the end velocity within `A·Δ` of the start
/// (pairs further apart are inconsistent by the velocity test alone).
fn contradiction_inconsistent<S: Source>(s: &mut S) {
    let (v_max, a_max, j_max) = limits(s, (V_HALF[0], A_ONE[0], J_HUNDRED[0]));
    let lim = joint(v_max, a_max, j_max);
    let (dt, t0) = span(s);
    let q0 = s.f64_in(-2.0, 2.0);
    let (c, d) = if cfg!(kani) {
        // Three pairs within `A·Δ = 0.01` of each other: equal, apart upwards, apart downwards
        // (the positions, the side and the excess stay symbolic).
        let k = s.index(3);
        if k == 0 {
            (0.0, 0.0)
        } else if k == 1 {
            (0.25, 0.255)
        } else {
            (-0.49, -0.5)
        }
    } else {
        let c = s.f64_in(-v_max, v_max);
        let w = a_max * dt;
        (c, (c + s.f64_in(-w, w)).clamp(-v_max, v_max))
    };
    let s0 = sample(t0, (q0, c, 0.0), false);
    let s1 = sample(t0 + dt, (q0, d, 0.0), false);
    let bad = contradicting(s, a_max, &s0, &s1);
    assert!(
        !span_boxes(&lim, &s0, &bad, 1e-9).consistent,
        "positions contradicting the logged velocities were judged consistent"
    );
}

// The Kani proof (4-bit inputs, the limits' accessors stubbed by the split's corner,
// [`kani_limits`]) and the twin.
harness!(
    h2_contradiction_inconsistent,
    unwind = 6,
    bits = 4,
    stubs = [
        (pacs_models::JointLimits::dof => kani_limits::one_joint),
        (pacs_models::JointLimits::v_max => kani_limits::v_half),
        (pacs_models::JointLimits::a_max => kani_limits::a_one),
        (pacs_models::JointLimits::j_max => kani_limits::j_hundred),
    ],
    cases = crate::DEFAULT_CASES,
    contradiction_inconsistent
);

#[cfg(test)]
mod tests {
    use super::*;

    /// The stubs of the Kani proofs return what the accessors return for each split's limits.
    #[test]
    fn kani_limits_match_the_accessors() {
        for (lim, a, j) in [
            (
                joint(V_HALF[0], A_TWENTY[0], J_TEN_THOUSAND[0]),
                kani_limits::a_twenty as fn(&JointLimits) -> &[f64],
                kani_limits::j_ten_thousand as fn(&JointLimits) -> &[f64],
            ),
            (
                joint(V_HALF[0], A_ONE[0], J_HUNDRED[0]),
                kani_limits::a_one,
                kani_limits::j_hundred,
            ),
        ] {
            assert_eq!(kani_limits::one_joint(&lim), lim.dof());
            assert_eq!(kani_limits::v_half(&lim), lim.v_max());
            assert_eq!(a(&lim), lim.a_max());
            assert_eq!(j(&lim), lim.j_max());
        }
    }
}
