//! Chunked policies. A trained diffusion policy is not available here; three stand-ins are:
//! - [`Demonstration`]: a nearest-neighbour policy over one demonstrated joint path;
//! - [`DemoSet`] (`pacs simulate --policy nearest`, the default): a nearest-neighbour policy
//!   over several demonstrations that, like the paper's requirement for the filter, sees only
//!   the current joint angles (no velocity) and outputs H joint deltas. Slowing down along the
//!   path keeps it in distribution; being pushed off the path makes its chunks pull back toward
//!   the demonstration, and beyond [`OOD_RADIUS`] it drifts at random;
//! - [`KernelPolicy`] (`--policy kernel`, `kernel-paced`): a policy learned from the same
//!   demonstrations by kernel regression, which observes the last two timesteps
//!   ([`Observation`]) as the paper's policies do ([`kernel`]).
//!
//! Episodes run them through [`TaskPolicy`].

use pacs_motion::chunk::{ActionKind, Chunk};

pub mod kernel;
pub use kernel::{KernelPolicy, Recording, TrainError};

/// Distance (rad, Euclidean in joint space) from every demonstrated configuration beyond which
/// a policy counts a chunk as out of distribution.
pub const OOD_RADIUS: f64 = 0.12;

/// What a chunk policy observes when it is queried.
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
    /// Joint angles now (rad).
    pub q: &'a [f64],
    /// Joint angles one policy step Δt earlier (rad; equal to `q` at the start).
    pub q_before: &'a [f64],
    /// How many of the task's sub-goals have been reached (the gripper's state: empty before
    /// the pick, holding after it), as a real policy sees it in its observations.
    pub stage: usize,
    /// Episode time (s).
    pub t: f64,
    /// The person's keypoints now (m, world frame; the simulation's truth, as a policy's own
    /// perception would report them; empty where the scene has no person).
    pub person: &'a [[f64; 3]],
    /// The person's keypoints one policy step Δt earlier (m; as `person` at the start).
    pub person_before: &'a [[f64; 3]],
}

/// Distance (rad, Euclidean in joint space) from `q` to the nearest of `configurations`.
pub(crate) fn nearest_distance<'a>(
    configurations: impl Iterator<Item = &'a Vec<f64>>,
    q: &[f64],
) -> f64 {
    configurations
        .map(|p| dist(p, q))
        .fold(f64::INFINITY, f64::min)
}

/// Anything that maps the current joint angles to an action chunk.
pub trait ChunkPolicy {
    /// The next chunk for joint angles `q` (rad).
    fn chunk(&mut self, q: &[f64]) -> Chunk;
}

/// A policy as an episode runs it: a chunk for each observation, and the measures the
/// evaluation reports.
pub trait TaskPolicy {
    /// The next chunk for `obs`.
    fn act(&mut self, obs: &Observation) -> Chunk;
    /// Distance (rad, Euclidean in joint space) from `q` to the nearest demonstrated
    /// configuration.
    fn deviation(&self, q: &[f64]) -> f64;
    /// Chunks produced out of the training distribution so far.
    fn ood_chunks(&self) -> usize;
    /// Name in audit-log headers (`meta.policy`).
    fn name(&self) -> &'static str;
    /// Actions executed per chunk (h).
    fn execute(&self) -> usize;
}

impl TaskPolicy for KernelPolicy {
    fn act(&mut self, obs: &Observation) -> Chunk {
        KernelPolicy::act(self, obs)
    }
    fn deviation(&self, q: &[f64]) -> f64 {
        KernelPolicy::deviation(self, q)
    }
    fn ood_chunks(&self) -> usize {
        KernelPolicy::ood_chunks(self)
    }
    fn name(&self) -> &'static str {
        if self.paced() {
            "kernel-regression-paced"
        } else {
            "kernel-regression"
        }
    }
    fn execute(&self) -> usize {
        KernelPolicy::execute(self)
    }
}

impl TaskPolicy for DemoSet {
    /// Sees only the joint angles (`obs.q`).
    fn act(&mut self, obs: &Observation) -> Chunk {
        self.chunk(obs.q)
    }
    fn deviation(&self, q: &[f64]) -> f64 {
        DemoSet::deviation(self, q)
    }
    fn ood_chunks(&self) -> usize {
        DemoSet::ood_chunks(self)
    }
    fn name(&self) -> &'static str {
        "nn-demonstration"
    }
    fn execute(&self) -> usize {
        self.execute
    }
}

