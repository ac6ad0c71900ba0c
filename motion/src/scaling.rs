//! Path-speed profiles: jerk-limited time scalings s(τ) of a trajectory, from **any** path state
//! (s, ṡ, s̈) toward a target path speed — 0 to brake along the path, 1 to resume the intended
//! timing — and their verification against joint limits.
//!
//! A trajectory q(s) is followed at path speed ṡ (ṡ = 1: the intended timing). By the chain rule
//! q̇ = q′ṡ, q̈ = q′s̈ + q″ṡ², q⃛ = q‴ṡ³ + 3q″ṡs̈ + q′s⃛. Over a path window with per-joint sound
//! bounds Q1 ≥ |q′|, Q2 ≥ |q″|, Q3 ≥ |q‴| and over a profile with ṡ ≤ σ, |s̈| ≤ α, |s⃛| ≤ J:
//! |q̇| ≤ Q1·σ, |q̈| ≤ Q1·α + Q2·σ², |q⃛| ≤ Q3·σ³ + 3·Q2·σ·α + Q1·J. [`admissible`] picks the
//! largest α, J (times a 0.98 safety factor) that satisfy these with the given limits, grows the
//! window until it covers the profile, and re-checks the final inequalities with outward rounding.
//! Configurations always lie on the path (s only moves forward: ṡ ≥ 0): path consistency holds by
//! construction, never by clamping joint values.

// Joint-indexed loops over parallel fixed-size arrays read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

use crate::trajectory::{JointState, Limits, Trajectory};
use pacs_models::MAX_DOF;
use pacs_reach::rounding::{add_up, mul_up};

/// A point of a time scaling: path position s (s of intended time), speed ṡ (1), acceleration
/// s̈ (1/s).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathState {
    /// Path position (intended-trajectory time, s).
    pub s: f64,
    /// Path speed (dimensionless, ≥ 0; 1 = intended timing).
    pub sd: f64,
    /// Path acceleration (1/s).
    pub sdd: f64,
}

/// Any path state (every field any value, NaN included): `stub_verified(SpeedProfile::eval)` draws
/// the result from here and keeps those the contract allows.
#[cfg(kani)]
impl kani::Arbitrary for PathState {
    fn any() -> Self {
        PathState {
            s: kani::any(),
            sd: kani::any(),
            sdd: kani::any(),
        }
    }
}

impl PathState {
    /// Bitwise equality of all three fields (a copy equals its original even where a field is
    /// NaN, which `==` would deny): what "the same state" means in the shield's proofs.
    pub fn same_bits(&self, other: &Self) -> bool {
        self.s.to_bits() == other.s.to_bits()
            && self.sd.to_bits() == other.sd.to_bits()
            && self.sdd.to_bits() == other.sdd.to_bits()
    }

    /// On the intended timing at `s` (ṡ = 1, s̈ = 0).
    pub fn intended(s: f64) -> Self {
        Self {
            s,
            sd: 1.0,
            sdd: 0.0,
        }
    }
    /// At rest at `s`.
    pub fn rest(s: f64) -> Self {
        Self {
            s,
            sd: 0.0,
            sdd: 0.0,
        }
    }
    /// Whether the path speed and acceleration are exactly those of the intended timing.
    pub fn is_intended(&self) -> bool {
        self.sd == 1.0 && self.sdd == 0.0
    }

