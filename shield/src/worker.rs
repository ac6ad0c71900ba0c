//! A planning thread for a real-time loop: [`ChunkWorker`].
//!
//! Planning a chunk (the spline's passes) takes too long to fit in a 1 ms step beside the
//! verification (measured in `docs/performance.md#chunk-planning-time`); a 1 kHz loop that
//! planned inside its step would miss its deadline. [`Shield::set_chunk`] plans in the caller's thread and suits
//! simulations and loops with time to spare. A real-time loop hands its chunks to a
//! `ChunkWorker` instead, which splits every re-plan across steps:
//!
//! 1. [`ChunkWorker::set_chunk`] (in the loop): predicts where the commands will be `lead`
//!    safety steps ahead ([`Shield::handover`]; [`Shield::handover_on_failsafe`] after an
//!    unverified step) and sends the chunk and that state to the
//!    worker's thread. No planning, no allocation: a few µs.
//! 2. The thread plans the chunk from the handover state ([`crate::shield::ChunkPlanner`], the
//!    shield's own planner and settings) while the loop keeps stepping.
//! 3. [`ChunkWorker::poll`] (in the loop, before each step): a finished plan is offered to the
//!    shield ([`Shield::offer`]). The step at the handover takes it over only if the commanded
//!    state is *bitwise* the state it was planned from, and the fresh trajectory runs only once
//!    one of its monitored steps is verified. If the commands went elsewhere (a step was not
//!    verified, the plan came back late), the offer is dropped and `poll` asks the thread to
//!    plan the same chunk again from a newer handover.
//!
//! **Safety.** Nothing here executes a command: every command still comes from
//! [`Shield::step`], which executes only verified steps or the last verified failsafe. The
//! worker changes *when* a chunk takes over, never what is verified (the argument is
//! [`Shield::offer`]'s: claim C8 in `docs/shield.md`).
//!
//! **Determinism.** With a paced loop the plan is back long before its handover, and the run is
//! the one [`Shield::set_chunk`] would give at the handover step (test
//! `shield/tests/worker.rs`). An unpaced loop (a simulation, a benchmark) calls
//! [`ChunkWorker::wait`] when [`ChunkWorker::due`] says the next step is the handover: it blocks
//! until the plan is back, which a 1 kHz loop would spend idle.
//!
//! The loop's share of a chunk is `set_chunk` plus the `poll` that offers it; `pacs bench shield`
//! measures both (`set_chunk_*_us` and the step figures, which include `poll`).

use crate::replan::ReplanPolicy;
use crate::shield::{Handover, OfferState, PreparedChunk, Shield, ShieldError};
use pacs_motion::chunk::Chunk;
use std::sync::mpsc::{
    Receiver, RecvTimeoutError, SyncSender, TryRecvError, TrySendError, sync_channel,
};
use std::time::{Duration, Instant};

/// Work for the planning thread.
enum Job {
    /// A new chunk (serial number in this worker), to plan from `handover`.
    Chunk {
        serial: u64,
        handover: Handover,
        chunk: Chunk,
    },
    /// The chunk `serial` again, from a newer handover (its last plan went stale).
    Again { serial: u64, handover: Handover },
}

/// A plan back from the thread.
struct Plan {
    serial: u64,
    result: Result<PreparedChunk, ShieldError>,
    /// Wall-clock time the thread spent planning.
    planning: Duration,
}

/// Where the latest chunk handed to a [`ChunkWorker`] is.
#[derive(Debug, Clone, PartialEq)]
pub enum WorkerState {
    /// No chunk handed in yet.
    Idle,
    /// Being planned on the thread (first time, or again after a stale offer), or waiting for
    /// the pause before planning it again.
    Planning,
    /// Planned and offered: waiting for the step at its handover.
    Offered,
    /// Taken over by the shield as its chunk with this serial number, and not tried yet: the
    /// next step tries it. Seen only where the offer was taken over at once (its start is the
    /// current commanded state, e.g. a robot at rest); an offer taken over at its handover step
    /// is tried by that same step and goes straight to [`Self::Taken`] or [`Self::Dropped`].
    Installed(u64),
    /// The commands follow it: the shield's chunk with this serial number
    /// ([`crate::shield::ChunkProgress::chunk`]).
    Taken(u64),
    /// Taken over, but its first step was not verified, so the shield dropped it and the
    /// commands kept their path — what [`Shield::set_chunk`] does with such a chunk. The next
    /// chunk is handled as usual.
    Dropped(u64),
    /// Refused by the planner (the robot keeps its verified motion; the error was returned by
    /// the [`ChunkWorker::poll`] that received it).
    Refused,
}