/// A demonstrated joint path (dense waypoints) and the chunk parameters.
#[derive(Debug, Clone)]
pub struct Demonstration {
    path: Vec<Vec<f64>>,
    /// Chunk length H.
    pub horizon: usize,
    /// Executed actions h.
    pub execute: usize,
    progress: usize,
}

impl Demonstration {
    /// A straight-line (in joint space) demonstration from `a` to `b` with `n` ≥ 2 points, eased
    /// at both ends.
    pub fn linear(a: &[f64], b: &[f64], n: usize, horizon: usize, execute: usize) -> Self {
        let n = n.max(2);
        let path = (0..n)
            .map(|k| {
                let u = k as f64 / (n - 1) as f64;
                let w = u * u * (3.0 - 2.0 * u);
                a.iter().zip(b).map(|(x, y)| x + w * (y - x)).collect()
            })
            .collect();
        Self {
            path,
            horizon,
            execute,
            progress: 0,
        }
    }

    /// The demonstrated waypoints.
    pub fn path(&self) -> &[Vec<f64>] {
        &self.path
    }

    /// Final waypoint (the task goal).
    pub fn goal(&self) -> &[f64] {
        self.path.last().expect("non-empty path")
    }

    /// Joint-space distance (rad, Euclidean) from `q` to the demonstrated path's points.
    pub fn deviation(&self, q: &[f64]) -> f64 {
        nearest_distance(self.path.iter(), q)
    }
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

impl ChunkPolicy for Demonstration {
    fn chunk(&mut self, q: &[f64]) -> Chunk {
        // Nearest demonstrated point (ahead of the progress already made, as a real policy with
        // task context would be), then the next H points relative to the current q.
        let k = (self.progress..self.path.len())
            .min_by(|&i, &j| dist(&self.path[i], q).total_cmp(&dist(&self.path[j], q)))
            .unwrap_or(self.path.len() - 1);
        self.progress = k;
        let mut prev = q.to_vec();
        let mut actions = Vec::with_capacity(self.horizon);
        for s in 1..=self.horizon {
            let target = &self.path[(k + s).min(self.path.len() - 1)];
            actions.push(
                target
                    .iter()
                    .zip(&prev)
                    .map(|(t, p)| t - p)
                    .collect::<Vec<f64>>(),
            );
            prev = target.clone();
        }
        Chunk {
            kind: ActionKind::Delta,
            actions,
            execute: self.execute,
            gripper: None,
        }
    }
}

/// Distance (rad) within which demonstrated points of one stretch count as one place (a pause).
const PAUSE_TOLERANCE: f64 = 0.003;

/// Cost (rad) per demonstration sample between a candidate and the phase the last chunk led to.
const PHASE_COST: f64 = 0.005;

/// A behaviour-cloning stand-in trained on several demonstrations of one task: a nearest-
/// neighbour policy over all demonstrated joint configurations that sees only the current joint
/// angles. Near the data (within `ood_radius`, rad, Euclidean in joint space) it replays the
/// demonstrated motion from the nearest demonstrated state, with the current offset decaying by
/// `pull` per action (a policy generalises a little around its data). Beyond `ood_radius` it has
/// no data: like a diffusion policy out of distribution it outputs unreliable actions (a slow
/// random drift), from which it recovers only by chance. Slowing down along the demonstrated
/// path therefore keeps it in distribution; being pushed off the path degrades it.
#[derive(Debug, Clone)]
pub struct DemoSet {
    demos: Vec<Vec<Vec<f64>>>,
    /// Chunk length H.
    pub horizon: usize,
    /// Executed actions h.
    pub execute: usize,
    /// Distance (rad) beyond which the policy is out of distribution.
    pub ood_radius: f64,
    /// Fraction of the offset to the demonstration removed per action (0..1).
    pub pull: f64,
    /// How far ahead (in demonstration samples) the policy may look for its nearest state.
    pub window: usize,
    progress: usize,
    last: Option<(usize, usize)>,
    rng: crate::humans::Rng,
    ood_chunks: usize,
}

impl DemoSet {
    /// A policy over `demos` (each a list of joint configurations, all of the same length ≥ 2).
    pub fn new(demos: Vec<Vec<Vec<f64>>>, horizon: usize, execute: usize, seed: u64) -> Self {
        Self {
            demos,
            horizon,
            execute,
            ood_radius: OOD_RADIUS,
            pull: 0.15,
            window: 24,
            progress: 0,
            last: None,
            rng: crate::humans::Rng::new(seed ^ 0x5EED),
            ood_chunks: 0,
        }
    }

