//! Demonstrations with the variety of human teleoperation, for training learned policies (the
//! paper's diffusion policies learn from 200 teleoperated demonstrations per task).
//!
//! [`task::demonstrations`](crate::task::demonstrations) are machine-made: six per task, one
//! constant pace, the tool on eased straight lines. A person teleoperating the arm does not
//! move like that. Each demonstration made here varies as such recordings do:
//! - **detours**: the tool bends away from the straight line between two waypoints (by 1–3 cm,
//!   sideways and up, smoothly, and back onto the line), and every waypoint is jittered: a
//!   sub-goal within 40 % of its success tolerance, the others by up to 1.2 cm;
//! - **changes of pace**: each segment runs at its own pace (0.55–1.15 of the nominal one), and
//!   the pace changes gradually (at most [`PACE_RATE`] per second);
//! - **pauses**: 0–2 per demonstration, 0.2–1.0 s each, at random times;
//! - **hesitations near people**: while the tool point is within [`HESITATE_DISTANCE`] of the
//!   person (the scenario's true keypoints at that time), the demonstrator slows to 25–45 % of
//!   the pace, and stops for 0.2–0.5 s when the person first comes that close.
//!
//! Every demonstration is recorded at `1/fps` and stays within the limits the robot is operated
//! at (joint velocities within the robot's, accelerations within the shield's intended fraction
//! of the robot's: [`within_operated_limits`]); one that would not is recorded again at a lower
//! nominal pace. Each reaches every sub-goal of its task, in order. Deterministic in `seed`.

use crate::humans::Rng;
use crate::task::{
    TaskKind, demo_acceleration_limits, dense_path_with_detours, scenario, segment_counts,
    tool_keyframes, tool_point,
};
use pacs_models::{RobotModel, fr3};

/// Tool-to-person distance (m) below which the demonstrator hesitates.
pub const HESITATE_DISTANCE: f64 = 0.3;

/// Largest change of the pace (fraction of the nominal pace) per second.
pub const PACE_RATE: f64 = 2.5;

/// Largest joint step (rad) between two samples of the fine geometric path.
const FINE_STEP: f64 = 0.004;

/// Nominal largest joint speed (rad/s) along the path at pace 1.
const NOMINAL_SPEED: f64 = 0.9;

/// Recordings per demonstration at most, each at 85 % of the last one's nominal pace.
const ATTEMPTS: usize = 8;

/// One teleoperation-like demonstration, sampled every `dt` seconds from rest to rest.
#[derive(Debug, Clone)]
pub struct TeleopDemo {
    /// The task.
    pub task: TaskKind,
    /// The scenario seed whose person the demonstrator saw (and the variety's seed).
    pub seed: u64,
    /// Sample period (s).
    pub dt: f64,
    /// Joint positions (rad), one per sample.
    pub q: Vec<Vec<f64>>,
    /// Sub-goals reached so far at each sample (in order, by the episode's rule).
    pub stage: Vec<usize>,
    /// The person's keypoint centroid (m, world frame) at each sample.
    pub person: Vec<[f64; 3]>,
    /// Distance (m) from the tool point to the person's nearest keypoint at each sample.
    pub person_distance: Vec<f64>,
    /// The demonstrator's pace at each sample (fraction of the nominal pace; 0 = paused).
    pub pace: Vec<f64>,
    /// Pauses (not counting hesitation stops).
    pub pauses: usize,
    /// Times the demonstrator hesitated because the person came within [`HESITATE_DISTANCE`].
    pub hesitations: usize,
    /// Segments with a detour.
    pub detours: usize,
}

impl TeleopDemo {
    /// Duration (s).
    pub fn duration(&self) -> f64 {
        (self.q.len().saturating_sub(1)) as f64 * self.dt
    }
}

