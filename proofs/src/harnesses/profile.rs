//! (e) The braking profile decreases ṡ monotonically to 0 within the reported time and respects
//! its acceleration and jerk bounds; the path position never decreases.
//!
//! Monotonicity holds from the moment s̈ ≤ 0; a start with s̈₀ > 0 first ramps s̈ down to 0 at
//! jerk −J (ṡ still rises by at most s̈₀²/(2J)), which the harness checks as the bound on ṡ.

use crate::{Source, harness};
use pacs_motion::profile::{Piece, Range};
use pacs_motion::scaling::{PathState, SpeedProfile};

/// Relative slack for the float evaluation of the cubic phases (the verification uses the sound
/// `ranges`, padded by 1e-12 relative; this harness checks the profile's own semantics).
const EPS: f64 = 1e-9;

/// Limits `(acc, jerk)` and a consistent start state: a decelerating state can bring s̈ to 0
/// before ṡ reaches 0. Others make `plan` undershoot (raw ṡ < 0, s decreasing); `admissible`
/// rejects those (`sd_lo < -1e-9`), so the shield never executes them. `None`: rejected.
///
/// The limits and the start position are drawn from their whole ranges (the property tests;
/// the Kani splits choose their own, `brake_start`).
fn consistent_start<S: Source>(s: &mut S) -> Option<(f64, f64, PathState)> {
    let (acc, jerk, s0) = (
        s.f64_in(0.05, 50.0),
        s.f64_in(0.05, 500.0),
        s.f64_in(0.0, 10.0),
    );
    let start = PathState {
        s: s0,
        sd: s.f64_in(0.0, 1.5),
        sdd: s.f64_in(-acc, acc),
    };
    s.assume(start.sdd >= 0.0 || start.sd >= start.sdd * start.sdd / (2.0 * jerk))
        .then_some((acc, jerk, start))
}

fn braking<S: Source>(s: &mut S) {
    let Some((acc, jerk, start)) = consistent_start(s) else {
        return;
    };
    let p = SpeedProfile::plan(start, 0.0, acc, jerk);
    let settle = p.settle_time();
    assert!(settle.is_finite() && settle >= 0.0);
    // At rest from the settle time on, at a fixed position.
    let rest = p.eval(settle);
    assert!(
        rest.sd == 0.0 && rest.sdd == 0.0,
        "not at rest at settle {settle}: {rest:?}"
    );
    let later = p.eval(settle + s.f64_in(0.0, 100.0));
    assert!(later.sd == 0.0 && later.sdd == 0.0);
    // The path never runs backwards at any instant.
    let any = p.eval(s.f64_in(0.0, settle));
    assert!(any.sd >= 0.0, "ṡ {} < 0", any.sd);
    // s̈ reaches 0 continuously at the settle time: just before it, on the last jerk ramp, s̈ is
    // within rounding of 0 (mutant x8, a last ramp half as long, leaves half the peak s̈).
    let before = p.eval(settle.next_down());
    assert!(
        before.sdd.abs() <= 1e-9 * (1.0 + acc + start.sdd.abs()),
        "s̈ = {} just before the settle time {settle}: a jump to rest",
        before.sdd
    );
    assert!(later.s == rest.s && p.settle_s() == rest.s);
    // Two times in [0, settle].
    let t1 = s.f64_in(0.0, settle);
    let t2 = s.f64_in(t1, settle);
    let (a, b) = (p.eval(t1), p.eval(t2));
    let scale = 1.0 + start.sd + acc + start.sdd.abs();
    let peak = start.sd + start.sdd.max(0.0).powi(2) / (2.0 * jerk);
    for e in [a, b] {
        assert!(
            e.sd >= 0.0 && e.sd <= peak + EPS * scale,
            "ṡ {} outside [0, {peak}]",
            e.sd
        );
        assert!(
            e.sdd.abs() <= acc.max(start.sdd.abs()) * (1.0 + EPS),
            "|s̈| {} > {acc}",
            e.sdd
        );
    }
    // s never decreases.
    assert!(
        b.s >= a.s - EPS * (1.0 + a.s.abs()),
        "s decreased: {} → {} ({t1} → {t2}, settle {settle}) from {start:?}, acc {acc}, jerk {jerk}: {p:?}",
        a.s,
        b.s
    );
    // ṡ non-increasing once s̈ ≤ 0 (always after the first jerk ramp).
    if a.sdd <= 0.0 {
        assert!(
            b.sd <= a.sd + EPS * scale,
            "ṡ rose while braking: {} → {} ({t1} → {t2})",
            a.sd,
            b.sd
        );
    }
    // Jerk bound: |Δs̈| ≤ J·Δτ.
    assert!(
        (b.sdd - a.sdd).abs() <= jerk * (t2 - t1) * (1.0 + EPS) + EPS * scale,
        "jerk above {jerk}: s̈ {} → {} over {}",
        a.sdd,
        b.sdd,
        t2 - t1
    );
}
// Property test only (a timeout under Kani, > 240 s even with `√` stubbed and
// the limits at corners): its Kani proofs are the splits `e1_brake_plan_*` below, on the plan's
// phases rather than on `eval` over time.
harness!(
    e1_braking_profile,
    twin_only,
    cases = crate::DEFAULT_CASES,
    braking
);

