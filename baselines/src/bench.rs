//! Reproducible timing scenarios for `pacs bench` (wall-clock statistics are measured by the
//! caller; nothing here asserts on time).

// Joint-indexed loops over parallel fixed-size arrays read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

use pacs_models::object::{ObjectContact, ObjectModel, default_ball};
use pacs_models::{ConstraintSpec, HumanModel, default_human, fr3};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::ChunkMotion;
use pacs_shield::shield::{Command, FilterMode, Shield, ShieldConfig, ShieldError};
use pacs_shield::worker::{ChunkWorker, WorkerState};
use std::time::Instant;

/// How a scenario hands its chunks to the shield.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChunkDelivery {
    /// [`Shield::set_chunk`] in the loop: the loop plans (timed as `chunk_*`).
    InLoop,
    /// A [`ChunkWorker`] with this lead (safety steps): the loop's share is
    /// [`ChunkWorker::set_chunk`] (timed as `chunk_*`) and [`ChunkWorker::poll`] before every
    /// step (timed with the step); the planning runs on the worker's thread (`plan_*`). The
    /// loop is unpaced, so where the next step is a handover whose plan is not back yet, it
    /// waits for the plan untimed ([`ChunkWorker::wait`]): the time a 1 kHz loop spends idle.
    Worker { lead: usize },
}

/// The lead of the bench's [`ChunkDelivery::Worker`] runs: 3 ms for planning (the planning
/// times it is meant to cover: `docs/performance.md#chunk-planning-time`).
pub const BENCH_LEAD: usize = 3;

/// Timing statistics of a run (seconds per step).
#[derive(Debug, Clone, serde::Serialize)]
pub struct StepStats {
    /// Scenario name.
    pub scenario: String,
    /// Number of timed steps.
    pub steps: usize,
    /// Median step time (s): the object measurements, `Shield::step`, and with a
    /// [`ChunkDelivery::Worker`] the worker's `poll` before it (the loop's whole share per step).
    pub median: f64,
    /// 90th percentile (s).
    pub p90: f64,
    /// 99th percentile (s).
    pub p99: f64,
    /// 99.9th percentile (s).
    pub p999: f64,
    /// Maximum (s).
    pub max: f64,
    /// Steps slower than 50 µs.
    pub over_50us: usize,
    /// The step's work without the machine's noise: per step the fastest of the step and two
    /// re-runs of it on copies of the shield (same state, same inputs); its maximum over the run
    /// (s). A step slower than this was interrupted, not busy. 0 where not measured (CBF).
    pub work_max: f64,
    /// 99.9th percentile of that work time (s).
    pub work_p999: f64,
    /// Steps whose work time exceeds 50 µs.
    pub work_over_50us: usize,
    /// The machine's floor: right after every step, a loop that only reads the clock spins
    /// for that step's work time (plus its poll) and is timed like the step. Its wall time is
    /// what the machine alone makes of a computation that long at that moment (the interrupts,
    /// the host's steal, preemption by other threads); it is never below the step's work time.
    /// 99.9th percentile and maximum (s), and the probes slower than 50 µs: compare them with
    /// the step's `p999`, `max` and `over_50us`. 0 where not measured (CBF).
    pub floor_p999: f64,
    pub floor_max: f64,
    pub floor_over_50us: usize,
    /// Fraction of steps whose intended motion was verified.
    pub verified_fraction: f64,
    /// Median time of handing a chunk in, s: `Shield::set_chunk` (planning in the loop) or
    /// `ChunkWorker::set_chunk` (a prediction and a send), by [`ChunkDelivery`].
    pub chunk_median: f64,
    /// 99th percentile of handing a chunk in, s.
    pub chunk_p99: f64,
    /// 99.9th percentile of handing a chunk in, s.
    pub chunk_p999: f64,
    /// Maximum time of handing a chunk in, s.
    pub chunk_max: f64,
    /// Chunks whose hand-in took longer than 100 µs.
    pub chunk_over_100us: usize,
    /// With a [`ChunkDelivery::Worker`]: median, 99th percentile and maximum of the planning on
    /// the worker's thread (`ChunkPlanner::prepare`), s. 0 otherwise.
    pub plan_median: f64,
    pub plan_p99: f64,
    pub plan_max: f64,
    /// With a worker: median and maximum of the polls that offered a plan (the loop's share
    /// of taking a plan back, included in the step's wall time), s. 0 otherwise.
    pub offer_median: f64,
    pub offer_max: f64,
    /// With a worker: chunks the commands followed, chunks handed in, and plans made again
    /// (an offer that went stale or was dropped). 0 otherwise.
    pub offers_taken: usize,
    pub offers: usize,
    pub replans: usize,
    /// The slowest steps by work time (at most 8, slowest first), with what the step did.
    pub slowest: Vec<SlowStep>,
}