/// Errors of [`teleop_demonstrations`].
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TeleopError {
    /// `fps` not in [10, 1000].
    #[error("fps: {0} is not a frame rate in [10, 1000] Hz")]
    Fps(f64),
    /// A demonstration stayed beyond the operated limits at every attempt.
    #[error("{task}: demonstration {seed} beyond the operated limits after {ATTEMPTS} recordings")]
    Limits {
        /// Task name.
        task: &'static str,
        /// Its seed.
        seed: u64,
    },
    /// A demonstration missed a sub-goal (the IK could not reach a waypoint).
    #[error("{task}: demonstration {seed} reached {reached} of {goals} sub-goals")]
    Goals {
        /// Task name.
        task: &'static str,
        /// Its seed.
        seed: u64,
        /// Sub-goals reached.
        reached: usize,
        /// Sub-goals of the task.
        goals: usize,
    },
}

/// `count` teleoperation-like demonstrations of `task` (seeds `seed`, `seed + 1`, …), sampled
/// at `fps` (Hz).
pub fn teleop_demonstrations(
    task: TaskKind,
    count: usize,
    seed: u64,
    fps: f64,
) -> Result<Vec<TeleopDemo>, TeleopError> {
    if !(10.0..=1000.0).contains(&fps) {
        return Err(TeleopError::Fps(fps));
    }
    (0..count as u64)
        .map(|i| teleop_demonstration(task, seed.wrapping_add(i), 1.0 / fps))
        .collect()
}

/// The variety one demonstration is drawn with.
struct Variety {
    tools: Vec<[f64; 3]>,
    detours: Vec<[f64; 3]>,
    segment_pace: Vec<f64>,
    pauses: Vec<(f64, f64)>,
    hesitation_pace: f64,
    hesitation_stop: f64,
}

