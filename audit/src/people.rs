//! Several people in one log: one pass of the span checks per person, merged into one result.
//!
//! The rule judges each (body part, link) pair on its own, and each person's occupancy comes
//! from that person's measurements only (a pinch against another person, which a pass cannot
//! locate, is assumed possible for every PFL contact: `ContactRule::set_other_people`); so a log
//! with people `P₁ … Pₖ` has a violation (or an unchecked span) exactly where the log restricted
//! to the robot, the objects and `Pᵢ` has one, for some `i`. [`PeopleAuditor`] feeds every robot
//! sample, object record and event to one [`Auditor`] per person and each person's records to
//! that person's auditor (an object's violations, found by every pass that checks the span, are
//! kept once), then merges: the
//! verdict is `fail` if any pass failed, else `inconclusive` if any pass left something
//! unchecked, else `pass` ([`crate::Verdict::of_findings`] on the union of the findings);
//! violating samples are counted once across people (the union of their indices), the minimum
//! separation is the least over people. Claim C9 holds per pass, hence for the union.

use crate::check::Auditor;
use crate::error::AuditError;
use crate::verdict::{
    InconclusiveReason as Reason, InconclusiveSpan, PersonModel, RunResult, SeriesPoint, Violation,
};
use crate::{AuditConfig, series::min_opt};
use pacs_log::LogModels;

/// Sample indices as sorted half-open ranges (pushed in increasing order, as the spans are
/// checked; any order is accepted and normalised by [`SampleSet::union_len`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct SampleSet {
    ranges: Vec<(u64, u64)>,
}

impl SampleSet {
    /// Add sample `i`.
    pub(crate) fn insert(&mut self, i: u64) {
        if let Some(last) = self.ranges.last_mut() {
            if i >= last.0 && i < last.1 {
                return;
            }
            if i == last.1 {
                last.1 += 1;
                return;
            }
        }
        self.ranges.push((i, i + 1));
    }

    /// Number of samples in the union of `sets`.
    pub(crate) fn union_len<'a>(sets: impl IntoIterator<Item = &'a SampleSet>) -> u64 {
        let mut all: Vec<(u64, u64)> = sets.into_iter().flat_map(|s| s.ranges.clone()).collect();
        all.sort_unstable();
        let (mut total, mut end) = (0u64, 0u64);
        for (a, b) in all {
            let a = a.max(end);
            if b > a {
                total += b - a;
                end = b;
            }
        }
        total
    }
}

/// What a pass keeps to be merged exactly: its violating and certainly violating samples.
#[derive(Debug, Clone, Default)]
pub(crate) struct Tracks {
    pub(crate) violating: SampleSet,
    pub(crate) certain: SampleSet,
}

/// The auditor of a log with several people: one [`Auditor`] per person (see the module docs).
pub struct PeopleAuditor {
    ids: Vec<String>,
    passes: Vec<Auditor>,
}

impl PeopleAuditor {
    /// One pass per person of `models.people` (each also checks the objects).
    pub fn new(models: &LogModels, cfg: &AuditConfig) -> Result<Self, AuditError> {
        let mut passes = Vec::with_capacity(models.people.len());
        let mut ids = Vec::with_capacity(models.people.len());
        for (id, human) in &models.people {
            let mut m = models.clone();
            m.human = human.clone();
            m.people = vec![(id.clone(), human.clone())];
            let mut pass = Auditor::for_person(m, cfg.clone(), id, true)?;
            // Each person may be pinched against another (`ContactRule::set_other_people`: this
            // pass does not see the others' occupancies, so they may be anywhere).
            pass.set_other_people(models.people.len() > 1);
            passes.push(pass);
            ids.push(id.clone());
        }
        Ok(Self { ids, passes })
    }

    /// The pass of person `id`, or the error naming the declared ones.
    fn pass(&mut self, id: Option<&str>) -> Result<&mut Auditor, AuditError> {
        let Some(id) = id else {
            return Err(AuditError::PersonMissing {
                declared: self.ids.join(", "),
            });
        };
        match self.ids.iter().position(|p| p == id) {
            Some(i) => Ok(&mut self.passes[i]),
            None => Err(AuditError::UnknownPerson {
                id: id.to_string(),
                declared: self.ids.join(", "),
            }),
        }
    }

    /// A measurement of person `id` (see [`Auditor::push_human`]).
    pub fn push_human(
        &mut self,
        id: Option<&str>,
        t: f64,
        t_meas: f64,
        positions: &[[f64; 3]],
    ) -> Result<(), AuditError> {
        self.pass(id)?.push_human(t, t_meas, positions)
    }

    /// A robot sample, for every person.
    pub fn push_robot_with_acc(
        &mut self,
        t: f64,
        q: &[f64],
        dq: Option<&[f64]>,
        ddq: Option<&[f64]>,
    ) -> Result<(), AuditError> {
        for p in &mut self.passes {
            p.push_robot_with_acc(t, q, dq, ddq)?;
        }
        Ok(())
    }

