//! Sound joint enclosures over one span between two logged robot samples, and the check that the
//! samples agree with each other and with the robot's limits.
//!
//! A sample carries positions `q` (rad) and optionally velocities `q̇` (rad/s) and accelerations
//! `q̈` (rad/s², only together with `q̇`). Between the samples every joint obeys
//! `|q̇| ≤ v_max`, `|q̈| ≤ a_max` (`A`) and `|q⃛| ≤ j_max` (`J`).
//!
//! # Consistency (never trust an input that other inputs contradict)
//! Per joint, with `Δ = t₁ − t₀`, the samples are *consistent* when an admissible motion joins
//! them:
//! - `|q₁ − q₀| ≤ v_max·Δ`;
//! - with velocities: `|q̇₀|, |q̇₁| ≤ v_max`, `|q̇₁ − q̇₀| ≤ AΔ` and
//!   `|q₁ − q₀ − Δ(q̇₀ + q̇₁)/2| ≤ (A²Δ² − (q̇₁ − q̇₀)²)/(4A)` — the displacement reachable between
//!   the two velocities under `|q̈| ≤ A` (extremes: bang-bang acceleration);
//! - with accelerations, the same one derivative up: `|q̈₀|, |q̈₁| ≤ A`, `|q̈₁ − q̈₀| ≤ JΔ` and
//!   `|q̇₁ − q̇₀ − Δ(q̈₀ + q̈₁)/2| ≤ (J²Δ² − (q̈₁ − q̈₀)²)/(4J)`.
//!
//! Every test is evaluated leniently (outward-rounded, each input widened by one ulp for decimal
//! parsing, plus a relative `slack`), so it never flags a true motion; a span that fails is
//! `exceeds_limits` (inconclusive, never pass) and its boxes are the *hull* of every enclosure
//! below (so they also cover what Δq implies), without clipping to the limits.
//!
//! # Enclosures (consistent spans: the intersection of all that apply)
//! - positions from `v_max`: `[(q₀+q₁−v_maxΔ)/2, (q₀+q₁+v_maxΔ)/2]`;
//! - positions from velocities and `A`: on `[0, Δ/2]`, `q(t) ≤ q₀ + q̇₀t + At²/2`, convex in `t`, so
//!   at most its value at an end (`q₀` or `q₀ + q̇₀Δ/2 + AΔ²/8`); likewise from `t₁` backwards on
//!   `[Δ/2, Δ]`; lower bounds alike;
//! - velocities from `A`: `[(q̇₀+q̇₁−AΔ)/2, (q̇₀+q̇₁+AΔ)/2]`; without logged velocities, the mean
//!   velocity `(q₁−q₀)/Δ` is attained somewhere, so `q̇ ∈ (q₁−q₀)/Δ ± AΔ`;
//! - velocities from accelerations and `J`: the convexity argument one derivative up:
//!   `q̇ ≤ max(q̇₀, q̇₁, q̇₀ + q̈₀Δ/2 + JΔ²/8, q̇₁ − q̈₁Δ/2 + JΔ²/8)`, lower bound alike;
//! - then clipped to `[−v_max, v_max]`.
//!
//! Soundness (claim C9; harness `proofs::harnesses::audit::h2_span_enclosure_sound`, property
//! tests in `verify/tests/enclosure.rs`): if the logged values are the true states at their
//! times and the motion between them obeys the limits, the span is consistent and the true
//! position and velocity at every instant of the span lie in the boxes.

use pacs_models::JointLimits;
use pacs_models::robot::MAX_DOF;
use pacs_reach::interval::Interval;

/// One logged robot sample (units: s, rad, rad/s, rad/s²).
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Time stamp (s).
    pub t: f64,
    /// Joint positions (rad); entries beyond the robot's dof are 0.
    pub q: [f64; MAX_DOF],
    /// Joint velocities (rad/s), valid when `has_dq`.
    pub dq: [f64; MAX_DOF],
    /// Joint accelerations (rad/s²), valid when `has_ddq` (only with `has_dq`).
    pub ddq: [f64; MAX_DOF],
    /// Velocities were logged.
    pub has_dq: bool,
    /// Accelerations were logged.
    pub has_ddq: bool,
}

