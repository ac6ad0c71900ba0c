//! The JSON Lines writer the shield uses.

use super::Header;
use std::io::Write;

/// Errors of [`LogWriter`].
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// A value is NaN or infinite (the format only holds finite numbers).
    #[error("{field}: value {value} is not finite")]
    NotFinite {
        /// Field name.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// Time went backwards.
    #[error("t = {t} s is before the previous record's t = {previous} s")]
    Backwards {
        /// This record's time (s).
        t: f64,
        /// Previous time (s).
        previous: f64,
    },
    /// The header was not written first, or written twice.
    #[error("{0}")]
    Order(&'static str),
    /// Accelerations without velocities (the format holds `ddq` only together with `dq`).
    #[error("ddq: accelerations are written only together with velocities (dq)")]
    AccelerationsWithoutVelocities,
    /// A measurement stamped after the record's time (the audit refuses such a log: a
    /// measurement cannot come from the future).
    #[error(
        "t_meas = {t_meas} s is after the record's t = {t} s (a measurement cannot come from the future)"
    )]
    FromFuture {
        /// The measurement's stamp (s).
        t_meas: f64,
        /// The record's time (s).
        t: f64,
    },
    /// Serialization or I/O failed.
    #[error("write failed: {0}")]
    Io(#[from] std::io::Error),
}

/// Writes a JSON Lines log. Guarantees: header first, finite numbers only, non-decreasing `t`;
/// floats are written in shortest round-trip form, so a reader gets back the exact values; where
/// the header promises a `start` event, it is written just before the first robot sample.
pub struct LogWriter<W: Write> {
    out: W,
    header_written: bool,
    last_t: f64,
    /// The header promises a `start` event (`start_event`).
    start_promised: bool,
    /// That event is still to be written (before the first robot sample).
    start_due: bool,
}

fn finite(field: &'static str, v: f64) -> Result<(), WriteError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(WriteError::NotFinite { field, value: v })
    }
}

fn write_list<W: Write>(out: &mut W, field: &'static str, v: &[f64]) -> Result<(), WriteError> {
    out.write_all(b"[")?;
    for (i, x) in v.iter().enumerate() {
        finite(field, *x)?;
        if i > 0 {
            out.write_all(b",")?;
        }
        write!(out, "{x:?}")?;
    }
    out.write_all(b"]")?;
    Ok(())
}

impl<W: Write> LogWriter<W> {
    /// A writer on `out` (wrap files in a `BufWriter`).
    pub fn new(out: W) -> Self {
        Self {
            out,
            header_written: false,
            last_t: f64::NEG_INFINITY,
            start_promised: false,
            start_due: false,
        }
    }

    /// Write the header line (must be first).
    pub fn write_header(&mut self, h: &Header) -> Result<(), WriteError> {
        if self.header_written {
            return Err(WriteError::Order("header written twice"));
        }
        serde_json::to_writer(&mut self.out, h).map_err(std::io::Error::from)?;
        self.out.write_all(b"\n")?;
        self.header_written = true;
        self.start_promised = h.start_event;
        self.start_due = h.start_event;
        Ok(())
    }

    fn begin(&mut self, t: f64) -> Result<(), WriteError> {
        if !self.header_written {
            return Err(WriteError::Order("write_header must come first"));
        }
        finite("t", t)?;
        if t < self.last_t {
            return Err(WriteError::Backwards {
                t,
                previous: self.last_t,
            });
        }
        self.last_t = t;
        Ok(())
    }

    /// A robot sample: time (s), joint positions (rad), optional velocities (rad/s).
    pub fn write_robot(&mut self, t: f64, q: &[f64], dq: Option<&[f64]>) -> Result<(), WriteError> {
        self.write_robot_with_acc(t, q, dq, None)
    }

    /// A robot sample with optional accelerations (rad/s²; only together with `dq`: `ddq`
    /// without `dq` is refused, never dropped silently).
    pub fn write_robot_with_acc(
        &mut self,
        t: f64,
        q: &[f64],
        dq: Option<&[f64]>,
        ddq: Option<&[f64]>,
    ) -> Result<(), WriteError> {
        if dq.is_none() && ddq.is_some() {
            return Err(WriteError::AccelerationsWithoutVelocities);
        }
        // Every value checked before anything is written: a refused sample leaves no partial
        // line (and no `start` event before it).
        for (field, v) in [("q", Some(q)), ("dq", dq), ("ddq", ddq)] {
            for x in v.unwrap_or(&[]) {
                finite(field, *x)?;
            }
        }
        self.begin(t)?;
        if self.start_due {
            // The promised `start`, at the first robot sample's time, just before it.
            self.start_due = false;
            self.event_line(t, super::START_EVENT)?;
        }
        write!(self.out, "{{\"type\":\"robot\",\"t\":{t:?},\"q\":")?;
        write_list(&mut self.out, "q", q)?;
        if let Some(dq) = dq {
            self.out.write_all(b",\"dq\":")?;
            write_list(&mut self.out, "dq", dq)?;
            if let Some(ddq) = ddq {
                self.out.write_all(b",\"ddq\":")?;
                write_list(&mut self.out, "ddq", ddq)?;
            }
        }
        self.out.write_all(b"}\n")?;
        Ok(())
    }