/// The path ranges the verification turns into joint boxes (claim C7): for a profile planned
/// from a consistent start and any τ in `[ta, tb]`, the state the shield executes at τ
/// (`eval`) lies in `ranges(ta, tb)`: s in `[s_lo, s_hi]`, ṡ in `[ṡ_lo, ṡ_hi]`, |s̈| ≤ the bound.
fn path_ranges<S: Source>(s: &mut S) {
    let Some((acc, jerk, start)) = consistent_start(s) else {
        return;
    };
    let target = if s.bool() { 0.0 } else { s.f64_in(0.0, 1.5) };
    let p = SpeedProfile::plan(start, target, acc, jerk);
    let horizon = p.settle_time() + 1.0;
    let ta = s.f64_in(0.0, horizon);
    let tb = s.f64_in(ta, horizon);
    let (s_lo, s_hi, sd_lo, sd_hi, sdd_max) = p.ranges(ta, tb);
    let tau = s.f64_in(ta, tb);
    let e = p.eval(tau);
    assert!(
        s_lo <= e.s && e.s <= s_hi,
        "s({tau}) = {} ∉ [{s_lo}, {s_hi}] over [{ta}, {tb}]",
        e.s
    );
    assert!(
        sd_lo <= e.sd && e.sd <= sd_hi,
        "ṡ({tau}) = {} ∉ [{sd_lo}, {sd_hi}] over [{ta}, {tb}]",
        e.sd
    );
    assert!(e.sdd.abs() <= sdd_max, "|s̈({tau})| = {} > {sdd_max}", e.sdd);
}
// Property test only (a timeout under Kani, the phase loop): its Kani proof is
// the per-phase split `f4_path_ranges_phase` below.
harness!(
    f4_path_ranges_enclose,
    twin_only,
    cases = crate::DEFAULT_CASES,
    path_ranges
);

// ---------------------------------------------------------------------------------------------
// e1's Kani splits: the braking plan's phases.

/// Which branch of the braking plan a split covers (`SpeedProfile::plan` with target 0 from a
/// consistent start, d = −1).
#[derive(Clone, Copy, PartialEq)]
enum BrakeCase {
    /// The peak deceleration `up = √(J·ṡ₀ + s̈₀²/2)` exceeds `A`: ramp to −A, a plateau at −A,
    /// ramp back to 0 (no `√` in the durations).
    Plateau,
    /// The peak stays below `A`: two ramps through the peak `up = √(J·ṡ₀ + s̈₀²/2)`.
    Ramps,
}

