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
//!   `|q̇₁ − q̇₀ − Δ(q̈₀ + q̈₁)/2| ≤ (J²Δ² − (q̈₁ − q̈₀)²)/(4J)`; and the displacement two
//!   derivatives up, `|q₁ − q₀ − Δ(q̇₀ + q̇₁)/2 − Δ²(q̈₀ − q̈₁)/8| ≤ JΔ³/24` (on each half span the
//!   velocity lies within its end's Taylor envelope `q̇ + q̈τ ± Jτ²/2`; integrated);
//! - the mean velocity `(q₁ − q₀)/Δ`, attained at some instant, lies in the velocity box below
//!   (implied by the tests above; checked on the box itself);
//! - derivatives logged at one end only (`q̇` at one sample, or `q̈` at one end of a span with `q̇`
//!   at both): the enclosures below do not use them, but they must agree with the span — a lone
//!   `q̇ = c`: `|c| ≤ v_max` and `|q₁ − q₀ − cΔ| ≤ AΔ²/2`; a lone `q̈ = e` (logged with its
//!   sample's `q̇ = c`): `|e| ≤ A`, `|q₁ − q₀ − cΔ − eΔ²/2| ≤ JΔ³/6` (from its end), and, where
//!   both velocities are logged, `|q̇₁ − q̇₀ − eΔ| ≤ JΔ²/2`.
//!
//! Every bound is rounded outward (each logged value standing for the reals within one ulp of it,
//! for decimal parsing; see `PAD`) and every test is evaluated leniently (plus a relative
//! `slack`), so it never flags a true motion; a span that fails is
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
//! - not clipped to `[−v_max, v_max]` (the speed limit is checked against the samples, but
//!   whether it and the acceleration limit can be met together is not decided here, and a clip
//!   would rest on that); `[−v_max, v_max]` only for a span of no length without velocities.
//!
//! Soundness (claim C9; property test `proofs::harnesses::enclosure::h2_span_enclosure_sound`,
//! also a Kani proof on one corner of the limits (outside CI), Kani proofs `h2_contradiction_inconsistent`, `h2_bang_bang_enclosed`, `h2_jerk_enclosed` beside
//! it, property tests in `audit/tests/audit_consistency.rs`): if the logged values are the true states at their
//! times and the motion between them obeys the limits, the span is consistent and the true
//! position and velocity at every instant of the span lie in the boxes.

use pacs_models::JointLimits;
use pacs_models::robot::MAX_DOF;
use pacs_reach::JointBox;

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
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpanBoxes {
    /// Positions (rad).
    pub q: JointBox,
    /// Velocities (rad/s).
    pub dq: JointBox,
}

impl SpanBoxes {
    /// The smallest boxes containing both (the union of two spans' enclosures).
    pub fn hull(&self, o: &SpanBoxes) -> SpanBoxes {
        SpanBoxes {
            q: self.q.hull(&o.q),
            dq: self.dq.hull(&o.dq),
        }
    }

    /// Grow `self` to [`Self::hull`] of both.
    pub fn hull_in_place(&mut self, o: &SpanBoxes) {
        self.q.hull_in_place(&o.q);
        self.dq.hull_in_place(&o.dq);
    }
}

/// The enclosure of one span: the boxes (`None` if a bound is not finite: absurd samples) and
/// whether the samples are consistent (module docs). Consistent spans always have boxes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpanEnclosure {
    /// The boxes; for an inconsistent span the hull of every enclosure.
    pub boxes: Option<SpanBoxes>,
    /// The samples agree with each other and with the limits.
    pub consistent: bool,
}

impl SpanEnclosure {
    /// No boxes, not consistent: a placeholder to fill with [`span_boxes_into`] (a function, as
    /// [`JointBox::empty`]).
    #[inline]
    pub fn empty() -> SpanEnclosure {
        SpanEnclosure {
            boxes: None,
            consistent: false,
        }
    }
}

/// Relative pad of every bound below: each is a short expression (≤ 12 rounded operations) of
/// logged values, each of which stands for the reals within one ulp (decimal parsing). With unit
/// roundoff u = 2⁻⁵³, its error is at most (2 + 12)·u·`mag`, where `mag` is the sum of the
/// magnitudes of the expression's terms; `PAD = 16u` covers it and the rounding of the padding
/// addition itself. `TINY` covers underflow (absolute errors ≤ 2⁻¹⁰⁷⁴ per operation).
const PAD: f64 = 8.0 * f64::EPSILON;
const TINY: f64 = 1e-300;

/// An upper bound of the exact value of the expression computed as `x`, whose terms have
/// magnitudes summing to `mag` (`mag ≥ |x|`).
#[inline(always)]
fn up(x: f64, mag: f64) -> f64 {
    x + (PAD * mag + TINY)
}

/// A lower bound, as [`up`].
#[inline(always)]
fn down(x: f64, mag: f64) -> f64 {
    x - (PAD * mag + TINY)
}

/// Taylor envelope over a half span: a quantity with value `x` and rate `y` at one end of the
/// span and second derivative bounded by `k` lies, at distance `τ ∈ [0, h]` from that end, within
/// `x + yτ ± kτ²/2`; the upper envelope is convex and the lower concave in τ, so their extremes
/// over the half span are at τ = 0 or τ = h, with `h ∈ [h_lo, h_hi]`. Returns (lower, upper).
#[inline(always)]
fn envelope(x: f64, y: f64, k: f64, h_lo: f64, h_hi: f64) -> (f64, f64) {
    let (yl, yh) = {
        let (p, q) = (y * h_lo, y * h_hi);
        (p.min(q), p.max(q))
    };
    let bend = 0.5 * k * h_hi * h_hi;
    let mag = x.abs() + y.abs() * h_hi + bend;
    (
        down(x + yl - bend, mag).min(down(x, x.abs())),
        up(x + yh + bend, mag).max(up(x, x.abs())),
    )
}

/// The bound `(K²Δ² − δ²)/(4K)` on the displacement between two rates differing by `δ` under
/// `|rate'| ≤ K` over `Δ ≤ dt_hi`, rounded up (`delta_abs_min` a lower bound of `|δ|`).
#[inline(always)]
fn reach_band(k: f64, dt_hi: f64, delta_abs_min: f64) -> f64 {
    let kd = k * dt_hi;
    let num = kd * kd - delta_abs_min * delta_abs_min;
    let mag = (kd * kd + delta_abs_min * delta_abs_min) / (4.0 * k);
    up(num / (4.0 * k), mag)
}

