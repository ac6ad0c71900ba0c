//! Records checked against records: the consistency of each human or object measurement with
//! the model beside the others kept (a record that the others contradict makes the audit
//! inconclusive over the stamps between them; [`super::Auditor`]'s `push_human` and
//! `push_object` call these). Every test is conservative: distances rounded up, allowances
//! rounded down, and the quick accepts in plain floats only where their rounding error is far
//! inside a 1e-9 margin, so rounding never hides a contradiction.

use super::*;

/// `(min, max)` of two times.
pub(super) fn order(a: f64, b: f64) -> (f64, f64) {
    (a.min(b), a.max(b))
}

/// The stamps of the records that contradict a new record at `t`, reduced to the nearest one at
/// or before `t` and the nearest one after it: the break is reported over the shortest spans of
/// time it is known to lie in.
pub(super) struct Nearest {
    t: f64,
    before: Option<f64>,
    after: Option<f64>,
}

impl Nearest {
    pub(super) fn new(t: f64) -> Self {
        Self {
            t,
            before: None,
            after: None,
        }
    }

    pub(super) fn add(&mut self, s: f64) {
        if s <= self.t {
            self.before = Some(self.before.map_or(s, |b| b.max(s)));
        } else {
            self.after = Some(self.after.map_or(s, |a| a.min(s)));
        }
    }

    /// `(t_start, t_end)` of each break found (none, one or two).
    pub(super) fn pairs(&self) -> impl Iterator<Item = (f64, f64)> + use<> {
        let t = self.t;
        self.before
            .map(|b| order(b, t))
            .into_iter()
            .chain(self.after.map(|a| order(t, a)))
    }
}

/// Whether two measurements of one person contradict the human model: some keypoint moved
/// farther than `v_max·|Δt| + 2·e_pos` (m) between their stamps ([`keypoint_breaks`] for each
/// keypoint and its own `v_max`).
pub(super) fn human_pair_breaks(
    model: &HumanModel,
    a: &HumanMeasurement,
    b: &HumanMeasurement,
) -> bool {
    let (lo, hi) = order(a.time(), b.time());
    let e_pos = model.measurement_error_pos();
    let pairs = || {
        a.positions()
            .iter()
            .zip(b.positions())
            .zip(model.v_max())
            .map(|((p, q), &v)| ([p.x, p.y, p.z], [q.x, q.y, q.z], v))
    };
    // Most pairs are accepted by every keypoint's plain-float test at once; only a pair one of
    // them does not accept is decided keypoint by keypoint.
    !keypoints_within_plain(pairs(), lo, hi, e_pos)
        && pairs().any(|(p, q, v)| keypoint_breaks(p, q, v, lo, hi, e_pos))
}

/// Whether every keypoint `(p, q, v)` of a pair of records passes the plain-float accept of
/// [`keypoint_breaks`] ([`keypoint_within_plain`]), all evaluated without early exit: true only
/// if `‖p − q‖ ≤ v·(hi − lo) + 2·e_pos` exactly for every one of them.
///
/// # Soundness
/// Claim C9 (the consistency check's fast accept): harness `h3_keypoints_accept_sound` (Kani on
/// grids of dyadic values with two keypoints; the twin nine keypoints at full width with the
/// exact oracle); mutant `x86` (the pair accepted where any one keypoint is) fails it.
#[inline]
fn keypoints_within_plain(
    pairs: impl Iterator<Item = ([f64; 3], [f64; 3], f64)>,
    lo: f64,
    hi: f64,
    e_pos: f64,
) -> bool {
    let mut all_within = true;
    for (p, q, v) in pairs {
        all_within &= keypoint_within_plain(p, q, v, lo, hi, e_pos);
    }
    all_within
}