fn variety(task: TaskKind, rng: &mut Rng) -> Variety {
    let (nominal, goals) = tool_keyframes(task);
    let tools: Vec<[f64; 3]> = nominal
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let r = goals.iter().find(|g| g.0 == k).map_or(0.012, |g| 0.4 * g.2);
            let j = rng.in_ball(r);
            [p[0] + j[0], p[1] + j[1], p[2] + j[2]]
        })
        .collect();
    let detours = (0..tools.len())
        .map(|_| {
            if rng.uniform() < 0.35 {
                let side = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                [0.0, side * rng.range(0.01, 0.03), rng.range(0.0, 0.015)]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let segment_pace = (0..tools.len()).map(|_| rng.range(0.55, 1.15)).collect();
    let n_pauses = (rng.uniform() * 3.0) as usize;
    let pauses = (0..n_pauses)
        .map(|_| (rng.uniform(), rng.range(0.2, 1.0)))
        .collect();
    Variety {
        tools,
        detours,
        segment_pace,
        pauses,
        hesitation_pace: rng.range(0.25, 0.45),
        hesitation_stop: rng.range(0.2, 0.5),
    }
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn teleop_demonstration(task: TaskKind, seed: u64, dt: f64) -> Result<TeleopDemo, TeleopError> {
    let robot = fr3::fr3();
    let sc = scenario(task, seed, true);
    let mut rng = Rng::new(
        seed.wrapping_mul(0x007E_1E0F)
            .wrapping_add(task as u64 + 17),
    );
    let v = variety(task, &mut rng);
    let start = fr3::Q_READY.to_vec();
    // Fine samples per segment from the joint distance between the IK keyframes.
    let counts = segment_counts(&robot, &start, &v.tools, FINE_STEP, 40);
    let path = dense_path_with_detours(&robot, &start, &v.tools, &counts, &v.detours);
    // The segment each fine sample belongs to.
    let mut segment = vec![0usize];
    for (k, &c) in counts.iter().enumerate() {
        segment.extend(std::iter::repeat_n(k, c.max(1)));
    }
    let a_max = demo_acceleration_limits(&robot);
    let v_max = robot.limits().v_max().to_vec();
    let mut nominal = nominal_rate(&path);
    for _ in 0..ATTEMPTS {
        let (demo, finished) = time_path(&robot, &sc, &v, &path, &segment, nominal, dt, task, seed);
        // A walk cut off by its sample cap is recorded again (slower), never returned short.
        if finished && within_operated_limits(&demo.q, dt, &v_max, &a_max) {
            let goals = sc.goals.len();
            let reached = demo.stage.last().copied().unwrap_or(0);
            if reached < goals {
                return Err(TeleopError::Goals {
                    task: task.name(),
                    seed,
                    reached,
                    goals,
                });
            }
            return Ok(demo);
        }
        nominal *= 0.85;
    }
    Err(TeleopError::Limits {
        task: task.name(),
        seed,
    })
}

/// Fine samples per second at pace 1: the largest joint step between fine samples taken at
/// [`NOMINAL_SPEED`].
fn nominal_rate(path: &[Vec<f64>]) -> f64 {
    let step = path
        .windows(2)
        .flat_map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| (a - b).abs()))
        .fold(0.0, f64::max);
    NOMINAL_SPEED / step.max(1e-6)
}

/// The configuration at fine-path coordinate `s` (linear between fine samples).
fn at(path: &[Vec<f64>], s: f64) -> Vec<f64> {
    let last = (path.len() - 1) as f64;
    let s = s.clamp(0.0, last);
    let i = (s.floor() as usize).min(path.len() - 2);
    let f = s - i as f64;
    path[i]
        .iter()
        .zip(&path[i + 1])
        .map(|(a, b)| a + f * (b - a))
        .collect()
}

/// Walk the fine path in time steps of `dt`, the pace following the demonstrator's target
/// pace (segment pace, pauses, hesitations near the person) at most [`PACE_RATE`] per second.
/// Returns the recording and whether it reached the path's end within its sample cap.
#[allow(clippy::too_many_arguments)]
fn time_path(
    robot: &RobotModel,
    sc: &crate::task::Scenario,
    v: &Variety,
    path: &[Vec<f64>],
    segment: &[usize],
    nominal: f64,
    dt: f64,
    task: TaskKind,
    seed: u64,
) -> (TeleopDemo, bool) {
    let last = (path.len() - 1) as f64;
    // Pauses at fractions of the path (so they happen whatever the pace).
    let mut pauses: Vec<(f64, f64)> = v.pauses.iter().map(|&(f, d)| (f * last, d)).collect();
    pauses.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut next_pause = 0;
    let mut stop_until = f64::NEG_INFINITY;
    let (mut s, mut pace, mut t) = (0.0f64, 0.0f64, 0.0f64);
    let mut near_before = false;
    let (mut n_pauses, mut hesitations) = (0, 0);
    let mut demo = TeleopDemo {
        task,
        seed,
        dt,
        q: Vec::new(),
        stage: Vec::new(),
        person: Vec::new(),
        person_distance: Vec::new(),
        pace: Vec::new(),
        pauses: 0,
        hesitations: 0,
        detours: v
            .detours
            .iter()
            .filter(|d| d.iter().any(|x| *x != 0.0))
            .count(),
    };
    let mut stage = 0;
    let mut finished = false;
    // Hard cap: the slowest walk (every pause, hesitation all the way) well within it.
    let max_samples = ((last / (nominal * 0.05) + 60.0) / dt) as usize;
    for _ in 0..max_samples {
        let q = at(path, s);
        let tool = tool_point(robot, &q);
        let keypoints = sc.script.keypoints(t);
        let d = keypoints
            .iter()
            .map(|k| dist(k, &tool))
            .fold(f64::INFINITY, f64::min);
        let n = keypoints.len().max(1) as f64;
        let mut c = [0.0; 3];
        for k in &keypoints {
            for i in 0..3 {
                c[i] += k[i] / n;
            }
        }
        while stage < sc.goals.len() && sc.goals[stage].reached(&tool) {
            stage += 1;
        }
        demo.q.push(q);
        demo.stage.push(stage);
        demo.person.push(c);
        demo.person_distance.push(d);
        demo.pace.push(pace);
        if s >= last {
            finished = true;
            break;
        }
        // The demonstrator's target pace now.
        let near = d < HESITATE_DISTANCE;
        if near && !near_before {
            hesitations += 1;
            stop_until = stop_until.max(t + v.hesitation_stop);
        }
        near_before = near;
        if next_pause < pauses.len() && s >= pauses[next_pause].0 {
            stop_until = stop_until.max(t + pauses[next_pause].1);
            next_pause += 1;
            n_pauses += 1;
        }
        let seg = segment[(s.floor() as usize).min(segment.len() - 1)];
        let mut target = v.segment_pace[seg.min(v.segment_pace.len() - 1)];
        if near {
            target *= v.hesitation_pace;
        }
        if t < stop_until {
            target = 0.0;
        }
        let step = PACE_RATE * dt;
        pace = if target > pace {
            (pace + step).min(target)
        } else {
            (pace - step).max(target)
        };
        // At the end of the path the eased segments bring the robot to rest.
        s = (s + pace * nominal * dt).min(last);
        t += dt;
    }
    demo.pauses = n_pauses;
    demo.hesitations = hesitations;
    (demo, finished)
}

/// Whether the joint path `q` (one sample per `dt` s) stays within the joint speeds `v_max`
/// (rad/s, first differences) and accelerations `a_max` (rad/s², second differences), and
/// starts and ends at rest (the first and last steps below `a_max·dt²`).
pub fn within_operated_limits(q: &[Vec<f64>], dt: f64, v_max: &[f64], a_max: &[f64]) -> bool {
    let n = v_max.len().min(a_max.len());
    let speeds = q
        .windows(2)
        .all(|w| (0..n).all(|i| (w[1][i] - w[0][i]).abs() <= v_max[i] * dt));
    let accels = q.windows(3).all(|w| {
        (0..n).all(|i| ((w[2][i] - 2.0 * w[1][i] + w[0][i]) / (dt * dt)).abs() <= a_max[i])
    });
    let rest = |a: &[f64], b: &[f64]| (0..n).all(|i| (a[i] - b[i]).abs() <= a_max[i] * dt * dt);
    let ends = q.len() >= 2 && rest(&q[0], &q[1]) && rest(&q[q.len() - 2], &q[q.len() - 1]);
    speeds && accels && ends
}

/// A change of pace applied to a recorded demonstration by [`paced_replay`], at path time
/// (s of the recording's own timing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PaceEvent {
    /// Brake to a stop when the path reaches `at` (s), stay stopped for `hold` (s), resume.
    Pause {
        /// Path time (s) where braking begins.
        at: f64,
        /// Time (s) at rest.
        hold: f64,
    },
    /// Slow to `pace` (0 < pace < 1 of the recorded pace) from path time `from` to `to` (s),
    /// then return to the recorded pace.
    Slow {
        /// Path time (s) where slowing begins.
        from: f64,
        /// Path time (s) where the recorded pace resumes.
        to: f64,
        /// The reduced pace.
        pace: f64,
    },
}

