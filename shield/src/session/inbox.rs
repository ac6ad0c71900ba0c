//! The measurement inbox: timed measurements of people and objects (and, ordered among them,
//! the runner's own timed inputs such as chunk hand-overs) held until the first safety step at or
//! after their arrival time, then handed to the [`Shield`] through its measurement calls and
//! written to the run's [`ShieldLog`].

use crate::shield::{Shield, ShieldError};
use crate::shield_log::ShieldLog;
use pacs_log::WriteError;
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use std::collections::VecDeque;
use std::io::Write;
use thiserror::Error;

/// What takes delivered measurements: the shield, or any filter behind the same interface (the
/// baselines). The receiver keeps the newest of each person and object
/// ([`pacs_reach::stamped`]).
pub trait MeasurementSink {
    /// Record a measurement of person `id` (held against the trusted ones: an older one than
    /// the latest that agrees is ignored).
    fn measure_human(&mut self, id: usize, m: &HumanMeasurement) -> Result<(), ShieldError>;
    /// Record a measurement of object `id` (held against the trusted ones: an older one than
    /// the latest that agrees is ignored).
    fn measure_object(&mut self, id: usize, m: &ObjectMeasurement) -> Result<(), ShieldError>;
}

impl MeasurementSink for Shield {
    fn measure_human(&mut self, id: usize, m: &HumanMeasurement) -> Result<(), ShieldError> {
        Shield::measure_human(self, id, m)
    }
    fn measure_object(&mut self, id: usize, m: &ObjectMeasurement) -> Result<(), ShieldError> {
        Shield::measure_object(self, id, m)
    }
}