/// Whether one keypoint, at `p` at one stamp and at `q` at the other (m; stamps `lo ≤ hi`, s),
/// moved farther than `v·(hi − lo) + 2·e_pos` (m; `v` its speed bound, m/s, `e_pos` the
/// position error, m, both ≥ 0).
///
/// # Soundness
/// Claim C9 (the audit's record-against-record consistency): false only if
/// `‖p − q‖ ≤ v·(hi − lo) + 2·e_pos` exactly. Conservative both ways: the distance rounded up,
/// the allowance rounded down, so rounding never hides a contradiction (one within an ulp is
/// flagged too). Harness `h3_keypoint_pair_sound` (Kani on grids of dyadic values, where the
/// decision's terms are exact, with `dist3_up` any upper bound (C1 makes it one); the twin at
/// full width with the exact oracle); mutant `x64` fails it.
#[inline(always)]
pub(crate) fn keypoint_breaks(
    p: [f64; 3],
    q: [f64; 3],
    v: f64,
    lo: f64,
    hi: f64,
    e_pos: f64,
) -> bool {
    // Equal positions moved by 0 m, within any allowance (≥ 0): an exact duplicate of a record
    // is no contradiction, even where outward rounding of a zero distance would exceed a zero
    // allowance (no measurement error, equal stamps).
    if p == q {
        return false;
    }
    if keypoint_within_plain(p, q, v, lo, hi, e_pos) {
        return false;
    }
    let dt = sub_down(hi, lo).max(0.0);
    let allowed = add_down(mul_down(v, dt), mul_down(2.0, e_pos));
    dist3_up(&p, &q) > allowed
}

/// The fast accept of [`keypoint_breaks`] in plain floats: true only if
/// `‖p − q‖ ≤ v·(hi − lo) + 2·e_pos` exactly (arguments as there). The squared distance and the
/// squared allowance (three rounded operations from exact values) each carry a relative
/// rounding error of a few ε, far inside the 1e-9 margin, so a pair accepted here is within the
/// allowance exactly. Only where neither overflows (d² finite) nor underflows (allowance
/// ≥ 1e-150, so its square is normal and an underflowed d² is far below it); false otherwise
/// (the caller decides by the outward-rounded distance and allowance). Evaluated for every
/// keypoint of a pair at once by [`keypoints_within_plain`]. Checked with `keypoint_breaks` by
/// `h3_keypoint_pair_sound`, and for several keypoints by `h3_keypoints_accept_sound`.
#[inline(always)]
fn keypoint_within_plain(p: [f64; 3], q: [f64; 3], v: f64, lo: f64, hi: f64, e_pos: f64) -> bool {
    let plain = v * (hi - lo).max(0.0) + 2.0 * e_pos;
    let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    let d2 = dx * dx + dy * dy + dz * dz;
    plain >= 1e-150 && d2.is_finite() && d2 <= plain * plain * (1.0 - 1e-9)
}

/// The axis-aligned bounding box of a measurement's keypoints (m): `[min x, min y, min z, max
/// x, max y, max z]`.
#[derive(Debug, Clone, Copy)]
pub(super) struct KeypointBox([f64; 6]);

impl KeypointBox {
    pub(super) fn of(m: &HumanMeasurement) -> Self {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in m.positions() {
            for (k, x) in [p.x, p.y, p.z].into_iter().enumerate() {
                b[k] = b[k].min(x);
                b[k + 3] = b[k + 3].max(x);
            }
        }
        Self(b)
    }
}

/// A quick accept for [`human_pair_breaks`]: true only if no keypoint of `a` and `b` moved more
/// than the least allowance of any keypoint (`v_min · |Δt| + e2`, `v_min` the least of the
/// model's `v_max`, `e2` twice its position error), shown by the diagonal of the box holding both
/// measurements' keypoints, which bounds every keypoint's displacement ([`boxes_within`]). False
/// says nothing; the caller then applies [`human_pair_breaks`].
pub(super) fn pair_within_boxes(
    v_min: f64,
    e2: f64,
    a: &HumanMeasurement,
    b: &HumanMeasurement,
    ba: &KeypointBox,
    bb: &KeypointBox,
) -> bool {
    boxes_within(v_min, e2, (a.time() - b.time()).abs(), &ba.0, &bb.0)
}

