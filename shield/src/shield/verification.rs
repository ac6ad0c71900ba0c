//! Verification of a monitored trajectory: per occupancy interval, joint boxes from the path
//! ranges, robot, human and object occupancies, and the ISO/TS 15066 rule.

use super::intervals::{Piece, verify_fine};
use super::{Binding, Diagnostics, FilterMode, ObjectSlot, OccupancyIntervals, Shield};
use pacs_models::MAX_DOF;
use pacs_motion::Trajectory;
use pacs_motion::scaling::SpeedProfile;
use pacs_reach::JointBox;
use pacs_reach::object::ObjectOccupancy;
use pacs_verify::iso15066::ConstraintKind;
use std::ops::ControlFlow;

/// Verifications that skip the whole-trajectory check after it failed once (see
/// [`Shield::verify`]); each further failure in a row doubles the skip (plus one), up to
/// [`COARSE_SKIP_MAX`].
pub(crate) const COARSE_SKIP: u32 = 7;
/// The longest skip of the whole-trajectory check (verifications).
pub(crate) const COARSE_SKIP_MAX: u32 = 63;

impl Shield {
    /// Verify the monitored trajectory (go for α_s from t, then brake) against the human and the
    /// objects.
    pub(super) fn verify(
        &mut self,
        slot: usize,
        go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        diag: &mut Diagnostics,
    ) -> bool {
        let alpha = self.config.safety_step;
        let stop = alpha + brake.settle_time();
        // The intervals below cover `[0, stop]` only under `interval_end`'s precondition (a
        // finite `stop ≥ α`, harnesses `f2_interval_end_contract`, `f2_intervals_cover_by_contract`):
        // a brake whose settle time is NaN, negative or infinite is not verified, whatever the
        // planner's contract says of it.
        if !(stop.is_finite() && stop >= alpha) {
            diag.binding = Binding::NoProfile;
            return false;
        }
        let m = Monitored { slot, go, brake, t };
        let span = |k, ta, tb| Span { k, ta, tb };
        if self.humans.is_empty() && self.objects.is_empty() {
            return true;
        }
        if self.humans.iter().any(|h| !h.has_meas) || self.objects.iter().any(|o| o.meas.is_none())
        {
            diag.binding = Binding::NoMeasurement;
            return false;
        }
        if let Some(human) = self.humans.iter().position(|h| h.contradicted) {
            diag.binding = Binding::ContradictedMeasurement { human };
            return false;
        }
        if let Some(object) = self.objects.iter().position(|o| o.contradicted) {
            diag.binding = Binding::ContradictedObject { object };
            return false;
        }
        // Each object's occupancy over the whole monitored trajectory `[t, t + stop]`, once per
        // verification: every interval below lies in it, so it contains theirs (claim C4′ holds
        // at every time of its window) and they compute their own only where it touches the
        // robot (`check_interval`).
        for (o, w) in self.objects.iter().zip(self.object_window.iter_mut()) {
            *w = object_occupancy(o, t, t + stop);
            if w.is_none() {
                diag.binding = Binding::NoMeasurement;
                return false;
            }
        }
        // Coarse check first: the whole monitored trajectory as one interval (its occupancy
        // contains that of every sub-interval, so passing it verifies the step). Usually decides
        // when the human is far; otherwise the fine intervals below decide.
        // After it failed, the next verifications go straight to the fine check (in a run of
        // steps near a person it keeps failing, and costs one interval check each time): 7 after
        // one failure, doubling with each failure in a row up to 63.
        if self.config.mode != FilterMode::Off && stop > alpha {
            if self.coarse_skip > 0 {
                self.coarse_skip -= 1;
            } else {
                let mut coarse = *diag;
                if self.check_interval(&m, span(0, 0.0, stop), &mut coarse) {
                    *diag = coarse;
                    self.coarse_backoff = COARSE_SKIP;
                    return true;
                }
                // Near a person it keeps failing: try it ever more rarely (7, 15, 31, 63).
                self.coarse_skip = self.coarse_backoff;
                self.coarse_backoff = (2 * self.coarse_backoff + 1).min(COARSE_SKIP_MAX);
                // Its separation bound holds for every part of the trajectory, the first
                // interval included (the fine check below may fail before reaching it).
                diag.min_separation = diag.min_separation.min(coarse.min_separation);
            }
        }
        let intervals = OccupancyIntervals::new(
            alpha,
            stop,
            self.config.first_interval,
            self.config.max_intervals,
        );
        if self.config.mode != FilterMode::Off {
            return verify_fine(intervals, |piece, ta, tb| match piece {
                Piece::Interval(k) => self.check_interval(&m, span(k, ta, tb), diag),
                // A merged piece reports like the coarse check (separation from its start on):
                // its diagnostics are kept only if it verifies.
                Piece::Before(_) => {
                    let mut merged = *diag;
                    let ok = self.check_interval(&m, span(0, ta, tb), &mut merged);
                    if ok {
                        *diag = merged;
                    }
                    ok
                }
            });
        }
        // Off: every interval is evaluated (diagnostics only).
        let mut ok = true;
        for (k, ta, tb) in intervals {
            if !self.check_interval(&m, span(k, ta, tb), diag) {
                ok = false;
            }
        }
        ok
    }