/// Plans a shield's chunks on its own thread (see the module documentation). One worker serves
/// one shield; hand every chunk of that shield to the worker (a chunk given to
/// [`Shield::set_chunk`] directly supersedes the worker's offer, and the worker does not know).
pub struct ChunkWorker {
    lead: usize,
    jobs: SyncSender<Job>,
    plans: Receiver<Plan>,
    /// A job the full queue did not take yet (sent by the next `poll`).
    queued: Option<Job>,
    /// A plan [`Self::wait`] received, offered by the next `poll`.
    back: Option<Plan>,
    /// Serial number of the latest chunk handed in (0: none).
    serial: u64,
    /// The handover time (s) of the plan requested for `serial` and not back yet.
    in_flight: Option<f64>,
    state: WorkerState,
    planning: Option<Duration>,
    plans_received: u64,
    replans: u64,
    /// Offers of the latest chunk that went stale in a row, and when the next re-plan is sent.
    stale_streak: u32,
    retry_at: Option<f64>,
}

/// Jobs and plans that may wait in the channels (a loop hands in a chunk every ~0.1–0.3 s; the
/// thread only plans the newest job it finds).
const QUEUE: usize = 4;

/// How often the idle planning thread looks for work (adds at most this to a plan's latency).
const POLL_INTERVAL: Duration = Duration::from_micros(200);

impl ChunkWorker {
    /// Start the planning thread for `shield` (a copy of its planner and chunk settings), with
    /// chunks taking over `lead ≥ 1` safety steps after they are handed in. Choose `lead`
    /// so that planning fits: `lead · safety_step` above the planning time's worst case
    /// (`pacs bench shield` reports it as `planning_max_us`); a late plan is not lost, only
    /// planned again.
    pub fn spawn(shield: &Shield, lead: usize) -> Result<Self, ShieldError> {
        if lead == 0 {
            return Err(ShieldError::ZeroLead);
        }
        let (jobs, job_rx) = sync_channel::<Job>(QUEUE);
        let (plan_tx, plans) = sync_channel::<Plan>(QUEUE);
        let mut planner = shield.chunk_planner();
        std::thread::Builder::new()
            .name("pacs-chunk-planner".into())
            .spawn(move || {
                let mut current: Option<(u64, Chunk)> = None;
                // The newest serial seen: a job for an older chunk is superseded.
                let mut newest = 0u64;
                loop {
                    // Polled, not blocked on: a send to a blocked receiver would wake it with a
                    // system call inside the loop's `set_chunk` (tens of µs on a VM).
                    let first = match job_rx.try_recv() {
                        Ok(job) => job,
                        Err(TryRecvError::Empty) => {
                            std::thread::sleep(POLL_INTERVAL);
                            continue;
                        }
                        Err(TryRecvError::Disconnected) => return,
                    };
                    // Only the newest request matters; older ones are superseded.
                    let mut target = None;
                    let mut absorb = |job: Job, target: &mut Option<(u64, Handover)>| match job {
                        Job::Chunk {
                            serial,
                            handover,
                            chunk,
                        } if serial >= newest => {
                            newest = serial;
                            current = Some((serial, chunk));
                            *target = Some((serial, handover));
                        }
                        Job::Again { serial, handover } if serial >= newest => {
                            newest = serial;
                            *target = Some((serial, handover));
                        }
                        _ => {}
                    };
                    absorb(first, &mut target);
                    while let Ok(job) = job_rx.try_recv() {
                        absorb(job, &mut target);
                    }
                    let Some((serial, handover)) = target else {
                        continue;
                    };
                    let Some((_, chunk)) = current.as_ref().filter(|(s, _)| *s == serial) else {
                        continue;
                    };
                    let t0 = Instant::now();
                    let result = planner.prepare(&handover, chunk);
                    let plan = Plan {
                        serial,
                        result,
                        planning: t0.elapsed(),
                    };
                    if plan_tx.send(plan).is_err() {
                        return; // the worker was dropped
                    }
                }
            })
            .map_err(|e| ShieldError::PlanningThread(e.kind()))?;
        Ok(Self {
            lead,
            jobs,
            plans,
            queued: None,
            back: None,
            serial: 0,
            in_flight: None,
            state: WorkerState::Idle,
            planning: None,
            plans_received: 0,
            replans: 0,
            stale_streak: 0,
            retry_at: None,
        })
    }