    /// The joint state on `traj` at this path state (chain rule: q̇ = q′ṡ, q̈ = q′s̈ + q″ṡ²; the
    /// jerk entry is q‴ṡ³, the part that does not depend on the path jerk).
    pub fn joint_state(&self, traj: &Trajectory) -> JointState {
        let d = traj.state_at(self.s);
        let mut out = JointState::default();
        for i in 0..traj.dof() {
            out.q[i] = d.q[i];
            out.dq[i] = d.dq[i] * self.sd;
            out.ddq[i] = d.dq[i] * self.sdd + d.ddq[i] * self.sd * self.sd;
            out.dddq[i] = d.dddq[i] * self.sd * self.sd * self.sd;
        }
        out
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Phase {
    /// Start time relative to the profile start (s).
    t0: f64,
    s: f64,
    sd: f64,
    sdd: f64,
    jerk: f64,
}

impl Phase {
    #[inline]
    fn eval(&self, tau: f64) -> PathState {
        let d = tau - self.t0;
        PathState {
            s: self.s + d * (self.sd + d * (0.5 * self.sdd + d * self.jerk / 6.0)),
            sd: self.sd + d * (self.sdd + 0.5 * d * self.jerk),
            sdd: self.sdd + d * self.jerk,
        }
    }
}

/// The constant-jerk ramps of [`SpeedProfile::plan`] from s̈₀ = `a0`, ṡ₀ = `v0` to `target`:
/// three `(jerk, duration)` pairs in order (a duration ≤ 0 is no phase: `plan` skips it; none
/// when a limit is not positive). Time-optimal: bring s̈ to 0 right away if that reaches the
/// target (within 1e-15), else ramp toward the target to the peak `up` (at most `max(acc, u0)`),
/// hold it, and ramp back to s̈ = 0. `plan`'s arithmetic, as a function for the proofs
/// (`pacs-proofs`: e1's Kani splits, on the ramps rather than on the evaluated profile).
///
/// # Soundness
/// Braking contract (claim C6, [`ramps_brake_to_rest`]): for a braking start the contract
/// covers ([`braking_start`]) and target 0, the ramps bring the path to rest without a jump and
/// within the limits. Proven by `e1_plan_ramps_contract_plateau` and
/// `e1_plan_ramps_contract_ramps` (`proof_for_contract`; Kani covers the inputs those harnesses
/// draw: A = 1, J = 8, s̈₀ = 0, the two branches), tested over the whole ranges by
/// `e1_brake_plan_plateau`/`e1_brake_plan_ramps`' twins and
/// `the_braking_ramps_keep_their_contract` (every branch, boundaries included).
#[doc(hidden)]
#[cfg_attr(kani, kani::ensures(|r: &Ramps| !(target == 0.0 && braking_start(a0, v0, acc, jerk)) || ramps_brake_to_rest(a0, v0, acc, jerk, *r)))]
pub fn plan_ramps(a0: f64, v0: f64, target: f64, acc: f64, jerk: f64) -> Ramps {
    let none = (0.0, 0.0);
    if !(jerk > 0.0 && acc > 0.0) {
        return (none, none, none);
    }
    // Speed reached by bringing s̈ to zero right away.
    let v_reach = v0 + a0 * a0.abs() / (2.0 * jerk);
    let diff = target - v_reach;
    if diff.abs() <= 1e-15 {
        return ((-a0.signum() * jerk, a0.abs() / jerk), none, none);
    }
    let d = diff.signum();
    let u0 = d * a0;
    let dist = d * (target - v0);
    let up_free = pacs_reach::ieee::sqrt((jerk * dist + 0.5 * u0 * u0).max(0.0));
    let cap = acc.max(u0);
    let (up, plateau) = if up_free <= cap {
        (up_free, 0.0)
    } else {
        let dv_ramps = (cap * cap - u0 * u0) / (2.0 * jerk) + cap * cap / (2.0 * jerk);
        (cap, ((dist - dv_ramps) / cap).max(0.0))
    };
    (
        (d * jerk, (up - u0) / jerk),
        (0.0, plateau),
        (-d * jerk, up / jerk),
    )
}

/// Three constant-jerk ramps `(jerk, duration)` in order ([`plan_ramps`]).
pub type Ramps = ((f64, f64), (f64, f64), (f64, f64));

/// A braking start the contract of [`plan_ramps`] covers: path acceleration limit `acc` ∈
/// [10⁻⁴, 50] 1/s² and jerk limit `jerk` ∈ [10⁻⁴, 500] 1/s³ (above the shield's caps
/// [`ACC_CAP`], [`JERK_CAP`], which [`admissible`] lowers further), path speed `v0` ∈ [0, 2] 1/s,
/// path acceleration `a0` ∈ [−3·acc, 3·acc] (a start may carry more than the limit it brakes
/// with), and consistent: a decelerating start can bring s̈ to 0 before ṡ reaches 0
/// (`v0 ≥ a0²/(2·jerk)` when `a0 < 0`; [`admissible`] rejects the profiles of the other starts,
/// which would run the path backwards). Starts beyond these ranges (a limit below 10⁻⁴, a
/// larger `a0` or `v0`) are outside the contract: the shield still verifies whatever braking it
/// plans over its sound path ranges (claim C7), but the no-jump-to-rest claim is not made there.
pub fn braking_start(a0: f64, v0: f64, acc: f64, jerk: f64) -> bool {
    (1e-4..=50.0).contains(&acc)
        && (1e-4..=500.0).contains(&jerk)
        && (0.0..=2.0).contains(&v0)
        && (-3.0 * acc..=3.0 * acc).contains(&a0)
        && (a0 >= 0.0 || v0 >= a0 * a0 / (2.0 * jerk))
}

/// The braking contract of [`plan_ramps`] on its result `r` from s̈₀ = `a0`, ṡ₀ = `v0`: applied
/// in order in floating point (ṡ += Δ(s̈ + Δ·j/2), s̈ += Δ·j; a duration ≤ 0 is skipped, never
/// NaN), every kept ramp is finite with jerk ±`jerk` or 0 and ends with ṡ ≥ −tol_ṡ,
/// |s̈| ≤ max(`acc`, |s̈₀|)(1 + 10⁻⁹) and s̈ ≤ tol_s̈ (braking only slows down after its first
/// ramp), and the last ends at rest: |s̈| ≤ tol_s̈ = 10⁻⁹(1 + acc + |s̈₀|), |ṡ| ≤ tol_ṡ =
/// 10⁻⁹(1 + ṡ₀ + acc + |s̈₀|) — no jump to rest. With s̈ linear on a ramp, the ramp ends bound s̈
/// everywhere on it, and ṡ from below (real arithmetic).
pub fn ramps_brake_to_rest(a0: f64, v0: f64, acc: f64, jerk: f64, r: Ramps) -> bool {
    const EPS: f64 = 1e-9;
    let a_max = acc.max(a0.abs()) * (1.0 + EPS);
    let tol_sdd = EPS * (1.0 + acc + a0.abs());
    let tol_sd = EPS * (1.0 + v0 + acc + a0.abs());
    let (mut sd, mut sdd) = (v0, a0);
    for (j, dur) in [r.0, r.1, r.2] {
        if dur > 0.0 {
            if !(dur.is_finite() && (j == jerk || j == -jerk || j == 0.0)) {
                return false;
            }
            sd += dur * (sdd + 0.5 * dur * j);
            sdd += dur * j;
            if !(sd >= -tol_sd && sdd.abs() <= a_max && sdd <= tol_sdd) {
                return false;
            }
        } else if dur.is_nan() {
            return false;
        }
    }
    sdd.abs() <= tol_sdd && sd.abs() <= tol_sd
}

/// One phase of a [`SpeedProfile`] as raw parts: `(t0, s, ṡ, s̈, jerk)` — the start time (s),
/// the path position (dimensionless), its first three derivatives (1/s, 1/s², 1/s³).
pub type PhaseParts = (f64, f64, f64, f64, f64);

/// A [`SpeedProfile`] as raw parts ([`SpeedProfile::to_parts`]): the 4 phase slots, the number
/// used, the settle time (s), the target speed (1/s) and the limits (1/s², 1/s³).
pub type ProfileParts = ([PhaseParts; 4], usize, f64, f64, f64, f64);

/// A jerk-limited path-speed profile from a start state to a constant target speed (at most
/// three constant-jerk phases, then constant speed). Copy, allocation-free.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedProfile {
    phases: [Phase; 4],
    n: usize,
    settle: f64,
    target: f64,
    acc: f64,
    jerk: f64,
}

impl SpeedProfile {
    /// Plan the time-optimal jerk-limited change of path speed from `start` to `target`
    /// (ending with s̈ = 0) with |s̈| ≤ max(`acc`, |s̈₀|) and |s⃛| = `jerk` during ramps.
    ///
    /// # Soundness
    /// Claim C6: from a consistent start, ṡ stays ≥ 0, s never decreases, and the profile is
    /// exactly at the target from `settle_time()` on. Harness `e1_braking_profile` (property
    /// test; Kani: its splits `e1_brake_plan_plateau`, `e1_brake_plan_ramps` on [`plan_ramps`]);
    /// mutant `x8` caught.
    pub fn plan(start: PathState, target: f64, acc: f64, jerk: f64) -> Self {
        let (a0, v0) = (start.sdd, start.sd);
        let mut phases = [Phase::default(); 4];
        let mut n = 0;
        let mut t = 0.0;
        let mut cur = Phase {
            t0: 0.0,
            s: start.s,
            sd: v0,
            sdd: a0,
            jerk: 0.0,
        };
        let mut push = |cur: &mut Phase, jerk: f64, dur: f64, t: &mut f64| {
            if dur <= 0.0 {
                return;
            }
            cur.jerk = jerk;
            phases[n] = *cur;
            n += 1;
            let e = cur.eval(*t + dur);
            *t += dur;
            *cur = Phase {
                t0: *t,
                s: e.s,
                sd: e.sd,
                sdd: e.sdd,
                jerk: 0.0,
            };
        };
        let (r0, r1, r2) = plan_ramps(a0, v0, target, acc, jerk);
        for (j, dur) in [r0, r1, r2] {
            push(&mut cur, j, dur, &mut t);
        }
        // Final constant-speed phase at exactly the target speed.
        cur.sd = target;
        cur.sdd = 0.0;
        cur.jerk = 0.0;
        phases[n] = cur;
        n += 1;
        Self {
            phases,
            n,
            settle: t,
            target,
            acc,
            jerk,
        }
    }

