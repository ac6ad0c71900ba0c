//! Closing a run: inconclusive stretches, the final instant, open violation intervals, and the
//! verdict with its metrics.

use super::*;

/// How many of the latest inconclusive entries a span's reason looks back through for the
/// stretch to extend: stretches of up to this many other reasons and objects may lie between.
/// Beyond it a stretch is listed in parts (the time counts alike).
const CHAIN_LOOKBACK: usize = 64;

impl Auditor {
    pub(super) fn mark_inconclusive(&mut self, t0: f64, t1: f64, reason: Reason) {
        self.mark_inconclusive_about(t0, t1, reason, None);
    }

    /// [`Self::mark_inconclusive`] for a reason about object `object` (index into the log's
    /// objects), which the span names; spans chain only for the same reason and object (a span
    /// may give several reasons: each stretch chains on its own).
    pub(super) fn mark_inconclusive_about(
        &mut self,
        t0: f64,
        t1: f64,
        reason: Reason,
        object: Option<usize>,
    ) {
        let idx = self.span_index;
        let name = object.map(|k| self.objects[k].id.as_str());
        // The stretch of this reason and object the previous span extended, among the latest
        // entries (a span gives a few reasons, one per object at most: stretches of other
        // reasons that ended in between sit after it).
        let chained = self
            .inconclusive
            .iter_mut()
            .rev()
            .take(CHAIN_LOOKBACK)
            .find(|(last, r, i)| *r == reason && *i + 1 == idx && last.object.as_deref() == name);
        if let Some((last, _, last_idx)) = chained {
            last.t_end = t1;
            last.spans += 1;
            *last_idx = idx;
        } else {
            self.inconclusive.push((
                InconclusiveSpan {
                    t_start: t0,
                    t_end: t1,
                    reason,
                    spans: 1,
                    person: None,
                    object: name.map(str::to_string),
                },
                reason,
                idx,
            ));
        }
    }

    /// Human records that no span used. Those pushed after the last robot sample: if any was
    /// measured inside the logged time (`t_meas − delay ≤ t_last`; the earliest counts), its
    /// information was not checked: `human_record_after_last_robot_sample` (inconclusive). The
    /// latest record pushed between the last two robot samples (in use from the last sample on,
    /// which starts no span): the last sample's instant is checked with it (a zero-length span),
    /// so a contact it shows at the end of the log is a violation. Without logged velocities,
    /// that instant's velocity box is the one of the span ending there.
    pub(super) fn check_final_instant(&mut self, inconclusive: &mut Option<InconclusiveSpan>) {
        // The block always ends with the last sample pushed (`flush_block` keeps it).
        let Some(&last) = self.block.last() else {
            return;
        };
        let delay = self.human.delay();
        if let Some(tm) = self.unused_human_t_meas
            && tm - delay <= last.t
        {
            *inconclusive = Some(InconclusiveSpan {
                t_start: last.t,
                t_end: last.t,
                reason: Reason::HumanRecordAfterLastRobotSample,
                spans: 0,
                person: None,
                object: None,
            });
            return;
        }
        // Copies count: two records of one sample still make a zero-length span to check.
        if self.awaiting_human_t_meas.is_some() && self.samples + self.copies >= 2 {
            let (was_violated, was_certain) = (self.last_span_violated, self.last_span_certain);
            let mut e = self.boxes(&last, &last);
            // Without logged velocities a zero-length span bounds them by the limits alone; the
            // span that ends at the last sample bounds them at its end (claim C9: every motion
            // consistent with its samples stays in its boxes at every instant of it, its end
            // included), so its velocity box is used where both enclosures are consistent.
            if !last.has_dq
                && let Some(prev) = self.before_last
                && prev.t < last.t
            {
                let span = self.boxes(&prev, &last);
                if let (true, true, Some(b), Some(s)) =
                    (e.consistent, span.consistent, e.boxes.as_mut(), span.boxes)
                {
                    b.dq = s.dq;
                }
            }
            self.check_span_with(&last, &last, &e, self.span_human);
            // The last sample counts once (finish adds it for a violated last span).
            let (v, c) = (self.last_span_violated, self.last_span_certain);
            self.last_span_violated = was_violated && !v;
            self.last_span_certain = was_certain && !c;
        }
    }

    /// Close the audit: the verdict, intervals and metrics.
    pub fn finish(self, log: &str, meta: serde_json::Map<String, serde_json::Value>) -> RunResult {
        self.finish_tracked(log, meta).0
    }

