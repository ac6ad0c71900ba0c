//! The span checks of [`Auditor`]: joint boxes, the block fast path, span by span, and the one
//! ISO/TS 15066 rule applied to each.

use super::*;

/// How many other records of a person or object a possibly violating span is judged against
/// (the newest usable ones; `Auditor::clear_by_other_measurements`). A bound on the work per
/// span only: fewer records can clear fewer spans, never more.
const OTHER_RECORDS: usize = 8;

/// The kept records of object `o` that may clear what the record in use (`o.span`) shows,
/// newest first, at most [`OTHER_RECORDS`], into `o.others` (valid until its records or the one
/// in use change): not the one in use and not contradicting it (`object_pair_breaks`, as for
/// people).
fn collect_other_object_records(o: &mut ObjectTrack) {
    o.others.clear();
    o.others_for = o.span;
    let Some(u) = o.span else { return };
    for m in o.history.iter().rev() {
        let consistent = if u.time <= m.time {
            u != *m && !object_pair_breaks(&o.bounds, &u, m)
        } else {
            !object_pair_breaks(&o.bounds, m, &u)
        };
        if consistent {
            o.others.push(*m);
            if o.others.len() == OTHER_RECORDS {
                return;
            }
        }
    }
}

/// Whether the older record `a` cannot clear anything the newer `u` shows, by a test in plain
/// floats: every keypoint of `u` lies within `v_max·(t_u − t_a)` of `a`'s, so (with the speed
/// bound, which is all a log without human velocities gives) each of `a`'s balls over any later
/// interval contains `u`'s, and so do its capsules. A cost filter only: skipping a record never
/// clears a pair, so an inexact answer (rounding, another reach model) costs completeness at
/// worst, never soundness. Where a person stands still with a model of no position error, every
/// older record is skipped so (the audit of a log with many violating spans stays as fast).
fn older_keypoints_cover(model: &HumanModel, a: &HumanMeasurement, u: &HumanMeasurement) -> bool {
    let dt = u.time() - a.time();
    dt >= 0.0
        && a.positions()
            .iter()
            .zip(u.positions())
            .zip(model.v_max())
            .all(|((p, q), v)| (p - q).norm_squared() <= (v * dt) * (v * dt))
}

/// Upper bound (J) of the whole robot's kinetic energy over the span's boxes (+∞ if it cannot be
/// bounded). Same joint box as the occupancy in `rcaps`: the scratch's frames are reused.
fn span_energy(
    rreach: &RobotReach,
    scratch: &mut ReachScratch,
    b: &SpanBoxes,
    energies: &mut [f64],
    n: usize,
) -> f64 {
    match rreach.subchain_energy_bounds_with(scratch, &b.q, &b.dq, energies) {
        Ok(()) => energies[n],
        Err(_) => f64::INFINITY,
    }
}

impl Auditor {
    /// The span's joint boxes ([`crate::enclosure::span_boxes`]); not consistent if the samples contradict each
    /// other or the robot's limits (the span is then `exceeds_limits`).
    pub(super) fn boxes(&self, s0: &Sample, s1: &Sample) -> SpanEnclosure {
        let mut e = SpanEnclosure::empty();
        self.boxes_into(s0, s1, &mut e);
        e
    }

    /// [`Self::boxes`] written into `e` in place.
    fn boxes_into(&self, s0: &Sample, s1: &Sample, e: &mut SpanEnclosure) {
        span_boxes_into(&self.span_limits, s0, s1, self.cfg.limit_slack, e);
        // A sample outside the joint position limits contradicts the robot model as much as
        // one moving faster than its limits: the span is inconsistent (`exceeds_limits`; it is
        // still checked with its boxes, and can never pass). The same relative slack as for
        // the other limits.
        // Over every lane, without early exit (the band is unbounded beyond the joints): four
        // joints per vector comparison.
        let (lo, hi) = &self.q_band;
        let within = |s: &Sample| {
            let mut ok = true;
            for j in 0..MAX_DOF {
                ok &= s.q[j] >= lo[j] && s.q[j] <= hi[j];
            }
            ok
        };
        if !(within(s0) && within(s1)) {
            e.consistent = false;
        }
    }