    /// The raw parts of the profile: per phase `(t0, s, ṡ, s̈, jerk)` (4 slots, the first `n`
    /// used), `n`, the settle time, the target speed and the limits. For the proofs: the twin of
    /// `f1` checks that planned profiles lie in the range its Kani stub draws from.
    #[doc(hidden)]
    pub fn to_parts(&self) -> ProfileParts {
        (
            self.phases.map(|p| (p.t0, p.s, p.sd, p.sdd, p.jerk)),
            self.n,
            self.settle,
            self.target,
            self.acc,
            self.jerk,
        )
    }

    /// A profile from its raw parts ([`Self::to_parts`]), for the model checker only
    /// (`cfg(kani)`): a Kani stub of [`Self::plan`] that returns *any* finite profile
    /// (`pacs_proofs::stubs::any_speed_profile`) over-approximates the planner for claims that
    /// hold for every profile (harness `f1`: the shield's `choose` only copies the profiles it
    /// is given). `n` must lie in `1..=4` (`eval` reads phase `n − 1`).
    #[cfg(kani)]
    #[doc(hidden)]
    pub fn from_parts(
        phases: [PhaseParts; 4],
        n: usize,
        settle: f64,
        target: f64,
        acc: f64,
        jerk: f64,
    ) -> Self {
        assert!((1..=4).contains(&n), "a profile has 1 to 4 phases");
        // Element by element (not `array::map`, whose iterator and pointer arithmetic add
        // hundreds of checks to a model checker's formula).
        let phase = |(t0, s, sd, sdd, jerk): PhaseParts| Phase {
            t0,
            s,
            sd,
            sdd,
            jerk,
        };
        let [p0, p1, p2, p3] = phases;
        Self {
            phases: [phase(p0), phase(p1), phase(p2), phase(p3)],
            n,
            settle,
            target,
            acc,
            jerk,
        }
    }