    /// Check one occupancy interval `iv` of the monitored trajectory `m`: the joint boxes over
    /// it, each person's and object's occupancy (broad phase: the robot's workspace ball), the
    /// robot's occupancy and energy bound only where something is near, then the one rule for
    /// every object and person. True iff verified; `diag` records what bound the step.
    fn check_interval(&mut self, m: &Monitored<'_>, iv: Span, diag: &mut Diagnostics) -> bool {
        let n = self.dof;
        let Some((q_box, v_box)) = self.interval_boxes(m, iv) else {
            // Non-finite path ranges never verify.
            return false;
        };
        let (wa, wb) = (m.t + iv.ta, m.t + iv.tb);
        let Self {
            reach,
            scratch,
            robot_caps,
            energies,
            humans,
            objects,
            object_rule,
            object_occ,
            object_pick,
            object_window,
            config,
            ..
        } = self;
        let Some(human_left) = humans_near(humans, wa, wb, iv.k, diag) else {
            return false;
        };
        let mut objs = ObjectsAt {
            objects,
            rule: object_rule,
            own: object_occ,
            pick: object_pick,
            window: object_window,
            wa,
            wb,
        };
        let Some(objects_left) = objs.near(human_left, diag) else {
            return false;
        };
        if !human_left && !objects_left {
            return true;
        }
        if reach.occupancy_with(scratch, &q_box, robot_caps).is_err() {
            return false;
        }
        // The robot's real velocities may differ from the commanded ones by the controller's
        // velocity tracking error (rounded outward): the energy bound uses the widened box.
        let e_track = config.velocity_tracking_error;
        let mut energy_cache: Option<f64> = None;
        let mut energy = || {
            *energy_cache.get_or_insert_with(|| {
                let widened = JointBox::from_fn(n, |i| {
                    let (lo, hi) = v_box.bounds(i);
                    ((lo - e_track).next_down(), (hi + e_track).next_up())
                });
                // Same joint box as the occupancy above: the scratch's frames are reused.
                match widened
                    .map(|w| reach.subchain_energy_bounds_with(scratch, &q_box, &w, energies))
                {
                    Ok(Ok(())) => energies[n],
                    _ => f64::INFINITY,
                }
            })
        };
        if !objs.clear(robot_caps, &v_box, &mut energy, iv.k, diag) {
            return false;
        }
        let figure = iv.k == 0 && config.separation_figure;
        humans_clear(humans, robot_caps, &v_box, &mut energy, figure, iv.k, diag)
    }

    /// The joint position and velocity boxes of `m` over `iv` (claim C7,
    /// [`monitored_joint_boxes`]); `None` where a range is not finite.
    fn interval_boxes(&self, m: &Monitored<'_>, iv: Span) -> Option<(JointBox, JointBox)> {
        let n = self.dof;
        let tr = self.trajs[m.slot]
            .as_ref()
            .expect("slot holds a trajectory");
        let mut q_lo = [0.0; MAX_DOF];
        let mut q_hi = [0.0; MAX_DOF];
        let mut v_lo = [0.0; MAX_DOF];
        let mut v_hi = [0.0; MAX_DOF];
        monitored_joint_boxes(
            tr,
            m.go,
            m.brake,
            self.config.safety_step,
            (iv.ta, iv.tb),
            (&mut q_lo[..n], &mut q_hi[..n]),
            (&mut v_lo[..n], &mut v_hi[..n]),
        );
        let q_box = JointBox::new(&q_lo[..n], &q_hi[..n]).ok()?;
        let v_box = JointBox::new(&v_lo[..n], &v_hi[..n]).ok()?;
        Some((q_box, v_box))
    }
}