/// One slow step of a run: when, how long, and what decided it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SlowStep {
    /// Step index.
    pub step: usize,
    /// Step time (s).
    pub time: f64,
    /// Steps since the last `set_chunk` (0: the first step after it).
    pub since_chunk: usize,
    /// The step verified its intended motion.
    pub verified: bool,
    /// What decided the step (`Binding` in its log form).
    pub binding: String,
    /// Median work time of the 101 steps around it (s; the steps `step − 50 ..= step + 50`
    /// that exist; wall time where no work time is measured, CBF). Near the run's median for a step that is expensive on its own; near the
    /// step's own time where the machine slowed a whole stretch of steps down (the host's busy
    /// spells), which no probe of the clock sees.
    pub around: f64,
    /// The same step re-run at the end of the run, from a copy of the shield kept before it:
    /// the fastest of [`RERUN_TIMES`] runs (s). `None` where no copy was kept (the run keeps
    /// copies for the [`RERUN_KEPT`] steps of largest work time, so every one of
    /// [`StepStats::slowest`] has one, CBF runs excepted). Near `time`:
    /// the step is that expensive; far below it: the step was slowed down when it ran (a burst
    /// of the machine that also caught its re-runs).
    pub rerun: Option<f64>,
}

/// How many times [`SlowStep::rerun`] re-runs a kept step.
pub const RERUN_TIMES: usize = 5;
/// How many steps a run keeps a copy of for [`SlowStep::rerun`].
pub const RERUN_KEPT: usize = 32;

/// What one step did, kept for [`StepStats::slowest`].
struct StepNote {
    since_chunk: usize,
    verified: bool,
    binding: pacs_shield::shield::Binding,
}

fn stats(
    name: &str,
    v: Vec<f64>,
    mut work: Vec<f64>,
    notes: &[StepNote],
    mut chunks: Vec<f64>,
) -> StepStats {
    let verified = notes.iter().filter(|n| n.verified).count();
    // Slowest by work time where measured (noise-free), else by wall time.
    let key = if work.len() == v.len() { &work } else { &v };
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| key[b].total_cmp(&key[a]));
    let slowest = order
        .iter()
        .take(8)
        .filter_map(|&k| {
            let n = notes.get(k)?;
            let mut near = key[k.saturating_sub(50)..(k + 51).min(key.len())].to_vec();
            near.sort_by(f64::total_cmp);
            Some(SlowStep {
                around: quantile(&near, 0.5),
                rerun: None,
                step: k,
                time: key[k],
                since_chunk: n.since_chunk,
                verified: n.verified,
                binding: serde_json::to_string(&n.binding).unwrap_or_default(),
            })
        })
        .collect();
    let over_50us = v.iter().filter(|&&x| x > 50e-6).count();
    let chunk_over_100us = chunks.iter().filter(|&&x| x > 100e-6).count();
    let work_over_50us = work.iter().filter(|&&x| x > 50e-6).count();
    let mut v = v;
    v.sort_by(f64::total_cmp);
    work.sort_by(f64::total_cmp);
    chunks.sort_by(f64::total_cmp);
    StepStats {
        scenario: name.into(),
        steps: v.len(),
        median: quantile(&v, 0.5),
        p90: quantile(&v, 0.9),
        p99: quantile(&v, 0.99),
        p999: quantile(&v, 0.999),
        max: v.last().copied().unwrap_or(0.0),
        over_50us,
        work_max: work.last().copied().unwrap_or(0.0),
        work_p999: quantile(&work, 0.999),
        work_over_50us,
        floor_p999: 0.0,
        floor_max: 0.0,
        floor_over_50us: 0,
        verified_fraction: verified as f64 / v.len().max(1) as f64,
        chunk_median: quantile(&chunks, 0.5),
        chunk_p99: quantile(&chunks, 0.99),
        chunk_p999: quantile(&chunks, 0.999),
        chunk_max: chunks.last().copied().unwrap_or(0.0),
        chunk_over_100us,
        plan_median: 0.0,
        plan_p99: 0.0,
        plan_max: 0.0,
        offer_median: 0.0,
        offer_max: 0.0,
        offers_taken: 0,
        offers: 0,
        replans: 0,
        slowest,
    }
}

