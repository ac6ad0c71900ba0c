//! Chunked policies. A trained diffusion policy is not available here: [`Demonstration`] is a
//! nearest-neighbour stand-in over a demonstrated joint path that, like the paper's policies, sees
//! only the current joint angles (no velocity) and outputs H joint deltas. Slowing down along the
//! path keeps it in distribution; being pushed off the path makes its chunks pull back toward the
//! demonstration from wherever the robot is (degrading the motion).

use pacs_verify::chunk::{ActionKind, Chunk};

/// Anything that maps the current joint angles to an action chunk.
pub trait ChunkPolicy {
    /// The next chunk for joint angles `q` (rad).
    fn chunk(&mut self, q: &[f64]) -> Chunk;
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
        Self { path, horizon, execute, progress: 0 }
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
        self.path.iter().map(|p| dist(p, q)).fold(f64::INFINITY, f64::min)
    }
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
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
            actions.push(target.iter().zip(&prev).map(|(t, p)| t - p).collect::<Vec<f64>>());
            prev = target.clone();
        }
        Chunk { kind: ActionKind::Delta, actions, execute: self.execute, gripper: None }
    }
}