/// Errors of [`MeasurementInbox`].
#[derive(Debug, Error)]
pub enum InboxError {
    /// An arrival time (s) that is NaN or infinite: it could never be ordered against a step.
    #[error("arrival time {0} s is not finite")]
    NotFinite(f64),
    /// The shield refused the measurement: pushed for a person or object index beyond those
    /// the inbox was made for ([`ShieldError::UnknownHuman`], [`ShieldError::UnknownObject`],
    /// the shield's own errors), or refused when delivered.
    #[error(transparent)]
    Shield(#[from] ShieldError),
    /// An arrival (s) before the measurement's time stamp (s): delivered then, it would reach
    /// the shield from the future.
    #[error("arrival time {arrival} s is before the time stamp {stamp} s")]
    BeforeStamp { arrival: f64, stamp: f64 },
}

/// One waiting input.
#[derive(Debug, Clone)]
enum Item<C> {
    Person(usize, HumanMeasurement),
    Object(usize, ObjectMeasurement),
    Other(C),
}

/// A waiting input as [`MeasurementInbox::pending`] shows it.
#[derive(Debug, Clone, Copy)]
pub enum Pending<'a, C> {
    /// A measurement of person `.0` (the shield's human index).
    Person(usize, &'a HumanMeasurement),
    /// A measurement of object `.0` (the shield's object index).
    Object(usize, &'a ObjectMeasurement),
    /// One of the runner's own inputs ([`MeasurementInbox::push_other`]).
    Other(&'a C),
}

/// Timed measurements waiting for their safety step.
///
/// Guarantees:
/// - **When**: an input pushed with arrival time `a` (s) is delivered by the first
///   [`Self::due`]`(t)` with `a <= t` (compared exactly, never early), and never again.
/// - **Order**: inputs due at one step are delivered in arrival order, inputs of equal arrival
///   in push order (the order of a stable sort by arrival).
/// - **Where**: a measurement of person 0 is logged and offered as the step's measurement (the
///   newest of the step's by [`pacs_reach::stamped::supersedes`], the first of equal stamps),
///   which the caller passes to [`Shield::step`]; one of another person goes to
///   [`Shield::measure_human`]; an object's to [`Shield::measure_object`] (the shield keeps the
///   newest, so out-of-order stamps are decided by its rule); every delivered measurement is
///   written to the log, whether the shield uses it or not. The runner's own inputs
///   ([`Self::push_other`]) are handed to its callback in the same order.
/// - **Cost**: [`Self::due`] does not allocate, apart from what the log writer does; pushes
///   allocate only while the queue grows beyond its largest size so far.
///
/// `C` is the runner's own timed input (a chunk index, for example); `()` when there is none.
#[derive(Debug, Clone)]
pub struct MeasurementInbox<C = ()> {
    /// Waiting inputs with their arrival times (s), sorted by arrival, stable.
    queue: VecDeque<(f64, Item<C>)>,
    /// The number of people (the shield's humans).
    people: usize,
    /// Object ids, in the shield's object order (the log names objects by id).
    object_ids: Vec<String>,
    /// Person 0's measurement for the current step.
    current: Option<HumanMeasurement>,
    /// Waiting measurements of people and of objects.
    waiting_people: usize,
    waiting_objects: usize,
}

/// What [`MeasurementInbox::due`] delivered at one step.
#[derive(Debug)]
pub struct Due<'a> {
    /// Person 0's measurement for this step (`None` if none was due), for [`Shield::step`] and
    /// [`ShieldLog::record`].
    pub first: Option<&'a HumanMeasurement>,
    /// The first log write that failed: every due input still reached the shield, but nothing
    /// more was written to the log in this step.
    pub log_error: Option<WriteError>,
}

impl<C> MeasurementInbox<C> {
    /// An empty inbox for `people` people (the shield's humans) and the objects `object_ids`
    /// (in the shield's object order; the log names objects by these ids).
    pub fn new(people: usize, object_ids: Vec<String>) -> Self {
        Self {
            queue: VecDeque::new(),
            people,
            object_ids,
            current: None,
            waiting_people: 0,
            waiting_objects: 0,
        }
    }

    /// Insert after every input arriving at or before `arrival` (s); a measurement stamped
    /// `stamp` (s) must not arrive before it.
    fn insert(&mut self, arrival: f64, stamp: f64, item: Item<C>) -> Result<(), InboxError> {
        if !arrival.is_finite() {
            return Err(InboxError::NotFinite(arrival));
        }
        if arrival < stamp {
            return Err(InboxError::BeforeStamp { arrival, stamp });
        }
        let at = self
            .queue
            .partition_point(|(a, _)| a.total_cmp(&arrival).is_le());
        self.queue.insert(at, (arrival, item));
        Ok(())
    }

    /// A measurement of person `person` (the shield's human index) arriving at `arrival` (s).
    /// Errors: a non-finite arrival, one before the measurement's stamp, an unknown person.
    pub fn push_person(
        &mut self,
        arrival: f64,
        person: usize,
        m: HumanMeasurement,
    ) -> Result<(), InboxError> {
        if person >= self.people {
            return Err(ShieldError::UnknownHuman {
                id: person,
                count: self.people,
            }
            .into());
        }
        self.insert(arrival, m.time(), Item::Person(person, m))?;
        self.waiting_people += 1;
        Ok(())
    }

    /// A measurement of object `object` (the shield's object index) arriving at `arrival` (s).
    /// Errors: a non-finite arrival, one before the measurement's stamp, an unknown object.
    pub fn push_object(
        &mut self,
        arrival: f64,
        object: usize,
        m: ObjectMeasurement,
    ) -> Result<(), InboxError> {
        if object >= self.object_ids.len() {
            return Err(ShieldError::UnknownObject {
                id: object,
                count: self.object_ids.len(),
            }
            .into());
        }
        self.insert(arrival, m.time, Item::Object(object, m))?;
        self.waiting_objects += 1;
        Ok(())
    }

    /// One of the runner's own inputs arriving at `arrival` (s), delivered to the callback of
    /// [`Self::due`] in order with the measurements. Errors: a non-finite arrival.
    pub fn push_other(&mut self, arrival: f64, other: C) -> Result<(), InboxError> {
        self.insert(arrival, f64::NEG_INFINITY, Item::Other(other))
    }

    /// The number of inputs waiting.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// The number of measurements of people waiting.
    pub fn people_waiting(&self) -> usize {
        self.waiting_people
    }

    /// The number of object measurements waiting.
    pub fn objects_waiting(&self) -> usize {
        self.waiting_objects
    }

    /// The inputs still waiting, in delivery order, each with its arrival time (s).
    pub fn pending(&self) -> impl Iterator<Item = (f64, Pending<'_, C>)> {
        self.queue.iter().map(|(a, i)| {
            let p = match i {
                Item::Person(k, m) => Pending::Person(*k, m),
                Item::Object(k, m) => Pending::Object(*k, m),
                Item::Other(c) => Pending::Other(c),
            };
            (*a, p)
        })
    }

    /// The object ids the inbox was made with, in the shield's object order.
    pub fn object_ids(&self) -> &[String] {
        &self.object_ids
    }

    /// Deliver every input that arrived at or before the step time `t` (s), in arrival order
    /// (see the type's guarantees): measurements of people other than person 0 and of objects
    /// to `shield`, each measurement to `log` if given (at step time `t`), the runner's own
    /// inputs to `other` (with the log, unless a write failed). Returns person 0's measurement
    /// for this step and the first log write that failed.
    ///
    /// A log write failure does not stop delivery (the log is left alone for the rest of the
    /// step). On an error of the shield or of `other` the failing input has been taken out of
    /// the queue; those after it still wait. The inbox does not allocate here (the log
    /// writer's object records do: they format the object's id).
    pub fn due<S, W, E>(
        &mut self,
        t: f64,
        shield: &mut S,
        mut log: Option<&mut ShieldLog<W>>,
        mut other: impl FnMut(&mut S, Option<&mut ShieldLog<W>>, C) -> Result<(), E>,
    ) -> Result<Due<'_>, E>
    where
        S: MeasurementSink + ?Sized,
        W: Write,
        E: From<InboxError>,
    {
        self.current = None;
        let mut log_error = None;
        let mut write =
            |log: &mut Option<&mut ShieldLog<W>>,
             f: &mut dyn FnMut(&mut ShieldLog<W>) -> Result<(), WriteError>| {
                if let Some(l) = log.as_deref_mut()
                    && let Err(e) = f(l)
                {
                    log_error = Some(e);
                    *log = None;
                }
            };
        while self.queue.front().is_some_and(|(a, _)| *a <= t) {
            let Some((_, item)) = self.queue.pop_front() else {
                break;
            };
            match item {
                Item::Person(p, m) => {
                    self.waiting_people -= 1;
                    write(&mut log, &mut |l| l.person(t, p, &m));
                    // Every measurement is held against the trusted ones (`HumanSlot::take`),
                    // person 0's too, not only the newest of the step that `step` is handed.
                    shield.measure_human(p, &m).map_err(InboxError::from)?;
                    if p == 0 && m.supersedes(self.current.as_ref()) {
                        self.current = Some(m);
                    }
                }
                Item::Object(k, m) => {
                    self.waiting_objects -= 1;
                    shield.measure_object(k, &m).map_err(InboxError::from)?;
                    let id = &self.object_ids[k];
                    write(&mut log, &mut |l| l.object(t, id, &m));
                }
                Item::Other(c) => other(shield, log.as_deref_mut(), c)?,
            }
        }
        Ok(Due {
            first: self.current.as_ref(),
            log_error,
        })
    }

    /// [`Self::due`] for an inbox without inputs of the runner's own.
    pub fn deliver<S: MeasurementSink + ?Sized, W: Write>(
        &mut self,
        t: f64,
        shield: &mut S,
        log: Option<&mut ShieldLog<W>>,
    ) -> Result<Due<'_>, InboxError> {
        self.due(t, shield, log, |_, _, _| Ok::<(), InboxError>(()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shield::ShieldConfig;
    use pacs_log::{Header, ModelRef, PersonEntry};
    use pacs_models::object::{ObjectContact, ObjectModel, ObjectSpec, ShapeSpec};
    use pacs_models::{ConstraintSpec, default_human, fr3};

    const DT: f64 = 0.001;

    fn ball() -> ObjectModel {
        ObjectModel::new(&ObjectSpec {
            name: "ball".into(),
            shape: ShapeSpec::Sphere { radius: 0.05 },
            max_acc: 2.0,
            acc_bias: [0.0; 3],
            acc_generators: vec![],
            max_speed: Some(1.0),
            measurement_error_pos: 0.005,
            measurement_error_vel: 0.02,
            delay: 0.02,
        })
        .unwrap()
    }

    /// A started shield with two people and one object, its inbox and a log into memory.
    fn setup() -> (Shield, MeasurementInbox<u32>, ShieldLog<Vec<u8>>) {
        let human = default_human();
        let spec = ConstraintSpec::builtin("sorting").unwrap();
        let mut sh = Shield::new(
            fr3::fr3(),
            Some((human.clone(), &spec)),
            vec![],
            ShieldConfig::default(),
        )
        .unwrap();
        sh.add_human(human, &spec).unwrap();
        sh.add_object(ball(), ObjectContact::NoContact).unwrap();
        sh.start(0.0, &fr3::Q_READY).unwrap();
        let people = ["a", "b"]
            .iter()
            .map(|id| PersonEntry {
                id: id.to_string(),
                human: ModelRef::Name("default".into()),
            })
            .collect();
        let header = Header::with_people(
            ModelRef::Name("fr3".into()),
            people,
            ModelRef::Name("sorting".into()),
        );
        let log = ShieldLog::new(Vec::new(), &header, 0.0, &fr3::Q_READY).unwrap();
        (sh, MeasurementInbox::new(2, vec!["ball".into()]), log)
    }

    fn person(t: f64) -> HumanMeasurement {
        let kp = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
        HumanMeasurement::new(&default_human(), t, &kp, None).unwrap()
    }

    fn object(t: f64) -> ObjectMeasurement {
        ObjectMeasurement {
            time: t,
            position: [2.0, 0.0, 0.5],
            velocity: None,
        }
    }

    /// The (kind, id, stamp) of every measurement record in the log, in order.
    fn logged(log: ShieldLog<Vec<u8>>) -> Vec<(String, String, f64)> {
        let bytes = log.finish().unwrap();
        String::from_utf8(bytes)
            .unwrap()
            .lines()
            .filter_map(|l| {
                let v: serde_json::Value = serde_json::from_str(l).unwrap();
                let kind = v["type"].as_str()?.to_string();
                (kind == "human" || kind == "object").then(|| {
                    let id = v["id"].as_str().unwrap_or_default().to_string();
                    let stamp = v["t_meas"].as_f64().unwrap_or(f64::NAN);
                    (kind, id, stamp)
                })
            })
            .collect()
    }

    fn no_other(
        _: &mut Shield,
        _: Option<&mut ShieldLog<Vec<u8>>>,
        _: u32,
    ) -> Result<(), InboxError> {
        Ok(())
    }

    #[test]
    fn arrival_exactly_at_a_step_is_delivered_at_that_step() {
        let (mut sh, mut inbox, mut log) = setup();
        inbox.push_person(2.0 * DT, 0, person(2.0 * DT)).unwrap();
        for k in 0..2 {
            let t = k as f64 * DT;
            assert!(
                inbox
                    .due(t, &mut sh, Some(&mut log), no_other)
                    .unwrap()
                    .first
                    .is_none()
            );
        }
        let m = inbox
            .due(2.0 * DT, &mut sh, Some(&mut log), no_other)
            .unwrap();
        assert_eq!(m.first.map(|m| m.time()), Some(2.0 * DT));
        assert!(inbox.is_empty());
        // Delivered once.
        assert!(
            inbox
                .due(3.0 * DT, &mut sh, Some(&mut log), no_other)
                .unwrap()
                .first
                .is_none()
        );
        assert_eq!(logged(log).len(), 1);
    }

    #[test]
    fn arrival_between_steps_waits_for_the_next_step() {
        let (mut sh, mut inbox, _) = setup();
        // Stamped at 1 ms, received 1.5 ms later.
        inbox.push_person(2.5 * DT, 1, person(DT)).unwrap();
        inbox.push_object(0.5 * DT, 0, object(0.0)).unwrap();
        assert_eq!((inbox.people_waiting(), inbox.objects_waiting()), (1, 1));
        inbox.deliver::<_, Vec<u8>>(0.0, &mut sh, None).unwrap();
        assert_eq!(inbox.len(), 2);
        inbox.deliver::<_, Vec<u8>>(DT, &mut sh, None).unwrap();
        assert_eq!((inbox.people_waiting(), inbox.objects_waiting()), (1, 0));
        inbox
            .deliver::<_, Vec<u8>>(2.0 * DT, &mut sh, None)
            .unwrap();
        assert_eq!(inbox.len(), 1);
        let first = inbox
            .deliver::<_, Vec<u8>>(3.0 * DT, &mut sh, None)
            .unwrap()
            .first;
        assert!(
            first.is_none(),
            "person 1 is not the step's person-0 measurement"
        );
        assert!(inbox.is_empty());
    }

    #[test]
    fn out_of_order_stamps_are_all_logged_and_the_newest_is_used() {
        let (mut sh, mut inbox, mut log) = setup();
        // Stamps 3, 1, 2 ms arriving in that order, then an equal-stamp one; all due at 5 ms.
        for (arrival, stamp) in [(3.0, 3.0), (3.5, 1.0), (4.0, 2.0), (4.5, 3.0)] {
            inbox
                .push_person(arrival * DT, 0, person(stamp * DT))
                .unwrap();
        }
        let m = inbox
            .due(5.0 * DT, &mut sh, Some(&mut log), no_other)
            .unwrap();
        assert_eq!(m.first.map(|m| m.time()), Some(3.0 * DT));
        let stamps: Vec<f64> = logged(log).iter().map(|r| r.2 / DT).collect();
        let rounded: Vec<i64> = stamps.iter().map(|s| s.round() as i64).collect();
        assert_eq!(rounded, [3, 1, 2, 3], "logged in arrival order, every one");
    }

    #[test]
    fn several_people_and_objects_in_arrival_order_with_the_runners_inputs() {
        let (mut sh, mut inbox, mut log) = setup();
        inbox.push_object(2.0 * DT, 0, object(DT)).unwrap();
        inbox.push_person(DT, 1, person(DT)).unwrap();
        inbox.push_other(DT, 7).unwrap();
        inbox.push_person(DT, 0, person(0.5 * DT)).unwrap();
        assert!(matches!(
            inbox.push_person(DT, 2, person(DT)),
            Err(InboxError::Shield(ShieldError::UnknownHuman {
                id: 2,
                count: 2
            }))
        ));
        assert!(matches!(
            inbox.push_object(f64::NAN, 0, object(DT)),
            Err(InboxError::NotFinite(_))
        ));
        assert!(matches!(
            inbox.push_object(0.5 * DT, 0, object(DT)),
            Err(InboxError::BeforeStamp { .. })
        ));
        let order: Vec<char> = inbox
            .pending()
            .map(|(_, p)| match p {
                Pending::Person(0, _) => '0',
                Pending::Person(_, _) => '1',
                Pending::Object(..) => 'o',
                Pending::Other(_) => 'c',
            })
            .collect();
        assert_eq!(order, ['1', 'c', '0', 'o']);
        let mut seen = Vec::new();
        let m = inbox
            .due(2.0 * DT, &mut sh, Some(&mut log), |_, _, c| {
                seen.push(c);
                Ok::<(), InboxError>(())
            })
            .unwrap()
            .first;
        assert_eq!(m.map(|m| m.time()), Some(0.5 * DT));
        assert_eq!(seen, [7]);
        let ids: Vec<String> = logged(log).into_iter().map(|r| r.1).collect();
        assert_eq!(ids, ["b", "a", "ball"]);
    }

    #[test]
    fn delivery_does_not_allocate_after_warm_up() {
        let (mut sh, mut inbox, _) = setup();
        let m = person(0.0);
        for k in 0..64 {
            inbox.push_person(k as f64 * DT, 1, m.clone()).unwrap();
        }
        let cap = inbox.queue.capacity();
        for k in 0..64 {
            inbox
                .deliver::<_, Vec<u8>>(k as f64 * DT, &mut sh, None)
                .unwrap();
        }
        assert!(inbox.is_empty());
        assert_eq!(inbox.queue.capacity(), cap, "the queue keeps its storage");
    }

    /// A writer that takes `budget` bytes, then fails.
    struct Failing {
        budget: usize,
    }

    impl Write for Failing {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if buf.len() > self.budget {
                return Err(std::io::Error::other("disk full"));
            }
            self.budget -= buf.len();
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_failing_log_does_not_stop_delivery() {
        let (mut sh, mut inbox, _) = setup();
        let header = Header::with_people(
            ModelRef::Name("fr3".into()),
            vec![
                PersonEntry {
                    id: "a".into(),
                    human: ModelRef::Name("default".into()),
                },
                PersonEntry {
                    id: "b".into(),
                    human: ModelRef::Name("default".into()),
                },
            ],
            ModelRef::Name("sorting".into()),
        );
        let mut log =
            ShieldLog::new(Failing { budget: 4096 }, &header, 0.0, &fr3::Q_READY).unwrap();
        for _ in 0..64 {
            inbox.push_person(0.0, 1, person(0.0)).unwrap();
        }
        inbox.push_person(0.0, 0, person(0.0)).unwrap();
        let due = inbox
            .due(0.0, &mut sh, Some(&mut log), |_, _, _: u32| {
                Ok::<(), InboxError>(())
            })
            .unwrap();
        assert!(due.log_error.is_some());
        assert!(due.first.is_some(), "person 0 was still delivered");
        assert!(inbox.is_empty());
    }
}