/// Range of the hold (s) of a training replay's pause ([`replay_event`]).
pub const REPLAY_HOLD: (f64, f64) = (0.3, 1.5);
/// Range of the pace (fraction of the recorded one) of a training replay's slow passage
/// ([`replay_event`]).
pub const REPLAY_PACE: (f64, f64) = (0.2, 0.6);

/// The event of training replay `k` of a recording lasting `end` s (the one recipe of the
/// training transform: `kernel-shield-paced` and `pacs.lerobot.paced_replays`): even `k` a
/// pause — braking to rest at 15–85 % of the recording, held for a time in `hold` (s) —, odd
/// `k` a slow passage over a fifth to a third of it at a pace in `pace`.
pub fn replay_event(
    end: f64,
    k: usize,
    hold: (f64, f64),
    pace: (f64, f64),
    rng: &mut Rng,
) -> PaceEvent {
    if k.is_multiple_of(2) {
        PaceEvent::Pause {
            at: rng.range(0.15, 0.85) * end,
            hold: rng.range(hold.0, hold.1),
        }
    } else {
        let span = rng.range(0.2, 0.33) * end;
        let from = rng.range(0.05 * end, (0.95 * end - span).max(0.05 * end));
        PaceEvent::Slow {
            from,
            to: from + span,
            pace: rng.range(pace.0, pace.1),
        }
    }
}

/// A demonstration replayed along its own path with changes of pace ([`paced_replay`]).
#[derive(Debug, Clone)]
pub struct PacedReplay {
    /// Joint positions (rad), one per `dt`.
    pub q: Vec<Vec<f64>>,
    /// The path position of each sample as a (fractional) index into the recording.
    pub source: Vec<f64>,
    /// Path speed at each sample (1 = the recording's pace).
    pub pace: Vec<f64>,
}