/// The monitored trajectory a verification checks: the intended trajectory in `slot`, one
/// intended step along the path-speed profile `go`, then braking along `brake`, from the step
/// time `t` (s).
#[derive(Clone, Copy)]
pub(super) struct Monitored<'a> {
    pub(super) slot: usize,
    pub(super) go: &'a SpeedProfile,
    pub(super) brake: &'a SpeedProfile,
    pub(super) t: f64,
}

/// One occupancy interval `[t + ta, t + tb]` (s, relative to the step time), reported as
/// interval `k` in the diagnostics.
#[derive(Clone, Copy)]
pub(super) struct Span {
    pub(super) k: usize,
    pub(super) ta: f64,
    pub(super) tb: f64,
}

/// Each person's occupancy over `[wa, wb]` (s) into its slot, and the broad phase's first stage:
/// a person outside the robot's workspace ball is cleared (`clear`; the separation figure of
/// interval 0 recorded). Returns whether a person is left for the narrow phase; `None` (with
/// [`Binding::NoMeasurement`]) where an occupancy cannot be computed.
#[inline]
fn humans_near(
    humans: &mut [super::HumanSlot],
    wa: f64,
    wb: f64,
    k: usize,
    diag: &mut Diagnostics,
) -> Option<bool> {
    let mut left = false;
    for h in humans.iter_mut() {
        if h.reach
            .occupancy_into(&h.meas, wa, wb, &mut h.caps)
            .is_err()
        {
            diag.binding = Binding::NoMeasurement;
            return None;
        }
        h.clear = match h.rule.workspace_clear(&h.caps) {
            Some(sep) => {
                if k == 0 {
                    diag.min_separation = diag.min_separation.min(sep);
                }
                true
            }
            None => {
                left = true;
                false
            }
        };
    }
    Some(left)
}

/// The one rule for every person not cleared by the broad phase against the robot's occupancy
/// `robot_caps` and velocity box `v_box` (energy bound by `energy`): true iff no contact the
/// constraints forbid is possible. Records the separation figure (interval 0, where `figure`),
/// the largest energy bound where contact is possible, and the first violation's binding.
#[inline]
fn humans_clear(
    humans: &mut [super::HumanSlot],
    robot_caps: &[pacs_models::Capsule],
    v_box: &JointBox,
    energy: &mut impl FnMut() -> f64,
    figure: bool,
    k: usize,
    diag: &mut Diagnostics,
) -> bool {
    for (hid, h) in humans.iter_mut().enumerate() {
        if h.clear {
            continue;
        }
        let mut first = None;
        let outcome = h
            .rule
            .check(robot_caps, v_box, &h.caps, &mut *energy, figure, |v| {
                first = Some(*v);
                ControlFlow::Break(())
            });
        // (Without the figure: 0 where contact is possible, +∞ otherwise.)
        if k == 0 {
            diag.min_separation = diag.min_separation.min(outcome.separation);
        }
        if let Some((e, thr)) = outcome.pfl
            && e > diag.contact_energy
        {
            diag.contact_energy = e;
            diag.contact_threshold = thr;
        }
        let Some(v) = first else { continue };
        if matches!(diag.binding, Binding::None) {
            diag.binding = match v.kind {
                // (The body-part rule reports SSM or PFL only.)
                ConstraintKind::Ssm | ConstraintKind::NoContact => Binding::Ssm {
                    human: hid,
                    link: v.link,
                    body_part: v.part,
                    interval: k,
                },
                ConstraintKind::Pfl => Binding::Pfl {
                    human: hid,
                    link: v.link,
                    body_part: v.part,
                    energy: v.energy,
                    threshold: v.threshold,
                    constrained: v.constrained,
                },
            };
        }
        return false;
    }
    true
}

/// The shield's objects over one occupancy interval `[wa, wb]` (s): their slots and the
/// occupancies the interval checks (`own`, `pick`, `window`: the shield's parallel per-object
/// buffers).
struct ObjectsAt<'s> {
    objects: &'s [ObjectSlot],
    rule: &'s pacs_verify::iso15066::ObjectRule,
    own: &'s mut [Option<ObjectOccupancy>],
    pick: &'s mut [ObjectPick],
    window: &'s [Option<ObjectOccupancy>],
    wa: f64,
    wb: f64,
}