/// The limits `(acc, jerk)` of e1's splits and a consistent braking start in the branch `case`.
/// The branch is fixed by the inputs with a margin of 1e-9 relative (the `√` stub's root is
/// within 1e-12 of the real root). Under Kani the limits are powers of two (A = 1/s², J = 8/s³:
/// the planner's divisions by them are exact), s = 0 and s̈₀ = 0 (braking from a constant path
/// speed; with a symbolic s̈₀ too, 4-bit, neither case decided within 300 s), any ṡ₀ (4-bit)
/// for `Plateau`;
/// the twin draws the limits from e1's whole ranges, s and s̈₀ from theirs.
fn brake_start<S: Source>(s: &mut S, case: BrakeCase) -> Option<(f64, f64, PathState)> {
    let (acc, jerk, s0) = if cfg!(kani) {
        (1.0, 8.0, 0.0)
    } else {
        (
            s.f64_in(0.05, 50.0),
            s.f64_in(0.05, 500.0),
            s.f64_in(0.0, 10.0),
        )
    };
    // Under Kani `Ramps` from ṡ₀ = 1/16 (8ṡ₀ = 1/2 < A²): only the `√` stub's root is free
    // (a symbolic ṡ₀ too, 4-bit, did not decide within 120 s).
    let sd = if cfg!(kani) && case == BrakeCase::Ramps {
        0.0625
    } else {
        s.f64_in(0.0, 1.5)
    };
    let sdd = if cfg!(kani) { 0.0 } else { s.f64_in(-acc, acc) };
    let start = PathState { s: s0, sd, sdd };
    let consistent = sdd >= 0.0 || sd >= sdd * sdd / (2.0 * jerk);
    // The square of the peak the planner computes: J·ṡ₀ + s̈₀²/2 (d = −1: u₀ = −s̈₀).
    let peak2 = jerk * sd + 0.5 * sdd * sdd;
    let in_case = match case {
        BrakeCase::Plateau => peak2 > acc * acc * (1.0 + 1e-9),
        BrakeCase::Ramps => peak2 < acc * acc * (1.0 - 1e-9),
    };
    s.assume(consistent && in_case)
        .then_some((acc, jerk, start))
}

/// The braking plan's ramps (claim C6, the part a model checker decides): from a consistent
/// start, the ramps `plan_ramps(s̈₀, ṡ₀, 0, A, J)` that `SpeedProfile::plan` pushes (a duration
/// ≤ 0 is skipped, a positive one is finite) have jerks ±J or 0, and applied in order
/// (ṡ += Δ(s̈ + Δ·j/2), s̈ += Δ·j per ramp, in floating point) they keep, at the end of every
/// ramp, ṡ ≥ −tol, |s̈| ≤ max(A, |s̈₀|)(1 + 1e-9) and s̈ ≤ tol (braking), and end at rest within
/// tol: |s̈| ≤ 1e-9·(1 + A + |s̈₀|), |ṡ| ≤ 1e-9·(1 + ṡ₀ + A + |s̈₀|) (no jump to rest: mutant x8,
/// a last ramp half as long, ends at half the peak s̈). With s̈ linear on a ramp, |s̈| at the
/// ends bounds it everywhere; with s̈ ≤ 0 after the first ramp, ṡ decreases from then on, and on
/// the first ramp from s̈₀ > 0 (jerk −J) ṡ is concave: the ends bound ṡ from below (real
/// arithmetic).
///
/// Left to the twin: `plan`'s own evaluation of the ramps (its phases, `eval` at any instant:
/// the twin checks the phases the same way, and e1's twin everything over time), other limits
/// (and, for `Ramps`, s̈₀ ≠ 0: `brake_start`).
// The ramps by index, not by iterator: cheaper for the model checker.
#[allow(clippy::needless_range_loop)]
fn brake_plan<S: Source>(s: &mut S, case: BrakeCase) {
    let Some((acc, jerk, start)) = brake_start(s, case) else {
        return;
    };
    let a_max = acc.max(start.sdd.abs()) * (1.0 + EPS);
    let tol_sdd = EPS * (1.0 + acc + start.sdd.abs());
    let tol_sd = EPS * (1.0 + start.sd + acc + start.sdd.abs());
    let ramps = pacs_motion::scaling::plan_ramps(start.sdd, start.sd, 0.0, acc, jerk);
    // The claim is `plan_ramps`' braking contract (one implementation of it).
    assert!(
        pacs_motion::scaling::ramps_brake_to_rest(start.sdd, start.sd, acc, jerk, ramps),
        "the ramps {ramps:?} break the braking contract from {start:?}, A {acc}, J {jerk}"
    );
    if cfg!(kani) {
        return;
    }
    // The twin: the same on the phases `plan` builds from these ramps (its own evaluation).
    let p = SpeedProfile::plan(start, 0.0, acc, jerk);
    let (ph, n, settle, target, _, _) = p.to_parts();
    assert!((1..=4).contains(&n) && target == 0.0, "{n} phases");
    assert!(ph[0].0 == 0.0, "the plan starts at {}", ph[0].0);
    let mut prev = 0.0;
    for (k, &(t0, _, sd, sdd, j)) in ph[..n].iter().enumerate() {
        assert!(t0 >= prev, "phase {k} starts at {t0} before {prev}");
        assert!(sd >= -tol_sd, "ṡ = {sd} < 0 at the start of phase {k}");
        assert!(sdd.abs() <= a_max, "|s̈| = {sdd} above {a_max} at phase {k}");
        assert!(k == 0 || sdd <= tol_sdd, "s̈ = {sdd} > 0 at phase {k}");
        assert!(k + 1 == n || j == jerk || j == -jerk || j == 0.0);
        prev = t0;
    }
    let last = ph[n - 1];
    assert!(
        last.0 == settle,
        "the last phase starts at {} ≠ settle {settle}",
        last.0
    );
    assert!(
        last.2 == 0.0 && last.3 == 0.0 && last.4 == 0.0,
        "last phase {last:?} not at rest"
    );
    if n >= 2 {
        let end = pacs_motion::scaling::phase_eval(ph[n - 2], settle);
        assert!(
            end.sdd.abs() <= tol_sdd,
            "the last ramp ends at s̈ = {}",
            end.sdd
        );
        assert!(
            end.sd.abs() <= tol_sd,
            "the last ramp ends at ṡ = {}",
            end.sd
        );
    }
}

