//! (c) Each human model's occupancy contains the position of any admissible motion at any time
//! of the queried interval.
//!
//! Admissible motion (module doc of `reach::human`): at `time − delay` each keypoint is within
//! `e_p` of its measured position (velocity within `e_v` of the measured one); afterwards speed
//! ≤ `v_max` (vel, pos, combined) and acceleration ≤ `a_max` (acc, combined); for `pos`, points of
//! an extremity's body parts stay within `length + thickness/2` of the base keypoint — unless the
//! measurement contradicts that (a measured keypoint farther than `length + thickness/2 + 2·e_p`
//! from the measured base), when only the speed bound is assumed. The set of
//! positions such motions reach at elapsed time T is exactly
//! - vel: Ball(p + e, v_max·T) over |e| ≤ e_p;
//! - acc: Ball(p + e + (v + ε)·T, ½·a_max·T²) over |e| ≤ e_p, |ε| ≤ e_v;
//! - combined: in both (we sample the acc set and keep samples also in the vel set);
//!
//! so sampling a point of these sets (lengths biased to the boundary) samples every reachable
//! position. A body-part point is a convex combination of its keypoints plus an offset ≤
//! thickness/2.
//!
//! Property test only (the whole claim: under Kani a one-arm `HumanModel` and
//! the sampled motions timed out). Its Kani proofs are the per-model splits beside the code,
//! `pacs_reach::human`'s `proofs.rs`: `c1_vel_reach`, `c1_pos_reach`, `c1_acc_ball_at`
//! (proofs/README.md: what they leave to this twin).

use crate::{Source, harness};
use nalgebra::{Point3, Vector3};
use pacs_models::{Capsule, default_human};
use pacs_reach::geometry::capsule_contains_point;
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}

fn occupancy<S: Source>(s: &mut S) {
    let kind = [
        HumanReachModel::Vel,
        HumanReachModel::Acc,
        HumanReachModel::Combined,
        HumanReachModel::Pos,
    ][s.index(4)];
    let (e_p, e_v, delay) = (s.f64_in(0.0, 0.05), s.f64_in(0.0, 0.3), s.f64_in(0.0, 0.1));
    let model = default_human()
        .with_uncertainty(e_p, e_v, delay)
        .expect("valid uncertainty");
    let (e_p, e_v, delay) = (
        model.measurement_error_pos(),
        model.measurement_error_vel(),
        model.delay(),
    );
    let n = model.keypoint_count();
    let part = s.index(model.body_parts().len());
    let bp = model.body_parts()[part].clone();
    // Only the two keypoints of the part matter; the others are measured anywhere.
    let mut pos = vec![[0.0; 3]; n];
    let mut vel = vec![[0.0; 3]; n];
    for k in [bp.from, bp.to] {
        pos[k] = s.vec3(-2.0, 2.0);
        vel[k] = s.vec3(-2.0, 2.0);
    }
    let m_time = s.f64_in(0.0, 10.0);
    let meas = HumanMeasurement::new(&model, m_time, &pos, Some(&vel)).expect("finite");
    // Query interval [t_a, t_b] starting no earlier than the measured state (time − delay).
    let t_a = s.f64_in(m_time - delay, m_time + 0.5);
    let t_b = t_a + s.f64_in(0.0, 0.5);
    let t = s.f64_in(t_a, t_b);
    // Elapsed time of the true motion at t (rounded down: never more motion than admissible).
    let elapsed = ((t - m_time) + delay).max(0.0) * (1.0 - 1e-12);
    let mut reach = HumanReach::new(model.clone(), kind);
    let mut caps = vec![
        Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        model.body_parts().len()
    ];
    reach
        .occupancy_into(&meas, t_a, t_b, &mut caps)
        .expect("valid query");
    // True keypoint positions at t.
    let mut truth = [[0.0; 3]; 2];
    // Either independent directions per error term, or one common direction (which reaches
    // the boundary of the sum of the balls).
    let aligned = s.bool();
    let dir = s.vec3(-1.0, 1.0);
    let ball = |s: &mut S, r: f64| {
        if aligned {
            s.in_ball_along(dir, r)
        } else {
            s.in_ball(r)
        }
    };
    for (slot, k) in [bp.from, bp.to].into_iter().enumerate() {
        let start = add(pos[k], ball(s, e_p));
        let vel_pos = add(start, ball(s, model.v_max()[k] * elapsed));
        let acc_pos = add(
            add(start, scale(add(vel[k], ball(s, e_v)), elapsed)),
            ball(s, 0.5 * model.a_max()[k] * elapsed * elapsed),
        );
        truth[slot] = match kind {
            HumanReachModel::Vel | HumanReachModel::Pos => vel_pos,
            HumanReachModel::Acc => acc_pos,
            HumanReachModel::Combined => {
                // Keep acc samples that also respect the speed bound's set (with margin).
                let d = Vector3::from(acc_pos) - Vector3::from(pos[k]);
                let r = (e_p + model.v_max()[k] * elapsed) * (1.0 - 1e-9);
                if !s.assume(d.norm_squared() <= r * r) {
                    return;
                }
                acc_pos
            }
        };
    }
    let lambda = s.f64_in(0.0, 1.0);
    let mut point = add(
        add(scale(truth[0], 1.0 - lambda), scale(truth[1], lambda)),
        ball(s, 0.5 * bp.thickness),
    );
    // The pos model's assumption holds only for measurements that do not contradict it (every
    // measured keypoint of the extremity, with its part's own radius, within length +
    // thickness/2 + 2·e_p of the measured base); a contradicted measurement falls back to the
    // speed bound (vel samples above).
    let extremity = model
        .extremities()
        .iter()
        .find(|e| e.body_parts.contains(&part))
        .filter(|e| {
            let limit = e.length + 0.5 * e.thickness + 2.0 * e_p;
            let base = Vector3::from(pos[e.base]);
            let worst = e
                .body_parts
                .iter()
                .flat_map(|&q| {
                    let b = &model.body_parts()[q];
                    [(b.from, b.thickness), (b.to, b.thickness)]
                })
                .map(|(k, th)| {
                    pacs_reach::ieee::sqrt((Vector3::from(pos[k]) - base).norm_squared()) + 0.5 * th
                })
                .fold(0.0, f64::max);
            worst <= limit
        });
    if kind == HumanReachModel::Pos
        && let Some(e) = extremity
    {
        // Any point within length + thickness/2 of the (admissibly moving) base keypoint.
        let b = e.base;
        let base = if b == bp.from || b == bp.to {
            truth[if b == bp.from { 0 } else { 1 }]
        } else {
            pos[b] // measured at 0 with zero velocity: move it admissibly
        };
        let base = if b == bp.from || b == bp.to {
            base
        } else {
            add(add(base, ball(s, e_p)), ball(s, model.v_max()[b] * elapsed))
        };
        point = add(base, ball(s, e.length + 0.5 * e.thickness));
    }
    let p = Point3::from(point);
    assert!(
        capsule_contains_point(&caps[part], &p),
        "{kind:?}: part {part} point {p:?} at t={t} ∉ {:?} (measured {m_time}, [{t_a}, {t_b}], delay {delay})",
        caps[part]
    );
}
harness!(
    c1_human_occupancy_contains_motion,
    twin_only,
    cases = crate::DEFAULT_CASES,
    occupancy
);