    /// Check the buffered spans (all using the human measurement `block_human` and the object
    /// measurements in use for them), keeping the last sample as the start of the next block.
    ///
    /// Every span's enclosure is computed once; the spans are then checked by [`Self::check_spans`]
    /// (block fast path, halves, span by span). The samples and enclosures are borrowed from
    /// buffers taken out of `self` for the duration (no copies, no allocation after warm-up).
    pub(super) fn flush_block(&mut self) {
        let m = self.block.len();
        if m >= 2 {
            let slot = self.block_human;
            let block = std::mem::take(&mut self.block);
            let mut encl = std::mem::take(&mut self.block_encl);
            // Resized, not cleared: each entry is overwritten in place.
            encl.resize(m - 1, SpanEnclosure::empty());
            // The latest sample stamped before the span's first (carried across blocks).
            let mut earlier = self.earlier;
            for (i, e) in encl.iter_mut().enumerate() {
                self.boxes_into(&block[i], &block[i + 1], e);
                // The span before it must agree with it at their shared sample.
                let before = if i > 0 {
                    Some(block[i - 1].t)
                } else {
                    self.before_last.map(|s| s.t)
                };
                let direct = before.is_some_and(|t| t < block[i].t);
                if let Some(p) = &earlier
                    && !adjacent_spans_agree(
                        &self.span_limits,
                        p,
                        &block[i],
                        &block[i + 1],
                        self.cfg.limit_slack,
                        direct,
                    )
                {
                    e.consistent = false;
                }
                if block[i + 1].t > block[i].t {
                    earlier = Some(block[i]);
                }
            }
            self.earlier = earlier;
            self.check_spans(&block, &encl, 0, m - 1, slot);
            self.before_last = Some(block[m - 2]);
            self.block = block;
            self.block_encl = encl;
            // The last sample starts the next block.
            self.block.drain(..m - 1);
        }
    }

    /// Check spans `lo..hi` of `block` (span `i` joins samples `i` and `i + 1`; `encl[i]` is its
    /// enclosure), in order. First the block fast path over all of them ([`Self::check_block`]);
    /// if that cannot prove them clean, the two halves the same way (down to
    /// [`MIN_SUB_BLOCK`] spans), then span by span. Every path is sound on its own (a clean
    /// block proves each of its spans clean; the span check is the reference), so the split only
    /// changes the cost, and the separation figures recorded (each a lower bound). Where the
    /// last spans checked one by one were mostly violating, the block and its halves are not
    /// tried (they would fail too).
    fn check_spans(
        &mut self,
        block: &[Sample],
        encl: &[SpanEnclosure],
        lo: usize,
        hi: usize,
        slot: Option<usize>,
    ) {
        let count = hi - lo;
        if !self.block_fast_path {
            for i in lo..hi {
                self.check_span_with(&block[i], &block[i + 1], &encl[i], slot);
            }
            return;
        }
        // Where the last spans checked one by one were mostly violating, neither this stretch
        // nor its halves are tried as blocks (they would fail too, at the cost of a robot
        // occupancy and a rule check each): it goes span by span, which also decides the flag
        // anew.
        if count >= 2 && !self.dense_violations && self.check_block(block, encl, lo, hi, slot) {
            return;
        }
        if count >= 2 * MIN_SUB_BLOCK && !self.dense_violations {
            let mid = lo + count / 2;
            self.check_spans(block, encl, lo, mid, slot);
            self.check_spans(block, encl, mid, hi, slot);
            return;
        }
        let before = self.violating_samples;
        for i in lo..hi {
            self.check_span_with(&block[i], &block[i + 1], &encl[i], slot);
        }
        let violating = self.violating_samples - before;
        self.dense_violations = count >= MIN_SUB_BLOCK && 2 * violating >= count as u64;
    }