fn brake_plan_plateau<S: Source>(s: &mut S) {
    brake_plan(s, BrakeCase::Plateau)
}

fn brake_plan_ramps<S: Source>(s: &mut S) {
    brake_plan(s, BrakeCase::Ramps)
}

// Under Kani `√` by `stubs::sqrt_by_square`: any root whose rounded square is within 1e-12
// relative of its argument, an over-approximation of IEEE `√` (proofs/README.md, What Kani sees).
harness!(
    e1_brake_plan_plateau,
    unwind = 5,
    bits = 4,
    stub = (pacs_reach::ieee::sqrt => crate::stubs::sqrt_by_square),
    cases = crate::DEFAULT_CASES,
    brake_plan_plateau
);

harness!(
    e1_brake_plan_ramps,
    unwind = 5,
    bits = 4,
    stub = (pacs_reach::ieee::sqrt => crate::stubs::sqrt_by_square),
    cases = crate::DEFAULT_CASES,
    brake_plan_ramps
);

/// `plan_ramps`' braking contract (`ramps_brake_to_rest`, claim C6) proven on the real function
/// (`proof_for_contract`) for the inputs `brake_start` draws under Kani in the plateau branch
/// (A = 1, J = 8, s̈₀ = 0, any 4-bit ṡ₀ with J·ṡ₀ > A²(1 + 10⁻⁹)); `√` by `sqrt_by_square`.
/// The contract over the whole ranges of `braking_start` is the twins' (e1's splits and
/// motion's `the_braking_ramps_keep_their_contract`).
#[cfg(kani)]
#[kani::proof_for_contract(pacs_motion::scaling::plan_ramps)]
#[kani::unwind(5)]
#[kani::stub(pacs_reach::ieee::sqrt, crate::stubs::sqrt_by_square)]
fn e1_plan_ramps_contract_plateau() {
    plan_ramps_under_contract(BrakeCase::Plateau);
}

/// As `e1_plan_ramps_contract_plateau`, in the two-ramp branch (ṡ₀ = 1/16, the `√` stub's root
/// free).
#[cfg(kani)]
#[kani::proof_for_contract(pacs_motion::scaling::plan_ramps)]
#[kani::unwind(5)]
#[kani::stub(pacs_reach::ieee::sqrt, crate::stubs::sqrt_by_square)]
fn e1_plan_ramps_contract_ramps() {
    plan_ramps_under_contract(BrakeCase::Ramps);
}