    /// An object measurement, for every pass: each checks the objects on the spans it checks,
    /// so an object's contact is found wherever any person's measurement lets a span be
    /// checked (the verdict does not depend on the order of the people).
    pub fn push_object(
        &mut self,
        t: f64,
        t_meas: f64,
        id: &str,
        position: [f64; 3],
        velocity: Option<[f64; 3]>,
    ) -> Result<(), AuditError> {
        for p in &mut self.passes {
            p.push_object(t, t_meas, id, position, velocity)?;
        }
        Ok(())
    }

    /// An event, for every person.
    pub fn push_event(&mut self, name: &str) {
        for p in &mut self.passes {
            p.push_event(name);
        }
    }

    /// Close every pass and merge them (see the module docs).
    pub fn finish(self, log: &str, meta: serde_json::Map<String, serde_json::Value>) -> RunResult {
        let mut results = Vec::with_capacity(self.passes.len());
        let mut tracks = Vec::with_capacity(self.passes.len());
        for p in self.passes {
            let (r, t) = p.finish_tracked(log, meta.clone());
            results.push(r);
            tracks.push(t.unwrap_or_default());
        }
        merge(results, &tracks, self.ids)
    }
}

/// Reasons whose spans add to `inconclusive_duration` (span by span).
fn spans_time(r: Reason) -> bool {
    matches!(
        r,
        Reason::Gap
            | Reason::NoHuman
            | Reason::StaleHuman
            | Reason::ExceedsLimits
            | Reason::HumanReachError
            | Reason::NoObject
            | Reason::StaleObject
            | Reason::ObjectReachError
            | Reason::UnresolvedTime
    )
}

/// Total length (s) of the union of intervals.
fn union_length(mut iv: Vec<(f64, f64)>) -> f64 {
    iv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut total, mut end) = (0.0, f64::NEG_INFINITY);
    for (a, b) in iv {
        let a = a.max(end);
        if b > a {
            total += b - a;
            end = b;
        }
    }
    total
}

/// An object's violation intervals of every pass, joined: each pass finds the object's violating
/// spans where its own person's measurement lets it check the span (a pass skips, inconclusive,
/// the spans its person is stale or unmeasured on), so one pass may see an interval whole and
/// another only parts of it. Intervals of one (object, link, constraint) whose spans overlap or
/// follow each other (by span index, the same in every pass) become one: the union of the
/// spans, the smallest separation, the largest energy bound, the smallest threshold, constrained
/// or certain if either was. Identical intervals are kept once. A person's violations are left
/// as they are (one pass each).
fn join_object_violations(violations: Vec<Violation>) -> Vec<Violation> {
    let (mut objects, mut out): (Vec<Violation>, Vec<Violation>) =
        violations.into_iter().partition(|v| v.person.is_none());
    objects.sort_by(|a, b| {
        (&a.body_part, &a.link, a.constraint as u8, a.first_span).cmp(&(
            &b.body_part,
            &b.link,
            b.constraint as u8,
            b.first_span,
        ))
    });
    let mut joined: Vec<Violation> = Vec::with_capacity(objects.len());
    for v in objects {
        if let Some(w) = joined.last_mut()
            && w.body_part == v.body_part
            && w.link == v.link
            && w.constraint == v.constraint
            && v.first_span <= w.first_span + w.spans
        {
            let end = (w.first_span + w.spans).max(v.first_span + v.spans);
            w.spans = end - w.first_span;
            w.t_start = w.t_start.min(v.t_start);
            w.t_end = w.t_end.max(v.t_end);
            w.min_separation = w.min_separation.min(v.min_separation);
            w.energy = w.energy.max(v.energy);
            w.threshold = w.threshold.min(v.threshold);
            w.constrained |= v.constrained;
            w.certain |= v.certain;
            continue;
        }
        joined.push(v);
    }
    out.extend(joined);
    out
}