    /// State at time `tau` (s) after the profile start (τ ≥ 0; constant target speed after settling).
    ///
    /// Guarantee (its Kani contract): the path speed is never negative, for any profile of
    /// finite fields ([`Self::has_finite_parts`], its precondition) and any `tau` not above
    /// 10²⁸⁰ s (NaN and −∞ included: they are read as 0).
    /// The bound keeps `tau − t₀` finite for every finite phase start, so no intermediate is NaN
    /// (Kani checks that too); the shield evaluates a profile at most as long after its start as
    /// the run has lasted, far below it.
    /// Proven on this function by `f3_eval_contract` (shield/src/shield/proofs.rs); the shield's
    /// step harnesses (`f3_*step*`) use the contract in its place, as they assert nothing of the
    /// executed state's values.
    #[cfg_attr(kani, kani::requires(self.has_finite_parts() && !(tau > 1e280)))]
    #[cfg_attr(kani, kani::ensures(|p: &PathState| p.sd >= 0.0))]
    #[inline]
    pub fn eval(&self, tau: f64) -> PathState {
        let mut p = self.eval_raw(tau);
        // Rounding must not make the path run backwards.
        p.sd = p.sd.max(0.0);
        p
    }

    #[inline]
    fn eval_raw(&self, tau: f64) -> PathState {
        let tau = tau.max(0.0);
        let mut k = 0;
        while k + 1 < self.n && self.phases[k + 1].t0 <= tau {
            k += 1;
        }
        let mut p = self.phases[k].eval(tau);
        if k + 1 == self.n {
            p.sd = self.target;
            p.sdd = 0.0;
        }
        p
    }

    /// Whether the profile is one the contract of [`Self::eval`] is proven for (its
    /// precondition): 1 to 4 phases,
    /// every field of all four phase slots finite, and a finite settle time, target speed and
    /// limits (the planner's profiles from finite states and limits are:
    /// the twin of `f1` checks `profile_in_stub_range` on every profile it plans).
    ///
    /// Written without loops: Kani evaluates a precondition at every call in a harness, where a
    /// loop would need an unwinding bound of its own.
    pub fn has_finite_parts(&self) -> bool {
        let finite = |p: &Phase| {
            p.t0.is_finite()
                && p.s.is_finite()
                && p.sd.is_finite()
                && p.sdd.is_finite()
                && p.jerk.is_finite()
        };
        let [p0, p1, p2, p3] = &self.phases;
        (1..=4).contains(&self.n)
            && finite(p0)
            && finite(p1)
            && finite(p2)
            && finite(p3)
            && self.settle.is_finite()
            && self.target.is_finite()
            && self.acc.is_finite()
            && self.jerk.is_finite()
    }

    /// Bitwise equality of every field (phases, settle time, target, limits): a copy equals its
    /// original even where a field is NaN, which `==` would deny.
    pub fn same_bits(&self, other: &Self) -> bool {
        let same = |x: f64, y: f64| x.to_bits() == y.to_bits();
        if self.n != other.n
            || !same(self.settle, other.settle)
            || !same(self.target, other.target)
            || !same(self.acc, other.acc)
            || !same(self.jerk, other.jerk)
        {
            return false;
        }
        for k in 0..self.phases.len() {
            let (a, b) = (&self.phases[k], &other.phases[k]);
            if !(same(a.t0, b.t0)
                && same(a.s, b.s)
                && same(a.sd, b.sd)
                && same(a.sdd, b.sdd)
                && same(a.jerk, b.jerk))
            {
                return false;
            }
        }
        true
    }

    /// Time (s, relative) at which the target speed is reached.
    #[inline]
    pub fn settle_time(&self) -> f64 {
        self.settle
    }
    /// Target path speed.
    #[inline]
    pub fn target(&self) -> f64 {
        self.target
    }
    /// Path position where the target speed is reached.
    #[inline]
    pub fn settle_s(&self) -> f64 {
        self.phases[self.n - 1].s
    }
    /// The path-acceleration and path-jerk limits the profile was planned with.
    pub fn limits(&self) -> (f64, f64) {
        (self.acc, self.jerk)
    }

    /// The constant-jerk phases: (start time relative to the profile start (s), the path state
    /// there, the path jerk (1/s²)); the last phase is the constant target speed.
    pub(crate) fn phases(&self) -> impl Iterator<Item = (f64, PathState, f64)> + '_ {
        self.phases[..self.n].iter().map(|p| {
            (
                p.t0,
                PathState {
                    s: p.s,
                    sd: p.sd,
                    sdd: p.sdd,
                },
                p.jerk,
            )
        })
    }

    /// Sound ranges over τ ∈ [ta, tb] (relative s): (s_lo, s_hi, ṡ_lo, ṡ_hi, max |s̈|). ṡ_lo is
    /// the raw (unclamped) lowest ṡ, so that a planner undershoot (ṡ_lo < 0) stays visible;
    /// ṡ_hi ≥ 0 covers `eval`'s clamp at 0.
    ///
    /// # Soundness
    /// Claim C7 (the joint boxes from path ranges): s(τ), ṡ(τ) and |s̈(τ)| of [`Self::eval`] lie
    /// in the ranges for every τ ∈ [ta, tb]. Harness `f4_path_ranges_enclose` (property test: any
    /// instant on planned profiles; Kani: its split `f4_path_ranges_phase`, one phase's step
    /// [`phase_window_ranges`] at any instant of one window; `motion`'s
    /// `ranges_enclose_eval_next_to_phase_boundaries` at every phase boundary); mutants `x12`
    /// (also under Kani) and `x26` caught.
    pub fn ranges(&self, ta: f64, tb: f64) -> (f64, f64, f64, f64, f64) {
        let ta = ta.max(0.0);
        let tb = tb.max(ta);
        let a = self.eval_raw(ta);
        let b = self.eval_raw(tb);
        let mut x = Extents::of_ends(a, b);
        for k in 0..self.n {
            let p = &self.phases[k];
            let end = if k + 1 < self.n {
                self.phases[k + 1].t0
            } else {
                f64::INFINITY
            };
            if end < ta || p.t0 > tb {
                continue;
            }
            let lo = ta.max(p.t0);
            let hi = tb.min(end);
            // The phase's own polynomial at both ends: `eval` uses it up to (not at) the next
            // phase's start, whose own value there differs by rounding.
            let ends = if k + 1 == self.n {
                (self.eval_raw(lo), self.eval_raw(hi))
            } else {
                (p.eval(lo), p.eval(hi))
            };
            p.extend_extents(lo, hi, ends, &mut x);
        }
        x.padded(a.s, b.s)
    }
}