/// Joint position and velocity boxes over a span (rad, rad/s), outward rounded.
#[derive(Debug, Clone, Copy)]
pub struct SpanBoxes {
    /// Lower position bounds.
    pub q_lo: [f64; MAX_DOF],
    /// Upper position bounds.
    pub q_hi: [f64; MAX_DOF],
    /// Lower velocity bounds.
    pub dq_lo: [f64; MAX_DOF],
    /// Upper velocity bounds.
    pub dq_hi: [f64; MAX_DOF],
}

impl Default for SpanBoxes {
    fn default() -> Self {
        Self {
            q_lo: [0.0; MAX_DOF],
            q_hi: [0.0; MAX_DOF],
            dq_lo: [0.0; MAX_DOF],
            dq_hi: [0.0; MAX_DOF],
        }
    }
}

/// A logged value as the interval of reals it may stand for (one ulp each way: decimal parsing).
#[inline]
fn logged(x: f64) -> Interval {
    Interval::new(x.next_down(), x.next_up()).unwrap_or(Interval::ENTIRE)
}

#[inline]
fn pt(x: f64) -> Interval {
    Interval::point(x)
}

/// `num / den` for `den.lo() > 0` (outward rounded).
#[inline]
fn div_pos(num: Interval, den: Interval) -> Interval {
    let c = [
        num.lo() / den.lo(),
        num.lo() / den.hi(),
        num.hi() / den.lo(),
        num.hi() / den.hi(),
    ];
    let lo = c.iter().copied().fold(f64::INFINITY, f64::min).next_down();
    let hi = c
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max)
        .next_up();
    Interval::new(lo, hi).unwrap_or(Interval::ENTIRE)
}

/// Bounds of `x + y·h ± k·h²/2` over the step `h` (an interval ≥ 0): the Taylor envelope
/// `[lo, hi]` of a quantity with value `x` and rate `y` at one end of the half span and second
/// derivative bounded by `k`, evaluated at `h` (its value at the span's end is `x` itself).
#[inline]
fn envelope(x: Interval, y: Interval, k: f64, h: Interval) -> (f64, f64) {
    let mid = x + y * h;
    let bend = (h.sqr() * pt(k)).scale(0.5);
    ((mid - bend).lo().min(x.lo()), (mid + bend).hi().max(x.hi()))
}

/// `|r| − bound > tol`, evaluated leniently: the smallest `|r|` against the largest bound.
#[inline]
fn exceeds(r: Interval, bound: Interval, tol: f64) -> bool {
    let r_min = if r.lo() > 0.0 {
        r.lo()
    } else if r.hi() < 0.0 {
        -r.hi()
    } else {
        0.0
    };
    r_min > bound.hi() + tol
}