/// The box of a quantity with the values `a` and `b` at the ends of the span whose rate bound
/// lets it change by at most `reach` over the span: within `(a + b ± reach)/2` at every
/// instant, widened to contain both ends (contradicted samples), rounded outwards. Returns
/// (lower, upper).
#[inline(always)]
fn ends_box(a: f64, b: f64, reach: f64) -> (f64, f64) {
    let mag = a.abs() + b.abs();
    (
        down(0.5 * (a + b - reach), mag + reach)
            .min(down(a, a.abs()))
            .min(down(b, b.abs())),
        up(0.5 * (a + b + reach), mag + reach)
            .max(up(a, a.abs()))
            .max(up(b, b.abs())),
    )
}

/// The span's boxes and whether the samples are consistent (module docs). `slack` is the
/// relative tolerance of the limit tests (the audit's `limit_slack`).
///
/// # Soundness
/// Claim C9: every motion between the two samples that obeys the joint limits and matches the
/// samples is judged consistent and lies in the boxes at every instant of the span; samples no
/// such motion matches are judged inconsistent. Property test `h2_span_enclosure_sound` (the whole
/// claim; Kani on one corner of the limits, outside CI); Kani in CI: `h2_contradiction_inconsistent` (inconsistency, one corner of the limits, one
/// span, any positions), `h2_bang_bang_enclosed` and `h2_jerk_enclosed` (one extreme motion each,
/// any instant); mutant `x11` caught (also by Kani).
pub fn span_boxes(lim: &JointLimits, s0: &Sample, s1: &Sample, slack: f64) -> SpanEnclosure {
    let mut b = Bounds::zero();
    let lim = SpanLimits::new(lim);
    let ok = span_bounds(&lim, s0, s1, slack, &mut b);
    let n = lim.n;
    // Any non-finite bound (absurd inputs) makes the span unusable as evidence.
    let boxes = match (
        JointBox::new(&b.q_lo[..n], &b.q_hi[..n]),
        JointBox::new(&b.dq_lo[..n], &b.dq_hi[..n]),
    ) {
        (Ok(q), Ok(dq)) => Some(SpanBoxes { q, dq }),
        _ => None,
    };
    SpanEnclosure {
        consistent: ok && boxes.is_some(),
        boxes,
    }
}

/// [`span_boxes`] written into `out` in place (whatever `out` held before), with the limits
/// prepared once ([`SpanLimits::new`]): the audit fills one enclosure per span of a block into
/// reused storage instead of moving ≈ 0.5 kB per span. The same bounds ([`span_bounds`]) and
/// the same result (test `the_in_place_enclosure_is_span_boxes`); its guarantees are
/// [`span_boxes`]'s. (The Kani harnesses run [`span_boxes`]: a write through the `Option`'s
/// payload is what CBMC's SMT encoding cannot give Bitwuzla.)
#[inline]
pub fn span_boxes_into(
    lim: &SpanLimits,
    s0: &Sample,
    s1: &Sample,
    slack: f64,
    out: &mut SpanEnclosure,
) {
    let mut b = Bounds::zero();
    let ok = span_bounds(lim, s0, s1, slack, &mut b);
    let n = lim.n;
    let sb = out.boxes.get_or_insert_with(|| SpanBoxes {
        q: JointBox::empty(),
        dq: JointBox::empty(),
    });
    let finite =
        sb.q.assign_lanes(&b.q_lo, &b.q_hi, n) && sb.dq.assign_lanes(&b.dq_lo, &b.dq_hi, n);
    if !finite {
        out.boxes = None;
    }
    out.consistent = ok && finite;
}

/// The rate limits the enclosures use, per joint in lanes of [`LANES`]: `v_max` (rad/s), `a_max`
/// (rad/s²) and `j_max` (rad/s³) of the model's joints, then 1.0 in the lanes up to a multiple
/// of [`LANES`] (computed and discarded, so that every joint is evaluated the same vector way).
#[derive(Debug, Clone)]
pub struct SpanLimits {
    v: [f64; MAX_DOF],
    a: [f64; MAX_DOF],
    j: [f64; MAX_DOF],
    /// The robot's joints.
    n: usize,
    /// `n` rounded up to a multiple of [`LANES`] (at most [`MAX_DOF`]).
    lanes: usize,
}

/// Joints evaluated at once (four doubles in an AVX register).
const LANES: usize = 4;
const _: () = assert!(MAX_DOF.is_multiple_of(LANES));

impl SpanLimits {
    /// The limits of `lim` (at most [`MAX_DOF`] joints, as every robot model).
    pub fn new(lim: &JointLimits) -> SpanLimits {
        let n = lim.dof().min(MAX_DOF);
        let mut l = SpanLimits {
            v: [1.0; MAX_DOF],
            a: [1.0; MAX_DOF],
            j: [1.0; MAX_DOF],
            n,
            lanes: n.div_ceil(LANES) * LANES,
        };
        // Element by element (a memcpy of float arrays is what CBMC's SMT encoding cannot give
        // Bitwuzla; the h2 harnesses run through here).
        for k in 0..n {
            l.v[k] = lim.v_max()[k];
            l.a[k] = lim.a_max()[k];
            l.j[k] = lim.j_max()[k];
        }
        l
    }
}

/// The quintic that matches a span's six logged values (positions `dpos` apart (rad), velocities
/// `c`, `d` (rad/s), accelerations `e0`, `e1` (rad/s²) at its ends, `Δ = dt` as computed):
/// `q(s) = q₀ + cΔs + e₀Δ²s²/2 + c₃s³ + c₄s⁴ + c₅s⁵`, `s = t/Δ`, and a padded bound of its
/// jerk's magnitude over the span. See [`jerk_feasible`].
struct Quintic {
    c3: f64,
    c4: f64,
    c5: f64,
    /// The jerk's largest magnitude over `[0, 1]`, padded for rounding and for Δ's uncertainty
    /// (rad/s³).
    j_bound: f64,
    /// The jerk terms' magnitudes (rad/s³): the scale of every padding below.
    mag: f64,
    /// Δ's relative uncertainty, `(dt_hi − dt_lo)/dt_lo`.
    rel_dt: f64,
}