/// Errors of [`paced_replay`].
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ReplayError {
    /// Fewer than two samples, or rows of different widths.
    #[error("the recording needs at least two samples of equal width")]
    Recording,
    /// `dt` not positive and finite.
    #[error("dt: {0} is not a positive sample period (s)")]
    Dt(f64),
    /// An event with a non-finite or negative time, a hold ≤ 0, or a pace outside (0, 1).
    #[error("events[{0}]: times must be finite and ≥ 0, a hold > 0, a pace in (0, 1), from < to")]
    Event(usize),
    /// The replay did not reach the recording's end within its step cap (paces too slow).
    #[error("the replay does not reach the recording's end within 4× its duration plus the holds")]
    Unfinished,
    /// The replay stayed beyond the operated limits with the gentlest ramps tried.
    #[error("the replay exceeds the operated limits even with the gentlest ramps")]
    Limits,
}

/// Path acceleration (1/s) and jerk (1/s²) of [`paced_replay`]'s first attempt; each retry
/// halves both.
const REPLAY_RAMPS: (f64, f64) = (2.0, 10.0);

/// Replay the recording `q` (one sample per `dt` s) along its own path, braking, holding,
/// slowing and resuming as `events` say, with the path-speed profiles the shield brakes and
/// resumes with ([`SpeedProfile::plan`](pacs_motion::scaling::SpeedProfile::plan): time-optimal
/// jerk-limited ramps of the path speed). The path is the recording's, linear between samples:
/// the replay passes through the same configurations, only the timing changes. Ramps start at
/// 2 /s path acceleration and 10 /s² path jerk and are halved until the replay stays within
/// `v_max`/`a_max` ([`within_operated_limits`], which a recording within them meets at pace 1).
pub fn paced_replay(
    q: &[Vec<f64>],
    dt: f64,
    events: &[PaceEvent],
    v_max: &[f64],
    a_max: &[f64],
) -> Result<PacedReplay, ReplayError> {
    if q.len() < 2 || q.iter().any(|r| r.len() != q[0].len()) {
        return Err(ReplayError::Recording);
    }
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(ReplayError::Dt(dt));
    }
    for (i, e) in events.iter().enumerate() {
        let ok = match *e {
            PaceEvent::Pause { at, hold } => {
                at.is_finite() && at >= 0.0 && hold > 0.0 && hold.is_finite()
            }
            PaceEvent::Slow { from, to, pace } => {
                from.is_finite()
                    && to.is_finite()
                    && from >= 0.0
                    && from < to
                    && pace > 0.0
                    && pace < 1.0
            }
        };
        if !ok {
            return Err(ReplayError::Event(i));
        }
    }
    let (mut acc, mut jerk) = REPLAY_RAMPS;
    let last = (q.len() - 1) as f64;
    for _ in 0..8 {
        let r = replay_with(q, dt, events, acc, jerk);
        // Slower ramps only take longer: a replay its step cap cut short stays short.
        if r.source.last().is_none_or(|s| *s < last) {
            return Err(ReplayError::Unfinished);
        }
        if within_operated_limits(&r.q, dt, v_max, a_max) {
            return Ok(r);
        }
        acc *= 0.5;
        jerk *= 0.5;
    }
    Err(ReplayError::Limits)
}

