//! Action chunks to waypoints: q̂_0 = q(0), q̂_k = q̂_(k-1) + Δq̂_(k-1) (or absolute targets).

use crate::error::TrajectoryError;
use pacs_models::{JointLimits, MAX_DOF};
use serde::{Deserialize, Serialize};

/// How the actions of a chunk are to be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ActionKind {
    /// Joint-position deltas Δq̂ (rad).
    #[default]
    Delta,
    /// Absolute joint positions q̂ (rad).
    Absolute,
}

/// What to do with a waypoint outside the joint position limits: the choice is explicit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum OutOfLimits {
    /// Reject the chunk with [`TrajectoryError::WaypointOutsideLimits`].
    #[default]
    Reject,
    /// Project the waypoint onto the position box (later deltas apply from the projected point).
    Project,
}

/// An action chunk: H actions of which the first `execute` are executed; an optional gripper
/// channel (one value per action) is passed through unchanged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chunk {
    /// How `actions` are read.
    #[serde(default)]
    pub kind: ActionKind,
    /// H actions, each with one value per joint (rad).
    pub actions: Vec<Vec<f64>>,
    /// Number h of executed actions, 1 ≤ h ≤ H.
    pub execute: usize,
    /// Optional gripper command per action (passed through, not planned).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gripper: Option<Vec<f64>>,
}

/// Waypoints q̂_0 … q̂_h (row 0 is the start configuration), row-major, `dof` values per row.
#[derive(Debug, Clone, PartialEq)]
pub struct Waypoints {
    dof: usize,
    rows: Vec<f64>,
    gripper: Option<Vec<f64>>,
    /// q̂_{h+1} … q̂_H: where the chunk's predicted but not executed actions lead (row-major; as
    /// long as they are finite and inside the position limits).
    next: Vec<f64>,
}

impl Waypoints {
    /// Build from rows q̂_0 … q̂_h directly; every row has `dof` finite values and at least two rows.
    pub fn from_rows(rows: &[Vec<f64>]) -> Result<Self, TrajectoryError> {
        let dof = rows.first().map_or(0, Vec::len);
        if dof == 0 || dof > MAX_DOF {
            return Err(TrajectoryError::Length {
                what: "waypoints[0]".into(),
                expected: MAX_DOF.min(dof.max(1)),
                found: dof,
            });
        }
        if rows.len() < 2 {
            return Err(TrajectoryError::Execute {
                execute: rows.len().saturating_sub(1),
                available: rows.len().saturating_sub(1),
            });
        }
        let mut flat = Vec::with_capacity(rows.len() * dof);
        for (k, r) in rows.iter().enumerate() {
            check(&format!("waypoints[{k}]"), r, dof)?;
            flat.extend_from_slice(r);
        }
        Ok(Self {
            dof,
            rows: flat,
            gripper: None,
            next: Vec::new(),
        })
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.dof
    }
    /// Number of segments h (rows minus one).
    pub fn segments(&self) -> usize {
        self.rows.len() / self.dof - 1
    }
    /// Waypoint q̂_k (k = 0 is the start configuration).
    pub fn row(&self, k: usize) -> &[f64] {
        &self.rows[k * self.dof..(k + 1) * self.dof]
    }
    /// Gripper values of the executed actions (passed through), if the chunk had a gripper channel.
    pub fn gripper(&self) -> Option<&[f64]> {
        self.gripper.as_deref()
    }
    /// q̂_{h+1}, the configuration the chunk's first predicted but not executed action leads to
    /// (when H > h, finite and inside the position limits): a hint of the direction and pace in
    /// which the next chunk will continue. It is never a waypoint of the trajectory.
    pub fn lookahead(&self) -> Option<&[f64]> {
        self.predicted(0)
    }
    /// q̂_{h+1+k}: the k-th predicted, not executed configuration (see [`Self::lookahead`]).
    pub fn predicted(&self, k: usize) -> Option<&[f64]> {
        self.next.get(k * self.dof..(k + 1) * self.dof)
    }

    /// The same waypoints without q̂_1 … q̂_k: q̂_0, q̂_{k+1}, …, q̂_h, the predicted ones kept
    /// (no gripper channel). What a blend from a moving start is planned through
    /// ([`crate::intended::Planner::plan`]). `None` unless 1 ≤ k < h.
    pub(crate) fn without_leading(&self, k: usize) -> Option<Waypoints> {
        let h = self.segments();
        if k == 0 || k >= h {
            return None;
        }
        let mut rows = Vec::with_capacity((h + 1 - k) * self.dof);
        rows.extend_from_slice(self.row(0));
        rows.extend_from_slice(&self.rows[(k + 1) * self.dof..]);
        Some(Self {
            dof: self.dof,
            rows,
            gripper: None,
            next: self.next.clone(),
        })
    }
}

