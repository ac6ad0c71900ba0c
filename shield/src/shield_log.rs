//! Writing a shield run as an audit log (format v1, `pacs_log`): the robot's commanded
//! samples (positions, velocities and accelerations), the human measurements the shield received, and the shield's diagnostics, so that
//! `pacs audit` can check the run offline.

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
}

impl<W: Write> ShieldLog<W> {
    /// Start a log with `header`; the robot is at rest at `q0` (rad) at time `t0` (s) (written
    /// with the first step, after its measurement).
    pub fn new(out: W, header: &Header, t0: f64, q0: &[f64]) -> Result<Self, WriteError> {
        let mut w = LogWriter::new(out);
        w.write_header(header)?;
        Ok(Self {
            w,
            last_meas: f64::NEG_INFINITY,
            last_t: t0,
            positions: Vec::new(),
            pending: Some(q0.to_vec()),
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
            && m.time() > self.last_meas
        {
            self.human(t, m)?;
        }
        if let Some(q0) = self.pending.take() {
            let t0 = self.last_t;
            let zeros = vec![0.0; q0.len()];
            self.w
                .write_robot_with_acc(t0, &q0, Some(&zeros), Some(&zeros))?;
        }
        let n = cmd.dof;
        let tc = cmd.t.max(self.last_t);
        self.last_t = tc;
        // The commanded accelerations let the audit use the jerk limit between samples.
        self.w.write_robot_with_acc(
            tc,
            &cmd.state.q[..n],
            Some(&cmd.state.dq[..n]),
            Some(&cmd.state.ddq[..n]),
        )?;
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
        self.last_meas = self.last_meas.max(m.time());
        self.positions.clear();
        self.positions
            .extend(m.positions().iter().map(|p| [p.x, p.y, p.z]));
        // Step times k·α and command times t + α may differ by rounding: keep t monotone. The
        // start sample, if still pending, follows at this time (the robot is at rest at q0 until
        // the first command: a first step later than the start must not put it before).
        self.last_t = t.max(self.last_t);
        self.w.write_human(self.last_t, m.time(), &self.positions)
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

    /// A named event (`episode_start`, `success`, `failure`, ...).
    pub fn event(&mut self, t: f64, name: &str) -> Result<(), WriteError> {
        self.last_t = t.max(self.last_t);
        self.w.write_event(self.last_t, name)
    }

    /// Flush and return the writer.
    pub fn finish(mut self) -> Result<W, WriteError> {
        if let Some(q0) = self.pending.take() {
            let t0 = self.last_t;
            let zeros = vec![0.0; q0.len()];
            self.w
                .write_robot_with_acc(t0, &q0, Some(&zeros), Some(&zeros))?;
        }
        self.w.finish()
    }
}