/// What [`SpeedProfile::ranges`] gathers before padding: the lowest and highest ṡ, the largest
/// |s̈|, and the largest magnitudes of the terms of the s, ṡ, s̈ polynomials (their rounding).
#[derive(Debug, Clone, Copy)]
struct Extents {
    sd_lo: f64,
    sd_hi: f64,
    sdd: f64,
    err_s: f64,
    err_sd: f64,
    err_sdd: f64,
}

impl Extents {
    /// The states at the window's ends `a`, `b`; no terms yet.
    #[inline]
    fn of_ends(a: PathState, b: PathState) -> Self {
        Self {
            sd_lo: a.sd.min(b.sd),
            sd_hi: a.sd.max(b.sd),
            sdd: a.sdd.abs().max(b.sdd.abs()),
            err_s: 0.0,
            err_sd: 0.0,
            err_sdd: 0.0,
        }
    }

    /// The ranges `(s_lo, s_hi, ṡ_lo, ṡ_hi, max |s̈|)`, padded, from the positions `a_s`, `b_s`
    /// at the window's ends (s is non-decreasing).
    #[inline]
    fn padded(self, a_s: f64, b_s: f64) -> (f64, f64, f64, f64, f64) {
        let Self {
            sd_lo,
            mut sd_hi,
            sdd,
            err_s,
            err_sd,
            err_sdd,
        } = self;
        // `eval` clamps ṡ at 0 (rounding must not run the path backwards): the executed ṡ is
        // at most max(ṡ_hi, 0). Without this, a window whose raw ṡ lies below −1e-15
        // throughout (rounding at the end of a braking ramp) would get an upper end below the
        // executed 0 (found while splitting `f4_path_ranges_enclose` for Kani).
        sd_hi = sd_hi.max(0.0);
        // Padding for the float evaluation of the polynomials: relative to the value, plus
        // 1e-14 of the terms' magnitudes. Each evaluation (here and in `eval`) rounds at most
        // ~8 times (the time difference, two products and two sums per level), so it is within
        // 8u ≈ 9e-16 of the terms' sum of the exact polynomial; two evaluations differ by at
        // most twice that. With the relative padding alone, ṡ at an instant just inside a phase
        // exceeds the range by 5e-16 (1 in 10⁶ random windows).
        let pad = |x: f64| x.abs() * 1e-12 + 1e-15;
        let (err_s, err_sd, err_sdd) = (err_s * 1e-14, err_sd * 1e-14, err_sdd * 1e-14);
        let s_lo = a_s - pad(a_s) - err_s;
        let s_hi = b_s + pad(b_s) + err_s;
        (
            s_lo,
            s_hi,
            sd_lo - pad(sd_lo) - err_sd,
            sd_hi + pad(sd_hi) + err_sd,
            sdd + pad(sdd) + err_sdd,
        )
    }
}

impl Phase {
    /// This phase's part of [`SpeedProfile::ranges`] over its part `[lo, hi]` of the window,
    /// given its states `ends` at `lo` and `hi`: ṡ and |s̈| there, ṡ at an interior extremum,
    /// the terms' magnitudes at the farthest instant.
    #[inline]
    fn extend_extents(&self, lo: f64, hi: f64, ends: (PathState, PathState), x: &mut Extents) {
        let p = self;
        for e in [ends.0, ends.1] {
            x.sd_lo = x.sd_lo.min(e.sd);
            x.sd_hi = x.sd_hi.max(e.sd);
            x.sdd = x.sdd.max(e.sdd.abs());
        }
        // Interior extremum of ṡ where s̈ = 0.
        if p.jerk != 0.0 {
            let tz = p.t0 - p.sdd / p.jerk;
            if tz > lo && tz < hi {
                let e = p.eval(tz);
                x.sd_lo = x.sd_lo.min(e.sd);
                x.sd_hi = x.sd_hi.max(e.sd);
            }
        }
        // Term magnitudes at the phase's farthest instant (they grow with τ − t0).
        let d = (hi - p.t0).abs();
        let (t_sd, t_sdd, t_j) = (p.sd.abs(), (d * p.sdd).abs(), (d * d * p.jerk).abs());
        x.err_s = x.err_s.max(p.s.abs() + d * t_sd + d * t_sdd + d * t_j);
        x.err_sd = x.err_sd.max(t_sd + t_sdd + t_j);
        x.err_sdd = x.err_sdd.max(p.sdd.abs() + (d * p.jerk).abs());
    }
}