/// Whether every point of the box `ba` is within `v_min·dt + e2` (m) of every point of `bb`
/// (boxes `[min x, min y, min z, max x, max y, max z]`, m; `dt` the stamps' distance, s): the
/// diagonal of the box holding both, in plain floats, with the margin and the range conditions
/// of the fast accept in [`keypoint_breaks`] (relative rounding errors of a few ε, far inside
/// 1e-9).
///
/// # Soundness
/// Claim C9 (the fast accept of the consistency check): true only if `‖p − q‖ ≤ v_min·dt + e2`
/// exactly for every `p` in `ba` and `q` in `bb` (so no keypoint pair the accept skips breaks
/// [`keypoint_breaks`]'s allowance, whose speed bound is ≥ `v_min`). Harness
/// `h3_box_accept_sound` (Kani on grids of dyadic values; the twin at full width with the exact
/// oracle); mutant `x66` fails it. Property test `the_box_accept_of_a_human_pair_is_sound`
/// (against [`human_pair_breaks`]).
#[inline]
pub(crate) fn boxes_within(v_min: f64, e2: f64, dt: f64, ba: &[f64; 6], bb: &[f64; 6]) -> bool {
    let allowed = v_min * dt + e2;
    let mut d2 = 0.0;
    for k in 0..3 {
        let e = ba[k + 3].max(bb[k + 3]) - ba[k].min(bb[k]);
        d2 += e * e;
    }
    allowed >= 1e-150 && d2.is_finite() && d2 <= allowed * allowed * (1.0 - 1e-9)
}

/// A Euclidean norm rounded down (`pacs_reach::rounding::norm3_down`, harness a3).
pub(super) fn norm3_down(v: [f64; 3]) -> f64 {
    pacs_reach::rounding::norm3_down(v[0], v[1], v[2])
}

/// An upper bound of the norm of every acceleration in an object's acceleration set (m/s²):
/// |bias| + Σ|generators| + `max_acc` (triangle inequality), each norm rounded down, so the
/// bound is below the exact one by ulps at most (a check using it flags within-ulp cases too).
pub(super) fn object_acc_bound(model: &ObjectModel) -> f64 {
    let mut acc = norm3_down(model.acc_bias());
    for g in model.acc_generators() {
        acc = add_down(acc, norm3_down(*g));
    }
    add_down(acc, model.max_acc())
}

/// Whether one measurement of an object contradicts its model: a measured velocity faster than
/// the speed bound plus the velocity error (the true velocity is within `vel_error` of it and
/// never faster than `max_speed`). Rounding never hides a contradiction ([`velocity_breaks`]).
pub(super) fn object_record_breaks(model: &ObjectModel, m: &ObjectMeasurement) -> bool {
    match (model.max_speed(), m.velocity) {
        (Some(vmax), Some(v)) => velocity_breaks(v, vmax, model.vel_error()),
        _ => false,
    }
}

/// Whether a measured velocity `v` (m/s) is faster than `vmax + ev` (m/s, both ≥ 0).
///
/// # Soundness
/// Claim C9: false only if `‖v‖ ≤ vmax + ev` exactly (the norm rounded up, the bound down).
/// Harness `h3_object_record_sound`; mutant `x57` fails it.
#[inline]
pub(crate) fn velocity_breaks(v: [f64; 3], vmax: f64, ev: f64) -> bool {
    norm3_up(v[0], v[1], v[2]) > add_down(vmax, ev)
}

/// What [`object_pair_breaks`] needs of an object model: the bound of every acceleration
/// ([`object_acc_bound`], m/s²), the speed bound (m/s) if any, and the velocity and position
/// errors (m/s, m), all ≥ 0.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ObjectBounds {
    pub(crate) acc: f64,
    pub(crate) max_speed: Option<f64>,
    pub(crate) vel_error: f64,
    pub(crate) pos_error: f64,
}