    /// A human measurement: log time `t`, measurement time `t_meas` (s), keypoints (m), without
    /// a person id (a v1 log, or a v2 log of one person).
    pub fn write_human(
        &mut self,
        t: f64,
        t_meas: f64,
        positions: &[[f64; 3]],
    ) -> Result<(), WriteError> {
        self.write_person(t, t_meas, None, positions)
    }

    /// A measurement of person `id` (a v2 header's `humans[].id`; `None`: the only person):
    /// log time `t`, measurement time `t_meas` (s), keypoints (m).
    pub fn write_person(
        &mut self,
        t: f64,
        t_meas: f64,
        id: Option<&str>,
        positions: &[[f64; 3]],
    ) -> Result<(), WriteError> {
        finite("t_meas", t_meas)?;
        if t_meas > t {
            return Err(WriteError::FromFuture { t_meas, t });
        }
        self.begin(t)?;
        write!(
            self.out,
            "{{\"type\":\"human\",\"t\":{t:?},\"t_meas\":{t_meas:?},"
        )?;
        if let Some(id) = id {
            self.out.write_all(b"\"id\":")?;
            serde_json::to_writer(&mut self.out, id).map_err(std::io::Error::from)?;
            self.out.write_all(b",")?;
        }
        self.out.write_all(b"\"positions\":[")?;
        for (i, p) in positions.iter().enumerate() {
            if i > 0 {
                self.out.write_all(b",")?;
            }
            write_list(&mut self.out, "positions", p)?;
        }
        self.out.write_all(b"]}\n")?;
        Ok(())
    }

    /// A measurement of the header's object `id` logged at `t`, taken at `t_meas` (s): position
    /// (m) and, if measured, velocity (m/s).
    pub fn write_object(
        &mut self,
        t: f64,
        t_meas: f64,
        id: &str,
        position: [f64; 3],
        velocity: Option<[f64; 3]>,
    ) -> Result<(), WriteError> {
        finite("t_meas", t_meas)?;
        if t_meas > t {
            return Err(WriteError::FromFuture { t_meas, t });
        }
        self.begin(t)?;
        let id = serde_json::to_string(id).map_err(|e| WriteError::Io(std::io::Error::other(e)))?;
        write!(
            self.out,
            "{{\"type\":\"object\",\"t\":{t:?},\"t_meas\":{t_meas:?},\"id\":{id},\"position\":"
        )?;
        write_list(&mut self.out, "position", &position)?;
        if let Some(v) = velocity {
            self.out.write_all(b",\"velocity\":")?;
            write_list(&mut self.out, "velocity", &v)?;
        }
        self.out.write_all(b"}\n")?;
        Ok(())
    }

    /// A named event at `t` (s). Where the header promises the `start` event, that name is
    /// the writer's own (written before the first robot sample) and refused here.
    pub fn write_event(&mut self, t: f64, name: &str) -> Result<(), WriteError> {
        if self.start_promised && name == super::START_EVENT {
            return Err(WriteError::Order(
                "the `start` event is written by the log writer itself, just before the first robot sample (the header promises it)",
            ));
        }
        self.begin(t)?;
        self.event_line(t, name)
    }

    fn event_line(&mut self, t: f64, name: &str) -> Result<(), WriteError> {
        write!(self.out, "{{\"type\":\"event\",\"t\":{t:?},\"name\":")?;
        serde_json::to_writer(&mut self.out, name).map_err(std::io::Error::from)?;
        self.out.write_all(b"}\n")?;
        Ok(())
    }

    /// Shield diagnostics at `t` (s): `fields` (a JSON object) is merged into the record.
    pub fn write_shield(
        &mut self,
        t: f64,
        fields: &serde_json::Map<String, serde_json::Value>,
    ) -> Result<(), WriteError> {
        self.begin(t)?;
        let mut m = fields.clone();
        m.insert("type".into(), "shield".into());
        m.insert("t".into(), t.into());
        serde_json::to_writer(&mut self.out, &m).map_err(std::io::Error::from)?;
        self.out.write_all(b"\n")?;
        Ok(())
    }

    /// The time (s) of the last record written (−∞ before the first).
    pub fn last_time(&self) -> f64 {
        self.last_t
    }

    /// Flush and return the inner writer.
    pub fn finish(mut self) -> Result<W, WriteError> {
        self.out.flush()?;
        Ok(self.out)
    }
}