    /// The one ISO/TS 15066 rule ([`ContactRule::check`]) on the occupancies in `self.rcaps`
    /// (computed for `b`'s position box) and `self.hcaps`, with the whole-robot energy bound over
    /// `b`. With `collect`, every violating pair is pushed to `self.hits`; otherwise the rule
    /// stops at the first.
    pub(super) fn apply_rule(&mut self, b: &SpanBoxes, collect: bool) -> Outcome {
        let n = self.n;
        let Self {
            rule,
            rreach,
            scratch,
            rcaps,
            hcaps,
            energies,
            hits,
            ..
        } = self;
        hits.clear();
        let energy = || span_energy(rreach, scratch, b, energies, n);
        rule.check(rcaps, &b.dq, hcaps, energy, true, |h| {
            if !collect {
                return ControlFlow::Break(());
            }
            hits.push(SpanHit {
                part: h.part,
                link: h.link,
                kind: h.kind,
                energy: h.energy,
                threshold: h.threshold,
                constrained: h.constrained,
                certain: false,
                separation: f64::INFINITY,
            });
            ControlFlow::Continue(())
        })
    }

    /// Fast path over spans `lo..hi` of `block`: one check over the union of their span boxes,
    /// with the human occupancy (and each object's) over the whole stretch — supersets of every
    /// span's enclosures, so "no violation possible" holds for every span. Returns false, having
    /// recorded nothing, if the stretch is not provably clean (or a span is not consistent, not
    /// resolved, or past a gap or a stale measurement); the caller then checks smaller parts.
    pub(super) fn check_block(
        &mut self,
        block: &[Sample],
        encl: &[SpanEnclosure],
        lo: usize,
        hi: usize,
        slot: Option<usize>,
    ) -> bool {
        if hi < lo + 2 {
            return false;
        }
        let Some(slot) = slot else { return false };
        let Some(meas) = self.humans[slot].as_ref() else {
            return false;
        };
        let (t0, t1) = (block[lo].t, block[hi].t);
        if t1 - meas.time() > self.cfg.max_human_age {
            return false;
        }
        if self
            .hreach
            .occupancy_into(meas, t0, t1, &mut self.hcaps)
            .is_err()
        {
            return false;
        }
        let mut union: Option<SpanBoxes> = None;
        for i in lo..hi {
            let (a, b) = (&block[i], &block[i + 1]);
            if longer_than_gap(a.t, b.t, self.cfg.max_gap) || !stamps_resolve(a.t, b.t) {
                return false;
            }
            let SpanEnclosure {
                boxes: Some(sb),
                consistent: true,
            } = &encl[i]
            else {
                return false;
            };
            match &mut union {
                Some(u) => u.hull_in_place(sb),
                None => union = Some(*sb),
            }
        }
        let Some(u) = union else { return false };
        let far = self.rule.workspace_clear(&self.hcaps);
        let mut robot_occupancy = false;
        let (sep, pfl_seen) = match far {
            Some(sep) => (sep, None),
            None => {
                if !self.robot_occupancy(&u) {
                    return false;
                }
                robot_occupancy = true;
                let out = self.apply_rule(&u, false);
                if out.violated {
                    return false;
                }
                (out.separation, out.pfl)
            }
        };
        if !self.objects_clear(&u, t0, t1, robot_occupancy) {
            return false;
        }
        // Every span of the stretch is clean: per-span bookkeeping only.
        for i in lo..hi {
            let (a, b) = (&block[i], &block[i + 1]);
            self.span_index += 1;
            let (bidx, new_bucket) = self.series.bucket(a.t);
            if new_bucket {
                self.series.nominal[bidx] = Some(self.nominal_state(a, b));
            }
            let rest = self.nominal_rest(a, b);
            self.series.buckets[bidx].at_rest &= rest;
            if let Some((e, thr)) = pfl_seen {
                let bk = &mut self.series.buckets[bidx];
                bk.energy_bound = max_opt(bk.energy_bound, Some(reportable(e)));
                bk.threshold = min_opt(bk.threshold, Some(thr));
            }
            self.record_separation(bidx, sep, far.is_some());
        }
        self.last_span_violated = false;
        self.last_span_certain = false;
        true
    }

    /// The robot occupancy of the position box `u.q` into `self.rcaps`; false where it cannot be
    /// computed (non-finite boxes), and the stretch is then not provably clean.
    fn robot_occupancy(&mut self, u: &SpanBoxes) -> bool {
        self.rreach
            .occupancy_with(&mut self.scratch, &u.q, &mut self.rcaps)
            .is_ok()
    }