fn check(what: &str, v: &[f64], n: usize) -> Result<(), TrajectoryError> {
    if v.len() != n {
        return Err(TrajectoryError::Length {
            what: what.into(),
            expected: n,
            found: v.len(),
        });
    }
    if let Some((index, &value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(TrajectoryError::NotFinite {
            what: what.into(),
            index,
            value,
        });
    }
    Ok(())
}

/// Joint moves between consecutive waypoints smaller than this (rad) are dropped: the joint holds
/// its previous waypoint value ([`Chunk::waypoints`]). 1 µrad is far below any arm's resolution
/// (the FR3's ±0.1 mm repeatability is ≈ 1e-4 rad at 1 m) and below the segment solver's
/// precision: pauses of a demonstration policy (deltas of 1e-8 rad) once made the planner
/// refuse chunks (positions 3e-9 rad off at a segment's end, jerks 2 % over the limit).
pub const MIN_JOINT_MOVE: f64 = 1e-6;

impl Chunk {
    /// Waypoints q̂_0 = `q0`, q̂_1 … q̂_h from the first h actions; every waypoint is inside the
    /// position limits on success (rejected or projected per `policy`). Deltas are integrated
    /// exactly; a joint whose next value is less than [`MIN_JOINT_MOVE`] from its previous
    /// waypoint holds that waypoint's value, so every waypoint is within `MIN_JOINT_MOVE` of the
    /// chunk's own configuration (no drift accumulates).
    pub fn waypoints(
        &self,
        q0: &[f64],
        limits: &JointLimits,
        policy: OutOfLimits,
    ) -> Result<Waypoints, TrajectoryError> {
        let n = limits.dof();
        check("state.q", q0, n)?;
        let h = self.execute;
        if h == 0 || h > self.actions.len() {
            return Err(TrajectoryError::Execute {
                execute: h,
                available: self.actions.len(),
            });
        }
        let mut rows = Vec::with_capacity((h + 1) * n);
        rows.extend_from_slice(q0);
        // The chunk's own configuration (deltas integrated without the dead band).
        let mut raw = q0.to_vec();
        for k in 0..h {
            let a = &self.actions[k];
            check(&format!("chunk.actions[{k}]"), a, n)?;
            for i in 0..n {
                let prev = raw[i];
                let mut x = match self.kind {
                    ActionKind::Delta => prev + a[i],
                    ActionKind::Absolute => a[i],
                };
                let (lo, hi) = (limits.q_min()[i], limits.q_max()[i]);
                if !x.is_finite() {
                    return Err(TrajectoryError::NotFinite {
                        what: format!("waypoint {}", k + 1),
                        index: i,
                        value: x,
                    });
                }
                if x < lo || x > hi {
                    match policy {
                        OutOfLimits::Reject => {
                            return Err(TrajectoryError::WaypointOutsideLimits {
                                waypoint: k + 1,
                                joint: i,
                                value: x,
                                lo,
                                hi,
                            });
                        }
                        OutOfLimits::Project => x = x.clamp(lo, hi),
                    }
                }
                raw[i] = x;
                let held = rows[k * n + i];
                rows.push(if (x - held).abs() < MIN_JOINT_MOVE {
                    held
                } else {
                    x
                });
            }
        }
        let gripper = match &self.gripper {
            None => None,
            Some(g) => {
                check("chunk.gripper", g, self.actions.len())?;
                Some(g[..h].to_vec())
            }
        };
        // The predicted rest of the chunk, as long as it stays finite and inside the limits.
        let mut next: Vec<f64> = Vec::new();
        for a in &self.actions[h..] {
            let last = if next.is_empty() {
                &rows[h * n..(h + 1) * n]
            } else {
                &next[next.len() - n..]
            };
            let x: Vec<f64> = (0..n)
                .map(|i| match self.kind {
                    ActionKind::Delta => last[i] + a.get(i).copied().unwrap_or(f64::NAN),
                    ActionKind::Absolute => a.get(i).copied().unwrap_or(f64::NAN),
                })
                .collect();
            if a.len() != n || !x.iter().all(|v| v.is_finite()) || !limits.contains(&x) {
                break;
            }
            next.extend_from_slice(&x);
        }
        Ok(Waypoints {
            dof: n,
            rows,
            gripper,
            next,
        })
    }
}