/// One call of `plan_ramps` from `brake_start`'s Kani inputs in branch `case`.
#[cfg(kani)]
fn plan_ramps_under_contract(case: BrakeCase) {
    let mut s = crate::KaniSource { bits: 4 };
    if let Some((acc, jerk, start)) = brake_start(&mut s, case) {
        let _ = pacs_motion::scaling::plan_ramps(start.sdd, start.sd, 0.0, acc, jerk);
    }
}

// ---------------------------------------------------------------------------------------------
// f4's Kani split: one phase of `ranges`.

/// One constant-jerk phase's ranges over a window inside it (claim C7, the part a model checker
/// decides): for a phase `(t0, s, ṡ, s̈, j)` that is not the profile's last and a window
/// `[lo, hi]` with `t0 < lo ≤ hi` before the next phase, the executed ṡ at any τ in the window
/// (`eval`'s polynomial with its clamp at 0) lies in `[ṡ_lo, ṡ_hi]` and |s̈(τ)| ≤ the bound of
/// `phase_window_ranges`, which is `SpeedProfile::ranges(lo, hi)` of such a profile (the twin
/// checks that bit for bit on planned profiles, and also s(τ) ∈ [s_lo, s_hi]).
///
/// Under Kani one phase and window, any τ (full width): the ramp t0 = 1 s, ṡ = 100, s̈ = −40/s,
/// j = 8/s² over [5, 7] s, whose ṡ = (10 − 2(τ − 1))² has its minimum 0 at τ = 6 s inside the
/// window (mutant x12, the interior extremum skipped, fails: the ends give ṡ = 4). With the
/// window's ends symbolic too (4-bit), a timeout at 150 s. Any other phase or window is the
/// twin's (any non-final phase of a planned profile, any window in it), and so is mutant x26
/// (padding relative to the value only, a phase's end sampled with the next phase's
/// polynomial): its failure needs two phases' polynomials at their boundary, and Kani verifies
/// this split with x26 applied.
fn phase_window<S: Source>(s: &mut S) {
    use pacs_motion::scaling::{phase_eval, phase_window_ranges};
    let (phase, lo, hi) = if cfg!(kani) {
        ((1.0, 0.0, 100.0, -40.0, 8.0), 5.0, 7.0)
    } else {
        // A non-final phase of a profile planned from a consistent start, any window inside it.
        let Some((acc, jerk, start)) = consistent_start(s) else {
            return;
        };
        let target = if s.bool() { 0.0 } else { s.f64_in(0.0, 1.5) };
        let p = SpeedProfile::plan(start, target, acc, jerk);
        let (ph, n, ..) = p.to_parts();
        if !s.assume(n >= 2) {
            return;
        }
        let k = s.index(n - 1);
        let (t0, t1) = (ph[k].0, ph[k + 1].0);
        let lo = s.f64_in(t0, t1);
        let hi = s.f64_in(lo, t1);
        if !s.assume(t0 < lo && hi < t1) {
            return;
        }
        let whole = p.ranges(lo, hi);
        let one = phase_window_ranges(ph[k], lo, hi);
        assert!(
            whole.0.to_bits() == one.0.to_bits()
                && whole.1.to_bits() == one.1.to_bits()
                && whole.2.to_bits() == one.2.to_bits()
                && whole.3.to_bits() == one.3.to_bits()
                && whole.4.to_bits() == one.4.to_bits(),
            "ranges {whole:?} ≠ the phase's {one:?}"
        );
        (ph[k], lo, hi)
    };
    let (s_lo, s_hi, sd_lo, sd_hi, sdd_max) = phase_window_ranges(phase, lo, hi);
    let tau = s.f64_full(lo, hi);
    let e = phase_eval(phase, tau);
    let sd = e.sd.max(0.0);
    assert!(
        sd_lo <= sd && sd <= sd_hi,
        "ṡ({tau}) = {sd} ∉ [{sd_lo}, {sd_hi}] over [{lo}, {hi}] of {phase:?}"
    );
    assert!(e.sdd.abs() <= sdd_max, "|s̈({tau})| = {} > {sdd_max}", e.sdd);
    if !cfg!(kani) {
        assert!(
            s_lo <= e.s && e.s <= s_hi,
            "s({tau}) = {} ∉ [{s_lo}, {s_hi}] over [{lo}, {hi}]",
            e.s
        );
    }
}

