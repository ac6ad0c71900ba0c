//! [`PacedHandover`]: a blocking chunk hand-over while a real-time loop steps the session.

use super::run::{Session, SessionError};
use crate::replan::ReplanPolicy;
use crate::shield::{ChunkPlanner, OfferState, Shield, ShieldError};
use pacs_motion::chunk::Chunk;
use std::io::Write;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// The planning time (µs) assumed before any chunk was planned: 1 ms (a lead of 3 steps at 1 ms).
const FIRST_PLANNING_US: u64 = 1000;

/// Hands chunks to a [`Session`] shared with a real-time loop, without ever making the loop's
/// steps wait for the planner.
///
/// How (paper: the chunk is planned from the state at its hand-over):
/// 1. the hand-over `lead` steps ahead is predicted under the session's lock
///    ([`Shield::likely_handover`], the shield's one prediction rule);
/// 2. the chunk is planned from it **off** the lock ([`ChunkPlanner::prepare`]);
/// 3. it is offered ([`Shield::offer`]) and the caller waits until a step decides it: followed
///    (its first monitored step verified: returned), dropped (not verified) or stale (the
///    commands went elsewhere);
/// 4. failed hand-overs are planned again under [`ReplanPolicy`] (blocking schedule: at most
///    `attempts`, a late plan doubles the lead).
///
/// Without a loop stepping the session ([`Session::paced`] false) this is
/// [`Session::set_chunk`]. The lead follows the recent planning times
/// ([`ReplanPolicy::lead_for`] of the longest, decaying by a quarter per chunk). The robot
/// keeps its verified motion throughout: the hand-over only decides when the chunk takes over.
pub struct PacedHandover {
    planner: Mutex<ChunkPlanner>,
    /// The longest recent planning time (µs), decaying per chunk.
    plan_us: AtomicU64,
    /// Held for a whole hand-over: the shield reports its latest offer only, so concurrent
    /// callers would read each other's.
    one: Mutex<()>,
    policy: ReplanPolicy,
    safety_step: f64,
}

impl std::fmt::Debug for PacedHandover {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PacedHandover")
            .field("lead", &self.lead())
            .field("policy", &self.policy)
            .finish()
    }
}

/// Why one paced attempt did not hand the chunk over.
enum Attempt {
    Moved,
    Dropped,
}

impl PacedHandover {
    /// A hand-over for `shield`'s chunks (its planner and safety step) under `policy`.
    pub fn new(shield: &Shield, policy: ReplanPolicy) -> Self {
        Self {
            planner: Mutex::new(shield.chunk_planner()),
            plan_us: AtomicU64::new(FIRST_PLANNING_US),
            one: Mutex::new(()),
            policy,
            safety_step: shield.config().safety_step,
        }
    }

    /// Safety steps between a hand-over's prediction and the step that takes the chunk over.
    pub fn lead(&self) -> usize {
        let plan_s = self.plan_us.load(Ordering::Relaxed) as f64 * 1e-6;
        self.policy.lead_for(plan_s, self.safety_step)
    }

    /// Hand `chunk` over to `session` (see the type): returns the chunk's serial number.
    pub fn hand_over<W: Write>(
        &self,
        session: &Mutex<Session<W>>,
        chunk: &Chunk,
    ) -> Result<u64, SessionError> {
        let _one = self
            .one
            .lock()
            .map_err(|_| SessionError::Poisoned("hand-over"))?;
        let lock = || session.lock().map_err(|_| SessionError::Poisoned("shield"));
        let mut lead = self.lead();
        let (mut late, mut moved, mut dropped) = (0, 0, 0);
        for _ in 0..self.policy.attempts {
            let ho = {
                let mut s = lock()?;
                if !s.started() {
                    return Err(SessionError::NotStarted("set_chunk"));
                }
                if !s.paced() {
                    return s.set_chunk(chunk);
                }
                s.shield()
                    .likely_handover(lead)
                    .ok_or(SessionError::NotStarted("set_chunk"))?
            };
            let prepared = match self.plan(&ho, chunk)? {
                Ok(p) => p,
                Err(e) => {
                    lock()?.log_chunk(false);
                    return Err(SessionError::ChunkRejected(e));
                }
            };
            match lock()?.shield_mut().offer(prepared) {
                Ok(()) => {}
                Err(ShieldError::Stale { .. }) => {
                    // Planned too late: look further ahead.
                    late += 1;
                    lead = self.policy.longer_lead(lead);
                    continue;
                }
                Err(e) => return Err(SessionError::Offer(e)),
            }
            match self.await_offer(&lock)? {
                Ok(n) => return Ok(n),
                Err(Attempt::Dropped) => dropped += 1,
                Err(Attempt::Moved) => moved += 1,
            }
        }
        lock()?.log_chunk(false);
        Err(SessionError::NotHandedOver {
            attempts: self.policy.attempts as u32,
            moved,
            dropped,
            late,
        })
    }

    /// Plan `chunk` from `ho` off the session's lock; updates the recent planning time.
    fn plan(
        &self,
        ho: &crate::shield::Handover,
        chunk: &Chunk,
    ) -> Result<Result<crate::shield::PreparedChunk, ShieldError>, SessionError> {
        let mut planner = self
            .planner
            .lock()
            .map_err(|_| SessionError::Poisoned("planner"))?;
        let clock = Instant::now();
        let p = planner.prepare(ho, chunk);
        let us = clock.elapsed().as_micros().min(u64::MAX as u128) as u64;
        let old = self.plan_us.load(Ordering::Relaxed);
        self.plan_us.store(us.max(old - old / 4), Ordering::Relaxed);
        Ok(p)
    }

    /// Wait for the shield's record of the offer's fate: followed (a step verified its first
    /// monitored step), dropped (that step did not) or stale.
    fn await_offer<'a, W: Write + 'a>(
        &self,
        lock: &impl Fn() -> Result<std::sync::MutexGuard<'a, Session<W>>, SessionError>,
    ) -> Result<Result<u64, Attempt>, SessionError> {
        loop {
            let mut s = lock()?;
            let paced = s.paced();
            match s.shield().offer_state() {
                OfferState::Followed(n) => {
                    s.log_chunk(true);
                    return Ok(Ok(n));
                }
                OfferState::Taken(n) if !paced => {
                    // Installed with nobody stepping: the next step tries it.
                    s.log_chunk(true);
                    return Ok(Ok(n));
                }
                OfferState::Taken(_) => {}
                OfferState::Waiting if paced => {}
                OfferState::Dropped(_) => return Ok(Err(Attempt::Dropped)),
                OfferState::Stale => return Ok(Err(Attempt::Moved)),
                OfferState::Waiting => {
                    // Nobody steps the shield now: withdraw, so that no later step takes over a
                    // chunk its caller was told was not handed over.
                    s.shield_mut().withdraw_offer();
                    return Err(SessionError::LoopStopped);
                }
                OfferState::None => return Err(SessionError::Restarted),
            }
            drop(s);
            std::thread::sleep(Duration::from_secs_f64(self.safety_step / 4.0));
        }
    }
}