impl ObjectsAt<'_> {
    /// Pick each object's occupancy and clear those outside the robot's workspace ball. The
    /// occupancy is the one over the whole monitored trajectory where that contains this
    /// interval (always, in `verify`): a superset, so clearing it clears the interval; the
    /// interval's own, tighter occupancy is computed in [`Self::clear`] only if the superset
    /// touches the robot. (The workspace test only saves the robot occupancy: when a person
    /// needs it anyway (`human_left`), every object goes to the object rule, whose box test is
    /// as cheap.) Returns whether an object is left; `None` (with
    /// [`Binding::NoMeasurement`]) where an occupancy is missing.
    #[inline]
    fn near(&mut self, human_left: bool, diag: &mut Diagnostics) -> Option<bool> {
        let (wa, wb) = (self.wa, self.wb);
        let mut left = false;
        for (o, ((own, pick), window)) in self.objects.iter().zip(
            self.own
                .iter_mut()
                .zip(self.pick.iter_mut())
                .zip(self.window.iter()),
        ) {
            *pick = match window {
                Some(w) if covers(w, wa, wb) => ObjectPick::Window,
                _ => {
                    *own = object_occupancy(o, wa, wb);
                    ObjectPick::Own
                }
            };
            let Some(occ) = pick.occupancy(own, window) else {
                diag.binding = Binding::NoMeasurement;
                return None;
            };
            if human_left || self.rule.workspace_clear(occ).is_none() {
                left = true;
            } else {
                *pick = ObjectPick::Cleared;
            }
        }
        Some(left)
    }

    /// The object rule for every object not cleared, against the robot's occupancy `robot_caps`
    /// and velocity box `v_box` (energy bound by `energy`): true iff no object's contact
    /// constraint may be violated. A violation with the whole trajectory's occupancy is decided
    /// again with the interval's own. Records the first violation's binding.
    #[inline]
    fn clear(
        &mut self,
        robot_caps: &[pacs_models::Capsule],
        v_box: &JointBox,
        energy: &mut impl FnMut() -> f64,
        k: usize,
        diag: &mut Diagnostics,
    ) -> bool {
        let (wa, wb) = (self.wa, self.wb);
        let rule = self.rule;
        for (id, (o, ((own, pick), window))) in self
            .objects
            .iter()
            .zip(
                self.own
                    .iter_mut()
                    .zip(self.pick.iter())
                    .zip(self.window.iter()),
            )
            .enumerate()
        {
            let Some(occ) = pick.occupancy(own, window) else {
                continue; // cleared (a missing occupancy was refused above)
            };
            let mut out = rule.check(robot_caps, v_box, occ, o.contact, &mut *energy, false);
            if out.violation.is_some() && *pick == ObjectPick::Window && occ.interval() != (wa, wb)
            {
                // The whole trajectory's occupancy touches the robot: decide with this
                // interval's own.
                *own = object_occupancy(o, wa, wb);
                let Some(occ) = own.as_ref() else {
                    diag.binding = Binding::NoMeasurement;
                    return false;
                };
                out = rule.check(robot_caps, v_box, occ, o.contact, &mut *energy, false);
            }
            if let Some(v) = out.violation {
                if matches!(diag.binding, Binding::None) {
                    diag.binding = Binding::Object {
                        object: id,
                        link: v.link,
                        interval: k,
                    };
                }
                return false;
            }
        }
        true
    }
}

/// The occupancy of object `o` over `[t_a, t_b]` (s) after its latest measurement; `None`
/// without a measurement or where `pacs_reach::object::occupancy` refuses the query.
fn object_occupancy(o: &ObjectSlot, t_a: f64, t_b: f64) -> Option<ObjectOccupancy> {
    pacs_reach::object::occupancy(&o.model, o.meas.as_ref()?, t_a, t_b).ok()
}

/// Which occupancy of an object an occupancy interval checks (see `Shield::check_interval`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ObjectPick {
    /// The workspace test cleared the object for this interval.
    Cleared,
    /// Its occupancy over the whole monitored trajectory (`Shield::object_window`), which
    /// contains the interval's.
    Window,
    /// The interval's own occupancy (`Shield::object_occ`).
    Own,
}

impl ObjectPick {
    /// The picked occupancy; `None` if cleared or if the picked one was not computed (the
    /// query refused: no measurement, or an interval before it).
    fn occupancy<'a>(
        self,
        own: &'a Option<ObjectOccupancy>,
        window: &'a Option<ObjectOccupancy>,
    ) -> Option<&'a ObjectOccupancy> {
        match self {
            ObjectPick::Cleared => None,
            ObjectPick::Window => window.as_ref(),
            ObjectPick::Own => own.as_ref(),
        }
    }
}

