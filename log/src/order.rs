//! Records with equal time stamps, put in the one order every log form follows: human and object
//! measurements first (a measurement logged at `t` is in use from the robot sample at `t` on),
//! then robot samples, then events and shield diagnostics, then file order. MCAP's reader orders
//! this way by construction; JSON Lines and CSV records pass through [`EqualTimeGroup`], so the
//! same data gets the same verdict whatever order a logger wrote it in.

use crate::error::Location;
use crate::format::Record;

/// Most records one time stamp may hold (see [`EqualTimeGroup::push`]).
pub const MAX_EQUAL_TIME: usize = 1 << 16;

/// An owned copy of one record (buffers reused across groups).
#[derive(Debug, Default)]
struct Slot {
    rank: u8,
    seq: usize,
    loc: Option<Location>,
    t: f64,
    t_meas: f64,
    q: Vec<f64>,
    dq: Vec<f64>,
    has_dq: bool,
    ddq: Vec<f64>,
    has_ddq: bool,
    positions: Vec<[f64; 3]>,
    name: String,
    position: [f64; 3],
    velocity: Option<[f64; 3]>,
    has_person: bool,
}

impl Slot {
    fn fill(&mut self, rec: &Record<'_>, seq: usize, loc: Location) {
        self.seq = seq;
        self.loc = Some(loc);
        self.t = rec.t();
        self.q.clear();
        self.dq.clear();
        self.ddq.clear();
        self.positions.clear();
        self.name.clear();
        self.has_dq = false;
        self.has_ddq = false;
        match *rec {
            Record::Human {
                t_meas,
                person,
                positions,
                ..
            } => {
                self.rank = 0;
                self.t_meas = t_meas;
                self.positions.extend_from_slice(positions);
                self.has_person = person.is_some();
                self.name.push_str(person.unwrap_or(""));
            }
            Record::Object {
                t_meas,
                id,
                position,
                velocity,
                ..
            } => {
                self.rank = 4;
                self.t_meas = t_meas;
                self.name.push_str(id);
                self.position = position;
                self.velocity = velocity;
            }
            Record::Robot { q, dq, ddq, .. } => {
                self.rank = 1;
                self.q.extend_from_slice(q);
                if let Some(dq) = dq {
                    self.dq.extend_from_slice(dq);
                    self.has_dq = true;
                }
                if let Some(ddq) = ddq {
                    self.ddq.extend_from_slice(ddq);
                    self.has_ddq = true;
                }
            }
            Record::Event { name, .. } => {
                self.rank = 2;
                self.name.push_str(name);
            }
            Record::Shield { .. } => self.rank = 3,
        }
    }

    fn record(&self) -> Record<'_> {
        match self.rank {
            0 => Record::Human {
                t: self.t,
                t_meas: self.t_meas,
                person: self.has_person.then_some(self.name.as_str()),
                positions: &self.positions,
            },
            1 => Record::Robot {
                t: self.t,
                q: &self.q,
                dq: self.has_dq.then_some(&self.dq[..]),
                ddq: self.has_ddq.then_some(&self.ddq[..]),
            },
            2 => Record::Event {
                t: self.t,
                name: &self.name,
            },
            4 => Record::Object {
                t: self.t,
                t_meas: self.t_meas,
                id: &self.name,
                position: self.position,
                velocity: self.velocity,
            },
            _ => Record::Shield { t: self.t },
        }
    }
}

/// The records of one time stamp, collected in file order and released in the canonical order.
#[derive(Debug, Default)]
pub struct EqualTimeGroup {
    slots: Vec<Slot>,
    len: usize,
    order: Vec<usize>,
}

/// More than [`MAX_EQUAL_TIME`] records share the time stamp `t` (s).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error(
    "more than {MAX_EQUAL_TIME} records at one time stamp t = {t} s (the audit holds at most {MAX_EQUAL_TIME} records of one time stamp: no real log has that many at one instant)"
)]
pub struct TooManyAtOneTime {
    /// The shared time stamp (s).
    pub t: f64,
}

impl EqualTimeGroup {
    /// Time stamp of the buffered records, if any.
    pub fn time(&self) -> Option<f64> {
        (self.len > 0).then(|| self.slots[0].t)
    }

    /// Buffer a copy of `rec` (found at `loc`). At most [`MAX_EQUAL_TIME`] records share one
    /// time stamp (memory stays flat, as in the MCAP reader): one more is refused with the
    /// problem to report.
    pub fn push(&mut self, rec: &Record<'_>, loc: Location) -> Result<(), TooManyAtOneTime> {
        if self.len >= MAX_EQUAL_TIME {
            return Err(TooManyAtOneTime { t: rec.t() });
        }
        if self.len == self.slots.len() {
            self.slots.push(Slot::default());
        }
        let seq = self.len;
        self.slots[self.len].fill(rec, seq, loc);
        self.len += 1;
        Ok(())
    }

    /// Set where the last buffered record was found (once the reader is free to say).
    pub fn locate_last(&mut self, loc: Location) {
        if self.len > 0 {
            self.slots[self.len - 1].loc = Some(loc);
        }
    }

    /// Hand every buffered record to `f` in the canonical order (human, robot, event, shield;
    /// file order within each), then empty the group. Stops at the first error, returned with
    /// the location of the record that caused it.
    pub fn drain<E>(
        &mut self,
        mut f: impl FnMut(Record<'_>) -> Result<(), E>,
    ) -> Result<(), (Location, E)> {
        self.order.clear();
        self.order.extend(0..self.len);
        let slots = &self.slots;
        // Object measurements (rank 4) go with the human ones, before the robot samples.
        let key = |r: u8| if r == 4 { 0 } else { r };
        self.order
            .sort_by_key(|&i| (key(slots[i].rank), slots[i].seq));
        let len = std::mem::take(&mut self.len);
        for k in 0..len {
            let s = &self.slots[self.order[k]];
            if let Err(e) = f(s.record()) {
                return Err((s.loc.unwrap_or(Location::File), e));
            }
        }
        Ok(())
    }
}