fn note(
    since_chunk: usize,
    cmd: Result<pacs_shield::shield::Command, pacs_shield::shield::ShieldError>,
) -> StepNote {
    match cmd {
        Ok(c) => StepNote {
            since_chunk,
            verified: c.diag.verified,
            binding: c.diag.binding,
        },
        Err(_) => StepNote {
            since_chunk,
            verified: false,
            binding: pacs_shield::shield::Binding::NoProfile,
        },
    }
}

/// Spin reading the clock until `nominal` seconds have passed; returns the wall time the spin
/// took (≥ `nominal`, and more where the machine interrupted it): one probe of
/// [`StepStats::floor_max`].
fn floor_probe(nominal: f64) -> f64 {
    let t0 = Instant::now();
    loop {
        let e = t0.elapsed().as_secs_f64();
        if e >= nominal {
            return e;
        }
    }
}

/// 99.9th percentile, maximum and count over 50 µs of the floor probes (s), sorting `v`.
fn floor_figures(v: &mut [f64]) -> (f64, f64, usize) {
    let over = v.iter().filter(|&&x| x > 50e-6).count();
    v.sort_by(f64::total_cmp);
    (quantile(v, 0.999), v.last().copied().unwrap_or(0.0), over)
}

/// The `p`-quantile of the ascending `sorted` (nearest rank: the element at
/// round((len − 1)·p)); 0 for an empty slice. Every figure of [`StepStats`] uses it.
fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        0.0
    } else {
        sorted[((sorted.len() - 1) as f64 * p).round() as usize]
    }
}

/// Keypoints of the default human walking between 1.5 m and 1.0 m in front of the robot at time `t` (s).
pub fn walking_human(t: f64) -> [[f64; 3]; 9] {
    let d = 1.25 + 0.25 * (std::f64::consts::PI * t).sin();
    [
        [d, 0.2, 1.4],
        [d - 0.1, 0.25, 1.15],
        [d - 0.2, 0.25, 0.95],
        [d, -0.2, 1.4],
        [d - 0.1, -0.25, 1.15],
        [d - 0.2, -0.25, 0.95],
        [d, 0.0, 1.5],
        [d, 0.0, 1.0],
        [d, 0.0, 1.65],
    ]
}

/// A chunk of 8 executed × 0.02 rad deltas on six joints, in direction `sign` (±1).
pub fn back_and_forth(sign: f64) -> Chunk {
    Chunk {
        kind: ActionKind::Delta,
        actions: vec![
            vec![
                0.02 * sign,
                0.02 * sign,
                0.02 * sign,
                -0.02 * sign,
                0.02 * sign,
                0.02 * sign,
                0.0
            ];
            16
        ],
        execute: 8,
        gripper: None,
    }
}

/// The same scenario as [`shield_scenario`] with the control-barrier-function baseline.
pub fn cbf_scenario(steps: usize) -> StepStats {
    use crate::cbf::{CbfConfig, CbfFilter};
    let human = default_human()
        .with_uncertainty(0.01, 0.1, 0.02)
        .expect("valid");
    let cfg = CbfConfig::default();
    let mut f = CbfFilter::new(fr3::fr3(), Some(human.clone()), cfg).expect("valid");
    f.start(0.0, &fr3::Q_READY).expect("start");
    let (mut times, mut chunk_times, mut notes, mut sign) = (
        Vec::with_capacity(steps),
        Vec::new(),
        Vec::with_capacity(steps),
        1.0,
    );
    for k in 0..steps {
        let t = k as f64 * cfg.safety_step;
        if k % 200 == 0 {
            let t0 = Instant::now();
            let _ = f.set_chunk(t, &back_and_forth(sign));
            chunk_times.push(t0.elapsed().as_secs_f64());
            sign = -sign;
        }
        let m =
            HumanMeasurement::new(&human, t, &walking_human(t), None).expect("valid measurement");
        let t0 = Instant::now();
        let cmd = f.step(t, Some(&m));
        times.push(t0.elapsed().as_secs_f64());
        notes.push(note(k % 200, cmd));
    }
    stats("cbf", times, vec![], &notes, chunk_times)
}