harness!(
    f4_path_ranges_phase,
    unwind = 3,
    cases = crate::DEFAULT_CASES,
    phase_window
);

// ---------------------------------------------------------------------------------------------
// f5's Kani splits: one joint piece's bounds (`pacs_motion::profile::Piece::extend_bounds`).

/// A joint piece and a window `[d0, d1]` of its local time, any `d` in it. The twin: any piece
/// with q ∈ [−4, 4] rad, q̇ ∈ [−4, 4] rad/s, q̈ ∈ [−32, 32] rad/s², j ∈ [−1024, 1024] rad/s³ (or 0
/// when `cubic` is false), any window in [0, 2] s, any d in it. Under Kani the piece and window
/// `kani` (constants) and any d in the window (full width): with a symbolic window (4-bit ends)
/// too, a timeout at 150 s.
fn piece_window<S: Source>(
    s: &mut S,
    cubic: bool,
    kani: (Piece, f64, f64),
) -> (Piece, f64, f64, f64) {
    if cfg!(kani) {
        let (piece, d0, d1) = kani;
        return (piece, d0, d1, s.f64_in(d0, d1));
    }
    let piece = Piece {
        t: 0.0,
        q: s.f64_in(-4.0, 4.0),
        v: s.f64_in(-4.0, 4.0),
        a: s.f64_in(-32.0, 32.0),
        j: if cubic {
            s.f64_in(-1024.0, 1024.0)
        } else {
            0.0
        },
    };
    let d0 = s.f64_in(0.0, 2.0);
    let d1 = s.f64_in(d0, 2.0);
    let d = s.f64_full(d0, d1);
    (piece, d0, d1, d)
}

/// The velocity and acceleration bounds of one cubic joint piece (claim C7, f5's boxes): after
/// `extend_bounds(d0, d1)` from empty ranges, q̇(d) and q̈(d) of `eval` lie in them for every d in
/// `[d0, d1]` (any jerk). Under Kani the piece q = 0, q̇ = 2, q̈ = −8, j = 8 over [0.5, 1.5] s:
/// q̇ has its minimum −2 at d = 1 s, between ends where it is −1 (mutant x31, the q̇ extremum
/// where q̈ = 0 skipped, fails).
fn piece_vel_acc<S: Source>(s: &mut S) {
    let kani_piece = Piece {
        t: 0.0,
        q: 0.0,
        v: 5.0,
        a: -8.0,
        j: 8.0,
    };
    let (piece, d0, d1, d) = piece_window(s, true, (kani_piece, 0.5, 1.5));
    let mut r = [Range::EMPTY; 3];
    piece.extend_bounds(d0, d1, &mut r);
    let (_, v, a) = piece.eval(d);
    assert!(
        r[1].lo <= v && v <= r[1].hi,
        "q̇({d}) = {v} ∉ {:?} over [{d0}, {d1}] of {piece:?}",
        r[1]
    );
    assert!(
        r[2].lo <= a && a <= r[2].hi,
        "q̈({d}) = {a} ∉ {:?} over [{d0}, {d1}] of {piece:?}",
        r[2]
    );
}

/// The position bounds of one joint piece without jerk (a quadratic: its extremum where q̇ = 0 is
/// `−v/a`, no square root): after `extend_bounds(d0, d1)`, q(d) lies in them for every d in
/// `[d0, d1]`. Under Kani the piece q = 0, q̇ = 2, q̈ = −4 over [0.25, 1] s: q has its maximum
/// 0.5 at d = 0.5 s, above the ends' 0.375 and 0 (mutant x32, the extremum of q skipped when
/// j = 0, fails). The cubic case (the roots of q̇ by the stable quadratic formula, with `√`) is
/// `f5_piece_position_cubic` (mutant x76, the second root skipped, fails it).
fn piece_position_quadratic<S: Source>(s: &mut S) {
    piece_position(s, false)
}

fn piece_position_cubic<S: Source>(s: &mut S) {
    piece_position(s, true)
}