    /// A single-demonstration policy that always targets the demonstrated points themselves
    /// (full pull, never out of distribution): the behaviour of [`Demonstration`].
    pub fn from_demonstration(d: &Demonstration) -> Self {
        let mut s = Self::new(vec![d.path().to_vec()], d.horizon, d.execute, 0);
        s.ood_radius = f64::INFINITY;
        s.pull = 1.0;
        s.window = usize::MAX;
        s
    }

    /// The demonstrations.
    pub fn demos(&self) -> &[Vec<Vec<f64>>] {
        &self.demos
    }

    /// Distance (rad) from `q` to the nearest demonstrated configuration of any demonstration.
    pub fn deviation(&self, q: &[f64]) -> f64 {
        nearest_distance(self.demos.iter().flatten(), q)
    }

    /// Number of chunks produced out of distribution so far.
    pub fn ood_chunks(&self) -> usize {
        self.ood_chunks
    }

    /// Restart at the beginning of the task.
    pub fn reset(&mut self) {
        self.progress = 0;
        self.last = None;
        self.ood_chunks = 0;
    }
}

impl ChunkPolicy for DemoSet {
    fn chunk(&mut self, q: &[f64]) -> Chunk {
        let len = self.demos[0].len();
        let hi = self.progress.saturating_add(self.window).min(len);
        // The phase the robot reached along the stretch the last chunk commanded.
        let expected = match self.last {
            Some((d, k0)) => {
                // The closest point of the stretch, or the latest one about as close: where
                // the demonstration pauses its points cluster within millimetres, and a robot
                // that ran the whole stretch must not be sent back to the start of the pause
                // (it would hunt back and forth); a robot slowed on a moving stretch is
                // closest to the point it reached, which is centimetres from the later ones.
                let demo = &self.demos[d];
                let at = |i: usize| dist(&demo[i.min(len - 1)], q);
                let closest = (k0..=k0 + self.execute)
                    .map(at)
                    .fold(f64::INFINITY, f64::min);
                (k0..=k0 + self.execute)
                    .rev()
                    .find(|&i| at(i) <= closest + PAUSE_TOLERANCE)
                    .unwrap_or(k0)
            }
            None => 0,
        };
        let mut best = (f64::INFINITY, 0usize, self.progress);
        for (d, demo) in self.demos.iter().enumerate() {
            for (k, p) in demo.iter().enumerate().take(hi).skip(self.progress) {
                // Demonstrations may pass the same configuration twice (approach and
                // withdraw): a small cost per sample away from the phase the last chunk led to
                // disambiguates (the task context a real policy gets from its observations).
                let e = dist(p, q);
                let cost = e + PHASE_COST * k.abs_diff(expected) as f64;
                if cost < best.0 {
                    best = (cost, d, k);
                }
            }
        }
        let (_, d, k) = best;
        let e = dist(&self.demos[d][k], q);
        let mut actions = Vec::with_capacity(self.horizon);
        if e > self.ood_radius {
            self.ood_chunks += 1;
            // Out of distribution: small random deltas (≤ 0.01 rad per joint and action).
            let step: Vec<f64> = (0..q.len())
                .map(|_| 0.02 * (self.rng.uniform() - 0.5))
                .collect();
            for _ in 0..self.horizon {
                actions.push(step.clone());
            }
        } else {
            self.progress = k;
            self.last = Some((d, k));
            let demo = &self.demos[d];
            let mut offset: Vec<f64> = q.iter().zip(&demo[k]).map(|(a, b)| a - b).collect();
            let mut prev = q.to_vec();
            for s in 1..=self.horizon {
                offset.iter_mut().for_each(|o| *o *= 1.0 - self.pull);
                let target = &demo[(k + s).min(len - 1)];
                let next: Vec<f64> = target.iter().zip(&offset).map(|(t, o)| t + o).collect();
                actions.push(next.iter().zip(&prev).map(|(n, p)| n - p).collect());
                prev = next;
            }
        }
        Chunk {
            kind: ActionKind::Delta,
            actions,
            execute: self.execute,
            gripper: None,
        }
    }
}