    /// [`Self::finish`], with the violating samples by index where the auditor tracks them
    /// ([`Self::for_person`]: one pass of several, merged by `crate::people`).
    pub(crate) fn finish_tracked(
        mut self,
        log: &str,
        meta: serde_json::Map<String, serde_json::Value>,
    ) -> (RunResult, Option<crate::people::Tracks>) {
        self.flush_block();
        let mut final_inconclusive = None;
        self.check_final_instant(&mut final_inconclusive);
        for key in 0..self.open.len() {
            if let Some(o) = self.open[key].take() {
                self.close(key, o);
            }
        }
        self.violations.sort_by(|a, b| {
            a.t_start
                .total_cmp(&b.t_start)
                .then(a.body_part.cmp(&b.body_part))
        });
        if self.samples >= 2 && self.last_span_violated {
            self.violating_samples += 1;
            if let Some(t) = &mut self.track {
                t.violating.insert(self.samples - 1);
            }
        }
        if self.samples >= 2 && self.last_span_certain {
            self.certain_samples += 1;
            if let Some(t) = &mut self.track {
                t.certain.insert(self.samples - 1);
            }
        }
        let mut inconclusive: Vec<InconclusiveSpan> =
            self.inconclusive.into_iter().map(|(s, _, _)| s).collect();
        inconclusive.extend(final_inconclusive);
        inconclusive.append(&mut self.model_breaks);
        // Copies of a sample count here: several records of one stamp cover no time.
        if self.samples + self.copies < 2 {
            inconclusive.push(InconclusiveSpan {
                t_start: if self.samples == 1 { self.t_first } else { 0.0 },
                t_end: if self.samples == 1 { self.t_last } else { 0.0 },
                reason: Reason::FewerThanTwoRobotSamples,
                spans: 0,
                person: None,
                object: None,
            });
        } else if self.t_last == self.t_first {
            inconclusive.push(InconclusiveSpan {
                t_start: self.t_first,
                t_end: self.t_last,
                reason: Reason::NoTimeCovered,
                spans: 0,
                person: None,
                object: None,
            });
        }
        // Reasons about a person's measurements name the person (v2 logs).
        if self.person.is_some() {
            for s in &mut inconclusive {
                if s.reason.about_a_person() {
                    s.person.clone_from(&self.person);
                }
            }
        }
        let verdict = Verdict::of_findings(!self.violations.is_empty(), !inconclusive.is_empty());
        let track = self.track.take();
        let samples = self.samples;
        let metrics = Metrics {
            samples,
            human_records: self.human_records,
            duration: if samples > 0 {
                self.t_last - self.t_first
            } else {
                0.0
            },
            violation_fraction: if samples > 0 {
                self.violating_samples as f64 / samples as f64
            } else {
                0.0
            },
            violating_samples: self.violating_samples,
            certain_violating_samples: self.certain_samples,
            inconclusive_duration: self.inconclusive_duration,
            // A figure beyond floating point (people ≳ 10¹⁵⁴ m away: the squared distances
            // overflow) is no number to report: left out, as where no span was checked.
            min_separation: self.min_separation.filter(|s| s.is_finite()),
            success: self.success,
            safe_success: self
                .success
                .map(|s| crate::verdict::safe_success(s, verdict == Verdict::Pass)),
        };
        // The plots' nominal energies, once per remaining bucket.
        let n = self.n;
        for (b, at) in self.series.buckets.iter_mut().zip(&self.series.nominal) {
            if let Some(at) = at {
                b.energy_nominal = Some(reportable(
                    self.robot.kinetic_energy(&at.q[..n], &at.dq[..n]),
                ));
            }
        }
        let result = RunResult {
            log: log.to_string(),
            verdict,
            violations: self.violations,
            inconclusive,
            metrics,
            evidence: crate::verdict::Evidence {
                t_start: if samples > 0 { self.t_first } else { 0.0 },
                t_end: if samples > 0 { self.t_last } else { 0.0 },
                completeness: crate::verdict::Completeness::NotPromised,
            },
            people: self.person.iter().cloned().collect(),
            meta,
            models: self.names,
            series: self.series.buckets,
        };
        (result, track.map(|b| *b))
    }

    pub(super) fn close(&mut self, key: usize, o: OpenInterval) {
        let part = key / self.links;
        let link = key % self.links;
        self.violations.push(Violation {
            t_start: o.v_start,
            t_end: o.v_end,
            constraint: o.kind,
            person: if part < self.parts {
                self.person.clone()
            } else {
                None
            },
            body_part: match self.human.body_parts().get(part) {
                Some(bp) => bp.name.clone(),
                None => format!("object `{}`", self.objects[part - self.parts].id),
            },
            link: self.robot.links()[link].name.clone(),
            min_separation: o.min_sep,
            energy: reportable(o.energy),
            threshold: o.threshold,
            constrained: o.constrained,
            certain: o.certain,
            spans: o.spans,
            first_span: o.last_span + 1 - o.spans,
        });
    }
}