impl Quintic {
    /// The quintic and its jerk bound, for `dt_lo > 0` and `dt³ > 0` (no quotient below is then
    /// 0/0). Straight-line code: evaluated for four joints at once by [`jerk_feasible_lanes`].
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn new(
        dpos: f64,
        c: f64,
        d: f64,
        e0: f64,
        e1: f64,
        dt: f64,
        dt_lo: f64,
        dt_hi: f64,
    ) -> Quintic {
        let h = dt;
        let hh = h * h;
        let h3 = hh * h;
        let c3 = 10.0 * dpos - 6.0 * c * h - 4.0 * d * h - (3.0 * e0 - e1) * hh * 0.5;
        let c4 = -15.0 * dpos + 8.0 * c * h + 7.0 * d * h + (3.0 * e0 - 2.0 * e1) * hh * 0.5;
        let c5 = 6.0 * dpos - 3.0 * (c + d) * h - (e0 - e1) * hh * 0.5;
        // The jerk `(6c₃ + 24c₄s + 60c₅s²)/Δ³`, a quadratic in `s`: largest at an end or at the
        // vertex.
        let at = |s: f64| (6.0 * c3 + 24.0 * c4 * s + 60.0 * c5 * s * s) / h3;
        let vertex_ok = c5 != 0.0 && c4.is_finite() && c5.is_finite();
        let vertex = if vertex_ok {
            (-c4 / (5.0 * c5)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let largest = at(0.0).abs().max(at(1.0).abs()).max(at(vertex).abs());
        // The terms' magnitudes (each coefficient's, times the largest factor it takes in the
        // jerk): every rounding, and each logged value's ulp, is within PAD of them; the jerk
        // scales as Δ⁻³ for fixed data, so Δ's relative uncertainty counts three times. The
        // vertex's own rounding moves the quadratic's value by second order only, within the
        // same pad.
        let mag = (60.0 * 31.0 * dpos.abs()
            + 60.0 * 17.0 * (c.abs() + d.abs()) * h
            + 60.0 * 3.0 * (e0.abs() + e1.abs()) * hh)
            / h3;
        let rel_dt = (dt_hi - dt_lo) / dt_lo;
        let pad = 16.0 * PAD * mag + 3.0 * mag * rel_dt + TINY;
        Quintic {
            c3,
            c4,
            c5,
            j_bound: largest + pad,
            mag,
            rel_dt,
        }
    }

    /// The cheap bound of the quintic's acceleration (rad/s²), rounded up: from either end the
    /// acceleration moves at most as fast as the jerk bound allows, so
    /// `|q̈| ≤ (|q̈₀| + |q̈₁| + j_bound·Δ)/2`.
    #[inline(always)]
    fn cheap_acc(&self, e0: f64, e1: f64, dt_hi: f64) -> f64 {
        let cheap = 0.5 * (e0.abs() + e1.abs() + self.j_bound * dt_hi);
        up(cheap, cheap)
    }

    /// The bound of the quintic's acceleration (rad/s²), padded: `q̈ = (e₀Δ² + 6c₃s + 12c₄s² +
    /// 20c₅s³)/Δ²`, a cubic in `s`, largest at an end or where the jerk (a quadratic) vanishes.
    fn exact_acc(&self, e0: f64, dt: f64) -> f64 {
        let (c3, c4, c5) = (self.c3, self.c4, self.c5);
        let hh = dt * dt;
        let acc_at =
            |s: f64| (e0 * hh + 6.0 * c3 * s + 12.0 * c4 * s * s + 20.0 * c5 * s * s * s) / hh;
        // The jerk's zeros (none, one or two; NaN where there are none), each within [0, 1].
        let disc = 576.0 * c4 * c4 - 1440.0 * c3 * c5;
        let zeros = if c5 != 0.0 && disc >= 0.0 {
            let root = disc.sqrt();
            [
                (-24.0 * c4 + root) / (120.0 * c5),
                (-24.0 * c4 - root) / (120.0 * c5),
            ]
        } else if c5 == 0.0 && c4 != 0.0 {
            [-c3 / (4.0 * c4), f64::NAN]
        } else {
            [f64::NAN; 2]
        };
        let mut a_q = acc_at(0.0).abs().max(acc_at(1.0).abs());
        for r in zeros.into_iter().filter(|r| r.is_finite()) {
            a_q = a_q.max(acc_at(r.clamp(0.0, 1.0)).abs());
        }
        // (Its terms' magnitudes, as for the jerk, one power of Δ fewer; the roots' own
        // rounding moves the cubic's value by second order only, bounded by the same generous
        // pad.)
        let mag_a = self.mag * dt;
        a_q + (64.0 * PAD * mag_a + 2.0 * mag_a * self.rel_dt + TINY)
    }
}

/// The speed bound `(|q̇₀| + |q̇₁| + a·Δ)/2` (rad/s), rounded up, of a motion whose acceleration
/// is bounded by `a`: between the ends the velocity moves from `q̇₀` and towards `q̇₁` at most
/// as fast as `a` allows.
#[inline(always)]
fn speed_bound(c: f64, d: f64, a: f64, dt_hi: f64) -> f64 {
    let v_q = 0.5 * (c.abs() + d.abs() + a * dt_hi);
    up(v_q, v_q)
}

/// Whether a motion within the limits (`|q̇| ≤ v_max`, `|q̈| ≤ acc`, `|q⃛| ≤ jerk`) joins two
/// samples with positions `dpos` apart (rad),
/// velocities `c`, `d` (rad/s) and accelerations `e0`, `e1` (rad/s²), `Δ = dt` (as computed;
/// the true Δ within `[dt_lo, dt_hi]`): a sufficient test. The quintic that matches the six
/// values ([`Quintic`]) has the jerk `(6c₃ + 24c₄s + 60c₅s²)/Δ³`, a quadratic in `s`: its
/// largest magnitude over `[0, 1]` is at an end or at the vertex; its acceleration, a cubic, at
/// an end or where the jerk vanishes (first a cheap bound, [`Quintic::cheap_acc`]); its speed
/// at most `(|q̇₀| + |q̇₁| + a·Δ)/2` (`a` that acceleration bound). If these bounds, padded for
/// rounding and for the uncertainty of Δ, are within the limits, the quintic is such a motion.
/// Otherwise (no such motion, or none this test finds) false: the caller does not narrow the
/// velocity box by the jerk limit. [`jerk_feasible_lanes`] computes the same for every joint.
///
/// # Soundness
/// True only where the padded bound holds, so only where a motion within the jerk limit joins
/// the samples. Test `audit_consistency.rs::accelerations_must_agree_with_the_positions_under_the_jerk_limit`;
/// mutant `x101`.
#[allow(clippy::too_many_arguments)]
fn jerk_feasible(
    dpos: f64,
    c: f64,
    d: f64,
    e0: f64,
    e1: f64,
    dt: f64,
    dt_lo: f64,
    dt_hi: f64,
    (v_max, acc, jerk): (f64, f64, f64),
) -> bool {
    let valid = dt_lo > 0.0 && dt * dt * dt > 0.0;
    if !valid {
        return false;
    }
    let q = Quintic::new(dpos, c, d, e0, e1, dt, dt_lo, dt_hi);
    let within_jerk = q.j_bound <= jerk;
    if !within_jerk {
        return false;
    }
    let cheap = q.cheap_acc(e0, e1, dt_hi);
    if cheap <= acc {
        return speed_bound(c, d, cheap, dt_hi) <= v_max;
    }
    let a_bound = q.exact_acc(e0, dt);
    let within_acc = a_bound <= acc;
    within_acc && speed_bound(c, d, a_bound, dt_hi) <= v_max
}

/// [`jerk_feasible`] for every lane of a span with velocities and accelerations logged at both
/// ends (the limits relative `sp.rel`): the jerk bound and the cheap acceleration bound in
/// straight-line code, four joints at once; [`jerk_feasible`] itself (the cubic's critical
/// points) only for the lanes where the cheap bound exceeds the acceleration limit. Each lane's
/// result is [`jerk_feasible`]'s (test `the_lanes_agree_with_jerk_feasible`).
#[inline(always)]
fn jerk_feasible_lanes(lim: &SpanLimits, s0: &Sample, s1: &Sample, sp: &Span) -> [bool; MAX_DOF] {
    let mut ok = [false; MAX_DOF];
    let (dt, dt_lo, dt_hi) = (sp.dt, sp.dt_lo, sp.dt_hi);
    let valid = dt_lo > 0.0 && dt * dt * dt > 0.0;
    if !valid {
        return ok;
    }
    let n = lim.lanes;
    let mut exact = [false; MAX_DOF];
    for j in 0..n {
        let (v_max, acc, jerk) = (lim.v[j] * sp.rel, lim.a[j] * sp.rel, lim.j[j] * sp.rel);
        let (c, d, e0, e1) = (s0.dq[j], s1.dq[j], s0.ddq[j], s1.ddq[j]);
        let q = Quintic::new(s1.q[j] - s0.q[j], c, d, e0, e1, dt, dt_lo, dt_hi);
        let within_jerk = q.j_bound <= jerk;
        let cheap = q.cheap_acc(e0, e1, dt_hi);
        let cheap_ok = cheap <= acc;
        ok[j] = within_jerk & cheap_ok & (speed_bound(c, d, cheap, dt_hi) <= v_max);
        exact[j] = within_jerk & !cheap_ok;
    }
    for j in 0..lim.n {
        if exact[j] {
            let limits = (lim.v[j] * sp.rel, lim.a[j] * sp.rel, lim.j[j] * sp.rel);
            let (c, d, e0, e1) = (s0.dq[j], s1.dq[j], s0.ddq[j], s1.ddq[j]);
            let dpos = s1.q[j] - s0.q[j];
            ok[j] = jerk_feasible(dpos, c, d, e0, e1, dt, dt_lo, dt_hi, limits);
        }
    }
    ok
}

/// Whether the span `s0`–`s1` agrees with the span before it, `sp`–`s0` (`sp` the latest sample
/// stamped before `s0`: spans of no length between them say nothing about the motion), at
/// their shared sample `s0`. A span's mean velocity is the average of the joint's velocity over
/// it, so it differs from the velocity at either end by at most `A·Δ/2`. Where `s0` logs no
/// velocity, the velocity there being one value, the two means differ by at most
/// `A·(Δ₀ + Δ₁)/2`; where `s0` logs `q̇ = c`, `|c − m₀| ≤ A·Δ₀/2` (what the earlier span's own
/// tests check of `c` when it ends at `s0`, but not across samples of `s0`'s stamp). Each span's
/// own tests cannot see this (a joint logged moving in one span and still in the next, or a
/// zig-zag of positions, each span alone within the limits). Outward rounded and lenient
/// (relative `slack`), so it never flags a true motion; true where a span has no length.
/// `direct`: `sp` is the sample just before `s0` (no sample of `s0`'s stamp between them).
///
/// # Soundness
/// Claim C9 (the consistency half): tests in `audit/tests/audit_consistency.rs`
/// (`adjacent_spans_must_agree_at_their_shared_sample`); mutant `x102`.
pub fn adjacent_spans_agree(
    lim: &SpanLimits,
    sp: &Sample,
    s0: &Sample,
    s1: &Sample,
    slack: f64,
    direct: bool,
) -> bool {
    // Velocities at both ends of the earlier span, `sp` just before `s0` (`direct`): its own
    // displacement test (`|m₀ − (q̇ₚ + c)/2| ≤ (A²Δ₀² − (c − q̇ₚ)²)/(4AΔ₀)`) implies
    // `|c − m₀| ≤ AΔ₀/2`: nothing more to check.
    if direct && sp.has_dq && s0.has_dq {
        return true;
    }
    let bounds = |a: &Sample, b: &Sample| {
        let dt = b.t - a.t;
        let err = PAD * (a.t.abs() + b.t.abs()) + TINY;
        ((dt - err).max(0.0), dt + err)
    };
    let ((d0_lo, d0_hi), (d1_lo, d1_hi)) = (bounds(sp, s0), bounds(s0, s1));
    if !(d0_lo > 0.0 && d0_hi.is_finite() && d1_hi.is_finite()) {
        return true;
    }
    // The mean velocity (b − a)/Δ over Δ ∈ [lo, hi], bounded outward.
    let mean = |a: f64, b: f64, lo: f64, hi: f64| {
        let (d, mag) = (b - a, a.abs() + b.abs());
        let (n_lo, n_hi) = (down(d, mag), up(d, mag));
        let m_lo = (n_lo / lo).min(n_lo / hi);
        let m_hi = (n_hi / lo).max(n_hi / hi);
        (down(m_lo, m_lo.abs()), up(m_hi, m_hi.abs()))
    };
    let mut ok = true;
    for j in 0..lim.n {
        let (l0, h0) = mean(sp.q[j], s0.q[j], d0_lo, d0_hi);
        // The other side: the logged velocity at `s0`, or the later span's mean.
        let ((l1, h1), reach) = if s0.has_dq {
            let c = s0.dq[j];
            ((c, c), d0_hi)
        } else if d1_lo > 0.0 {
            (mean(s0.q[j], s1.q[j], d1_lo, d1_hi), d0_hi + d1_hi)
        } else {
            continue;
        };
        let apart = (l1 - h0).max(l0 - h1);
        let allowed = 0.5 * lim.a[j] * reach;
        // (A NaN, from means beyond floating point, agrees with nothing.)
        ok &= apart <= up(allowed, allowed) * (1.0 + slack);
    }
    ok
}

/// The bounds of the span's boxes per joint (rad, rad/s), before they are checked finite.
struct Bounds {
    q_lo: [f64; MAX_DOF],
    q_hi: [f64; MAX_DOF],
    dq_lo: [f64; MAX_DOF],
    dq_hi: [f64; MAX_DOF],
}

impl Bounds {
    #[inline(always)]
    fn zero() -> Bounds {
        Bounds {
            q_lo: [0.0; MAX_DOF],
            q_hi: [0.0; MAX_DOF],
            dq_lo: [0.0; MAX_DOF],
            dq_hi: [0.0; MAX_DOF],
        }
    }
}

/// The computation of [`span_boxes`]: the bounds of the boxes into `out` and whether the samples
/// are consistent (module docs). Shared by [`span_boxes`] and [`span_boxes_into`].
///
/// Every joint is computed the same way, without branches that differ between joints (the
/// logged derivatives are the same for all joints of a sample, so each combination has its own
/// loop, [`joint_bounds`]): the compiler evaluates four joints at once. A span is consistent
/// only if every joint is; an inconsistent span gets the hull boxes for every joint.
#[inline(always)]
fn span_bounds(lim: &SpanLimits, s0: &Sample, s1: &Sample, slack: f64, out: &mut Bounds) -> bool {
    // Δ ∈ [dt_lo, dt_hi] (time stamps within one ulp each, one rounded subtraction).
    let dt = s1.t - s0.t;
    let dt_err = PAD * (s0.t.abs() + s1.t.abs()) + TINY;
    let dt_hi = dt + dt_err;
    let span = Span {
        dt,
        dt_lo: (dt - dt_err).max(0.0),
        dt_hi,
        rel: 1.0 + slack,
        slack,
    };
    let both_dq = s0.has_dq && s1.has_dq;
    let both_ddq = both_dq && s0.has_ddq && s1.has_ddq;
    // The intersection boxes and the consistency tests first; the hull boxes (the same
    // expressions, kept instead of intersected) only for a span that fails them.
    // A duration without a finite bound: no joint's enclosure holds.
    // Derivatives logged at one end only: not used by the enclosures, but checked against them.
    let lone = s0.has_dq != s1.has_dq || s0.has_ddq != s1.has_ddq;
    let ok = dt_hi.is_finite()
        && match (both_dq, both_ddq) {
            (false, _) => joint_bounds::<false, false, false>(lim, s0, s1, &span, out),
            (true, false) => joint_bounds::<true, false, false>(lim, s0, s1, &span, out),
            (true, true) => joint_bounds::<true, true, false>(lim, s0, s1, &span, out),
        }
        && (!lone || lone_derivatives_agree(lim, s0, s1, &span));
    if !ok {
        match (both_dq, both_ddq) {
            (false, _) => joint_bounds::<false, false, true>(lim, s0, s1, &span, out),
            (true, false) => joint_bounds::<true, false, true>(lim, s0, s1, &span, out),
            (true, true) => joint_bounds::<true, true, true>(lim, s0, s1, &span, out),
        };
        // The hull also covers a velocity logged at one end only (what that sample claims).
        for s in [s0, s1] {
            if s.has_dq && !both_dq {
                for j in 0..lim.n {
                    let c = s.dq[j];
                    out.dq_lo[j] = out.dq_lo[j].min(down(c, c.abs()));
                    out.dq_hi[j] = out.dq_hi[j].max(up(c, c.abs()));
                }
            }
        }
    }
    ok
}

/// Derivatives logged at one end of the span only — `q̇` at one sample and not at the other, or
/// `q̈` at one end of a span with `q̇` at both — take no part in the enclosures, which hold
/// without them; but a log whose derivatives contradict its positions is no evidence (module
/// docs), and a sample's own `q̇` is what the zero-length final instant uses. So each must agree
/// with the span, leniently as the other tests (outward rounded, relative `slack`):
/// - a lone `q̇ = c` at either end: `|c| ≤ v_max` and `|q₁ − q₀ − cΔ| ≤ AΔ²/2` (from one end's
///   velocity, `|q̈| ≤ A` lets the displacement differ from `cΔ` by at most that);
/// - a lone `q̈ = e` at either end: `|e| ≤ A`, and with velocities at both ends
///   `|q̇₁ − q̇₀ − eΔ| ≤ JΔ²/2` (the same one derivative up).
///
/// Returns whether every joint agrees.
#[inline(never)]
fn lone_derivatives_agree(lim: &SpanLimits, s0: &Sample, s1: &Sample, sp: &Span) -> bool {
    let both_dq = s0.has_dq && s1.has_dq;
    let both_ddq = s0.has_ddq && s1.has_ddq;
    // `|x − rate·Δ|` beyond `k·Δ²/2` (rounded outward, lenient): `x` is a difference of two
    // logged values of magnitudes summing to `mag`, `rate` one logged value.
    let beyond = |x: f64, mag: f64, rate: f64, k: f64| {
        let r = x - sp.dt * rate;
        let r_min = r.abs()
            - (PAD * (mag + sp.dt_hi * rate.abs()) + TINY)
            - rate.abs() * (sp.dt_hi - sp.dt_lo);
        let band = 0.5 * k * sp.dt_hi * sp.dt_hi;
        r_min > up(band, band) + sp.slack * k * sp.dt_hi * sp.dt_hi
    };
    for j in 0..lim.n {
        let (v, acc, jerk) = (lim.v[j], lim.a[j], lim.j[j]);
        let (a, b) = (s0.q[j], s1.q[j]);
        for s in [s0, s1] {
            if s.has_dq && !both_dq {
                let c = s.dq[j];
                if down(c.abs(), c.abs()) > v * sp.rel || beyond(b - a, a.abs() + b.abs(), c, acc) {
                    return false;
                }
            }
            if s.has_ddq && !both_ddq {
                let e = s.ddq[j];
                if down(e.abs(), e.abs()) > acc * sp.rel {
                    return false;
                }
                let (c, d) = (s0.dq[j], s1.dq[j]);
                if both_dq && beyond(d - c, c.abs() + d.abs(), e, jerk) {
                    return false;
                }
                // The positions from this end's velocity and acceleration under |q⃛| ≤ J:
                // `|x − rate·Δ − eΔ²/2| ≤ JΔ³/6` (x the displacement away from this end).
                let (x, rate) = if std::ptr::eq(s, s0) {
                    (b - a, s.dq[j])
                } else {
                    (a - b, -s.dq[j])
                };
                let r = x - sp.dt * rate - 0.5 * e * sp.dt * sp.dt;
                let (h, h2) = (sp.dt_hi, sp.dt_hi * sp.dt_hi);
                let r_min = r.abs()
                    - (PAD * (a.abs() + b.abs() + h * rate.abs() + h2 * e.abs()) + TINY)
                    - rate.abs() * (sp.dt_hi - sp.dt_lo)
                    - 0.5 * e.abs() * (h2 - sp.dt_lo * sp.dt_lo);
                let band = jerk * h2 * h / 6.0;
                if r_min > up(band, band) + sp.slack * jerk * h2 * h {
                    return false;
                }
            }
        }
    }
    true
}

/// The span's duration and the limit tests' tolerance, shared by every joint.
struct Span {
    /// `t₁ − t₀` as computed (s).
    dt: f64,
    /// Bounds of the true duration (s): `dt_lo ≤ Δ ≤ dt_hi`, `dt_lo ≥ 0`.
    dt_lo: f64,
    dt_hi: f64,
    /// `1 + slack`.
    rel: f64,
    /// The relative slack of the limit tests.
    slack: f64,
}

/// [`span_bounds`] for every joint, with velocities logged at both ends (`DQ`) and
/// accelerations too (`DDQ`, only with `DQ`). Writes the intersection boxes (consistent span),
/// or with `HULL` the hull boxes (every candidate enclosure kept, for a span that is not);
/// returns whether every joint is consistent (the same tests either way). Lanes beyond the
/// robot's joints (up to a multiple of [`LANES`]) are computed alike and ignored: their flags do
/// not count, their bounds are never read. One body for both, so that the hull is the union of
/// exactly the enclosures intersected; `HULL` is a constant, so the intersection's instance
/// computes no hull.
#[inline(always)]
fn joint_bounds<const DQ: bool, const DDQ: bool, const HULL: bool>(
    lim: &SpanLimits,
    s0: &Sample,
    s1: &Sample,
    sp: &Span,
    out: &mut Bounds,
) -> bool {
    let n = lim.lanes;
    let (v_max, a_max, j_max) = (&lim.v[..n], &lim.a[..n], &lim.j[..n]);
    let (q0, q1) = (&s0.q[..n], &s1.q[..n]);
    let (dq0, dq1) = (&s0.dq[..n], &s1.dq[..n]);
    let (ddq0, ddq1) = (&s0.ddq[..n], &s1.ddq[..n]);
    let Span {
        dt,
        dt_lo,
        dt_hi,
        rel,
        slack,
    } = *sp;
    let (h_lo, h_hi) = (0.5 * dt_lo, 0.5 * dt_hi);
    // The mean velocity (b − a)/Δ is attained somewhere in the span (needs Δ > 0).
    let has_mean = dt_lo > 0.0;
    let mut bad_lane = [false; MAX_DOF];
    let jerk_ok = if DDQ {
        jerk_feasible_lanes(lim, s0, s1, sp)
    } else {
        [false; MAX_DOF]
    };
    for j in 0..n {
        let (v, acc, jerk) = (v_max[j], a_max[j], j_max[j]);
        let (a, b) = (q0[j], q1[j]);
        let mag_ab = a.abs() + b.abs();
        // Positions from v_max.
        let reach = v * dt_hi;
        let (p_lo, p_hi) = ends_box(a, b, reach);
        let dpos = b - a;
        let mut bad_j = down(dpos.abs(), mag_ab) > reach * rel;
        // The mean velocity (b − a)/Δ, bounded outward (`mean_lo`, `mean_hi`), is attained at
        // some instant of the span (where Δ > 0): q̇ ∈ mean ± AΔ.
        let (mean_lo, mean_hi) = {
            let (n_lo, n_hi) = (down(dpos, mag_ab), up(dpos, mag_ab));
            let m_hi = (n_hi / dt_lo).max(n_hi / dt_hi);
            let m_lo = (n_lo / dt_lo).min(n_lo / dt_hi);
            (down(m_lo, m_lo.abs()), up(m_hi, m_hi.abs()))
        };
        let (m_lo, m_hi) = {
            let w = acc * dt_hi;
            (
                down(mean_lo - w, mean_lo.abs() + w),
                up(mean_hi + w, mean_hi.abs() + w),
            )
        };
        // Velocity box: the intersection of the candidates (not clipped to ±v_max: the speed
        // limit is checked against the samples, but no test here decides that it and the
        // acceleration limit can be met together, so the box rests on the acceleration and
        // jerk limits alone); their hull (the mean's box included) for a contradicted span.
        let (mut v_lo, mut v_hi) = (f64::NEG_INFINITY, f64::INFINITY);
        let (mut hv_lo, mut hv_hi) = if has_mean {
            (m_lo, m_hi)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        };
        let (mut i_lo, mut i_hi) = (p_lo, p_hi);
        let (mut hp_lo, mut hp_hi) = (p_lo, p_hi);
        if DQ {
            let (c, d) = (dq0[j], dq1[j]);
            let mag_cd = c.abs() + d.abs();
            let w = acc * dt_hi;
            let (e_lo, e_hi) = ends_box(c, d, w);
            (v_lo, v_hi) = (v_lo.max(e_lo), v_hi.min(e_hi));
            (hv_lo, hv_hi) = (hv_lo.min(e_lo), hv_hi.max(e_hi));
            bad_j |= down(c.abs(), c.abs()) > v * rel;
            bad_j |= down(d.abs(), d.abs()) > v * rel;
            let dv = d - c;
            let dv_min = down(dv.abs(), mag_cd).max(0.0);
            bad_j |= dv_min > w * rel;
            // Displacement reachable between the two velocities under |q̈| ≤ A:
            // |b − a − Δ(c + d)/2| ≤ (A²Δ² − (d − c)²)/(4A).
            let r = dpos - dt * 0.5 * (c + d);
            let r_min =
                r.abs() - (PAD * (mag_ab + dt_hi * mag_cd) + TINY) - 0.5 * mag_cd * (dt_hi - dt_lo);
            bad_j |= r_min > reach_band(acc, dt_hi, dv_min) + slack * acc * dt_hi * dt_hi;
            // Positions from velocities and A: envelopes from both ends.
            let (l0, h0) = envelope(a, c, acc, h_lo, h_hi);
            let (l1, h1) = envelope(b, -d, acc, h_lo, h_hi);
            let (l, h) = (l0.min(l1), h0.max(h1));
            (i_lo, i_hi) = (p_lo.max(l), p_hi.min(h));
            (hp_lo, hp_hi) = (p_lo.min(l), p_hi.max(h));
            if DDQ {
                let (e0, e1) = (ddq0[j], ddq1[j]);
                let mag_e = e0.abs() + e1.abs();
                bad_j |= down(e0.abs(), e0.abs()) > acc * rel;
                bad_j |= down(e1.abs(), e1.abs()) > acc * rel;
                let de = e1 - e0;
                let de_min = down(de.abs(), mag_e).max(0.0);
                bad_j |= de_min > jerk * dt_hi * rel;
                let r = dv - dt * 0.5 * (e0 + e1);
                let r_min = r.abs()
                    - (PAD * (mag_cd + dt_hi * mag_e) + TINY)
                    - 0.5 * mag_e * (dt_hi - dt_lo);
                bad_j |= r_min > reach_band(jerk, dt_hi, de_min) + slack * jerk * dt_hi * dt_hi;
                // Displacement reachable from both ends' velocities and accelerations under
                // |q⃛| ≤ J: on each half span the velocity lies within its end's Taylor envelope
                // (q̇₀ + q̈₀τ ± Jτ²/2 from t₀, q̇₁ − q̈₁τ ± Jτ²/2 from t₁), so
                // |b − a − Δ(c + d)/2 − Δ²(e₀ − e₁)/8| ≤ JΔ³/24.
                let dt3 = dt_hi * dt_hi * dt_hi;
                let r3 = dpos - dt * 0.5 * (c + d) - dt * dt * 0.125 * (e0 - e1);
                let r3_min = r3.abs()
                    - (PAD * (mag_ab + dt_hi * mag_cd + dt_hi * dt_hi * mag_e) + TINY)
                    - 0.5 * mag_cd * (dt_hi - dt_lo)
                    - 0.125 * mag_e * (dt_hi * dt_hi - dt_lo * dt_lo);
                let band3 = jerk * dt3 / 24.0;
                bad_j |= r3_min > up(band3, band3) + slack * jerk * dt3;
                let (l0, h0) = envelope(c, e0, jerk, h_lo, h_hi);
                let (l1, h1) = envelope(d, -e1, jerk, h_lo, h_hi);
                let (l, h) = (l0.min(l1), h0.max(h1));
                // The jerk limit narrows the velocity box only where a motion within it is known
                // to join the samples (`jerk_feasible`): where none does, the log refutes the
                // limit the narrowing rests on, and the box keeps what the acceleration limit
                // gives (the tests above flag the spans they prove infeasible).
                if jerk_ok[j] {
                    (v_lo, v_hi) = (v_lo.max(l), v_hi.min(h));
                }
                (hv_lo, hv_hi) = (hv_lo.min(l), hv_hi.max(h));
            }
        } else if has_mean {
            (v_lo, v_hi) = (v_lo.max(m_lo), v_hi.min(m_hi));
        } else {
            // No time and no velocities: the speed limit is all there is.
            (v_lo, v_hi) = (-v, v);
        }
        // The velocity box holds every admissible motion's velocity at every instant, the mean
        // velocity's instant included: a box that misses the mean leaves no admissible motion
        // (what the displacement tests above imply, checked once more on the box itself).
        if has_mean {
            let tol = slack * (v + acc * dt_hi + jerk * dt_hi * dt_hi);
            bad_j |= mean_lo > v_hi + tol || mean_hi < v_lo - tol;
        }
        // Comparisons with NaN are false: a NaN bound makes the joint inconsistent.
        bad_lane[j] = bad_j || !(v_lo <= v_hi && i_lo <= i_hi);
        if HULL {
            // Contradicted: the hull of every enclosure (it covers what Δq implies), no
            // clipping to the limits; the velocity limits where no candidate applies.
            (out.q_lo[j], out.q_hi[j]) = (hp_lo, hp_hi);
            (out.dq_lo[j], out.dq_hi[j]) = if hv_lo <= hv_hi {
                (hv_lo, hv_hi)
            } else {
                (-v, v)
            };
        } else {
            (out.q_lo[j], out.q_hi[j]) = (i_lo, i_hi);
            (out.dq_lo[j], out.dq_hi[j]) = (v_lo, v_hi);
        }
    }
    let mut bad = false;
    for &b in &bad_lane[..lim.n] {
        bad |= b;
    }
    !bad
}

#[cfg(test)]
mod tests {
    use super::*;
    use pacs_models::RobotModel;
    use proptest::prelude::*;

    /// A sample of 7 joints from the test's values: positions, velocities, accelerations.
    fn sample(t: f64, v: &[f64], has_dq: bool, has_ddq: bool) -> Sample {
        let mut s = Sample {
            t,
            q: [0.0; MAX_DOF],
            dq: [0.0; MAX_DOF],
            ddq: [0.0; MAX_DOF],
            has_dq,
            has_ddq: has_dq && has_ddq,
        };
        for j in 0..7 {
            (s.q[j], s.dq[j], s.ddq[j]) = (v[j], v[7 + j], v[14 + j]);
        }
        s
    }

    /// Values from ordinary motion to absurd ones (non-finite bounds: no boxes).
    fn value() -> impl Strategy<Value = f64> {
        prop_oneof![
            8 => -3.0..3.0f64,
            1 => prop::num::f64::ANY,
            1 => Just(f64::MAX),
        ]
    }

    /// Every lane of [`jerk_feasible_lanes`] is [`jerk_feasible`]'s verdict on that joint, on
    /// spans of constant jerk near and beyond each limit (scaled by up to 1.3 and perturbed),
    /// at 1 kHz and 100 Hz, from stamp 0 and from 1.7e9 s: each way to a verdict (the cheap
    /// bound or the cubic's critical points; feasible or not) is taken many times.
    #[test]
    fn the_lanes_agree_with_jerk_feasible() {
        let robot = RobotModel::builtin("fr3").unwrap();
        let lim = SpanLimits::new(robot.limits());
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut feasible, mut infeasible, mut exact, mut exact_feasible) = (0, 0, 0, 0);
        for case in 0..20_000 {
            let dt = if case % 2 == 0 { 1e-3 } else { 1e-2 };
            let t0 = if case % 4 < 2 { 0.5 } else { 1.7e9 };
            let scale = 0.7 + 0.6 * uniform();
            let mut s0 = sample(t0, &[0.0; 21], true, true);
            let mut s1 = sample(t0 + dt, &[0.0; 21], true, true);
            for j in 0..7 {
                let (v, a, jm) = (lim.v[j], lim.a[j], lim.j[j]);
                let q0 = 2.0 * uniform() - 1.0;
                let c = v * scale * (2.0 * uniform() - 1.0);
                // Accelerations near the limit half of the time: the cheap bound then exceeds it.
                let e0 = a
                    * scale
                    * if uniform() < 0.5 {
                        2.0 * uniform() - 1.0
                    } else {
                        0.98
                    };
                let jerk = jm * scale * (2.0 * uniform() - 1.0);
                let wobble = 1.0 + 1e-3 * (uniform() - 0.5);
                (s0.q[j], s0.dq[j], s0.ddq[j]) = (q0, c, e0);
                s1.q[j] = q0 + (c * dt + e0 * dt * dt / 2.0 + jerk * dt * dt * dt / 6.0) * wobble;
                s1.dq[j] = c + e0 * dt + jerk * dt * dt / 2.0;
                s1.ddq[j] = e0 + jerk * dt;
            }
            let dt_c = s1.t - s0.t;
            let err = PAD * (s0.t.abs() + s1.t.abs()) + TINY;
            let sp = Span {
                dt: dt_c,
                dt_lo: (dt_c - err).max(0.0),
                dt_hi: dt_c + err,
                rel: 1.0 + 1e-9,
                slack: 1e-9,
            };
            let lanes = jerk_feasible_lanes(&lim, &s0, &s1, &sp);
            for (j, &lane) in lanes.iter().enumerate().take(7) {
                let limits = (lim.v[j] * sp.rel, lim.a[j] * sp.rel, lim.j[j] * sp.rel);
                let (c, d, e0, e1) = (s0.dq[j], s1.dq[j], s0.ddq[j], s1.ddq[j]);
                let dpos = s1.q[j] - s0.q[j];
                let one = jerk_feasible(dpos, c, d, e0, e1, sp.dt, sp.dt_lo, sp.dt_hi, limits);
                assert_eq!(lane, one, "case {case}, joint {j}");
                let q = Quintic::new(dpos, c, d, e0, e1, sp.dt, sp.dt_lo, sp.dt_hi);
                let cheap_over = q.cheap_acc(e0, e1, sp.dt_hi) > limits.1;
                let by_cubic = q.j_bound <= limits.2 && cheap_over;
                exact += usize::from(by_cubic);
                exact_feasible += usize::from(by_cubic && one);
                (feasible, infeasible) =
                    (feasible + usize::from(one), infeasible + usize::from(!one));
            }
        }
        assert!(
            feasible > 5_000 && infeasible > 5_000 && exact > 5_000 && exact_feasible > 500,
            "{feasible} {infeasible} {exact} {exact_feasible}"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]

        /// `span_boxes_into` gives `span_boxes`'s result whatever the reused storage held
        /// before (boxes, none, another span's).
        #[test]
        fn the_in_place_enclosure_is_span_boxes(
            v0 in prop::collection::vec(value(), 21),
            v1 in prop::collection::vec(value(), 21),
            dt in prop_oneof![Just(0.0), 1e-4..0.05f64, Just(1e300)],
            flags in 0u8..8,
            before in 0u8..3,
        ) {
            let robot = RobotModel::builtin("fr3").unwrap();
            let lim = robot.limits();
            let (dq, ddq) = (flags & 1 == 1, flags & 2 == 2);
            let s0 = sample(1.0, &v0, dq, ddq);
            let s1 = sample(1.0 + dt, &v1, dq || flags & 4 == 4, ddq);
            let mut out = match before {
                0 => SpanEnclosure::empty(),
                1 => span_boxes(lim, &s1, &s0, 1e-9),
                _ => span_boxes(lim, &sample(0.0, &[0.1; 21], true, false), &sample(0.001, &[0.1; 21], true, false), 1e-9),
            };
            span_boxes_into(&SpanLimits::new(lim), &s0, &s1, 1e-9, &mut out);
            prop_assert_eq!(out, span_boxes(lim, &s0, &s1, 1e-9));
        }

        /// Values beyond the robot's joints (the lanes the enclosure computes and ignores)
        /// change neither the boxes nor the verdict on consistency, whatever they hold.
        #[test]
        fn lanes_beyond_the_joints_change_nothing(
            v0 in prop::collection::vec(value(), 21),
            v1 in prop::collection::vec(value(), 21),
            junk in prop::collection::vec(value(), 6),
            dt in prop_oneof![1e-4..0.05f64, Just(0.0)],
            flags in 0u8..4,
        ) {
            let robot = RobotModel::builtin("fr3").unwrap();
            let lim = robot.limits();
            let (dq, ddq) = (flags & 1 == 1, flags & 2 == 2);
            let (s0, s1) = (sample(1.0, &v0, dq, ddq), sample(1.0 + dt, &v1, dq, ddq));
            let clean = span_boxes(lim, &s0, &s1, 1e-9);
            let (mut d0, mut d1) = (s0, s1);
            // Lane 7 completes the second group of four joints.
            (d0.q[7], d0.dq[7], d0.ddq[7]) = (junk[0], junk[1], junk[2]);
            (d1.q[7], d1.dq[7], d1.ddq[7]) = (junk[3], junk[4], junk[5]);
            prop_assert_eq!(span_boxes(lim, &d0, &d1, 1e-9), clean);
        }
    }
}