fn replay_with(q: &[Vec<f64>], dt: f64, events: &[PaceEvent], acc: f64, jerk: f64) -> PacedReplay {
    use pacs_motion::scaling::{PathState, SpeedProfile};
    let end = (q.len() - 1) as f64 * dt;
    let at_path = |s: f64| -> Vec<f64> {
        let x = (s / dt).clamp(0.0, (q.len() - 1) as f64);
        let i = (x.floor() as usize).min(q.len() - 2);
        let f = x - i as f64;
        q[i].iter()
            .zip(&q[i + 1])
            .map(|(a, b)| a + f * (b - a))
            .collect()
    };
    // Per event: (trigger path time, target pace, hold after reaching it).
    #[derive(Clone, Copy)]
    enum Next {
        Idle,
        Holding(f64),
    }
    let mut triggers: Vec<(f64, f64, f64)> = Vec::new();
    for e in events {
        match *e {
            PaceEvent::Pause { at, hold } => triggers.push((at, 0.0, hold)),
            PaceEvent::Slow { from, to, pace } => {
                triggers.push((from, pace, 0.0));
                triggers.push((to, 1.0, 0.0));
            }
        }
    }
    triggers.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut next: usize = 0;
    let mut profile = SpeedProfile::plan(PathState::intended(0.0), 1.0, acc, jerk);
    let mut t0 = 0.0;
    let mut state = Next::Idle;
    let (mut out, mut source, mut pace) = (Vec::new(), Vec::new(), Vec::new());
    let mut t = 0.0;
    // Bounded: every event at most stops the path for its hold and the ramps.
    let holds: f64 = triggers.iter().map(|x| x.2).sum();
    let max_steps = ((end * 4.0 + holds + 10.0 * triggers.len() as f64 + 10.0) / dt) as usize;
    for _ in 0..max_steps {
        let st = profile.eval(t - t0);
        out.push(at_path(st.s));
        source.push((st.s / dt).min((q.len() - 1) as f64));
        pace.push(st.sd);
        if st.s >= end {
            break;
        }
        match state {
            Next::Holding(until) if t >= until => {
                profile = SpeedProfile::plan(st, 1.0, acc, jerk);
                t0 = t;
                state = Next::Idle;
            }
            Next::Holding(_) => {}
            Next::Idle => {
                if st.sd == 0.0 && st.sdd == 0.0 && profile.settle_time() <= t - t0 && t > 0.0 {
                    // Stopped by a pause: hold.
                    let hold = triggers[next.saturating_sub(1)].2;
                    state = Next::Holding(t + hold);
                } else if next < triggers.len() && st.s >= triggers[next].0 {
                    profile = SpeedProfile::plan(st, triggers[next].1, acc, jerk);
                    t0 = t;
                    next += 1;
                }
            }
        }
        t += dt;
    }
    PacedReplay {
        q: out,
        source,
        pace,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demonstrations_vary_like_teleoperation_and_stay_within_the_operated_limits() {
        let robot = fr3::fr3();
        let a_max = demo_acceleration_limits(&robot);
        let v_max = robot.limits().v_max().to_vec();
        for task in [TaskKind::Sorting, TaskKind::Handover] {
            let demos = teleop_demonstrations(task, 12, 1, 30.0).expect("demos");
            assert_eq!(demos.len(), 12);
            let goals = crate::task::tool_goals(task).len();
            for d in &demos {
                assert!(within_operated_limits(&d.q, d.dt, &v_max, &a_max));
                assert_eq!(*d.stage.last().unwrap(), goals, "{task:?} {}", d.seed);
                assert!(d.stage.windows(2).all(|w| w[1] >= w[0]));
                assert_eq!(d.q.len(), d.person.len());
                assert_eq!(d.q.len(), d.pace.len());
            }
            // Variety: durations differ, pauses and detours occur.
            let durations: Vec<f64> = demos.iter().map(TeleopDemo::duration).collect();
            let (lo, hi) = durations
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
            assert!(hi > 1.2 * lo, "{task:?}: durations {durations:?}");
            assert!(demos.iter().any(|d| d.pauses > 0));
            assert!(demos.iter().any(|d| d.detours > 0));
            assert!(
                demos
                    .iter()
                    .any(|d| d.pace.iter().skip(1).any(|p| *p == 0.0))
            );
        }
        // The handover partner is approached: the demonstrator hesitates there.
        let demos = teleop_demonstrations(TaskKind::Handover, 6, 1, 30.0).unwrap();
        assert!(demos.iter().all(|d| d.hesitations > 0));
    }

    #[test]
    fn demonstrations_are_deterministic_in_the_seed() {
        let a = teleop_demonstrations(TaskKind::Feeding, 2, 7, 30.0).unwrap();
        let b = teleop_demonstrations(TaskKind::Feeding, 2, 7, 30.0).unwrap();
        assert_eq!(a[1].q, b[1].q);
        let c = teleop_demonstrations(TaskKind::Feeding, 1, 8, 30.0).unwrap();
        assert_eq!(a[1].q, c[0].q);
        assert_ne!(a[0].q, a[1].q);
    }

    #[test]
    fn bad_frame_rates_are_refused() {
        assert_eq!(
            teleop_demonstrations(TaskKind::Sorting, 1, 0, 0.0).unwrap_err(),
            TeleopError::Fps(0.0)
        );
        assert!(teleop_demonstrations(TaskKind::Sorting, 1, 0, f64::NAN).is_err());
    }

    #[test]
    fn the_limit_check_catches_a_jump_and_a_start_in_motion() {
        let v_max = vec![1.0; 2];
        let a_max = vec![10.0; 2];
        let dt = 0.01;
        let rest = vec![vec![0.0, 0.0]; 4];
        assert!(within_operated_limits(&rest, dt, &v_max, &a_max));
        let mut jump = rest.clone();
        jump[2][1] = 0.2; // 2 rad/s
        assert!(!within_operated_limits(&jump, dt, &v_max, &a_max));
        let moving: Vec<Vec<f64>> = (0..4).map(|k| vec![0.005 * k as f64, 0.0]).collect();
        assert!(!within_operated_limits(&moving, dt, &v_max, &a_max));
    }

    #[test]
    fn a_paced_replay_keeps_the_path_and_changes_only_the_timing() {
        let robot = fr3::fr3();
        let a_max = demo_acceleration_limits(&robot);
        let v_max = robot.limits().v_max().to_vec();
        let d = &teleop_demonstrations(TaskKind::Sorting, 1, 3, 30.0).unwrap()[0];
        let end = d.duration();
        let events = [
            PaceEvent::Pause {
                at: 0.3 * end,
                hold: 1.0,
            },
            PaceEvent::Slow {
                from: 0.6 * end,
                to: 0.8 * end,
                pace: 0.4,
            },
        ];
        let r = paced_replay(&d.q, d.dt, &events, &v_max, &a_max).unwrap();
        assert!(within_operated_limits(&r.q, d.dt, &v_max, &a_max));
        // Longer by at least the hold and the slow window's lost time; the same end.
        assert!(r.q.len() as f64 * d.dt > end + 1.0 + 0.2 * end * 0.6 * 0.9);
        assert_eq!(r.q.last().unwrap(), d.q.last().unwrap());
        // Stopped for about the hold (at the pause's place), never moving backwards.
        let stopped = r.pace.iter().filter(|p| **p == 0.0).count() as f64 * d.dt;
        assert!((stopped - 1.0).abs() <= 0.1 + 2.0 * d.dt, "{stopped}");
        assert!(r.source.windows(2).all(|w| w[1] >= w[0]));
        let slow: Vec<f64> = r
            .source
            .iter()
            .zip(&r.pace)
            .filter(|(s, _)| **s * d.dt > 0.7 * end && **s * d.dt < 0.78 * end)
            .map(|(_, p)| *p)
            .collect();
        assert!(
            !slow.is_empty() && slow.iter().all(|p| (*p - 0.4).abs() < 1e-9),
            "{slow:?}"
        );
        // Every replayed configuration lies on the recorded path (between two samples).
        for (x, s) in r.q.iter().zip(&r.source) {
            let i = (s.floor() as usize).min(d.q.len() - 2);
            for (j, xj) in x.iter().enumerate() {
                let (a, b) = (d.q[i][j], d.q[i + 1][j]);
                assert!(*xj >= a.min(b) - 1e-12 && *xj <= a.max(b) + 1e-12);
            }
        }
        // Without events: the recording itself (pace 1 from rest).
        let same = paced_replay(&d.q, d.dt, &[], &v_max, &a_max).unwrap();
        // A pace so slow the replay cannot end within its cap is refused, not cut short.
        let crawl = [PaceEvent::Slow {
            from: 0.0,
            to: end,
            pace: 1e-3,
        }];
        assert_eq!(
            paced_replay(&d.q, d.dt, &crawl, &v_max, &a_max).unwrap_err(),
            ReplayError::Unfinished
        );
        assert!(same.q.len() >= d.q.len());
        assert_eq!(
            paced_replay(
                &d.q,
                d.dt,
                &[PaceEvent::Pause { at: 1.0, hold: 0.0 }],
                &v_max,
                &a_max
            )
            .unwrap_err(),
            ReplayError::Event(0)
        );
    }
}