impl ObjectBounds {
    pub(crate) fn of(model: &ObjectModel) -> Self {
        Self {
            acc: object_acc_bound(model),
            max_speed: model.max_speed(),
            vel_error: model.vel_error(),
            pos_error: model.pos_error(),
        }
    }
}

/// Whether two measurements of one object, `early` stamped no later than `late`, contradict its
/// model's bounds `b` (both describe the state `delay` before their stamps, so `Δt` is the
/// stamps' difference):
/// - velocities, where both are measured, farther apart than `a·Δt + 2·vel_error`;
/// - positions farther apart than the model allows over `Δt` plus twice the position error:
///   the smallest of `max_speed·Δt` (with a speed bound) and `(|v| + vel_error)·Δt + a·Δt²/2`
///   for each measured velocity `v` (forward from the early one, backward from the late one);
///   with none of these the model bounds nothing and no pair contradicts it.
///
/// # Soundness
/// Claim C9: false only if each of these holds exactly (allowances rounded down, distances and
/// norms bounded from the safe side: rounding never hides a contradiction). Harness
/// `h3_object_pair_sound`: its twin checks the whole function at full width with the exact
/// oracle, its Kani proof the velocity test ([`velocities_break`], on grids of dyadic values);
/// mutants `x56` (the velocity test dropped) and `x53` (the check dropped in the auditor, by the
/// audit's tests) fail.
pub(crate) fn object_pair_breaks(
    b: &ObjectBounds,
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
) -> bool {
    !object_pair_within_plain(b, early, late) && object_pair_breaks_rounded(b, early, late)
}

