//! Writing a shield run as an audit log (format v2, `pacs_log`): the robot's commanded
//! samples (positions, velocities and accelerations), every person's measurements the shield
//! received (each with its person id), and the shield's diagnostics, so that `pacs audit` can
//! check the run offline; the header promises an `end` event and [`ShieldLog::finish`] writes
//! it, so that a log cut short is never audited as the whole run.

use crate::shield::Command;
use pacs_log::{Header, LogWriter, WriteError};
use pacs_reach::human::HumanMeasurement;
use std::io::Write;

/// A JSON Lines log of one shield run.
pub struct ShieldLog<W: Write> {
    w: LogWriter<W>,
    last_meas: f64,
    last_t: f64,
    positions: Vec<[f64; 3]>,
    /// The initial robot sample, written after the first measurement so that the first span
    /// already has a human record.
    pending: Option<Vec<f64>>,
    /// Person ids of the header, in the shield's human order.
    people: Vec<String>,
    /// Whether the `end` event was written.
    ended: bool,
}

impl<W: Write> ShieldLog<W> {
    /// Start a log with `header`; the robot is at rest at `q0` (rad) at time `t0` (s) (written
    /// with the first step, after its measurement).
    ///
    /// The header is written as version 2 with the end-event promise
    /// ([`Header::promising_end`]: a v1 header's person becomes person `human`); its people are
    /// the shield's humans in order (human `i` of the shield is `header.humans[i]`).
    pub fn new(out: W, header: &Header, t0: f64, q0: &[f64]) -> Result<Self, WriteError> {
        let header = header.clone().promising_end();
        let mut w = LogWriter::new(out);
        w.write_header(&header)?;
        Ok(Self {
            w,
            last_meas: f64::NEG_INFINITY,
            last_t: t0,
            positions: Vec::new(),
            pending: Some(q0.to_vec()),
            people: header.humans.iter().map(|p| p.id.clone()).collect(),
            ended: false,
        })
    }

    /// Record one step at time `t`: the measurement the shield received (if new), then the
    /// commanded sample at `cmd.t` and its diagnostics.
    pub fn record(
        &mut self,
        t: f64,
        meas: Option<&HumanMeasurement>,
        cmd: &Command,
    ) -> Result<(), WriteError> {
        if let Some(m) = meas
            && pacs_reach::stamp_supersedes(m.time(), Some(self.last_meas))
        {
            self.human(t, m)?;
        }
        if let Some(q0) = self.pending.take() {
            let t0 = self.last_t;
            let zeros = vec![0.0; q0.len()];
            self.w
                .write_robot_with_acc(t0, &q0, Some(&zeros), Some(&zeros))?;
        }
        let tc = cmd.t.max(self.last_t);
        self.last_t = tc;
        // The commanded accelerations let the audit use the jerk limit between samples.
        self.w
            .write_robot_with_acc(tc, cmd.q(), Some(cmd.dq()), Some(cmd.ddq()))?;
        let d = &cmd.diag;
        let mut fields = serde_json::Map::new();
        fields.insert("verified".into(), d.verified.into());
        fields.insert("on_failsafe".into(), d.on_failsafe.into());
        fields.insert("path_speed".into(), d.path_speed.into());
        if d.min_separation.is_finite() {
            fields.insert("min_separation".into(), d.min_separation.into());
        }
        // JSON has no infinity or NaN (serde would write `null` where a number is promised):
        // an energy bound that overflowed (or is NaN, which the shield treats as unbounded) is
        // logged as the largest float, still an upper bound of every energy.
        let bound = |x: f64| if x.is_finite() { x } else { f64::MAX };
        fields.insert("contact_energy".into(), bound(d.contact_energy).into());
        fields.insert(
            "contact_threshold".into(),
            bound(d.contact_threshold).into(),
        );
        if let Ok(b) = serde_json::to_value(d.binding) {
            fields.insert("binding".into(), b);
        }
        self.w.write_shield(tc, &fields)
    }

    /// A human measurement delivered to the shield at step time `t` (s), written whether or not
    /// the shield uses it (it keeps the newest by stamp): a runner that receives several in one
    /// step, or one late, logs each, so that the audit checks every one against the human model
    /// beside its neighbours in time (a record contradicting the others cannot hide behind a
    /// newer one). [`Self::record`] then writes no copy of it.
    pub fn human(&mut self, t: f64, m: &HumanMeasurement) -> Result<(), WriteError> {
        self.person(t, 0, m)
    }

    /// A measurement of the shield's human `index` (the header's `humans[index]`), delivered
    /// at step time `t` (s): as [`Self::human`], with the person's id.
    pub fn person(&mut self, t: f64, index: usize, m: &HumanMeasurement) -> Result<(), WriteError> {
        let Some(id) = self.people.get(index) else {
            return Err(WriteError::Order(
                "a measurement of a human the log header does not declare",
            ));
        };
        if index == 0 && pacs_reach::stamp_supersedes(m.time(), Some(self.last_meas)) {
            self.last_meas = m.time();
        }
        self.positions.clear();
        self.positions
            .extend(m.positions().iter().map(|p| [p.x, p.y, p.z]));
        // Step times k·α and command times t + α may differ by rounding: keep t monotone. The
        // start sample, if still pending, follows at this time (the robot is at rest at q0 until
        // the first command: a first step later than the start must not put it before).
        self.last_t = t.max(self.last_t);
        self.w
            .write_person(self.last_t, m.time(), Some(id), &self.positions)
    }

    /// A measurement of the header's object `id`, given to the shield at step time `t` (s):
    /// written as an `object` record (before the step's robot sample in the audit's order).
    pub fn object(
        &mut self,
        t: f64,
        id: &str,
        m: &pacs_reach::object::ObjectMeasurement,
    ) -> Result<(), WriteError> {
        self.last_t = t.max(self.last_t);
        self.w
            .write_object(self.last_t, m.time, id, m.position, m.velocity)
    }

    /// A named event (`episode_start`, `success`, `failure`, ...). The `end` event is
    /// [`Self::finish`]'s: it is refused here.
    pub fn event(&mut self, t: f64, name: &str) -> Result<(), WriteError> {
        if name == pacs_log::END_EVENT {
            return Err(WriteError::Order(
                "the `end` event is written by ShieldLog::finish, last",
            ));
        }
        self.last_t = t.max(self.last_t);
        self.w.write_event(self.last_t, name)
    }

    /// Write the `end` event (at the last record's time, which the last robot sample reaches
    /// unless measurements were logged after it), flush and return the writer. A log not
    /// finished this way lacks its end and audits `incomplete_log`.
    pub fn finish(mut self) -> Result<W, WriteError> {
        if let Some(q0) = self.pending.take() {
            let t0 = self.last_t;
            let zeros = vec![0.0; q0.len()];
            self.w
                .write_robot_with_acc(t0, &q0, Some(&zeros), Some(&zeros))?;
        }
        if !self.ended {
            self.ended = true;
            self.w.write_event(self.last_t, pacs_log::END_EVENT)?;
        }
        self.w.finish()
    }
}
