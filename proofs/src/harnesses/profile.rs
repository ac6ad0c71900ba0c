//! (e) The braking profile decreases ṡ monotonically to 0 within the reported time and respects
//! its acceleration and jerk bounds; the path position never decreases.
//!
//! Monotonicity holds from the moment s̈ ≤ 0; a start with s̈₀ > 0 first ramps s̈ down to 0 at
//! jerk −J (ṡ still rises by at most s̈₀²/(2J)), which the harness checks as the bound on ṡ.

use crate::{Source, harness};
use pacs_motion::scaling::{PathState, SpeedProfile};

/// Relative slack for the float evaluation of the cubic phases (the verification uses the sound
/// `ranges`, padded by 1e-12 relative; this harness checks the profile's own semantics).
const EPS: f64 = 1e-9;

/// Limits `(acc, jerk)` and a consistent start state: a decelerating state can bring s̈ to 0
/// before ṡ reaches 0. Others make `plan` undershoot (raw ṡ < 0, s decreasing); `admissible`
/// rejects those (`sd_lo < -1e-9`), so the shield never executes them. `None`: rejected.
///
/// Under Kani the limits are corners and the middle of the twin's ranges (acc ∈ {0.05, 1, 50},
/// jerk ∈ {0.05, 10, 500}: the planner's arithmetic then divides by constants) and the start
/// position is 0 (s only shifts the positions, whose claims are the twin's); the twin draws all
/// of them from the whole ranges.
fn consistent_start<S: Source>(s: &mut S) -> Option<(f64, f64, PathState)> {
    let (acc, jerk, s0) = if cfg!(kani) {
        (
            [0.05, 1.0, 50.0][s.index(3)],
            [0.05, 10.0, 500.0][s.index(3)],
            0.0,
        )
    } else {
        (
            s.f64_in(0.05, 50.0),
            s.f64_in(0.05, 500.0),
            s.f64_in(0.0, 10.0),
        )
    };
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
    if cfg!(kani) {
        // Split (proofs/README.md): the continuity of s̈ at the settle time, the position claims
        // (s fixed from the settle time on: they need the planner's cubic evaluation to stay
        // finite) and the tolerance claims on the cubic evaluation below (peak speed, s and ṡ
        // monotone, jerk bound) are the twin's; Kani checks the claims above (session 14: with
        // the continuity claim, a timeout at 300 s).
        return;
    }
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
// Under Kani `√x` is any `r ≥ 0` with `fl(r²)` within 1e-12 relative of `x`
// (`stubs::sqrt_by_square`, an over-approximation of IEEE `√`): the claims Kani checks (a finite
// settle time, at rest from it on, ṡ ≥ 0) hold for any such root. (The continuity claim, the
// twin's, would also hold for any such root; with session 13's stub, any value in [0, x + 1], it
// would not: a peak below the start's s̈ skips the first ramp and the last one ends away from 0.)
harness!(
    e1_braking_profile,
    unwind = 6,
    bits = 4,
    stub = (pacs_reach::ieee::sqrt => crate::stubs::sqrt_by_square),
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
    // Under Kani `plan` is `stubs::any_bounded_profile`: any profile with bounded fields, which
    // contains every profile planned here (checked in the twin).
    assert!(
        cfg!(kani) || crate::profile_in_bounded_range(&p),
        "planned profile outside the stub's range: {p:?}"
    );
    let horizon = if cfg!(kani) {
        crate::PROFILE_BOUND
    } else {
        p.settle_time() + 1.0
    };
    let ta = s.f64_in(0.0, horizon);
    let tb = s.f64_in(ta, horizon);
    let (s_lo, s_hi, sd_lo, sd_hi, sdd_max) = p.ranges(ta, tb);
    if cfg!(kani) {
        // Split (proofs/README.md): Kani checks the ends of the window for any profile with
        // bounded fields, where `ranges` and `eval` must agree on the phase and the state (s from
        // below at `ta`, from above at `tb`; ṡ with `eval`'s clamp at 0): the bound between them
        // rests on s being monotone and the float evaluation of the cubic staying within the
        // padding, properties of planned profiles only, which the twin checks at every instant.
        let (at_a, at_b) = (p.eval(ta), p.eval(tb));
        assert!(
            s_lo <= at_a.s && at_b.s <= s_hi,
            "s at the ends ∉ [{s_lo}, {s_hi}]"
        );
        for e in [at_a, at_b] {
            assert!(
                sd_lo <= e.sd && e.sd <= sd_hi,
                "ṡ = {} ∉ [{sd_lo}, {sd_hi}] at an end of [{ta}, {tb}]",
                e.sd
            );
            assert!(e.sdd.abs() <= sdd_max, "|s̈| = {} > {sdd_max}", e.sdd);
        }
        return;
    }
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
harness!(
    f4_path_ranges_enclose,
    unwind = 6,
    bits = 4,
    stub = (pacs_motion::scaling::SpeedProfile::plan => crate::stubs::any_bounded_profile),
    cases = crate::DEFAULT_CASES,
    path_ranges
);
