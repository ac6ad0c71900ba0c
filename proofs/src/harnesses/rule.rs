//! (i1) The one ISO/TS 15066 rule is sound (claim C8′, `verify::iso15066::ContactRule::check`).
//!
//! Three robot capsules (one link each, on random frames 0–2: the same frame, adjacent frames or
//! the base), two body parts with random constraints (SSM, or PFL with random thresholds) and a
//! random clampable relation, optionally one environment capsule. *True* capsules are random; the
//! occupancies handed to the rule contain them (axis endpoints moved by at most `e`, radius grown
//! by `e` + 1e-9). The true joint velocities lie in the velocity box, the true kinetic energy is at
//! most the bound `E`. If the rule reports no violation, then for every body part that truly
//! touches the robot: SSM → every true joint speed ≤ `rest_speed`; PFL → true energy ≤ the
//! threshold of the *true* contact type (constrained if the part truly touches capsules on two
//! different frames, the environment, or a clampable part).

use crate::{Source, harness};
use nalgebra::Point3;
use pacs_models::{Capsule, Constraint};
use pacs_reach::JointBox;
use pacs_verify::iso15066::{ContactRule, EnvShape};
use std::ops::ControlFlow;

/// Distance between two segments, computed finely in floating point (for the ground truth).
fn segment_distance(a0: [f64; 3], a1: [f64; 3], b0: [f64; 3], b1: [f64; 3]) -> f64 {
    // Dense sampling of one segment against the exact point–segment distance of the other;
    // ground truth only needs to decide "touching" for pairs at least 1e-9 m inside the
    // occupancies' margin, so the sampling error (≤ |a1 − a0| / 2·512) is covered below by
    // comparing with a tolerance that favours "touching" only when clearly so.
    let pd = |p: [f64; 3]| {
        let d = [b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]];
        let w = [p[0] - b0[0], p[1] - b0[1], p[2] - b0[2]];
        let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let t = if dd > 0.0 {
            ((w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / dd).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let r = [w[0] - t * d[0], w[1] - t * d[1], w[2] - t * d[2]];
        (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt()
    };
    let mut best = f64::INFINITY;
    for i in 0..=64 {
        let u = i as f64 / 64.0;
        let p = [
            a0[0] + u * (a1[0] - a0[0]),
            a0[1] + u * (a1[1] - a0[1]),
            a0[2] + u * (a1[2] - a0[2]),
        ];
        best = best.min(pd(p));
    }
    best
}

#[derive(Clone, Copy)]
struct Cap {
    p1: [f64; 3],
    p2: [f64; 3],
    r: f64,
}

impl Cap {
    /// Truly touching (with a sampling tolerance: only pairs overlapping by ≥ 1e-6 m count).
    /// Under Kani an under-approximation without the sampling loop: two axis endpoints closer
    /// than `r + r' − 1e-6` (squares compared; the margin dwarfs their rounding). Fewer true
    /// contacts only weaken the claims checked below (a contact not seen is not checked; a
    /// pinch not seen checks the larger unconstrained threshold), they never make one false.
    fn touches(&self, o: &Cap) -> bool {
        if cfg!(kani) {
            let reach = self.r + o.r - 1e-6;
            reach >= 0.0
                && [self.p1, self.p2].iter().any(|a| {
                    [o.p1, o.p2].iter().any(|b| {
                        let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
                        d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= reach * reach
                    })
                })
        } else {
            segment_distance(self.p1, self.p2, o.p1, o.p2) + 1e-6 <= self.r + o.r
        }
    }
    fn capsule(&self) -> Capsule {
        Capsule::new_unchecked(Point3::from(self.p1), Point3::from(self.p2), self.r)
    }
}

/// The threshold (J) of a PFL contact of the true type, stated from ISO/TS 15066 without the
/// rule's `threshold`: the constrained (quasi-static) value for a clamped contact, else the
/// unconstrained (transient) one.
fn true_threshold(c: Constraint, clamped: bool) -> f64 {
    match c {
        Constraint::Ssm => 0.0,
        Constraint::Pfl {
            unconstrained,
            constrained,
        } => {
            if clamped {
                constrained
            } else {
                unconstrained
            }
        }
    }
}

fn random_cap<S: Source>(s: &mut S) -> Cap {
    Cap {
        p1: s.vec3(-0.2, 0.2),
        p2: s.vec3(-0.2, 0.2),
        r: s.f64_in(0.0, 0.08),
    }
}

/// An occupancy capsule containing `c`: endpoints moved by at most `e`, radius `r + e + 1e-9`.
fn enclose<S: Source>(s: &mut S, c: &Cap, e: f64) -> Capsule {
    let d1 = s.in_ball(e);
    let d2 = s.in_ball(e);
    let add = |p: [f64; 3], d: [f64; 3]| Point3::new(p[0] + d[0], p[1] + d[1], p[2] + d[2]);
    Capsule::new_unchecked(add(c.p1, d1), add(c.p2, d2), c.r + e + 1e-9)
}

fn rule_sound<S: Source>(s: &mut S) {
    const CAPS: usize = 3;
    const PARTS: usize = 2;
    let frames: [usize; CAPS] = [s.index(3), s.index(3), s.index(3)];
    let mut constraints = [Constraint::Ssm; PARTS];
    for c in &mut constraints {
        if s.bool() {
            *c = Constraint::Pfl {
                unconstrained: s.f64_in(0.0, 1.0),
                constrained: s.f64_in(0.0, 1.0),
            };
        }
    }
    let clampable = [false, s.bool(), s.bool(), false];
    let env = if s.bool() { Some(random_cap(s)) } else { None };
    let rest_speed = s.f64_in(0.0, 0.05);
    let workspace = Capsule::new_unchecked(Point3::origin(), Point3::origin(), 1.0);
    let mut rule = ContactRule::from_tables(
        (0..CAPS).collect(),
        frames.to_vec(),
        constraints.to_vec(),
        clampable.to_vec(),
        env.iter().map(|c| EnvShape::from(&c.capsule())).collect(),
        rest_speed,
        workspace,
    )
    .expect("valid tables");
    // True geometry and occupancies.
    let robot: [Cap; CAPS] = [random_cap(s), random_cap(s), random_cap(s)];
    let human: [Cap; PARTS] = [random_cap(s), random_cap(s)];
    let e_robot = s.f64_in(0.0, 0.05);
    let e_human = s.f64_in(0.0, 0.05);
    let robot_occ = [
        enclose(s, &robot[0], e_robot),
        enclose(s, &robot[1], e_robot),
        enclose(s, &robot[2], e_robot),
    ];
    let human_occ = [
        enclose(s, &human[0], e_human),
        enclose(s, &human[1], e_human),
    ];
    // True velocities (2 joints) inside the box; true energy below the bound.
    let mut dq_lo = [0.0; 2];
    let mut dq_hi = [0.0; 2];
    let mut dq = [0.0; 2];
    for j in 0..2 {
        let a = s.f64_in(-0.1, 0.1);
        let b = s.f64_in(-0.1, 0.1);
        dq_lo[j] = a.min(b);
        dq_hi[j] = a.max(b);
        dq[j] = s.f64_in(dq_lo[j], dq_hi[j]);
    }
    let e_bound = s.f64_in(0.0, 1.0);
    let e_true = s.f64_in(0.0, e_bound);
    let dq_box = JointBox::new(&dq_lo, &dq_hi).expect("ordered finite bounds");
    let out = rule.check(
        &robot_occ,
        &dq_box,
        &human_occ,
        || e_bound,
        true,
        |_| ControlFlow::Break(()),
    );
    if out.violated {
        return;
    }
    let moving = dq.iter().any(|v| v.abs() > rest_speed);
    for p in 0..PARTS {
        let touched: Vec<usize> = (0..CAPS).filter(|&c| robot[c].touches(&human[p])).collect();
        if touched.is_empty() {
            continue;
        }
        assert!(out.contact, "a true contact was not seen");
        assert!(
            out.separation <= 0.0,
            "separation figure above 0 on contact"
        );
        match constraints[p] {
            Constraint::Ssm => assert!(!moving, "SSM contact while moving passed"),
            c @ Constraint::Pfl { .. } => {
                // Two capsules on different frames pinch (the rule's spec, stated here without
                // the rule's own `frames_can_pinch`, so a change there is caught).
                let pinched = touched
                    .iter()
                    .any(|&a| touched.iter().any(|&b| frames[a] != frames[b]));
                let clamped = pinched
                    || env.is_some_and(|e| e.touches(&human[p]))
                    || (0..PARTS)
                        .any(|o| o != p && clampable[p * PARTS + o] && human[o].touches(&human[p]));
                assert!(
                    e_true <= true_threshold(c, clamped),
                    "PFL contact above the true threshold passed (clamped: {clamped})"
                );
            }
        }
    }
    // The separation figure never exceeds a true signed gap (core distance minus radii, negative
    // when the true shapes overlap): occupancies containing the true shapes can only lower it.
    // Twin only: the gap needs the sampled segment distance (split, proofs/README.md).
    if cfg!(kani) {
        return;
    }
    for h in &human {
        for c in &robot {
            let gap = segment_distance(c.p1, c.p2, h.p1, h.p2) - c.r - h.r;
            assert!(
                out.separation <= gap + 1e-6,
                "separation figure {} above a true signed gap {gap}",
                out.separation
            );
        }
    }
}

// The whole claim is the twin's (a Kani timeout at 3 bits, the capsule geometry of 3 × 2
// pairs); Kani checks it in parts: `i1_rule_judgement_sound` (the narrow phase for any masks
// containing the true contacts), `i1_broad_phase_boxes_contain` (the broad phase's boxes), and
// the capsule test's claims b1/b2.
harness!(
    i1_rule_sound,
    twin_only,
    cases = crate::DEFAULT_CASES,
    rule_sound
);

/// (i1, the Kani split) The narrow phase [`ContactRule::judge`] is sound for any contact masks
/// that contain the true contacts. Three robot capsules on frames 0–2 (one link each), two body
/// parts with any constraints (SSM, or PFL with any thresholds in [0, 1] J), the truly touched
/// capsules of each part any subset, the masks handed to the rule any supersets of them, a true
/// clamp by the environment or a clampable part any boolean and the geometry's flag any value
/// that reports it; true joint velocities (2 joints) inside the box, the true energy at most the
/// bound (or any energy when the bound is NaN, which the rule must read as +∞). If the rule
/// reports no violation: no SSM part truly touched while moving, no PFL part truly touched above
/// the threshold of its true contact type (pinched between two frames, or clamped).
///
/// What it leaves to the geometry's claims and to the twin `i1_rule_sound` (the whole `check`):
/// that the masks contain the true contacts (the broad phase's boxes contain the capsules,
/// `i1_broad_phase_boxes_contain`; `capsules_may_intersect` is conservative, b1/b2) and that the
/// clamping geometry reports true clamps (the same capsule test; `EnvShape::may_touch`).
fn judgement_sound<S: Source>(s: &mut S) {
    const PARTS: usize = 2;
    let frames = vec![s.index(3), s.index(3), s.index(3)];
    let mut constraints = vec![Constraint::Ssm; PARTS];
    for c in &mut constraints {
        if s.bool() {
            *c = Constraint::Pfl {
                unconstrained: s.f64_in(0.0, 1.0),
                constrained: s.f64_in(0.0, 1.0),
            };
        }
    }
    let rest_speed = s.f64_in(0.0, 0.05);
    let workspace = Capsule::new_unchecked(Point3::origin(), Point3::origin(), 1.0);
    let rule = ContactRule::from_tables(
        vec![0, 1, 2],
        frames.clone(),
        constraints.clone(),
        vec![false; PARTS * PARTS],
        vec![],
        rest_speed,
        workspace,
    )
    .expect("valid tables");
    // The truth and the (over-approximating) inputs of the narrow phase.
    let mut truth = [0u128; PARTS];
    let mut masks = [0u128; PARTS];
    let mut true_clamp = [false; PARTS];
    let mut clamp_flag = [false; PARTS];
    for p in 0..PARTS {
        truth[p] = s.index(8) as u128;
        masks[p] = truth[p] | s.index(8) as u128;
        true_clamp[p] = s.bool();
        clamp_flag[p] = true_clamp[p] || s.bool();
    }
    let mut dq_lo = [0.0; 2];
    let mut dq_hi = [0.0; 2];
    let mut dq = [0.0; 2];
    for j in 0..2 {
        dq_lo[j] = s.f64_in(-0.1, 0.1);
        dq_hi[j] = s.f64_in(dq_lo[j], 0.1);
        dq[j] = s.f64_in(dq_lo[j], dq_hi[j]);
    }
    let (e_bound, e_true) = if s.bool() {
        (f64::NAN, s.f64_in(0.0, 10.0))
    } else {
        let b = s.f64_in(0.0, 1.0);
        (b, s.f64_in(0.0, b))
    };
    let dq_box = JointBox::new(&dq_lo, &dq_hi).expect("ordered finite bounds");
    let verdict = rule.judge(
        &masks,
        &dq_box,
        || e_bound,
        |p| clamp_flag[p],
        |_| ControlFlow::Break(()),
    );
    if verdict.violated {
        return;
    }
    let moving = dq[0].abs() > rest_speed || dq[1].abs() > rest_speed;
    for p in 0..PARTS {
        if truth[p] == 0 {
            continue;
        }
        match constraints[p] {
            Constraint::Ssm => assert!(!moving, "SSM contact while moving passed"),
            c @ Constraint::Pfl { .. } => {
                let mut pinched = false;
                for a in 0..3 {
                    for b in 0..3 {
                        if truth[p] >> a & 1 == 1 && truth[p] >> b & 1 == 1 {
                            pinched |= frames[a] != frames[b];
                        }
                    }
                }
                let clamped = pinched || true_clamp[p];
                assert!(
                    e_true <= true_threshold(c, clamped),
                    "PFL contact above the true threshold passed (clamped: {clamped})"
                );
            }
        }
    }
}

harness!(
    i1_rule_judgement_sound,
    unwind = 5,
    cases = crate::DEFAULT_CASES,
    judgement_sound
);

/// (i1, the broad phase) The box the rule's broad phase puts around a capsule contains it: per
/// axis, the box's lower end is at most `sub_down(min(a, b), r)` and its upper end at least
/// `add_up(max(a, b), r)`, which bound the exact `min(a, b) − r` and `max(a, b) + r` (a1). So
/// boxes of two capsules that share a point overlap, and a pair the broad phase skips is
/// provably disjoint. Under Kani the first axis (the others 0: the code is the same per axis)
/// with 20-bit significands at any exponent (rounding still occurs: exponent gaps above 20);
/// the twin draws every axis and full-width values.
fn broad_phase_boxes<S: Source>(s: &mut S) {
    let c = broad_phase_capsule(s);
    let b = pacs_verify::iso15066::broad_phase_box(&c);
    assert!(
        pacs_verify::iso15066::box_contains_capsule(&c, &b),
        "box {b:?} does not reach min − r and max + r of {c:?}"
    );
}

/// A capsule for the broad phase's claims: endpoints and radius of any magnitude up to 1e300;
/// under Kani on the first axis only (the others 0: the code is the same per axis).
fn broad_phase_capsule<S: Source>(s: &mut S) -> Capsule {
    let a = s.f64_in(-1e300, 1e300);
    let b = s.f64_in(-1e300, 1e300);
    let r = s.f64_in(0.0, 1e300);
    let axis = if cfg!(kani) { 0 } else { s.index(3) };
    let mut p1 = [0.0; 3];
    let mut p2 = [0.0; 3];
    p1[axis] = a;
    p2[axis] = b;
    Capsule::new_unchecked(Point3::from(p1), Point3::from(p2), r)
}

/// `broad_phase_box`'s Kani contract (`box_contains_capsule`), proven on the real function for
/// the capsules of `i1_broad_phase_boxes_contain` (the first axis, 20-bit significands at any
/// exponent).
#[cfg(kani)]
#[kani::proof_for_contract(pacs_verify::iso15066::broad_phase_box)]
#[kani::unwind(4)]
fn i1_broad_phase_box_contract() {
    let c = broad_phase_capsule(&mut crate::KaniSource { bits: 20 });
    let _ = pacs_verify::iso15066::broad_phase_box(&c);
}

harness!(
    i1_broad_phase_boxes_contain,
    unwind = 4,
    bits = 20,
    cases = crate::DEFAULT_CASES,
    broad_phase_boxes
);

// ---------------------------------------------------------------------------------------------
// The rule's decision atoms: the threshold a contact is judged against, and an object contact's
// decision. Both carry Kani function contracts, proven here on the real functions.

/// A threshold or energy (J): any float (NaN, ±∞, subnormals included: any bit pattern, as in
/// h3), the twin biased toward the special values and small magnitudes.
fn any_joules<S: Source>(s: &mut S) -> f64 {
    match s.index(6) {
        0 => f64::NAN,
        1 => f64::INFINITY,
        2 => -0.0,
        3 => 0.0,
        4 => s.f64_in(0.0, 10.0),
        _ => f64::from_bits(s.index(usize::MAX) as u64),
    }
}

/// A constraint: SSM or PFL with any two thresholds.
fn any_constraint<S: Source>(s: &mut S) -> Constraint {
    if s.bool() {
        Constraint::Ssm
    } else {
        Constraint::Pfl {
            unconstrained: any_joules(s),
            constrained: any_joules(s),
        }
    }
}

/// A joint velocity box (rad/s) of up to `max_dof` joints with any finite bounds (`lo ≤ hi`).
fn any_velocity_box<S: Source>(s: &mut S, max_dof: usize) -> JointBox {
    let n = s.index(max_dof + 1);
    let (mut lo, mut hi) = ([0.0; 7], [0.0; 7]);
    for j in 0..n {
        let (a, b) = (any_joules(s), any_joules(s));
        (lo[j], hi[j]) = if a <= b { (a, b) } else { (b, a) };
    }
    match JointBox::new(&lo[..n], &hi[..n]) {
        Ok(b) => b,
        Err(_) => {
            s.assume(false);
            JointBox::empty()
        }
    }
}

/// An object's contact rule: no contact, SSM, or PFL with any threshold.
fn any_object_contact<S: Source>(s: &mut S) -> pacs_models::object::ObjectContact {
    use pacs_models::object::ObjectContact;
    match s.index(3) {
        0 => ObjectContact::NoContact,
        1 => ObjectContact::Ssm,
        _ => ObjectContact::Pfl {
            threshold: any_joules(s),
        },
    }
}

/// (i1, the decision atoms) For any constraint and clamp flag, the threshold `threshold` returns
/// is within the limits that apply (`threshold_within_limits`); `at_rest` holds only for a
/// velocity box whose every speed is within the rest speed (`every_speed_within`; the twin, up
/// to 7 joints: under Kani `i1_at_rest_contract`); for any object contact rule,
/// rest flag and energy, `contact_violates` reports no violation only where the rule allows the
/// contact (`contact_allowed_only_within_rule`). The claims of both functions' Kani contracts,
/// proven on the real functions by `i1_threshold_contract` and `i1_object_decision_contract`.
fn decision_atoms<S: Source>(s: &mut S) {
    use pacs_verify::iso15066::{
        contact_allowed_only_within_rule, contact_violates, every_speed_within, threshold,
        threshold_within_limits,
    };
    let c = any_constraint(s);
    let clamp = s.bool();
    let r = threshold(c, clamp);
    assert!(
        threshold_within_limits(c, clamp, r),
        "threshold {r} for {c:?} (clamp {clamp}) is above a limit that applies"
    );
    // Under Kani `at_rest` is `i1_at_rest_contract`'s (the velocity box makes this body too
    // slow for MiniSat, and Bitwuzla rejects CBMC's encoding of the box's float arrays).
    if !cfg!(kani) {
        let dq = any_velocity_box(s, 7);
        let rest = any_joules(s);
        assert!(
            !pacs_verify::iso15066::at_rest(&dq, rest) || every_speed_within(&dq, rest),
            "at rest with {dq:?} against rest speed {rest}"
        );
    }
    let contact = any_object_contact(s);
    let at_rest = s.bool();
    let e = any_joules(s);
    let out = contact_violates(contact, at_rest, || e);
    assert!(
        contact_allowed_only_within_rule(contact, at_rest, out),
        "{contact:?} at rest {at_rest} with energy {e}: {out:?} lets a contact pass"
    );
}

harness!(
    i1_decision_atoms_within_rule,
    unwind = 2,
    cases = crate::DEFAULT_CASES,
    decision_atoms
);

/// `threshold`'s Kani contract (`threshold_within_limits`), proven on the real function for every
/// constraint, clamp flag and pair of thresholds (any floats).
#[cfg(kani)]
#[kani::proof_for_contract(pacs_verify::iso15066::threshold)]
fn i1_threshold_contract() {
    let c = any_constraint(&mut crate::KaniSource { bits: 52 });
    let _ = pacs_verify::iso15066::threshold(c, kani::any());
}

/// `contact_violates`'s Kani contract (`contact_allowed_only_within_rule`), proven on the real
/// function for every contact rule, rest flag, threshold and energy (any floats).
#[cfg(kani)]
#[kani::proof_for_contract(pacs_verify::iso15066::contact_violates)]
fn i1_object_decision_contract() {
    let contact = any_object_contact(&mut crate::KaniSource { bits: 52 });
    let e: f64 = kani::any();
    let _ = pacs_verify::iso15066::contact_violates(contact, kani::any(), || e);
}

/// `at_rest`'s Kani contract (`every_speed_within`), proven on the real function for every
/// 7-joint velocity box any floats give (`JointBox::new` keeps the finite ones with `lo ≤ hi`)
/// and any rest speed (any float). Plain float arrays, not `KaniSource`: drawn through it the
/// box's arrays get an encoding Bitwuzla rejects. (A symbolic joint count, slicing the arrays,
/// is rejected too; fewer joints are the twin's, `i1_decision_atoms_within_rule`.)
#[cfg(kani)]
#[kani::proof_for_contract(pacs_verify::iso15066::at_rest)]
#[kani::unwind(9)]
fn i1_at_rest_contract() {
    let lo: [f64; 7] = kani::any();
    let hi: [f64; 7] = kani::any();
    if let Ok(dq) = JointBox::new(&lo, &hi) {
        let _ = pacs_verify::iso15066::at_rest(&dq, kani::any());
    }
}