    /// Safety steps between handing a chunk in and its handover.
    pub fn lead(&self) -> usize {
        self.lead
    }

    /// Hand a chunk in (in the loop, a few µs): it is planned on the thread from the state the
    /// commands will have `lead` steps from now, and offered by a later [`Self::poll`]. A newer
    /// chunk supersedes one still planned or waiting. Errors: the shield is not started.
    pub fn set_chunk(&mut self, shield: &mut Shield, chunk: Chunk) -> Result<(), ShieldError> {
        let handover = self.predict(shield).ok_or(ShieldError::NotStarted)?;
        self.serial += 1;
        self.stale_streak = 0;
        self.retry_at = None;
        // A waiting offer of an older chunk must not take over after this one was handed in.
        shield.withdraw_offer();
        self.send(Job::Chunk {
            serial: self.serial,
            handover,
            chunk,
        });
        self.in_flight = Some(handover.t);
        self.state = WorkerState::Planning;
        Ok(())
    }

    /// Before each step (in the loop): offer a plan that came back, and plan the chunk again
    /// where its offer went stale. Returns the planner's error for a refused chunk (the robot
    /// keeps its verified motion), or [`ShieldError::PlanningThreadEnded`] if the planning thread has ended.
    pub fn poll(&mut self, shield: &mut Shield) -> Result<(), ShieldError> {
        if let Some(job) = self.queued.take() {
            self.send(job);
        }
        if let Some(plan) = self.back.take() {
            self.receive(shield, plan)?;
        }
        loop {
            match self.plans.try_recv() {
                Ok(plan) => self.receive(shield, plan)?,
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return Err(thread_ended()),
            }
        }
        self.follow(shield);
        self.retry(shield);
        Ok(())
    }

    /// Whether the plan of the latest chunk is still on the thread although the step at `t` (s)
    /// is its handover or later: an unpaced loop calls [`Self::wait`] (then [`Self::poll`]), a
    /// paced loop has
    /// missed the handover (the plan is offered late, goes stale and is planned again).
    pub fn due(&self, t: f64) -> bool {
        self.in_flight
            .is_some_and(|h| t >= h - crate::shield::time_tolerance(t))
    }

    /// Block until the plan of the latest chunk is back from the thread (for unpaced loops:
    /// simulations and benchmarks); the next [`Self::poll`] offers it. Returns at once if none
    /// is on the thread.
    pub fn wait(&mut self) -> Result<(), ShieldError> {
        while self.in_flight.is_some() && self.back.is_none() {
            // A job the full queue refused is sent again while waiting: the plan waited for
            // may be that job's.
            if let Some(job) = self.queued.take() {
                self.send(job);
            }
            match self.plans.recv_timeout(POLL_INTERVAL) {
                Ok(plan) if plan.serial == self.serial => self.back = Some(plan),
                Ok(_) | Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return Err(thread_ended()),
            }
        }
        Ok(())
    }

    /// Where the latest chunk is.
    pub fn state(&self) -> &WorkerState {
        &self.state
    }

    /// Wall-clock time the thread spent on the latest plan it returned.
    pub fn last_planning(&self) -> Option<Duration> {
        self.planning
    }

    /// Plans requested again because an offer went stale.
    pub fn replans(&self) -> u64 {
        self.replans
    }

    /// Plans of the latest chunks received from the thread (superseded ones not counted).
    pub fn plans(&self) -> u64 {
        self.plans_received
    }