/// FR3 moving back and forth (chunks of 8 × 0.02 rad on six joints, alternating direction every
/// chunk, a new chunk every 200 ms), the default human walking between 1.5 m and 1.0 m in front
/// of the robot (0.5 Hz), measured every step; `spec` = "sorting" (SSM) or "handover" (PFL).
pub fn shield_scenario(spec: &str, mode: FilterMode, steps: usize) -> StepStats {
    shield_scenario_with(spec, mode, ChunkMotion::Stop, steps)
}

/// [`shield_scenario`] with the given chunk motion (continuous: spline chunks ending moving, each
/// planned from the moving state the previous one left; the policy clock stays at 200 ms).
pub fn shield_scenario_with(
    spec: &str,
    mode: FilterMode,
    motion: ChunkMotion,
    steps: usize,
) -> StepStats {
    shield_scenario_delivered(spec, mode, motion, ChunkDelivery::InLoop, steps)
}

/// [`shield_scenario_with`], with the chunks delivered as `delivery` says.
pub fn shield_scenario_delivered(
    spec: &str,
    mode: FilterMode,
    motion: ChunkMotion,
    delivery: ChunkDelivery,
    steps: usize,
) -> StepStats {
    let mut name = match motion {
        ChunkMotion::Stop => format!("{spec} ({mode:?}"),
        ChunkMotion::Continuous => format!("{spec} ({mode:?}, continuous chunks"),
    };
    name += &delivery_label(delivery);
    run_walking_scenario(
        &name,
        spec,
        mode,
        motion,
        steps,
        delivery,
        |_| {},
        |_, _| {},
    )
}

/// The scenario name's tail for a delivery.
fn delivery_label(delivery: ChunkDelivery) -> String {
    match delivery {
        ChunkDelivery::InLoop => ", planned in the loop)".into(),
        ChunkDelivery::Worker { lead } => format!(", planning thread, lead {lead})"),
    }
}

/// The continuous-chunks scenario with every chunk planned on a [`ChunkWorker`]'s thread, as a
/// real-time loop does it.
pub fn shield_scenario_offloop(
    spec: &str,
    mode: FilterMode,
    lead: usize,
    steps: usize,
) -> StepStats {
    shield_scenario_delivered(
        spec,
        mode,
        ChunkMotion::Continuous,
        ChunkDelivery::Worker { lead },
        steps,
    )
}