/// The state of one constant-jerk phase `(t0, s, ṡ, s̈, jerk)` at time `tau` (the phase's
/// polynomial, as [`SpeedProfile::eval`] evaluates it inside the phase, before its clamp of ṡ
/// at 0). For the proofs (`pacs-proofs`: the Kani splits of e1 and f4).
#[doc(hidden)]
pub fn phase_eval(phase: PhaseParts, tau: f64) -> PathState {
    let (t0, s, sd, sdd, jerk) = phase;
    Phase {
        t0,
        s,
        sd,
        sdd,
        jerk,
    }
    .eval(tau)
}

/// [`SpeedProfile::ranges`]`(lo, hi)` of a profile whose window `[lo, hi]` lies inside one
/// phase `phase` that is not its last one (`t0 < lo ≤ hi <` the next phase's start; then no
/// other phase meets the window and the ends are the phase's own states): the same operations
/// on the one phase. For the proofs (`pacs-proofs`: f4's per-phase Kani split; its twin checks
/// that this equals `ranges` bit for bit on planned profiles).
#[doc(hidden)]
pub fn phase_window_ranges(phase: PhaseParts, lo: f64, hi: f64) -> (f64, f64, f64, f64, f64) {
    let (t0, s, sd, sdd, jerk) = phase;
    let p = Phase {
        t0,
        s,
        sd,
        sdd,
        jerk,
    };
    let ends = (p.eval(lo), p.eval(hi));
    let mut x = Extents::of_ends(ends.0, ends.1);
    p.extend_extents(lo, hi, ends, &mut x);
    x.padded(ends.0.s, ends.1.s)
}

/// Per-joint bounds of |q′|, |q″|, |q‴| over a path window.
#[derive(Debug, Clone, Copy)]
struct Window {
    q1: [f64; MAX_DOF],
    q2: [f64; MAX_DOF],
    q3: [f64; MAX_DOF],
}

fn window(traj: &Trajectory, s_a: f64, s_b: f64) -> Window {
    let mut w = Window {
        q1: [0.0; MAX_DOF],
        q2: [0.0; MAX_DOF],
        q3: [0.0; MAX_DOF],
    };
    w.include(traj, s_a, s_b);
    w
}

impl Window {
    /// Widen the bounds to cover the path window [s_a, s_b] as well (a window over [a, b] and
    /// one over [b, c] together bound [a, c]: the union of the derivative ranges).
    fn include(&mut self, traj: &Trajectory, s_a: f64, s_b: f64) {
        for i in 0..traj.dof() {
            let [d1, d2, d3] = traj.joint_deriv_abs(i, s_a, s_b);
            self.q1[i] = self.q1[i].max(d1);
            self.q2[i] = self.q2[i].max(d2);
            self.q3[i] = self.q3[i].max(d3);
        }
    }
}

/// Sound check of the chain-rule bounds (outward rounded) for speed ≤ `sd_max`, |s̈| ≤ `sdd_max`,
/// |s⃛| ≤ `jerk` over window `w`.
fn within_limits(w: &Window, lim: &Limits, sd_max: f64, sdd_max: f64, jerk: f64) -> bool {
    let s2 = mul_up(sd_max, sd_max);
    let s3 = mul_up(s2, sd_max);
    (0..lim.dof).all(|i| {
        let v = mul_up(w.q1[i], sd_max);
        let a = add_up(mul_up(w.q1[i], sdd_max), mul_up(w.q2[i], s2));
        let j = add_up(
            add_up(
                mul_up(w.q3[i], s3),
                mul_up(3.0, mul_up(mul_up(w.q2[i], sd_max), sdd_max)),
            ),
            mul_up(w.q1[i], jerk),
        );
        v <= lim.v[i] && a <= lim.a[i] && j <= lim.j[i]
    })
}

const SAFETY: f64 = 0.98;
/// Cap on path acceleration |s̈| (1/s): ṡ from 1 to 0 in no less than 0.1 s. Without a cap, states
/// near a trajectory's start (q′ ≈ 0) would take huge s̈ that later windows cannot continue.
pub const ACC_CAP: f64 = 10.0;
/// Cap on path jerk |s⃛| (1/s²).
pub const JERK_CAP: f64 = 500.0;