/// Whether `occ`'s time interval contains `[t_a, t_b]` (s): then every point of the object at
/// every time of `[t_a, t_b]` lies in `occ` (claim C4′ of `pacs_reach::object::occupancy`),
/// which may stand for the occupancy over `[t_a, t_b]` wherever a superset is sound.
fn covers(occ: &ObjectOccupancy, t_a: f64, t_b: f64) -> bool {
    let (a, b) = occ.interval();
    a <= t_a && t_b <= b
}

/// Path and speed ranges `(s_lo, s_hi, ṡ_lo, ṡ_hi)` of the monitored trajectory (go for α, then
/// brake from α) over relative time `[ta, tb]` (s).
fn path_ranges(
    go: &SpeedProfile,
    brake: &SpeedProfile,
    alpha: f64,
    ta: f64,
    tb: f64,
) -> (f64, f64, f64, f64) {
    let mut s_lo = f64::INFINITY;
    let mut s_hi = f64::NEG_INFINITY;
    let mut sd_lo = f64::INFINITY;
    let mut sd_hi = f64::NEG_INFINITY;
    let mut add = |r: (f64, f64, f64, f64, f64)| {
        s_lo = s_lo.min(r.0);
        s_hi = s_hi.max(r.1);
        sd_lo = sd_lo.min(r.2);
        sd_hi = sd_hi.max(r.3);
    };
    if ta < alpha {
        add(go.ranges(ta, tb.min(alpha)));
    }
    if tb > alpha {
        add(brake.ranges(ta.max(alpha) - alpha, tb - alpha));
    }
    (s_lo, s_hi, sd_lo.max(0.0), sd_hi)
}

/// The joint position (rad) and velocity (rad/s) boxes of one occupancy interval: the monitored
/// trajectory (the path-speed profile `go` for `alpha` s, then `brake`) executed on the intended
/// trajectory `tr`, over relative time `[ta, tb]` (s). Writes one range per joint into
/// `q = (lo, hi)` and `v = (lo, hi)` (slices of the robot's joint count); allocates nothing.
/// A non-finite range (which never verifies: `JointBox::new` refuses it) can result from
/// non-finite inputs.
///
/// # Soundness
/// Claim C7 (the joint boxes from path ranges): for every `τ ∈ [ta, tb]` and every joint `i`,
/// the executed configuration `q_i(s(τ))` lies in `q` and the executed velocity
/// `q_i′(s(τ))·ṡ(τ)` in `v`, where `(s, ṡ)` is `go.eval(τ)` before `alpha` and
/// `brake.eval(τ − alpha)` from `alpha` on. It rests on `SpeedProfile::ranges` (harness
/// `f4_path_ranges_enclose`), `Trajectory::joint_derivs` (motion's tests) and the outward
/// product `q′·ṡ` (ṡ ≥ 0 is the profile's own claim, `e1_braking_profile`). Harness
/// `f5_joint_boxes_enclose` (property test: the executed state sampled on random trajectories
/// and profiles).
pub fn monitored_joint_boxes(
    tr: &Trajectory,
    go: &SpeedProfile,
    brake: &SpeedProfile,
    alpha: f64,
    (ta, tb): (f64, f64),
    (q_lo, q_hi): (&mut [f64], &mut [f64]),
    (v_lo, v_hi): (&mut [f64], &mut [f64]),
) {
    let (s_lo, s_hi, sd_lo, sd_hi) = path_ranges(go, brake, alpha, ta, tb);
    for i in 0..q_lo.len() {
        let d = tr.joint_derivs(i, s_lo, s_hi);
        q_lo[i] = d.r[0].lo;
        q_hi[i] = d.r[0].hi;
        // q̇ = q′·ṡ with ṡ ∈ [sd_lo, sd_hi] ⊂ [0, ∞): interval product, rounded outward.
        let (a, b) = (d.r[1].lo, d.r[1].hi);
        let c = [a * sd_lo, a * sd_hi, b * sd_lo, b * sd_hi];
        v_lo[i] = c.iter().copied().fold(f64::INFINITY, f64::min).next_down();
        v_hi[i] = c
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
            .next_up();
        if sd_hi == 0.0 {
            // Path speed exactly 0 over the interval: the commanded joints are at rest.
            (v_lo[i], v_hi[i]) = (0.0, 0.0);
        }
    }
}