fn piece_position<S: Source>(s: &mut S, cubic: bool) {
    let kani_piece = if cubic {
        // q̇ = (d − ½)(d − 3/2): the stable quadratic formula's roots ½ and 3/2 (discriminant 1,
        // `√` by its stub), q's maximum 1/6 at d = ½ inside [¼, 1], above the ends' 25/192 and
        // 1/12.
        Piece {
            t: 0.0,
            q: 0.0,
            v: 0.75,
            a: -2.0,
            j: 2.0,
        }
    } else {
        Piece {
            t: 0.0,
            q: 0.0,
            v: 2.0,
            a: -4.0,
            j: 0.0,
        }
    };
    let (piece, d0, d1, d) = piece_window(s, cubic, (kani_piece, 0.25, 1.0));
    let mut r = [Range::EMPTY; 3];
    piece.extend_bounds(d0, d1, &mut r);
    let (q, _, _) = piece.eval(d);
    assert!(
        r[0].lo <= q && q <= r[0].hi,
        "q({d}) = {q} ∉ {:?} over [{d0}, {d1}] of {piece:?}",
        r[0]
    );
}

// Under Kani `√` (the roots of q̇, which only widen the ranges) by `stubs::sqrt_by_square`.
harness!(
    f5_piece_velocity_acceleration,
    unwind = 3,
    bits = 8,
    stub = (pacs_reach::ieee::sqrt => crate::stubs::sqrt_by_square),
    cases = crate::DEFAULT_CASES,
    piece_vel_acc
);

harness!(
    f5_piece_position_quadratic,
    unwind = 3,
    bits = 8,
    cases = crate::DEFAULT_CASES,
    piece_position_quadratic
);

// Under Kani the cubic piece above, `√` (of the discriminant 1) by `stubs::sqrt_by_square`: any
// root within 1e-12 relative of 1, so the roots of q̇ are near, not at, ½ and 3/2.
harness!(
    f5_piece_position_cubic,
    unwind = 3,
    bits = 8,
    stub = (pacs_reach::ieee::sqrt => crate::stubs::sqrt_by_square),
    cases = crate::DEFAULT_CASES,
    piece_position_cubic
);

/// The piece at `t = 0`, `q = 0` with velocity `v`, acceleration `a` and jerk `j`.
#[cfg(kani)]
fn piece(v: f64, a: f64, j: f64) -> Piece {
    Piece {
        t: 0.0,
        q: 0.0,
        v,
        a,
        j,
    }
}

/// `p.extend_bounds(d0, d1, r)` from any prior ranges `r` (the call whose contract a
/// `proof_for_contract` harness checks).
#[cfg(kani)]
fn extend_bounds_from_any_ranges(p: &Piece, d0: f64, d1: f64) {
    let mut r = any_ranges();
    p.extend_bounds(d0, d1, &mut r);
}

/// Prior ranges for `extend_bounds`' contract: any floats without NaN (infinite ends included),
/// or `EMPTY`.
#[cfg(kani)]
fn any_ranges() -> [Range; 3] {
    let any_range = || {
        if kani::any() {
            return Range::EMPTY;
        }
        let (lo, hi): (f64, f64) = (kani::any(), kani::any());
        kani::assume(!lo.is_nan() && !hi.is_nan());
        Range { lo, hi }
    };
    [any_range(), any_range(), any_range()]
}

/// `Piece::extend_bounds`' contract (claim C7: the ranges only widen and hold the piece's
/// evaluated state at every instant of the window, `ranges_cover_piece_at` at any instant of
/// the postcondition's grid of 2⁻⁸ s) proven on the real function for the quadratic piece of
/// `f5_piece_position_quadratic` (q = 0, q̇ = 2, q̈ = −4, no jerk; q's maximum inside the window
/// [¼, 1] s) and any prior ranges without NaN. `f5_extend_bounds_contract_cubic` takes a cubic
/// piece; the cubic pieces whose q̇ has real roots (the roots by `√`) and symbolic pieces are the
/// twin's (`f5_extend_bounds_contract_holds`) and the f5 splits'.
#[cfg(kani)]
#[kani::proof_for_contract(Piece::extend_bounds)]
#[kani::unwind(3)]
fn f5_extend_bounds_contract() {
    extend_bounds_from_any_ranges(&piece(2.0, -4.0, 0.0), 0.25, 1.0);
}

