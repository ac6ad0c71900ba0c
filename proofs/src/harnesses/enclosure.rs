//! (h2) The audit's span enclosures and consistency check (claim C9, `verify::audit::enclosure`).
//!
//! One joint with random limits moves admissibly over a span of random length: either
//! piecewise-constant acceleration in `[−A, A]` with one switch (bang-bang included; the samples
//! carry `q` and `q̇`), or piecewise-constant jerk in `[−J, J]` over three pieces with `|q̈| ≤ A`
//! (the samples also carry `q̈`). Every such motion must be judged consistent, and its exact
//! position and velocity at sampled instants must lie in the span's boxes (tolerance 1e-12
//! relative for the generator's own rounding). Then the same samples with the end position moved
//! beyond the displacement reachable between the logged velocities (the issue's "`dq` contradicts
//! Δq" case) must be judged inconsistent.

use crate::{Source, harness};
use pacs_audit::enclosure::{Sample, span_boxes};
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

fn enclosure_sound<S: Source>(s: &mut S) {
    // Under Kani, limits from the corners of the twin's ranges (validation then runs on
    // constants); the twin draws them from the whole ranges.
    let (v_max, a_max, j_max) = if cfg!(kani) {
        (
            [0.5, 3.0][s.index(2)],
            [1.0, 20.0][s.index(2)],
            [100.0, 10_000.0][s.index(2)],
        )
    } else {
        (
            s.f64_in(0.5, 3.0),
            s.f64_in(1.0, 20.0),
            s.f64_in(100.0, 10_000.0),
        )
    };
    let lim = JointLimits::new(
        vec![-10.0],
        vec![10.0],
        vec![v_max],
        vec![a_max],
        vec![j_max],
    )
    .expect("valid limits");
    let dt = s.f64_in(1e-4, 0.05);
    let jerk_mode = s.bool();
    let t0 = s.f64_in(0.0, 10.0);
    let f1 = s.f64_in(0.0, 1.0);
    let f2 = s.f64_in(0.0, 1.0 - f1);
    let dur = [dt * f1, dt * f2, dt * (1.0 - f1 - f2).max(0.0)];
    let mut m = Motion {
        q0: s.f64_in(-2.0, 2.0),
        v0: s.f64_in(-v_max, v_max),
        a0: 0.0,
        dur,
        u: [0.0; 3],
        jerk_mode,
    };
    if jerk_mode {
        m.a0 = s.f64_in(-a_max, a_max);
        let j_eff = j_max.min(4.0 * a_max / dt);
        for k in 0..3 {
            m.u[k] = s.f64_in(-j_eff, j_eff);
        }
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
    let enc = span_boxes(&lim, &s0, &s1, 1e-9);
    let Some(b) = enc.boxes.filter(|_| enc.consistent) else {
        panic!("an admissible motion was judged inconsistent");
    };
    let ((q_lo, q_hi), (dq_lo, dq_hi)) = (b.q.bounds(0), b.dq.bounds(0));
    // The ends, and any instant in between (one symbolic instant under Kani, 9 more in tests).
    let instants = if cfg!(kani) { 0 } else { 8 };
    let any = s.f64_in(0.0, dt);
    for i in 0..=instants + 1 {
        let tau = if i > instants {
            any
        } else {
            dt * i as f64 / instants.max(1) as f64
        };
        let (q, v, _) = m.at(tau);
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
    // Contradiction: move the end position beyond the displacement reachable between the two
    // logged velocities under |q̈| ≤ A (by at least 1 % of the reachable band plus 1e-9 rad).
    let (c, d) = (s0.dq[0], s1.dq[0]);
    let reach = (a_max * a_max * dt * dt - (d - c) * (d - c)) / (4.0 * a_max);
    let sign = if s.bool() { 1.0 } else { -1.0 };
    let extra = s.f64_in(0.01, 1.0) * reach.max(0.0) + 1e-9;
    let mut bad = s1;
    bad.q[0] = s0.q[0] + dt * (c + d) / 2.0 + sign * (reach.max(0.0) + extra);
    assert!(
        !span_boxes(&lim, &s0, &bad, 1e-9).consistent,
        "positions contradicting the logged velocities were judged consistent"
    );
}

harness!(
    h2_span_enclosure_sound,
    unwind = 18,
    bits = 8,
    cases = crate::DEFAULT_CASES,
    enclosure_sound
);