fn merge(mut results: Vec<RunResult>, tracks: &[Tracks], ids: Vec<String>) -> RunResult {
    // Every person's human model (each pass was audited with its person's), for the results and
    // the report: a report must not present one person's model as everyone's.
    let people_models: Vec<PersonModel> = results
        .iter()
        .zip(&ids)
        .map(|(r, id)| PersonModel {
            id: id.clone(),
            human: r.models.human.clone(),
            human_v_max: r.models.human_v_max.clone(),
            human_measurement_error_pos: r.models.human_measurement_error_pos,
            human_delay: r.models.human_delay,
        })
        .collect();
    let human_specs: serde_json::Map<String, serde_json::Value> = results
        .iter()
        .zip(&ids)
        .map(|(r, id)| (id.clone(), r.models.specs["human"].clone()))
        .collect();
    let rest = results.split_off(1);
    let mut out = results.pop().expect("at least one person");
    let mut inconclusive_iv: Vec<(f64, f64)> = out
        .inconclusive
        .iter()
        .filter(|s| spans_time(s.reason))
        .map(|s| (s.t_start, s.t_end))
        .collect();
    // The objects' spans listed so far (a span found again by a later pass is not listed twice).
    let key = |s: &InconclusiveSpan| {
        (
            s.t_start.to_bits(),
            s.t_end.to_bits(),
            s.reason.as_str(),
            s.object.clone(),
        )
    };
    // Each listed object span's place in `out.inconclusive`.
    let mut object_spans: std::collections::HashMap<_, usize> = out
        .inconclusive
        .iter()
        .enumerate()
        .filter(|(_, s)| s.reason.about_an_object())
        .map(|(i, s)| (key(s), i))
        .collect();
    for r in rest {
        // A person's violations are this pass's own; an object's (no person) are found by every
        // pass that checks the span (joined below).
        out.violations.extend(r.violations);
        // Findings about the robot alone (gaps, limits, time) and about the objects' records
        // (`object_exceeds_model`) are the same in every pass: kept once, from the first. Every
        // pass checks the objects, but a pass whose person's record arrives between the last
        // two samples also checks the last sample's instant: an object's span listed already
        // keeps the larger span count of the two.
        for s in r.inconclusive {
            let keep = if s.reason.about_a_person() {
                true
            } else if s.reason.about_an_object() && s.reason != Reason::ObjectExceedsModel {
                match object_spans.get(&key(&s)) {
                    Some(&i) => {
                        let listed = &mut out.inconclusive[i];
                        listed.spans = listed.spans.max(s.spans);
                        false
                    }
                    None => {
                        object_spans.insert(key(&s), out.inconclusive.len());
                        true
                    }
                }
            } else {
                false
            };
            if keep {
                if spans_time(s.reason) {
                    inconclusive_iv.push((s.t_start, s.t_end));
                }
                out.inconclusive.push(s);
            }
        }
        let m = &mut out.metrics;
        m.human_records += r.metrics.human_records;
        m.min_separation = min_opt(m.min_separation, r.metrics.min_separation);
        out.series = merge_series(std::mem::take(&mut out.series), &r.series);
    }
    out.violations = join_object_violations(std::mem::take(&mut out.violations));
    out.violations.sort_by(|a, b| {
        a.t_start
            .total_cmp(&b.t_start)
            .then(a.person.cmp(&b.person))
            .then(a.body_part.cmp(&b.body_part))
    });
    out.inconclusive
        .sort_by(|a, b| a.t_start.total_cmp(&b.t_start));
    let m = &mut out.metrics;
    m.violating_samples = SampleSet::union_len(tracks.iter().map(|t| &t.violating));
    m.certain_violating_samples = SampleSet::union_len(tracks.iter().map(|t| &t.certain));
    m.violation_fraction = if m.samples > 0 {
        m.violating_samples as f64 / m.samples as f64
    } else {
        0.0
    };
    m.inconclusive_duration = union_length(inconclusive_iv);
    if ids.len() > 1 {
        let first = &people_models[0].human;
        if people_models.iter().any(|p| &p.human != first) {
            out.models.human = people_models
                .iter()
                .map(|p| format!("{}: {}", p.id, p.human))
                .collect::<Vec<_>>()
                .join("; ");
        }
        if let Some(specs) = out.models.specs.as_object_mut() {
            specs.insert("humans".into(), serde_json::Value::Object(human_specs));
        }
        out.models.people = people_models;
    }
    out.people = ids;
    out.refresh_verdict();
    out
}

/// The plot series of two passes over the same robot samples: bucket by bucket where they
/// align (least separation, largest energy bound, least threshold, either flag), else the
/// first's.
fn merge_series(mut a: Vec<SeriesPoint>, b: &[SeriesPoint]) -> Vec<SeriesPoint> {
    if a.len() != b.len()
        || a.iter()
            .zip(b)
            .any(|(x, y)| x.t != y.t || x.t_end != y.t_end)
    {
        return a;
    }
    for (x, y) in a.iter_mut().zip(b) {
        x.min_separation = min_opt(x.min_separation, y.min_separation);
        x.far_separation = min_opt(x.far_separation, y.far_separation);
        x.energy_bound = crate::series::max_opt(x.energy_bound, y.energy_bound);
        x.threshold = min_opt(x.threshold, y.threshold);
        x.violation |= y.violation;
        x.inconclusive |= y.inconclusive;
        x.at_rest &= y.at_rest;
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_sets_count_their_union_once() {
        let (mut a, mut b) = (SampleSet::default(), SampleSet::default());
        for i in [1, 2, 3, 7, 8] {
            a.insert(i);
        }
        for i in [3, 4, 8, 20] {
            b.insert(i);
        }
        // {1,2,3,4,7,8,20}
        assert_eq!(SampleSet::union_len([&a, &b]), 7);
        assert_eq!(SampleSet::union_len([&a]), 5);
        assert_eq!(SampleSet::union_len(std::iter::empty()), 0);
    }

    #[test]
    fn interval_union_counts_overlaps_once() {
        assert_eq!(union_length(vec![(0.0, 1.0), (0.5, 2.0), (3.0, 3.5)]), 2.5);
        assert_eq!(union_length(vec![]), 0.0);
    }
}