/// The loop of the walking-human scenarios: build the shield (`setup` adds objects), then per
/// step a chunk every 200 ms (timed apart), `measure` (extra measurements, timed with the step)
/// and the step with the human's measurement.
#[allow(clippy::too_many_arguments)]
fn run_walking_scenario(
    name: &str,
    spec: &str,
    mode: FilterMode,
    motion: ChunkMotion,
    steps: usize,
    delivery: ChunkDelivery,
    setup: impl FnOnce(&mut Shield),
    mut measure: impl FnMut(&mut Shield, f64),
) -> StepStats {
    let (mut sh, human, safety_step) = walking_shield(name, spec, mode, motion);
    setup(&mut sh);
    sh.start(0.0, &fr3::Q_READY).expect("start");
    let mut times = Vec::with_capacity(steps);
    let mut chunk_times = Vec::new();
    let mut notes = Vec::with_capacity(steps);
    let mut work = Vec::with_capacity(steps);
    let mut floor = Vec::with_capacity(steps);
    // Copies of the shield before its slowest steps by work time, re-run at the end: (work
    // time, step, time, shield). A streaming top-RERUN_KEPT: a step among the run's 8 slowest
    // is never the smallest of the kept, so it is never dropped.
    let mut kept: Vec<(f64, usize, f64, Shield)> = Vec::with_capacity(RERUN_KEPT);
    let mut sign = 1.0;
    let mut worker = match delivery {
        ChunkDelivery::InLoop => None,
        ChunkDelivery::Worker { lead } => Some(ChunkWorker::spawn(&sh, lead).expect("lead ≥ 1")),
    };
    let mut tally = WorkerTally::new();
    for k in 0..steps {
        let t = k as f64 * safety_step;
        if k % 200 == 0 {
            let c = back_and_forth(sign);
            sign = -sign;
            let t0 = Instant::now();
            match worker.as_mut() {
                None => {
                    let _ = sh.set_chunk(&c);
                }
                Some(w) => {
                    if w.set_chunk(&mut sh, c).is_ok() {
                        tally.offers += 1;
                    }
                }
            }
            chunk_times.push(t0.elapsed().as_secs_f64());
        }
        // The worker's share of the step: offer a plan that came back (timed with the step).
        let mut poll = 0.0;
        if let Some(w) = worker.as_mut() {
            poll = tally.poll(w, &mut sh, t);
        }
        let m =
            HumanMeasurement::new(&human, t, &walking_human(t), None).expect("valid measurement");
        // The state before the step, kept below if the step is among the slowest (untimed).
        let snapshot = sh.clone();
        let (cmd, real, fastest) = timed_step(&mut sh, t, &m, &mut measure);
        // Wall time: the poll and the step. Work: the step's (a poll cannot be re-run; its
        // offers are reported apart, `offer_*`).
        times.push(real + poll);
        work.push(fastest.min(real));
        // Keep the state before a step whose work is among the slowest so far.
        let w = fastest.min(real);
        let kept_min = kept.iter().map(|x| x.0).fold(f64::INFINITY, f64::min);
        if kept.len() < RERUN_KEPT || w > kept_min {
            if kept.len() == RERUN_KEPT
                && let Some(i) = kept.iter().position(|x| x.0 == kept_min)
            {
                kept.swap_remove(i);
            }
            kept.push((w, k, t, snapshot));
        }
        notes.push(note(k % 200, cmd));
        // The machine's floor for a computation as long as this step's, right after it.
        floor.push(floor_probe(fastest.min(real) + poll));
    }
    let mut out = stats(name, times, work, &notes, chunk_times);
    (out.floor_p999, out.floor_max, out.floor_over_50us) = floor_figures(&mut floor);
    rerun_kept(&kept, &mut out, &human, &mut measure);
    if let Some(w) = &worker {
        tally.report(w, &mut out);
    }
    out
}

/// The walking-human scenarios' FR3 shield, not started: constraint preset `spec`, filter
/// `mode`, chunk `motion`, the separation figure only where `name` asks for it; with the
/// person's model (with measurement uncertainty) and the safety step (s).
fn walking_shield(
    name: &str,
    spec: &str,
    mode: FilterMode,
    motion: ChunkMotion,
) -> (Shield, HumanModel, f64) {
    let robot = fr3::fr3();
    let human = default_human()
        .with_uncertainty(0.01, 0.1, 0.02)
        .expect("valid");
    let cs = ConstraintSpec::builtin(spec).expect("preset");
    let mut cfg = ShieldConfig {
        mode,
        // As a real-time loop runs it: the separation figure (a diagnostic) off, except where the
        // scenario name asks for it.
        separation_figure: name.contains(WITH_FIGURE),
        ..ShieldConfig::default()
    };
    motion.apply(&mut cfg);
    let sh = Shield::new(robot, Some((human.clone(), &cs)), vec![], cfg).expect("valid shield");
    (sh, human, cfg.safety_step)
}

/// One step at `t` (s) with the human measurement `m`, `measure` before it: two re-runs on
/// copies of the shield first (their result is discarded), then the real step. The step's
/// command, its time and the fastest re-run's (s).
fn timed_step(
    sh: &mut Shield,
    t: f64,
    m: &HumanMeasurement,
    measure: &mut impl FnMut(&mut Shield, f64),
) -> (Result<Command, ShieldError>, f64, f64) {
    let mut fastest = f64::INFINITY;
    for _ in 0..2 {
        let mut copy = sh.clone();
        let t0 = Instant::now();
        measure(&mut copy, t);
        let _ = std::hint::black_box(copy.step(t, Some(m)));
        fastest = fastest.min(t0.elapsed().as_secs_f64());
    }
    let t0 = Instant::now();
    measure(sh, t);
    let cmd = sh.step(t, Some(m));
    let real = t0.elapsed().as_secs_f64();
    (cmd, real, fastest)
}

