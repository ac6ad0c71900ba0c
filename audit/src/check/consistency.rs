//! Records checked against records: the consistency of each human or object measurement with
//! the model beside the others kept (a record that the others contradict makes the audit
//! inconclusive over the stamps between them; [`super::Auditor`]'s `push_human` and
//! `push_object` call these). Every test is conservative: distances rounded up, allowances
//! rounded down, and the quick accepts in plain floats only where their rounding error is far
//! inside a 1e-9 margin, so rounding never hides a contradiction.

use super::*;
// The record-against-record test of a person's measurements is the shield's too: it lives
// beside the human occupancy (`pacs_reach::human::consistency`).
pub(super) use pacs_reach::human::consistency::human_pair_breaks;
pub(crate) use pacs_reach::human::consistency::squared_within;
// The record-against-record test of an object's measurements is the shield's too: it lives
// beside the object occupancy (`pacs_reach::object::consistency`).
pub(crate) use pacs_reach::object::consistency::{ObjectBounds, object_pair_breaks};
// (Checked by the harnesses and tests beside this module.)
#[cfg(any(test, kani))]
pub(crate) use pacs_reach::human::consistency::{
    keypoint_breaks, keypoint_within_plain, keypoints_within_plain, within_plain,
};
#[cfg(test)]
pub(crate) use pacs_reach::object::consistency::object_pair_breaks_rounded;
#[cfg(any(test, kani))]
pub(crate) use pacs_reach::object::consistency::{object_pair_within_plain, velocities_break};
#[cfg(test)]
use pacs_reach::rounding::{dist3_up, mul_down};

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
    let mut d2 = 0.0;
    for k in 0..3 {
        let e = ba[k + 3].max(bb[k + 3]) - ba[k].min(bb[k]);
        d2 += e * e;
    }
    squared_within(d2, v_min * dt + e2)
}