    /// Whether every object provably keeps the object rule over `[t0, t1]` with the robot in the
    /// boxes `u`: each object's occupancy over the whole stretch, from the measurement in use for
    /// all of its spans (`ObjectTrack::span`; blocks close when it changes), outside the
    /// workspace ball or clear by [`ObjectRule::check`] against the robot occupancy of `u.q`
    /// (computed here unless `have_robot`). False (nothing recorded) for a missing, stale or
    /// unusable measurement: the span-by-span check reports those.
    fn objects_clear(&mut self, u: &SpanBoxes, t0: f64, t1: f64, mut have_robot: bool) -> bool {
        let n = self.n;
        let mut energy_cache: Option<f64> = None;
        for k in 0..self.objects.len() {
            let o = &self.objects[k];
            let Some(m) = o.span else { return false };
            if t1 - m.time > self.cfg.max_human_age {
                return false;
            }
            let Ok(occ) = pacs_reach::object::occupancy(&o.model, &m, t0, t1) else {
                return false;
            };
            if self.object_rule.workspace_clear(&occ).is_some() {
                continue;
            }
            if !have_robot {
                if !self.robot_occupancy(u) {
                    return false;
                }
                have_robot = true;
            }
            let contact = self.objects[k].contact;
            let Self {
                object_rule,
                rreach,
                scratch,
                rcaps,
                energies,
                ..
            } = self;
            let energy = || {
                *energy_cache.get_or_insert_with(|| span_energy(rreach, scratch, u, energies, n))
            };
            if object_rule
                .check(rcaps, &u.dq, &occ, contact, energy, true)
                .violation
                .is_some()
            {
                return false;
            }
        }
        true
    }

    /// The joint state whose nominal whole-robot kinetic energy (J) a plot bucket shows: `a`
    /// with its logged velocity, else the span's mean velocity.
    pub(super) fn nominal_state(&self, a: &Sample, b: &Sample) -> NominalAt {
        let n = self.n;
        let dt = b.t - a.t;
        let mut dq = [0.0; MAX_DOF];
        for j in 0..n {
            dq[j] = if a.has_dq {
                a.dq[j]
            } else if dt > 0.0 {
                (b.q[j] - a.q[j]) / dt
            } else {
                0.0
            };
        }
        NominalAt { q: a.q, dq }
    }

    /// Whether the robot is nominally at rest over the span `a`–`b` (for the plots only): the
    /// logged velocities (else the sample difference) within `rest_speed` on every joint.
    pub(super) fn nominal_rest(&self, a: &Sample, b: &Sample) -> bool {
        let dt = b.t - a.t;
        (0..self.n).all(|j| {
            let v = if a.has_dq && b.has_dq {
                a.dq[j].abs().max(b.dq[j].abs())
            } else if dt > 0.0 {
                ((b.q[j] - a.q[j]) / dt).abs()
            } else {
                0.0
            };
            v <= self.cfg.rest_speed
        })
    }