/// The fastest admissible profile from `start` to `target` speed over `traj` against `lim`,
/// verified over the time range [0, `horizon`] of the profile (`None`: until it settles).
/// Returns `None` if no admissible path acceleration exists (e.g. a joint already at its
/// acceleration limit with no margin).
pub fn admissible(
    traj: &Trajectory,
    lim: &Limits,
    start: PathState,
    target: f64,
    horizon: Option<f64>,
) -> Option<SpeedProfile> {
    let n = traj.dof();
    let sd_max0 = start.sd.max(target);
    let mut wlen = 0.01_f64.max(start.sd * 0.01);
    if horizon.is_none() && target < start.sd {
        // First window: the path run while slowing down at the caps, which no admissible
        // profile beats by much (the limits below only lower s̈ and s⃛); usually the loop then
        // ends after one widening instead of two. Only a starting guess: every window is
        // re-checked against the profile it yields.
        let fast = SpeedProfile::plan(start, target, ACC_CAP, JERK_CAP);
        let run = fast.eval(fast.settle_time()).s - start.s;
        if run.is_finite() {
            wlen = wlen.max(run);
        }
    }
    // The window grows only: each pass adds the path beyond the previous one.
    let mut w = window(traj, start.s, start.s + wlen);
    let mut covered = start.s + wlen;
    for _ in 0..8 {
        let end = start.s + wlen;
        if end > covered {
            w.include(traj, covered, end);
            covered = end;
        }
        let sd_max = sd_max0 * (1.0 + 1e-9);
        let mut acc = ACC_CAP;
        for i in 0..n {
            if w.q1[i] > 0.0 {
                acc = acc.min((lim.a[i] - w.q2[i] * sd_max * sd_max) / w.q1[i]);
            }
            if w.q2[i] > 0.0 && sd_max > 0.0 {
                // Leave at least half of the jerk margin for the path jerk.
                acc =
                    acc.min(0.5 * (lim.j[i] - w.q3[i] * sd_max.powi(3)) / (3.0 * w.q2[i] * sd_max));
            }
        }
        acc *= SAFETY;
        let sdd_max = acc.max(start.sdd.abs());
        let mut jerk = JERK_CAP;
        for i in 0..n {
            if w.q1[i] > 0.0 {
                jerk = jerk.min(
                    (lim.j[i] - w.q3[i] * sd_max.powi(3) - 3.0 * w.q2[i] * sd_max * sdd_max)
                        / w.q1[i],
                );
            }
        }
        jerk *= SAFETY;
        if !(acc > 0.0 && jerk > 0.0 && acc.is_finite() && jerk.is_finite()) {
            return None;
        }
        let p = SpeedProfile::plan(start, target, acc, jerk);
        let t_end = horizon.unwrap_or(p.settle_time()).max(0.0);
        let (_, s_hi, sd_lo, sd_hi, sdd_hi) = p.ranges(0.0, t_end);
        if sd_lo < -1e-9 {
            // The path would have to run backwards (start state inconsistent with this jerk).
            return None;
        }
        let need = s_hi - start.s;
        if need <= wlen {
            // Final sound re-check with the profile's actual ranges.
            return within_limits(&w, lim, sd_hi.max(sd_max), sdd_hi, jerk).then_some(p);
        }
        wlen = need * 1.25;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The planner's profiles from finite states have finite parts (the precondition of the
    /// `eval` and `choose` contracts); one planned from a NaN speed, or with a phase slot made
    /// infinite, has not.
    #[test]
    fn planned_profiles_have_finite_parts() {
        let rest = PathState::rest(0.0);
        for (target, acc, jerk) in [(0.0, 1.0, 10.0), (1.0, 2.0, 50.0), (0.3, 0.05, 0.05)] {
            assert!(SpeedProfile::plan(rest, target, acc, jerk).has_finite_parts());
            assert!(
                SpeedProfile::plan(PathState::intended(0.5), target, acc, jerk).has_finite_parts()
            );
        }
        let nan = PathState {
            s: 0.0,
            sd: f64::NAN,
            sdd: 0.0,
        };
        assert!(!SpeedProfile::plan(nan, 0.0, 1.0, 10.0).has_finite_parts());
        let mut p = SpeedProfile::plan(rest, 1.0, 1.0, 10.0);
        p.phases[3].jerk = f64::INFINITY;
        assert!(!p.has_finite_parts());
        let mut p = SpeedProfile::plan(rest, 1.0, 1.0, 10.0);
        p.n = 0;
        assert!(!p.has_finite_parts());
    }

    /// A value in `[lo, hi]`, often at its ends.
    fn within(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
        prop_oneof![Just(lo), Just(hi), lo..=hi, lo..=hi, lo..=hi]
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 100_000,
            max_global_rejects: 10_000_000,
            ..ProptestConfig::default()
        })]
        /// The twin of `plan_ramps`' braking contract over the whole ranges of
        /// [`braking_start`] (the limits also log-uniform down to 10⁻⁴),
        /// every branch (single ramp, two ramps, plateau) and its boundaries:
        /// starts at the consistency boundary `v0 = a0²/(2J)` and at the plateau boundary
        /// `J·v0 + a0²/2 = A²` are drawn on purpose.
        #[test]
        fn the_braking_ramps_keep_their_contract(
            acc in prop_oneof![within(1e-4, 50.0), (-4.0f64..1.7).prop_map(|e| 10f64.powf(e).min(50.0))],
            jerk in prop_oneof![within(1e-4, 500.0), (-4.0f64..2.7).prop_map(|e| 10f64.powf(e).min(500.0))],
            v in within(0.0, 2.0),
            a_frac in prop_oneof![Just(0.0f64), Just(1.0), Just(-1.0), Just(3.0), Just(-3.0), -3.0f64..=3.0],
            edge in 0usize..3,
        ) {
            let a0 = a_frac * acc;
            let v0 = match edge {
                // On the consistency boundary (a decelerating start that just reaches rest).
                1 if a0 < 0.0 => a0 * a0 / (2.0 * jerk),
                // On the plateau boundary: J·v0 + a0²/2 = A².
                2 => (acc * acc - 0.5 * a0 * a0) / jerk,
                _ => v,
            };
            prop_assume!(braking_start(a0, v0, acc, jerk));
            let r = plan_ramps(a0, v0, 0.0, acc, jerk);
            prop_assert!(
                ramps_brake_to_rest(a0, v0, acc, jerk, r),
                "ramps {r:?} from s̈₀ {a0}, ṡ₀ {v0}, A {acc}, J {jerk}"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(10_000))]
        #[test]
        fn profile_reaches_target_with_bounded_acc_and_jerk(
            sd0 in 0.0f64..1.2, sdd0 in -5.0f64..5.0, target in prop_oneof![Just(0.0), Just(1.0)],
            acc in 0.5f64..20.0, jerk in 1.0f64..500.0,
        ) {
            let sdd0 = sdd0.clamp(-acc, acc);
            // Consistent start: a decelerating state can still reach s̈ = 0 with ṡ ≥ 0.
            let sd0 = if sdd0 < 0.0 { sd0.max(sdd0 * sdd0 / (2.0 * jerk)) } else { sd0 };
            let p = SpeedProfile::plan(PathState { s: 0.3, sd: sd0, sdd: sdd0 }, target, acc, jerk);
            let end = p.eval(p.settle_time() + 1.0);
            prop_assert_eq!(end.sd, target);
            prop_assert_eq!(end.sdd, 0.0);
            // Continuity at the settle time and bounded path acceleration along the way.
            let e = p.phases[p.n - 1];
            prop_assert!((e.sd - target).abs() < 1e-9 * (1.0 + sd0 + sdd0.abs()), "ṡ at settle {} vs {target}", e.sd);
            prop_assert!(e.sdd.abs() < 1e-9 * (1.0 + sdd0.abs()), "s̈ at settle {}", e.sdd);
            let k = 200;
            let mut prev = p.eval(0.0);
            for i in 1..=k {
                let tau = p.settle_time() * i as f64 / k as f64;
                let x = p.eval(tau);
                prop_assert!(x.sdd.abs() <= acc.max(sdd0.abs()) * (1.0 + 1e-9) + 1e-12);
                prop_assert!(x.s >= prev.s - 1e-12, "path runs backwards");
                // Jerk bound between samples.
                let dt = p.settle_time() / k as f64;
                prop_assert!((x.sdd - prev.sdd).abs() <= jerk * dt * (1.0 + 1e-6) + 1e-9);
                prev = x;
            }
        }
    }

    /// `eval` never reads a negative path speed (its Kani contract, `f3_eval_contract`): where a
    /// phase's polynomial dips below 0 — by rounding near a stop, here by a profile whose first
    /// phase decelerates past it — the speed read is 0 (catches mutant `x75`, a clamp at −1).
    #[test]
    fn a_negative_path_speed_is_read_as_zero() {
        let phase = |t0, sd, sdd| Phase {
            t0,
            s: 0.0,
            sd,
            sdd,
            jerk: 0.0,
        };
        let p = SpeedProfile {
            phases: [
                phase(0.0, 0.1, -1.0),
                phase(1.0, 0.0, 0.0),
                phase(2.0, 0.0, 0.0),
                phase(3.0, 0.0, 0.0),
            ],
            n: 2,
            settle: 1.0,
            target: 0.0,
            acc: 1.0,
            jerk: 1.0,
        };
        // Raw: ṡ = 0.1 − 0.5 at τ = 0.5, ṡ = 0.1 − 0.9 at τ = 0.9.
        for tau in [0.5, 0.9] {
            let e = p.eval(tau);
            assert_eq!(e.sd, 0.0, "ṡ at {tau}");
            assert_eq!(e.sdd, -1.0);
        }
        assert_eq!(p.eval(0.05).sd, 0.1 - 0.05);
    }

    /// `ranges` encloses `eval` at instants next to a phase boundary, where the phase before it
    /// and the one after it evaluate ṡ differently by rounding (the case f4's twin found at 10⁶
    /// windows: ṡ 5e-16 above the range one ulp inside a phase, with padding
    /// relative to the value only). Windows from just before each boundary (a few ulps to 1e-6 s)
    /// to beyond it, on 20 000 planned profiles; also catches a `ranges` without the terms'
    /// padding or sampling a phase's end with the next phase's polynomial.
    #[test]
    fn ranges_enclose_eval_next_to_phase_boundaries() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut unit = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for _ in 0..20_000 {
            let acc = 0.05 + 50.0 * unit();
            let jerk = 0.05 + 500.0 * unit();
            let sdd0 = acc * (2.0 * unit() - 1.0);
            let mut sd0 = 1.5 * unit();
            if sdd0 < 0.0 {
                sd0 = sd0.max(sdd0 * sdd0 / (2.0 * jerk));
            }
            let target = if unit() < 0.5 { 0.0 } else { 1.5 * unit() };
            let p = SpeedProfile::plan(
                PathState {
                    s: 10.0 * unit(),
                    sd: sd0,
                    sdd: sdd0,
                },
                target,
                acc,
                jerk,
            );
            for k in 1..p.n {
                let t_b = p.phases[k].t0;
                for back in [4.0 * f64::EPSILON * t_b, 1e-12 * t_b, 1e-9, 1e-6] {
                    let ta = (t_b - back).max(0.0);
                    let tb = t_b + back;
                    let (s_lo, s_hi, sd_lo, sd_hi, sdd_max) = p.ranges(ta, tb);
                    let mut tau = ta;
                    for _ in 0..8 {
                        let e = p.eval(tau);
                        assert!(
                            sd_lo <= e.sd && e.sd <= sd_hi,
                            "ṡ({tau}) = {} ∉ [{sd_lo}, {sd_hi}] over [{ta}, {tb}]",
                            e.sd
                        );
                        assert!(s_lo <= e.s && e.s <= s_hi, "s({tau}) = {}", e.s);
                        assert!(e.sdd.abs() <= sdd_max, "|s̈({tau})| = {}", e.sdd);
                        checked += 1;
                        tau = tau.next_up().min(tb);
                    }
                }
            }
        }
        assert!(checked > 100_000, "only {checked} instants checked");
    }
}