/// Re-run the kept steps (work time, step, time in s, the shield before it) now, each from its
/// copy, and give the slowest steps of `out` the fastest of [`RERUN_TIMES`] re-runs (s).
fn rerun_kept(
    kept: &[(f64, usize, f64, Shield)],
    out: &mut StepStats,
    human: &HumanModel,
    measure: &mut impl FnMut(&mut Shield, f64),
) {
    for (_, k, t, snapshot) in kept {
        let Some(slow) = out.slowest.iter_mut().find(|w| w.step == *k) else {
            continue;
        };
        let m =
            HumanMeasurement::new(human, *t, &walking_human(*t), None).expect("valid measurement");
        let mut best = f64::INFINITY;
        for _ in 0..RERUN_TIMES {
            let mut copy = snapshot.clone();
            let t0 = Instant::now();
            measure(&mut copy, *t);
            let _ = std::hint::black_box(copy.step(*t, Some(&m)));
            best = best.min(t0.elapsed().as_secs_f64());
        }
        slow.rerun = Some(best);
    }
}

/// What a run's [`ChunkWorker`] did: its planning and offering times (s), the chunks handed in
/// and taken over.
struct WorkerTally {
    plan_times: Vec<f64>,
    offer_times: Vec<f64>,
    offers: usize,
    taken: usize,
    last_state: WorkerState,
    plans_seen: u64,
}

impl WorkerTally {
    fn new() -> Self {
        Self {
            plan_times: Vec::new(),
            offer_times: Vec::new(),
            offers: 0,
            taken: 0,
            last_state: WorkerState::Idle,
            plans_seen: 0,
        }
    }

    /// The worker's share of the step at `t` (s): wait (untimed) for a plan due now, then poll,
    /// which offers a plan that came back. The poll's time (s).
    fn poll(&mut self, w: &mut ChunkWorker, sh: &mut Shield, t: f64) -> f64 {
        if w.due(t) {
            // Unpaced: the plan's handover is this step; a 1 kHz loop would have idled.
            let _ = w.wait();
        }
        let t0 = Instant::now();
        let _ = w.poll(sh);
        let poll = t0.elapsed().as_secs_f64();
        if w.plans() != self.plans_seen {
            self.plans_seen = w.plans();
            self.offer_times.push(poll);
            if let Some(d) = w.last_planning() {
                self.plan_times.push(d.as_secs_f64());
            }
        }
        let st = w.state().clone();
        if st != self.last_state {
            self.taken += matches!(st, WorkerState::Taken(_)) as usize;
            self.last_state = st;
        }
        poll
    }

    /// Into `out`: the planning and offering times' quantiles (s), the offers, the chunks taken
    /// over and the worker's re-plans.
    fn report(mut self, w: &ChunkWorker, out: &mut StepStats) {
        self.plan_times.sort_by(f64::total_cmp);
        out.plan_median = quantile(&self.plan_times, 0.5);
        out.plan_p99 = quantile(&self.plan_times, 0.99);
        out.plan_max = self.plan_times.last().copied().unwrap_or(0.0);
        self.offer_times.sort_by(f64::total_cmp);
        out.offer_median = quantile(&self.offer_times, 0.5);
        out.offer_max = self.offer_times.last().copied().unwrap_or(0.0);
        out.offers = self.offers;
        out.offers_taken = self.taken;
        out.replans = w.replans() as usize;
    }
}

/// Position (m) and velocity (m/s) of a ball rolling back and forth on the table in front of the
/// robot (0.6 m ahead, y = ±0.3 m, 0.4 m/s peak) at time `t` (s).
pub fn rolling_ball(t: f64) -> ([f64; 3], [f64; 3]) {
    let w = 4.0 / 3.0;
    let y = 0.3 * (w * t).sin();
    ([0.6, y, 0.04], [0.0, 0.3 * w * (w * t).cos(), 0.0])
}

/// [`shield_scenario`] (SSM, `sorting`) with two dynamic objects besides the walking human: the
/// built-in ball rolling on the table in front of the robot (no contact allowed) and a second
/// ball resting on the table to the side (SSM), both measured every step.
pub fn shield_objects_scenario(steps: usize) -> StepStats {
    shield_objects_scenario_with(steps, false, ChunkDelivery::InLoop)
}

/// Marks the scenarios that compute the separation figure ([`ShieldConfig::separation_figure`]);
/// the others run without it, as a real-time loop that does not log it would.
pub const WITH_FIGURE: &str = "separation figure on";