/// As `f5_extend_bounds_contract`, for the cubic piece of `f5_piece_velocity_acceleration`
/// (q = 0, q̇ = 5, q̈ = −8, j = 8 over [½, 3/2] s: q̇ has its minimum 1 inside, where q̈ = 0, and
/// no real root, so q is monotone and no `√` is taken).
#[cfg(kani)]
#[kani::proof_for_contract(Piece::extend_bounds)]
#[kani::unwind(3)]
fn f5_extend_bounds_contract_cubic() {
    extend_bounds_from_any_ranges(&piece(5.0, -8.0, 8.0), 0.5, 1.5);
}

/// The twin of `f5_extend_bounds_contract`: pieces and windows over the contract's whole input
/// range (`piece_window_input`: half of the pieces without jerk, windows from 0 to 64 s, some
/// of zero length), prior ranges empty, finite or infinite, and the postcondition checked at
/// both ends, 15 instants between, 8 full-width instants and each interior extremum of q (where
/// q̇ = 0) and q̇ (where q̈ = 0) and the neighbouring floats of each.
#[cfg(test)]
#[test]
fn f5_extend_bounds_contract_holds() {
    use pacs_motion::profile::{piece_window_input, ranges_cover_piece_at, ranges_input};
    crate::run_cases("f5_extend_bounds_contract_holds", 20_000, |s| {
        let piece = Piece {
            t: s.f64_in(0.0, 100.0),
            q: s.f64_in(-8.0, 8.0),
            v: s.f64_in(-8.0, 8.0),
            a: s.f64_in(-64.0, 64.0),
            j: if s.bool() {
                0.0
            } else {
                s.f64_in(-8192.0, 8192.0)
            },
        };
        let d1 = match s.index(3) {
            0 => s.f64_in(0.0, 0.05),
            1 => s.f64_in(0.0, 2.0),
            _ => s.f64_in(0.0, 64.0),
        };
        let d0 = if s.bool() { 0.0 } else { s.f64_in(0.0, d1) };
        let range = |s: &mut crate::RandomSource| match s.index(3) {
            0 => Range::EMPTY,
            1 => {
                let (a, b) = (s.f64_in(-100.0, 100.0), s.f64_in(-100.0, 100.0));
                Range {
                    lo: a.min(b),
                    hi: a.max(b),
                }
            }
            _ => Range {
                lo: f64::NEG_INFINITY,
                hi: s.f64_in(-1.0, 1.0),
            },
        };
        let before = [range(s), range(s), range(s)];
        if !(piece_window_input(&piece, d0, d1) && ranges_input(&before)) {
            return;
        }
        let mut after = before;
        piece.extend_bounds(d0, d1, &mut after);
        let mut instants: Vec<f64> = (0..=16).map(|k| d0 + (d1 - d0) * k as f64 / 16.0).collect();
        instants.extend((0..8).map(|_| s.f64_full(d0, d1)));
        // Interior extrema: q̇ = 0 (v + a d + j d²/2, in closed form) and q̈ = 0 (−a/j).
        let (c2, c1, c0) = (0.5 * piece.j, piece.a, piece.v);
        let mut extrema = Vec::new();
        if c2 == 0.0 {
            if c1 != 0.0 {
                extrema.push(-c0 / c1);
            }
        } else {
            let disc = c1 * c1 - 4.0 * c2 * c0;
            if disc >= 0.0 {
                extrema.push((-c1 + disc.sqrt()) / (2.0 * c2));
                extrema.push((-c1 - disc.sqrt()) / (2.0 * c2));
            }
            extrema.push(-piece.a / piece.j);
        }
        for e in extrema {
            instants.extend([e.next_down(), e, e.next_up()]);
        }
        for d in instants {
            assert!(
                ranges_cover_piece_at(&piece, d0, d1, &before, &after, d),
                "{piece:?} over [{d0}, {d1}] at {d}: {before:?} → {after:?}, state {:?}",
                piece.eval(d)
            );
        }
    });
}