    /// Send the newest job. A job still waiting for room is older and superseded: it is
    /// dropped, so the thread never receives an older chunk after a newer one.
    fn send(&mut self, job: Job) {
        self.queued = None;
        match self.jobs.try_send(job) {
            Ok(()) => {}
            // The thread is busy and the queue full: keep the newest job for the next poll.
            Err(TrySendError::Full(job)) => self.queued = Some(job),
            // The thread has ended: `poll` reports it.
            Err(TrySendError::Disconnected(_)) => {}
        }
    }

    fn receive(&mut self, shield: &mut Shield, plan: Plan) -> Result<(), ShieldError> {
        if plan.serial != self.serial {
            return Ok(()); // superseded by a newer chunk
        }
        self.in_flight = None;
        self.planning = Some(plan.planning);
        self.plans_received += 1;
        match plan.result {
            Err(e) => {
                self.state = WorkerState::Refused;
                Err(e)
            }
            Ok(p) => match shield.offer(p) {
                Ok(()) => {
                    self.state = WorkerState::Offered;
                    self.follow(shield);
                    Ok(())
                }
                Err(ShieldError::Stale { .. }) => {
                    self.again(shield);
                    Ok(())
                }
                Err(e) => Err(e),
            },
        }
    }

    /// Track the offer as the shield records it ([`Shield::offer_state`]): stale (then plan
    /// again from a newer handover), taken over, then followed or dropped.
    fn follow(&mut self, shield: &Shield) {
        if !matches!(self.state, WorkerState::Offered | WorkerState::Installed(_)) {
            return;
        }
        match shield.offer_state() {
            OfferState::Taken(n) => {
                self.stale_streak = 0;
                self.state = WorkerState::Installed(n);
            }
            OfferState::Followed(n) => {
                self.stale_streak = 0;
                self.state = WorkerState::Taken(n);
            }
            OfferState::Dropped(n) => {
                self.stale_streak = 0;
                self.state = WorkerState::Dropped(n);
            }
            OfferState::Stale => self.again(shield),
            OfferState::Waiting => {}
            // The shield was restarted (`Shield::start`), which forgets offers: a chunk taken
            // over before is gone, one still offered was never taken over.
            OfferState::None => {
                self.state = match self.state {
                    WorkerState::Installed(n) => WorkerState::Dropped(n),
                    _ => WorkerState::Idle,
                };
            }
        }
    }

    /// Where the commands will be at the handover: the next `lead` steps are predicted to go as
    /// the latest one did (verified: along the path; not verified: along the failsafe, so a
    /// person who keeps the arm braking or at rest does not make every plan stale).
    fn predict(&self, shield: &Shield) -> Option<Handover> {
        shield.likely_handover(self.lead)
    }

    /// An offer went stale: plan the chunk again after [`ReplanPolicy::backoff`] steps (at once
    /// the first time, then 1, 3, 7, … at most [`ReplanPolicy::max_backoff`]), so a loop whose
    /// steps keep alternating between verified and not (an arm creeping past a person; neither
    /// prediction holds) does not plan the chunk every few steps.
    fn again(&mut self, shield: &Shield) {
        self.stale_streak += 1;
        let wait = ReplanPolicy::DEFAULT.backoff(self.stale_streak);
        self.state = WorkerState::Planning;
        self.in_flight = None;
        self.retry_at = Some(shield.time() + wait as f64 * shield.config().safety_step);
        self.retry(shield);
    }

    /// Send a scheduled re-plan once its time has come.
    fn retry(&mut self, shield: &Shield) {
        let Some(at) = self.retry_at else { return };
        if shield.time() < at - crate::shield::time_tolerance(at) {
            return;
        }
        let Some(handover) = self.predict(shield) else {
            return;
        };
        self.retry_at = None;
        self.replans += 1;
        self.send(Job::Again {
            serial: self.serial,
            handover,
        });
        self.in_flight = Some(handover.t);
        self.state = WorkerState::Planning;
    }
}

fn thread_ended() -> ShieldError {
    ShieldError::PlanningThreadEnded
}