/// [`object_pair_breaks`] without its fast accept: each test with outward rounding.
fn object_pair_breaks_rounded(
    b: &ObjectBounds,
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
) -> bool {
    let dt = sub_down(late.time, early.time).max(0.0);
    let (acc, ev) = (b.acc, b.vel_error);
    if let (Some(a), Some(v)) = (early.velocity, late.velocity)
        && velocities_break(&a, &v, acc, dt, ev)
    {
        return true;
    }
    // Equal positions are within any allowance (exact duplicates are no contradiction).
    if early.position == late.position {
        return false;
    }
    let by_speed = b.max_speed.map(|v| mul_down(v, dt));
    let by_velocity = [early.velocity, late.velocity]
        .into_iter()
        .flatten()
        .map(|v| {
            let speed = add_down(norm3_down(v), ev);
            add_down(
                mul_down(speed, dt),
                mul_down(mul_down(0.5, acc), mul_down(dt, dt)),
            )
        })
        .reduce(f64::min);
    let allowed = match (by_speed, by_velocity) {
        (Some(a), Some(b)) => a.min(b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => return false,
    };
    let allowed = add_down(allowed, mul_down(2.0, b.pos_error));
    dist3_up(&early.position, &late.position) > allowed
}

/// The fast accept of [`object_pair_breaks`] in plain floats (arguments as there): true only
/// if, exactly, the velocities (where both are measured) are within `a·Δt + 2·vel_error` of each
/// other and the positions within the least allowance plus `2·pos_error`. Each squared distance
/// and each allowance is a sum of non-negative terms computed from exact values in a few
/// rounded operations (the norm of a velocity through `√`, correctly rounded), so each carries
/// a relative error of a few ε, far inside the 1e-9 margin; with an allowance ≥ 1e-135 (its
/// square normal) and a finite squared distance an underflow cannot matter either (as in
/// [`keypoint_within_plain`]). The bound 1e-135 also keeps the outward-rounded distance's
/// absolute slack (1e-150, `SQRT_TINY`) below 1e-15 of the allowance, so a pair accepted here
/// is one the outward-rounded tests accept too: the accept changes no verdict. False
/// otherwise: the caller then decides with outward rounding. Checked with [`object_pair_breaks`] by `h3_object_pair_sound`'s twin (the
/// exact oracle, on pairs drawn near each allowance) and by
/// `the_plain_accept_of_an_object_pair_is_sound`; mutant `x87` (the position allowance
/// doubled) fails them.
#[inline]
fn object_pair_within_plain(
    b: &ObjectBounds,
    early: &ObjectMeasurement,
    late: &ObjectMeasurement,
) -> bool {
    let within = |p: &[f64; 3], q: &[f64; 3], allowed: f64| {
        let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
        let d2 = dx * dx + dy * dy + dz * dz;
        allowed >= 1e-135 && d2.is_finite() && d2 <= allowed * allowed * (1.0 - 1e-9)
    };
    let dt = (late.time - early.time).max(0.0);
    let (acc, ev) = (b.acc, b.vel_error);
    if let (Some(a), Some(v)) = (early.velocity, late.velocity)
        && !within(&a, &v, acc * dt + 2.0 * ev)
    {
        return false;
    }
    let by_speed = b.max_speed.map(|v| v * dt);
    let by_velocity = [early.velocity, late.velocity]
        .into_iter()
        .flatten()
        .map(|v| {
            ((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() + ev) * dt + 0.5 * acc * (dt * dt)
        })
        .reduce(f64::min);
    let allowed = match (by_speed, by_velocity) {
        (Some(a), Some(b)) => a.min(b),
        (Some(a), None) | (None, Some(a)) => a,
        // Nothing bounds the positions: `object_pair_breaks` decides by the velocities alone.
        (None, None) => return true,
    };
    within(&early.position, &late.position, allowed + 2.0 * b.pos_error)
}

/// Whether two measured velocities `a`, `v` (m/s) of one object, stamped `dt` (s, at most the
/// stamps' real difference) apart, differ by more than `acc·dt + 2·ev` (`acc`: the bound of
/// every acceleration, m/s²; `ev`: the velocity error, m/s; all ≥ 0).
///
/// # Soundness
/// Claim C9: false only if `‖a − v‖ ≤ acc·dt + 2·ev` exactly (the distance rounded up, the
/// allowance down). Harness `h3_object_pair_sound` (Kani: this test, on grids of dyadic values;
/// the twin: the whole [`object_pair_breaks`]); mutant `x56` fails it.
#[inline]
pub(crate) fn velocities_break(a: &[f64; 3], v: &[f64; 3], acc: f64, dt: f64, ev: f64) -> bool {
    a != v && dist3_up(a, v) > add_down(mul_down(acc, dt), mul_down(2.0, ev))
}

#[cfg(any(test, kani))]
mod proofs;

#[cfg(test)]
mod tests {
    use super::*;

    /// `p` moved by `len` (m) along the direction `d` (any non-zero vector).
    fn moved_along(p: &[f64; 3], d: [f64; 3], len: f64) -> [f64; 3] {
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-300);
        [
            p[0] + d[0] / n * len,
            p[1] + d[1] / n * len,
            p[2] + d[2] / n * len,
        ]
    }

    /// The box accept never hides a contradiction: wherever `pair_within_boxes` accepts a pair,
    /// `human_pair_breaks` (the reference) finds none; and it accepts most pairs far apart in
    /// time (what it is for). 20 000 random pairs of the default model's keypoints, moved up to
    /// 2× the allowance, at time differences from 0 to 2 s.
    #[test]
    fn the_box_accept_of_a_human_pair_is_sound() {
        let model = HumanModel::builtin("default").unwrap();
        let mut next = uniform(0x9e37_79b9_7f4a_7c15u64);
        let (mut accepted, mut far, mut far_accepted) = (0, 0, 0);
        for _ in 0..20_000 {
            let dt = 2.0 * next() * next();
            let size = 2.0 * next();
            let base: Vec<[f64; 3]> = (0..9)
                .map(|_| [next() * size, next() * size, 1.0 + next() * size])
                .collect();
            let reach = 2.0 * (2.0 * dt + 2.0 * model.measurement_error_pos()) * next();
            let moved: Vec<[f64; 3]> = base
                .iter()
                .map(|p| {
                    let d = [next() - 0.5, next() - 0.5, next() - 0.5];
                    moved_along(p, d, reach * next())
                })
                .collect();
            let (Ok(a), Ok(b)) = (
                HumanMeasurement::new(&model, 0.0, &base, None),
                HumanMeasurement::new(&model, dt, &moved, None),
            ) else {
                continue;
            };
            let v_min = model.v_max().iter().copied().fold(f64::INFINITY, f64::min);
            let e2 = 2.0 * model.measurement_error_pos();
            let quick = pair_within_boxes(
                v_min,
                e2,
                &a,
                &b,
                &KeypointBox::of(&a),
                &KeypointBox::of(&b),
            );
            if quick {
                accepted += 1;
                assert!(
                    !human_pair_breaks(&model, &a, &b),
                    "dt {dt}, size {size}: accepted a contradicting pair"
                );
            }
            // Far apart in time, a person of up to 0.5 m moved by at most a quarter of the
            // allowance: the box diagonal is within it, so the box accepts.
            let allowance = 2.0 * dt + 2.0 * model.measurement_error_pos();
            if dt > 1.0 && size < 0.5 && reach < 0.25 * allowance {
                far += 1;
                far_accepted += quick as usize;
            }
        }
        assert!(accepted > 1_000, "{accepted}");
        assert!(far > 50 && far_accepted == far, "{far_accepted} of {far}");
    }

    /// The fast accept in `human_pair_breaks` is sound: a pair it accepts is within the
    /// allowance by the outward-rounded test applied to the same pair scaled by a power of two
    /// into the unit range (exact scaling, where the rounded test's absolute error terms are
    /// negligible). 20 000 random pairs at scales from 1e-160 to 1e150 m, a third of them with
    /// a keypoint within a relative 1e-12 of the allowance, where rounding decides; where the
    /// fast path does not accept, the answer is the rounded test's.
    /// The plain-float accept of an object pair never accepts a pair the outward-rounded tests
    /// flag: 30,000 random pairs at scales from 1e-160 to 1e150, with or without a speed bound
    /// and velocities, moved to within the allowances, to ±1e-12 of them, or up to twice them;
    /// and it accepts most pairs well inside (what it is for).
    #[test]
    fn the_plain_accept_of_an_object_pair_is_sound() {
        let mut next = uniform(0x6a09_e667_f3bc_c909u64);
        let (mut accepted, mut inside, mut inside_accepted) = (0, 0, 0);
        for i in 0..30_000 {
            let scale = 10f64.powf(-160.0 + 310.0 * next());
            let dt = scale * next();
            let b = ObjectBounds {
                acc: 16.0 * next(),
                max_speed: (i % 4 != 0).then(|| 3.0 * next()),
                vel_error: 0.05 * next() * next(),
                pos_error: 0.05 * next() * next() * scale,
            };
            let dir = |next: &mut dyn FnMut() -> f64| [next() - 0.5, next() - 0.5, next() - 0.5];
            let velocity = |next: &mut dyn FnMut() -> f64| {
                (next() < 0.6).then(|| {
                    let d = dir(next);
                    moved_along(&[0.0; 3], d, 3.0 * next())
                })
            };
            let ev = velocity(&mut next);
            let vb = b.acc * dt + 2.0 * b.vel_error;
            let lv = match ev {
                Some(v) if next() < 0.7 => {
                    let d = dir(&mut next);
                    Some(moved_along(
                        &v,
                        d,
                        vb * (1.0 + 1e-12 * (2.0 * next() - 1.0)) * next(),
                    ))
                }
                _ => velocity(&mut next),
            };
            let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            let allowed = [b.max_speed.map(|v| v * dt)]
                .into_iter()
                .chain(
                    [ev, lv]
                        .into_iter()
                        .map(|v| v.map(|v| (norm(v) + b.vel_error) * dt + 0.5 * b.acc * dt * dt)),
                )
                .flatten()
                .reduce(f64::min)
                .unwrap_or(scale)
                + 2.0 * b.pos_error;
            let p = [next() * scale, next() * scale, next() * scale];
            let k = match i % 3 {
                0 => next(),
                1 => 1.0 + 1e-12 * (2.0 * next() - 1.0),
                _ => 2.0 * next(),
            };
            let d = dir(&mut next);
            let q = moved_along(&p, d, allowed * k);
            let (early, late) = (
                ObjectMeasurement {
                    time: 0.0,
                    position: p,
                    velocity: ev,
                },
                ObjectMeasurement {
                    time: dt,
                    position: q,
                    velocity: lv,
                },
            );
            let accept = object_pair_within_plain(&b, &early, &late);
            if accept {
                accepted += 1;
                assert!(
                    !object_pair_breaks_rounded(&b, &early, &late),
                    "case {i}, scale {scale}: accepted a pair the rounded tests flag: {b:?} {early:?} {late:?}"
                );
            }
            if k < 0.9 && allowed >= 1e-130 && lv.is_none_or(|_| ev.is_none()) {
                inside += 1;
                inside_accepted += accept as usize;
            }
        }
        assert!(accepted > 8_000, "{accepted}");
        assert!(
            inside_accepted * 10 > inside * 9,
            "{inside_accepted} of {inside}"
        );
    }

    #[test]
    fn the_fast_accept_of_a_human_pair_is_sound() {
        let model = HumanModel::builtin("default").unwrap();
        let mut next = uniform(0x2545_f491_4f6c_dd1du64);
        let (mut breaks, mut cases) = (0, 0);
        for i in 0..20_000 {
            let scale = 10f64.powf(-160.0 + 310.0 * next());
            let dt = scale * next();
            let v = model.v_max()[0];
            let base: Vec<[f64; 3]> = (0..9)
                .map(|_| [next() * scale, next() * scale, next() * scale])
                .collect();
            let moved: Vec<[f64; 3]> = base
                .iter()
                .enumerate()
                .map(|(j, p)| {
                    // A direction, and a length: within the allowance (one case in three), at it
                    // (±1e-12) for the first keypoint and half of it for the others, or anywhere
                    // up to 2× for one keypoint.
                    let d = [next() - 0.5, next() - 0.5, next() - 0.5];
                    let len = match (i % 3, j) {
                        (0, _) => v * dt * next(),
                        (1, 0) => v * dt * (1.0 + 1e-12 * (2.0 * next() - 1.0)),
                        (2, 0) => 2.0 * v * dt * next(),
                        _ => 0.5 * v * dt,
                    };
                    moved_along(p, d, len)
                })
                .collect();
            let (Ok(a), Ok(b)) = (
                HumanMeasurement::new(&model, 0.0, &base, None),
                HumanMeasurement::new(&model, dt, &moved, None),
            ) else {
                continue;
            };
            let got = human_pair_breaks(&model, &a, &b);
            // The rounded test on the pair scaled by 2^k (exact) into the unit range.
            let k = -(scale.log2().round() as i32);
            let f = 2f64.powi(k);
            let e2 = mul_down(2.0, model.measurement_error_pos());
            let allowed = add_down(mul_down(v, sub_down(dt, 0.0).max(0.0)), e2) * f;
            let reference = base.iter().zip(&moved).any(|(p, q)| {
                let (ps, qs) = (
                    [p[0] * f, p[1] * f, p[2] * f],
                    [q[0] * f, q[1] * f, q[2] * f],
                );
                dist3_up(&ps, &qs) > allowed
            });
            if !got {
                assert!(
                    !reference,
                    "case {i}, scale {scale}: accepted a pair beyond the allowance"
                );
            }
            let rounded = base
                .iter()
                .zip(&moved)
                .zip(model.v_max())
                .any(|((p, q), v)| {
                    dist3_up(p, q) > add_down(mul_down(*v, sub_down(dt, 0.0).max(0.0)), e2)
                });
            if got {
                assert!(rounded, "case {i}: flagged what the rounded test does not");
            }
            breaks += got as usize;
            cases += 1;
        }
        assert!(
            cases > 19_000 && breaks > cases / 5 && breaks < cases / 2,
            "{breaks} of {cases}"
        );
    }
}