/// A Euclidean norm rounded down (`pacs_reach::rounding::norm3_down`, harness a3).
#[cfg(any(test, kani))]
pub(super) fn norm3_down(v: [f64; 3]) -> f64 {
    pacs_reach::rounding::norm3_down(v[0], v[1], v[2])
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

/// What the records let go from a history of [`crate::check::HUMAN_HISTORY`] still require of
/// every later record, in constant memory: per point (a keypoint, or an object's reference
/// point) and axis, the least `p − v·t_r` and the largest `p + v·t_r` over the records let go
/// (position `p`, m; stamp `t_r`, s; `v` the point's speed bound, m/s). A record at `t ≥` every
/// let-go stamp agrees with each of them only if, per axis, `q − v·t − 2e ≤ min(p − v·t_r)` and
/// `q + v·t + 2e ≥ max(p + v·t_r)` (`|q − p| ≤ v·(t − t_r) + 2e` per axis, implied by the pair
/// test's distance bound). Without it, a chain of records each within the allowance of the 64
/// kept ones could drift away from one let go (66 records, the last 0.145 m from the first
/// where 0.1 m is allowed). A necessary condition only (per axis, the speed
/// bound alone), lenient (a relative margin of 10⁻¹²): it never flags a log that agrees with its
/// model.
///
/// # Soundness
/// Test `audit_consistency.rs::records_drifting_from_one_let_go_break_the_model`; mutant `x104`.
#[derive(Debug, Clone)]
pub(crate) struct LetGo {
    lo: Vec<[f64; 3]>,
    hi: Vec<[f64; 3]>,
    /// Times are taken from the first let-go stamp (s), so that `v·t` stays small at Unix-time
    /// stamps and the margin with it.
    base: Option<f64>,
}

impl LetGo {
    /// Nothing let go yet, for `points` points per record.
    pub(crate) fn new(points: usize) -> Self {
        LetGo {
            lo: vec![[f64::INFINITY; 3]; points],
            hi: vec![[f64::NEG_INFINITY; 3]; points],
            base: None,
        }
    }

    /// A record stamped `t` let go: its points `(position, speed bound)`.
    pub(crate) fn add(&mut self, t: f64, points: impl Iterator<Item = ([f64; 3], f64)>) {
        let t = t - *self.base.get_or_insert(t);
        for ((p, v), (lo, hi)) in points.zip(self.lo.iter_mut().zip(self.hi.iter_mut())) {
            let vt = v * t;
            for i in 0..3 {
                lo[i] = lo[i].min(p[i] - vt);
                hi[i] = hi[i].max(p[i] + vt);
            }
        }
    }

    /// Whether a record stamped `t` (at or after every let-go stamp) with its points
    /// `(position, speed bound)` contradicts a let-go record (`e2`: twice the position error, m).
    pub(crate) fn breaks(
        &self,
        t: f64,
        e2: f64,
        points: impl Iterator<Item = ([f64; 3], f64)>,
    ) -> bool {
        let Some(base) = self.base else {
            return false;
        };
        // The stamps' own rounding from the base (each difference within an ulp of the larger
        // stamp), times the speed bound, joins the relative margin.
        let dt_err = 4.0 * f64::EPSILON * t.abs().max(base.abs());
        let t = t - base;
        let mut broken = false;
        for ((q, v), (lo, hi)) in points.zip(self.lo.iter().zip(&self.hi)) {
            let vt = v * t;
            for i in 0..3 {
                if !(lo[i].is_finite() && hi[i].is_finite()) {
                    continue;
                }
                let margin = 1e-12 * (q[i].abs() + vt.abs() + e2 + lo[i].abs().max(hi[i].abs()))
                    + v * dt_err
                    + 1e-300;
                broken |= (q[i] - vt - e2) - lo[i] > margin || hi[i] - (q[i] + vt + e2) > margin;
            }
        }
        broken
    }
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

    /// The plain-float accept of an object pair never accepts a pair the outward-rounded tests
    /// flag: 30,000 random pairs at scales from 1e-160 to 1e150, with or without a speed bound
    /// and velocities, moved to within the allowances, to ±1e-12 of them, or up to twice them;
    /// 30,000 more with every quantity from 1e-320 to 1e300, zero or just below zero
    /// (overflowing and underflowing intermediates: `Δt²`, `‖v‖²`, `a·Δt²`); and the cases the
    /// range conditions exist for (an infinite velocity norm, a subnormal `Δt²` scaled by a huge
    /// acceleration, a model without acceleration over a long `Δt`). And it accepts most pairs
    /// well inside (what it is for).
    /// A measured velocity bounds the direction of the displacement, not only its length: from
    /// `v = (−0.6, 0, 0)` m/s, 0.5 s later the object lies within `vel_error·Δt + a·Δt²/2 +
    /// 2·pos_error` of `p + v·Δt` — not 0.3 m the other way (a length within `|v|·Δt` passed
    /// before). Forward from the early record and backward from the late one; the aligned
    /// velocity, and one sideways within the band, pass.
    #[test]
    fn a_velocity_pointing_away_from_the_displacement_breaks_the_model() {
        let b = ObjectBounds::new(0.5, None, 0.01, 0.005);
        let rec = |time: f64, x: f64, v: Option<[f64; 3]>| ObjectMeasurement {
            time,
            position: [1.0 + x, 2.0, 0.5],
            velocity: v,
        };
        let away = Some([-0.6, 0.0, 0.0]);
        let along = Some([0.6, 0.0, 0.0]);
        // Band: 0.01·0.5 + 0.5·0.5·0.25 + 0.01 = 0.0775 m.
        assert!(object_pair_breaks(
            &b,
            &rec(0.0, 0.0, away),
            &rec(0.5, 0.3, None)
        ));
        assert!(object_pair_breaks(
            &b,
            &rec(0.0, 0.0, None),
            &rec(0.5, 0.3, away)
        ));
        assert!(!object_pair_breaks(
            &b,
            &rec(0.0, 0.0, along),
            &rec(0.5, 0.3, None)
        ));
        assert!(!object_pair_breaks(
            &b,
            &rec(0.0, 0.0, None),
            &rec(0.5, 0.3, along)
        ));
        // Within the band of `v·Δt` (0.07 m off it, sideways): consistent; 0.09 m: not.
        let side = |y: f64| ObjectMeasurement {
            time: 0.5,
            position: [1.3, 2.0 + y, 0.5],
            velocity: None,
        };
        assert!(!object_pair_breaks(&b, &rec(0.0, 0.0, along), &side(0.07)));
        assert!(object_pair_breaks(&b, &rec(0.0, 0.0, along), &side(0.09)));
    }

    #[test]
    fn the_plain_accept_of_an_object_pair_is_sound() {
        let mut next = uniform(0x6a09_e667_f3bc_c909u64);
        let (mut accepted, mut inside, mut inside_accepted) = (0, 0, 0);
        for i in 0..30_000 {
            let scale = 10f64.powf(-160.0 + 310.0 * next());
            let dt = scale * next();
            let b = ObjectBounds::new(
                16.0 * next(),
                (i % 4 != 0).then(|| 3.0 * next()),
                0.05 * next() * next(),
                0.05 * next() * next() * scale,
            );
            let dir = |next: &mut dyn FnMut() -> f64| [next() - 0.5, next() - 0.5, next() - 0.5];
            let velocity = |next: &mut dyn FnMut() -> f64| {
                (next() < 0.6).then(|| {
                    let d = dir(next);
                    moved_along(&[0.0; 3], d, 3.0 * next())
                })
            };
            let ev = velocity(&mut next);
            let vb = b.acc() * dt + 2.0 * b.vel_error();
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
            let allowed =
                [b.max_speed().map(|v| v * dt)]
                    .into_iter()
                    .chain([ev, lv].into_iter().map(|v| {
                        v.map(|v| (norm(v) + b.vel_error()) * dt + 0.5 * b.acc() * dt * dt)
                    }))
                    .flatten()
                    .reduce(f64::min)
                    .unwrap_or(scale)
                    + 2.0 * b.pos_error();
            let p = [next() * scale, next() * scale, next() * scale];
            let k = match i % 3 {
                0 => next(),
                1 => 1.0 + 1e-12 * (2.0 * next() - 1.0),
                _ => 2.0 * next(),
            };
            let d = dir(&mut next);
            // The direction band of a measured velocity, and (in half the cases with exactly one
            // velocity) the late position along it: `p + u·Δt` moved by `k` bands.
            let band = b.vel_error() * dt + 0.5 * b.acc() * dt * dt + 2.0 * b.pos_error();
            let one = match (ev, lv) {
                (Some(u), None) | (None, Some(u)) => Some(u),
                _ => None,
            };
            let q = match one {
                Some(u) if i % 2 == 0 => {
                    let ahead = [p[0] + u[0] * dt, p[1] + u[1] * dt, p[2] + u[2] * dt];
                    moved_along(&ahead, d, band * k)
                }
                _ => moved_along(&p, d, allowed * k),
            };
            let residual = |u: [f64; 3]| {
                norm([
                    q[0] - p[0] - u[0] * dt,
                    q[1] - p[1] - u[1] * dt,
                    q[2] - p[2] - u[2] * dt,
                ])
            };
            let well_inside = norm([q[0] - p[0], q[1] - p[1], q[2] - p[2]]) <= 0.9 * allowed
                && [ev, lv]
                    .into_iter()
                    .flatten()
                    .all(|u| residual(u) <= 0.9 * band);
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
            // Inside, and where the accept's range conditions hold.
            let tame = (1e-130..=1e140).contains(&allowed)
                && dt <= 1e100
                && (dt * dt == 0.0 || dt * dt >= f64::MIN_POSITIVE);
            if well_inside
                && tame
                && (1e-130..=1e140).contains(&band)
                && lv.is_none_or(|_| ev.is_none())
            {
                inside += 1;
                inside_accepted += accept as usize;
            }
        }
        assert!(accepted > 4_000, "{accepted}");
        assert!(inside > 2_000, "{inside}");
        assert!(
            inside_accepted * 10 > inside * 9,
            "{inside_accepted} of {inside}"
        );
        let object = |t: f64, position: [f64; 3], velocity: Option<[f64; 3]>| ObjectMeasurement {
            time: t,
            position,
            velocity,
        };
        let flagged_if_accepted =
            |b: &ObjectBounds, e: &ObjectMeasurement, l: &ObjectMeasurement| {
                if object_pair_within_plain(b, e, l) {
                    assert!(
                        !object_pair_breaks_rounded(b, e, l),
                        "accepted a pair the rounded tests flag: {b:?} {e:?} {l:?}"
                    );
                    true
                } else {
                    false
                }
            };
        // An infinite velocity norm (1e155² overflows) with no speed bound.
        let b = ObjectBounds::new(3.0, None, 0.01, 0.01);
        let v = Some([1e155, 0.0, 0.0]);
        let (e, l) = (
            object(0.0, [0.0; 3], v),
            object(0.001, [1e153, 0.0, 0.0], v),
        );
        assert!(object_pair_breaks_rounded(&b, &e, &l));
        assert!(!flagged_if_accepted(&b, &e, &l));
        // A subnormal Δt² scaled by a huge acceleration.
        let b = ObjectBounds::new(1e300, None, 0.0, 0.0);
        let v = Some([0.0; 3]);
        let (e, l) = (
            object(0.0, [0.0; 3], v),
            object(2e-162, [2.3e-24, 0.0, 0.0], v),
        );
        assert!(object_pair_breaks_rounded(&b, &e, &l));
        assert!(!flagged_if_accepted(&b, &e, &l));
        // A model without acceleration (its bound rounded down to just below zero) over a
        // long Δt: the rounded tests' acceleration term stays at least 0, as the exact one.
        let b = ObjectBounds::new(-f64::from_bits(1), Some(1.0), 0.0, 1e-125);
        let (e, l) = (
            object(0.0, [0.0; 3], Some([0.0; 3])),
            object(1e100, [1e-125, 0.0, 0.0], None),
        );
        assert!(!object_pair_breaks_rounded(&b, &e, &l));
        assert!(flagged_if_accepted(&b, &e, &l));
        // Every quantity from 1e-320 to 1e300, or zero, or just below zero (an acceleration
        // bound rounded down from zero).
        let wild = |next: &mut dyn FnMut() -> f64| match (next() * 8.0) as u32 {
            0 => 0.0,
            1 => -f64::from_bits(1),
            _ => 10f64.powf(-320.0 + 620.0 * next()),
        };
        let vec = |next: &mut dyn FnMut() -> f64| {
            let d = [next() - 0.5, next() - 0.5, next() - 0.5];
            let len = wild(next).abs();
            moved_along(&[0.0; 3], d, len)
        };
        let mut wild_accepted = 0;
        for _ in 0..30_000 {
            let b = ObjectBounds::new(
                wild(&mut next),
                (next() < 0.5).then(|| wild(&mut next).abs()),
                wild(&mut next).abs(),
                wild(&mut next).abs(),
            );
            let dt = wild(&mut next).abs();
            let (ev, lv) = (
                (next() < 0.6).then(|| vec(&mut next)),
                (next() < 0.6).then(|| vec(&mut next)),
            );
            let p = vec(&mut next);
            let q = if next() < 0.5 { vec(&mut next) } else { p };
            let (e, l) = (object(0.0, p, ev), object(dt, q, lv));
            wild_accepted += flagged_if_accepted(&b, &e, &l) as usize;
        }
        // Some of these are accepted (the accept is reached), the rest decided by the rounded
        // tests.
        assert!(wild_accepted > 500, "{wild_accepted}");
    }

    /// The fast accept in `human_pair_breaks` is sound: a pair it accepts is within the
    /// allowance by the outward-rounded test applied to the same pair scaled by a power of two
    /// into the unit range (exact scaling, where the rounded test's absolute error terms are
    /// negligible). 20 000 random pairs at scales from 1e-160 to 1e150 m, a third of them with
    /// a keypoint within a relative 1e-12 of the allowance, where rounding decides; where the
    /// fast path does not accept, the answer is the rounded test's.
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