/// The span's boxes and whether the samples are consistent (module docs). `slack` is the
/// relative tolerance of the limit tests (the audit's `limit_slack`).
pub fn span_boxes(
    lim: &JointLimits,
    s0: &Sample,
    s1: &Sample,
    slack: f64,
    out: &mut SpanBoxes,
) -> bool {
    let n = lim.dof();
    let dt = logged(s1.t) - logged(s0.t);
    let dt = Interval::new(dt.lo().max(0.0), dt.hi()).unwrap_or(Interval::ENTIRE);
    let h = dt.scale(0.5);
    let dt_hi = dt.hi();
    let positive = dt.lo() > 0.0;
    let both_dq = s0.has_dq && s1.has_dq;
    let both_ddq = both_dq && s0.has_ddq && s1.has_ddq;
    let rel = 1.0 + slack;
    let mut ok = true;
    for j in 0..n {
        let (v, acc, jerk) = (lim.v_max()[j], lim.a_max()[j], lim.j_max()[j]);
        let (a, b) = (logged(s0.q[j]), logged(s1.q[j]));
        let scale = 16.0 * f64::EPSILON;
        // Positions from v_max.
        let mid = (a + b).scale(0.5);
        let reach = (pt(v) * dt).scale(0.5);
        let mut p_lo = (mid - reach).lo().min(a.lo()).min(b.lo());
        let mut p_hi = (mid + reach).hi().max(a.hi()).max(b.hi());
        let dq_pos = b - a;
        if exceeds(
            dq_pos,
            pt(v) * dt,
            slack * v * dt_hi + scale * (a.mag() + b.mag()),
        ) {
            ok = false;
        }
        // Velocity candidates.
        let mut v_lo = -v;
        let mut v_hi = v;
        let (mut hull_lo, mut hull_hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut take = |lo: f64, hi: f64, v_lo: &mut f64, v_hi: &mut f64| {
            *v_lo = v_lo.max(lo);
            *v_hi = v_hi.min(hi);
            hull_lo = hull_lo.min(lo);
            hull_hi = hull_hi.max(hi);
        };
        if positive {
            // The mean velocity is attained somewhere in the span.
            let m = div_pos(dq_pos, dt);
            let w = pt(acc) * dt;
            take((m - w).lo(), (m + w).hi(), &mut v_lo, &mut v_hi);
        }
        let mut pos_dq: Option<(f64, f64)> = None;
        if both_dq {
            let (c, d) = (logged(s0.dq[j]), logged(s1.dq[j]));
            let mid_v = (c + d).scale(0.5);
            let w = (pt(acc) * dt).scale(0.5);
            take(
                (mid_v - w).lo().min(c.lo()).min(d.lo()),
                (mid_v + w).hi().max(c.hi()).max(d.hi()),
                &mut v_lo,
                &mut v_hi,
            );
            let tol_v = scale * (c.mag() + d.mag());
            if c.mag() > v * rel || d.mag() > v * rel {
                ok = false;
            }
            let dv = d - c;
            if exceeds(dv, pt(acc) * dt, slack * acc * dt_hi + tol_v) {
                ok = false;
            }
            // Displacement reachable between the two velocities under |q̈| ≤ A.
            let r = dq_pos - dt * mid_v;
            let bound = div_pos((pt(acc) * dt).sqr() - dv.sqr(), pt(4.0 * acc));
            let tol = slack * acc * dt_hi * dt_hi + scale * (a.mag() + b.mag() + dt_hi * tol_v);
            if exceeds(r, bound, tol) {
                ok = false;
            }
            // Positions from velocities and A (Taylor envelopes from both ends).
            let (l0, h0) = envelope(a, c, acc, h);
            let (l1, h1) = envelope(b, -d, acc, h);
            pos_dq = Some((l0.min(l1), h0.max(h1)));
            if both_ddq {
                let (e0, e1) = (logged(s0.ddq[j]), logged(s1.ddq[j]));
                let tol_a = scale * (e0.mag() + e1.mag());
                if e0.mag() > acc * rel || e1.mag() > acc * rel {
                    ok = false;
                }
                let de = e1 - e0;
                if exceeds(de, pt(jerk) * dt, slack * jerk * dt_hi + tol_a) {
                    ok = false;
                }
                let r = dv - dt * (e0 + e1).scale(0.5);
                let bound = div_pos((pt(jerk) * dt).sqr() - de.sqr(), pt(4.0 * jerk));
                let tol = slack * jerk * dt_hi * dt_hi + tol_v + dt_hi * tol_a;
                if exceeds(r, bound, tol) {
                    ok = false;
                }
                let (l0, h0) = envelope(c, e0, jerk, h);
                let (l1, h1) = envelope(d, -e1, jerk, h);
                take(l0.min(l1), h0.max(h1), &mut v_lo, &mut v_hi);
            }
        }
        let (i_lo, i_hi) = match pos_dq {
            Some((l, h)) => (p_lo.max(l), p_hi.min(h)),
            None => (p_lo, p_hi),
        };
        if ok && v_lo <= v_hi && i_lo <= i_hi {
            (p_lo, p_hi) = (i_lo, i_hi);
        } else {
            ok = false;
            // Contradicted: the hull of every enclosure (covers what Δq implies), no clipping.
            if let Some((l, h)) = pos_dq {
                (p_lo, p_hi) = (p_lo.min(l), p_hi.max(h));
            }
            (v_lo, v_hi) = if hull_lo <= hull_hi {
                (hull_lo, hull_hi)
            } else {
                (-v, v)
            };
        }
        out.q_lo[j] = p_lo;
        out.q_hi[j] = p_hi;
        out.dq_lo[j] = v_lo;
        out.dq_hi[j] = v_hi;
    }
    // Any non-finite bound (absurd inputs) makes the span unusable as evidence.
    if (0..n).any(|j| {
        !(out.q_lo[j].is_finite()
            && out.q_hi[j].is_finite()
            && out.dq_lo[j].is_finite()
            && out.dq_hi[j].is_finite())
    }) {
        ok = false;
    }
    ok
}