/// [`shield_objects_scenario`], with the separation figure computed every step if `figure`, and
/// the chunks delivered as `delivery` says.
pub fn shield_objects_scenario_with(
    steps: usize,
    figure: bool,
    delivery: ChunkDelivery,
) -> StepStats {
    let ball = ObjectModel::new(&default_ball()).expect("valid ball");
    let (rolling, resting) = (0, 1);
    let mut name = if figure {
        format!("sorting + 2 objects (Pacs, {WITH_FIGURE}")
    } else {
        "sorting + 2 objects (Pacs".to_string()
    };
    name += &delivery_label(delivery);
    run_walking_scenario(
        &name,
        "sorting",
        FilterMode::Pacs,
        ChunkMotion::Stop,
        steps,
        delivery,
        |sh| {
            assert_eq!(
                sh.add_object(ball, ObjectContact::NoContact).ok(),
                Some(rolling)
            );
            assert_eq!(sh.add_object(ball, ObjectContact::Ssm).ok(), Some(resting));
        },
        |sh, t| {
            let (p, v) = rolling_ball(t);
            let m = |position, velocity| ObjectMeasurement {
                time: t,
                position,
                velocity,
            };
            sh.measure_object(rolling, &m(p, Some(v)))
                .expect("valid measurement");
            sh.measure_object(resting, &m([0.3, 0.6, 0.04], Some([0.0; 3])))
                .expect("valid measurement");
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn notes(n: usize) -> Vec<StepNote> {
        (0..n)
            .map(|k| StepNote {
                since_chunk: k % 200,
                verified: k % 2 == 0,
                binding: pacs_shield::shield::Binding::NoProfile,
            })
            .collect()
    }

    /// Hand-computed figures: 1000 steps of 2 µs work (3 µs wall), one expensive step (500:
    /// 100 µs) and a slow stretch (800–900: 40 µs). The expensive step's neighbourhood median
    /// is the run's 2 µs; the stretch's first step (800, the slowest after 500 by index among
    /// equals) has 50 steps of 2 µs and 51 of 40 µs around it: median 40 µs.
    #[test]
    fn stats_quantiles_and_neighbourhoods_are_exact() {
        let mut work = vec![2e-6; 1000];
        work[500] = 100e-6;
        work[800..=900].iter_mut().for_each(|w| *w = 40e-6);
        let wall: Vec<f64> = work.iter().map(|w| w + 1e-6).collect();
        let s = stats("t", wall, work, &notes(1000), vec![5e-6, 7e-6, 200e-6]);
        // Sorted wall: 898 × 3 µs, 101 × 41 µs, 1 × 101 µs; nearest ranks 500, 899, 989, 998.
        assert_eq!(s.median, 3e-6);
        assert_eq!(s.p90, 41e-6);
        assert_eq!(s.p99, 41e-6);
        assert_eq!(s.p999, 41e-6);
        assert_eq!(s.max, 101e-6);
        assert_eq!((s.over_50us, s.work_over_50us), (1, 1));
        assert_eq!((s.work_max, s.work_p999), (100e-6, 40e-6));
        assert_eq!(s.verified_fraction, 0.5);
        assert_eq!(
            (s.chunk_median, s.chunk_max, s.chunk_over_100us),
            (7e-6, 200e-6, 1)
        );
        assert_eq!(s.slowest.len(), 8);
        assert_eq!((s.slowest[0].step, s.slowest[0].time), (500, 100e-6));
        assert_eq!(s.slowest[0].around, 2e-6);
        assert_eq!((s.slowest[1].step, s.slowest[1].time), (800, 40e-6));
        assert_eq!(s.slowest[1].around, 40e-6);
        assert!(s.slowest.iter().all(|w| w.rerun.is_none()));
    }

    #[test]
    fn floor_figures_count_and_rank_exactly() {
        let mut v = vec![10e-6, 60e-6, 51e-6, 20e-6, 50e-6];
        // Over 50 µs: 60 and 51 (50 itself is not over); p99.9 = rank round(4 · 0.999) = 4.
        assert_eq!(floor_figures(&mut v), (60e-6, 60e-6, 2));
        assert_eq!(floor_figures(&mut []), (0.0, 0.0, 0));
        assert_eq!(quantile(&[1.0, 2.0, 3.0, 4.0], 0.5), 3.0);
        assert_eq!(quantile(&[1.0, 2.0, 3.0], 0.5), 2.0);
    }
}