    /// Check the span `s0`–`s1` with its enclosure `encl` (`self.boxes(s0, s1)`): the reference
    /// check, every violating pair collected and tested for certainty.
    pub(super) fn check_span_with(
        &mut self,
        s0: &Sample,
        s1: &Sample,
        encl: &SpanEnclosure,
        span_human: Option<usize>,
    ) {
        self.span_index += 1;
        let (t0, t1) = (s0.t, s1.t);
        let dt = t1 - t0;
        let (bidx, new_bucket) = self.series.bucket(t0);
        let rest = self.nominal_rest(s0, s1);
        self.series.buckets[bidx].at_rest &= rest;
        let mut certain = false;
        if longer_than_gap(t0, t1, self.cfg.max_gap) {
            self.skip_span(t0, t1, bidx, Reason::Gap);
            return;
        }
        // The person's occupancy over the span, or why there is none. A person who cannot be
        // checked (never measured, stale, a measurement the model cannot place) makes the span
        // inconclusive, and so does an object; each is checked all the same where the other
        // can be: a certain contact with the one still fails the log.
        let human_unusable = match span_human.map(|slot| self.humans[slot].as_ref()) {
            // (`Some(None)` is unreachable by construction; never let an unchecked span pass.)
            None | Some(None) => Some(Reason::NoHuman),
            Some(Some(m)) if t1 - m.time() > self.cfg.max_human_age => Some(Reason::StaleHuman),
            Some(Some(m)) => self
                .hreach
                .occupancy_into(m, t0, t1, &mut self.hcaps)
                .err()
                .map(|_| Reason::HumanReachError),
        };
        let slot = span_human.filter(|_| human_unusable.is_none());
        // Whether the span's time is already in `inconclusive_duration` (it counts once).
        let mut counted = false;
        if let Some(reason) = human_unusable {
            self.mark_inconclusive(t0, t1, reason);
            self.inconclusive_duration += dt;
            counted = true;
            self.series.buckets[bidx].inconclusive = true;
        }
        let (objects_left, any_unusable) = self.object_occupancies(t0, t1);
        if any_unusable {
            for k in 0..self.objects.len() {
                if let Some(reason) = self.objects[k].unusable {
                    self.mark_inconclusive_about(t0, t1, reason, Some(k));
                }
            }
            if !counted {
                self.inconclusive_duration += dt;
                counted = true;
            }
            self.series.buckets[bidx].inconclusive = true;
        }
        if slot.is_none() && !objects_left {
            self.finish_span(bidx, false, false);
            return;
        }
        let (boxes, consistent) = (&encl.boxes, encl.consistent);
        if !stamps_resolve(t0, t1) {
            // Checked below all the same (a violation found still fails the log), never passed.
            self.mark_inconclusive(t0, t1, Reason::UnresolvedTime);
            self.series.buckets[bidx].inconclusive = true;
            if !counted {
                self.inconclusive_duration += dt;
                counted = true;
            }
        }
        if !consistent {
            self.mark_inconclusive(t0, t1, Reason::ExceedsLimits);
            if !counted {
                self.inconclusive_duration += dt;
                counted = true;
            }
            self.series.buckets[bidx].inconclusive = true;
        }
        if new_bucket {
            self.series.nominal[bidx] = Some(self.nominal_state(s0, s1));
        }
        // Broad phase, stage 1: every body part (and object) outside the robot's workspace ball.
        let human_clear = match slot {
            Some(_) => self.rule.workspace_clear(&self.hcaps),
            None => None,
        };
        if let Some(sep) = human_clear
            && !objects_left
        {
            self.record_separation(bidx, sep, true);
            self.finish_span(bidx, false, false);
            return;
        }
        // Robot occupancy over the span.
        let Some(bx) = boxes else {
            // Only non-finite boxes (absurd samples; already inconclusive) get here: never let
            // the span pass.
            self.finish_span(bidx, false, false);
            return;
        };
        if self
            .rreach
            .occupancy_with(&mut self.scratch, &bx.q, &mut self.rcaps)
            .is_err()
        {
            // Only non-finite boxes (absurd samples) get here: never let the span pass.
            if consistent {
                self.mark_inconclusive(t0, t1, Reason::ExceedsLimits);
                if !counted {
                    self.inconclusive_duration += dt;
                }
            }
            self.finish_span(bidx, false, false);
            return;
        }
        let out = match human_clear {
            _ if slot.is_none() => {
                // No person to check: the objects only (and no separation to report).
                self.hits.clear();
                Outcome {
                    contact: false,
                    violated: false,
                    separation: f64::INFINITY,
                    pfl: None,
                }
            }
            Some(sep) => {
                self.hits.clear();
                Outcome {
                    contact: false,
                    violated: false,
                    separation: sep,
                    pfl: None,
                }
            }
            None => self.apply_rule(bx, true),
        };
        if slot.is_some() {
            self.record_separation(bidx, out.separation, false);
        }
        self.apply_object_rule(bx);
        if let Some((e, thr)) = out.pfl {
            let b = &mut self.series.buckets[bidx];
            b.energy_bound = max_opt(b.energy_bound, Some(reportable(e)));
            b.threshold = min_opt(b.threshold, Some(thr));
        }
        if !self.hits.is_empty() {
            self.clear_by_other_measurements(t0, t1, bx, slot);
        }
        if self.hits.is_empty() {
            self.finish_span(bidx, false, false);
            return;
        }
        let violated = true;
        // Certain check at both recorded samples, with the measured keypoints — only where the
        // samples agree with each other: "certain" takes the logged state at face value, which a
        // contradicted sample does not deserve (the span's possible violation still fails the log).
        if consistent {
            for s in [s0, s1] {
                certain |= self.certain_at(s, s0, s1, slot);
            }
        } else {
            for s in [s0, s1] {
                self.certain_at(s, s0, s1, slot);
            }
            for h in self.hits.iter_mut() {
                h.certain = false;
            }
        }
        self.extend_intervals(t0, t1);
        self.finish_span(bidx, violated, certain);
    }

    /// Drop from `self.hits` every pair that another measurement still usable for the span
    /// `t0`–`t1` clears: a person's other kept records (the latest [`HUMAN_HISTORY`] by stamp),
    /// an object's likewise, each no older than `max_human_age` at `t1` and not describing a
    /// state after the span's start (its occupancy is then defined; others are skipped), and
    /// consistent with the measurement in use (`human_pair_breaks`, `object_pair_breaks`: of
    /// two records that contradict each other one is wrong, and a violation the one in use
    /// shows stands; the log is inconclusive for the contradiction as well).
    ///
    /// # Soundness
    /// The audit's occupancies assume every measurement within the model's errors (and the
    /// record-against-record checks make any log that contradicts this inconclusive); then the
    /// true person (object) lies, at every instant of the span, in the occupancy from *each*
    /// such measurement, not only from the newest. The rule's decision is per pair and monotone
    /// in the occupancy (claim C8′: a pair it does not report cannot truly violate while the
    /// truth lies in the occupancy judged), so a pair that the rule clears on any one of them
    /// cannot truly violate; a pair stays only while every measurement tried reports it. This is
    /// what lets a log pass whose robot brakes on a failsafe the shield verified against an
    /// earlier measurement, when a newer one's occupancy reaches further (by up to its
    /// measurement error) than the earlier one's. Tests
    /// `audit_objects::an_earlier_measurement_clears_a_span_the_newest_cannot` and
    /// `audit_checks::an_earlier_person_measurement_clears_a_span_the_newest_cannot` (mutants
    /// `x73`, `x74`: a pair dropped when another measurement still reports it); a contradicting
    /// record clears nothing: `audit_checks::one_sample_human_spike_is_caught`,
    /// `audit_objects::a_ball_record_the_others_contradict_is_inconclusive_not_a_pass`.
    fn clear_by_other_measurements(
        &mut self,
        t0: f64,
        t1: f64,
        b: &SpanBoxes,
        slot: Option<usize>,
    ) {
        let n = self.n;
        let parts = self.parts;
        let max_age = self.cfg.max_human_age;
        // (Hits on body parts come only with a person checked, `slot`.)
        if let Some(slot) = slot
            && self.hits.iter().any(|h| h.part < parts)
        {
            if self.alt_humans_for != Some(slot) {
                self.collect_other_human_records(slot);
            }
            for c in 0..self.alt_humans.len() {
                let h = &self.human_history[self.alt_humans[c]];
                if t1 - h.time() > max_age {
                    break; // newest first: every later one is older still
                }
                if self
                    .hreach
                    .occupancy_into(h, t0, t1, &mut self.alt_hcaps)
                    .is_err()
                {
                    continue;
                }
                let Self {
                    rule,
                    rreach,
                    scratch,
                    rcaps,
                    alt_hcaps,
                    alt_pairs,
                    energies,
                    hits,
                    ..
                } = self;
                alt_pairs.clear();
                let energy = || span_energy(rreach, scratch, b, energies, n);
                rule.check(rcaps, &b.dq, alt_hcaps, energy, false, |v| {
                    alt_pairs.push((v.part, v.link));
                    ControlFlow::Continue(())
                });
                hits.retain(|x| x.part >= parts || alt_pairs.contains(&(x.part, x.link)));
                if !hits.iter().any(|h| h.part < parts) {
                    break;
                }
            }
        }
        for k in 0..self.objects.len() {
            if !self.hits.iter().any(|h| h.part == parts + k) {
                continue;
            }
            let Self {
                object_rule,
                objects,
                rreach,
                scratch,
                rcaps,
                energies,
                hits,
                ..
            } = self;
            let o = &mut objects[k];
            if o.others_for != o.span {
                collect_other_object_records(o);
            }
            let o = &objects[k];
            let mut energy_cache: Option<f64> = None;
            for m in &o.others {
                if t1 - m.time > max_age {
                    break; // newest first: every later one is older still
                }
                let Ok(occ) = pacs_reach::object::occupancy(&o.model, m, t0, t1) else {
                    continue;
                };
                let energy = || {
                    *energy_cache
                        .get_or_insert_with(|| span_energy(rreach, scratch, b, energies, n))
                };
                let cleared = object_rule.workspace_clear(&occ).is_some()
                    || object_rule
                        .check(rcaps, &b.dq, &occ, o.contact, energy, false)
                        .violation
                        .is_none();
                if cleared {
                    hits.retain(|h| h.part != parts + k);
                    break;
                }
            }
        }
    }

    /// The kept records of the person that may clear what the record in use (`slot`) shows,
    /// newest first (at most [`OTHER_RECORDS`]), into `alt_humans` (valid until the records or
    /// the one in use change):
    /// not the one in use, not covered by it (`older_keypoints_cover`, a cost filter), and not
    /// contradicting it (`human_pair_breaks`: of two records that contradict each other one is
    /// wrong, and a violation the one in use shows stands; the log is inconclusive as well).
    fn collect_other_human_records(&mut self, slot: usize) {
        self.alt_humans.clear();
        self.alt_humans_for = Some(slot);
        let Some(u) = self.humans[slot].as_ref() else {
            return;
        };
        for i in (0..self.human_history.len()).rev() {
            let h = &self.human_history[i];
            if u != h
                && !older_keypoints_cover(&self.human, h, u)
                && !human_pair_breaks(&self.human, u, h)
            {
                self.alt_humans.push(i);
                if self.alt_humans.len() == OTHER_RECORDS {
                    return;
                }
            }
        }
    }

    /// A span that cannot be checked for `reason`: inconclusive (its duration counted, its plot
    /// bucket marked), neither violated nor certain.
    #[inline]
    fn skip_span(&mut self, t0: f64, t1: f64, bidx: usize, reason: Reason) {
        self.skip_span_about(t0, t1, bidx, reason, None);
    }

    /// [`Self::skip_span`] for a reason about object `object` (index), which the span names.
    fn skip_span_about(
        &mut self,
        t0: f64,
        t1: f64,
        bidx: usize,
        reason: Reason,
        object: Option<usize>,
    ) {
        self.mark_inconclusive_about(t0, t1, reason, object);
        self.inconclusive_duration += t1 - t0;
        self.series.buckets[bidx].inconclusive = true;
        self.finish_span(bidx, false, false);
    }

    /// Account the span just checked (the current `span_index`, plot bucket `bidx`): violated
    /// and certain counts, the tracked sample sets, the last span's flags and the bucket.
    #[inline]
    fn finish_span(&mut self, bidx: usize, violated: bool, certain: bool) {
        // The span's first sample (span k starts at sample k − 1).
        let sample = self.span_index - 1;
        if violated {
            self.violating_samples += 1;
            if let Some(t) = &mut self.track {
                t.violating.insert(sample);
            }
        }
        if certain {
            self.certain_samples += 1;
            if let Some(t) = &mut self.track {
                t.certain.insert(sample);
            }
        }
        self.last_span_violated = violated;
        self.last_span_certain = certain;
        self.series.buckets[bidx].violation |= violated;
    }

    /// Each object's occupancy over the span `t0`–`t1`, from the measurement in use for it (into
    /// the object's `occ`; `None` where the workspace ball clears it or where the object cannot
    /// be checked, the reason then in its `unusable`): whether any object is left for the
    /// object rule, and whether any cannot be checked (the others are checked all the same).
    #[inline]
    fn object_occupancies(&mut self, t0: f64, t1: f64) -> (bool, bool) {
        let mut objects_left = false;
        let mut any_unusable = false;
        for k in 0..self.objects.len() {
            let o = &mut self.objects[k];
            o.occ = None;
            o.unusable = match o.span {
                None => Some(Reason::NoObject),
                Some(m) if t1 - m.time > self.cfg.max_human_age => Some(Reason::StaleObject),
                Some(m) => match pacs_reach::object::occupancy(&o.model, &m, t0, t1) {
                    Err(_) => Some(Reason::ObjectReachError),
                    Ok(occ) => {
                        if self.object_rule.workspace_clear(&occ).is_none() {
                            o.occ = Some(occ);
                            objects_left = true;
                        }
                        None
                    }
                },
            };
            any_unusable |= o.unusable.is_some();
        }
        (objects_left, any_unusable)
    }

    /// The violating pairs of the span `t0`–`t1` (`self.hits`) into the open violation
    /// intervals: a pair's interval open since the previous span of the same kind is extended,
    /// any other closed and a new one opened.
    #[inline]
    fn extend_intervals(&mut self, t0: f64, t1: f64) {
        let idx = self.span_index;
        for k in 0..self.hits.len() {
            let h = self.hits[k];
            let key = h.part * self.links + h.link;
            let extend =
                matches!(&self.open[key], Some(o) if o.last_span + 1 == idx && o.kind == h.kind);
            if extend {
                let Some(o) = self.open[key].as_mut() else {
                    continue;
                };
                o.v_end = t1;
                o.min_sep = o.min_sep.min(h.separation);
                o.energy = o.energy.max(h.energy);
                o.threshold = o.threshold.min(h.threshold);
                o.constrained |= h.constrained;
                o.certain |= h.certain;
                o.spans += 1;
                o.last_span = idx;
            } else {
                if let Some(o) = self.open[key].take() {
                    self.close(key, o);
                }
                self.open[key] = Some(OpenInterval {
                    v_start: t0,
                    v_end: t1,
                    kind: h.kind,
                    min_sep: h.separation,
                    energy: h.energy,
                    threshold: h.threshold,
                    constrained: h.constrained,
                    certain: h.certain,
                    spans: 1,
                    last_span: idx,
                });
            }
        }
    }

    /// The object rule ([`ObjectRule::check`]) for every object whose occupancy is not cleared
    /// by the workspace ball, on the robot occupancy in `self.rcaps` (computed for `b`'s
    /// position box); each violation is appended to `self.hits` as part `parts + k`.
    pub(super) fn apply_object_rule(&mut self, b: &SpanBoxes) {
        let n = self.n;
        let Self {
            object_rule,
            objects,
            rreach,
            scratch,
            rcaps,
            energies,
            hits,
            parts,
            ..
        } = self;
        let mut energy_cache: Option<f64> = None;
        for (k, o) in objects.iter().enumerate() {
            let Some(occ) = &o.occ else { continue };
            let energy = || {
                *energy_cache.get_or_insert_with(|| span_energy(rreach, scratch, b, energies, n))
            };
            let out = object_rule.check(rcaps, &b.dq, occ, o.contact, energy, true);
            if let Some(v) = out.violation {
                let threshold = match o.contact {
                    ObjectContact::Pfl { threshold } => threshold,
                    _ => 0.0,
                };
                hits.push(SpanHit {
                    part: *parts + k,
                    link: v.link,
                    kind: ConstraintKind::of_object(o.contact),
                    energy: v.energy,
                    threshold,
                    constrained: false,
                    certain: false,
                    separation: f64::INFINITY,
                });
            }
        }
    }

    /// Record a span's separation lower bound (m) in the run's minimum and its plot bucket;
    /// `far`: only the distance to the workspace ball was computed (the bucket's
    /// `far_separation`, drawn apart from the figure of the robot's occupancy).
    pub(super) fn record_separation(&mut self, bidx: usize, sep: f64, far: bool) {
        if sep.is_finite() {
            self.min_separation = min_opt(self.min_separation, Some(sep));
            let b = &mut self.series.buckets[bidx];
            if far {
                b.far_separation = min_opt(b.far_separation, Some(sep));
            } else {
                b.min_separation = min_opt(b.min_separation, Some(sep));
            }
        }
    }
}
