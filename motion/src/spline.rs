//! Intended trajectories as time-optimised C² cubic splines: one constant-jerk piece per segment
//! between consecutive waypoints (the first and last segments are split into two pieces, which
//! gives the two extra degrees of freedom a clamped start (q, q̇, q̈) and end (q̇, q̈ = 0) need),
//! knots at the waypoint times. For given segment durations the spline is the unique solution of a
//! small linear system (the same matrix for every joint); the durations are then optimised by a
//! fixed-point iteration that lengthens segments whose pieces exceed a limit and shortens those
//! with slack, with an exact uniform time scaling (for starts at rest) making every iterate a
//! feasible candidate. The caller checks the assembled trajectory exactly before using it.
//!
//! Moving starts (the next chunk planned from wherever the robot is) do not scale exactly, so the
//! optimiser starts three times and keeps the shortest plan: from the rest-to-rest durations,
//! at the start's own pace, and *shaped*: the later segments at a common multiple of the
//! durations the same waypoints get from rest, the first segment's duration searched on its own
//! (a start that is already moving reaches the next waypoint within the jerk limit only in a
//! narrow window of durations, which the fixed-point update cannot find).
//!
//! Uniform time scaling by λ keeps the spline shape (for a start at rest): velocities scale by
//! 1/λ, accelerations by 1/λ², jerks by 1/λ³, so the smallest admissible λ for given durations
//! follows from the per-piece ratios in closed form.
//!
//! The module's parts: `system` sets up and solves the linear system for given durations,
//! `evaluation` measures the solved spline against the limits and assembles its trajectory,
//! `end` picks the velocity a Moving chunk ends with, `optimise` runs the duration
//! optimiser from each start, and `shaped` holds the shaped start's search.

mod end;
mod evaluation;
mod optimise;
mod shaped;
mod system;

use crate::chunk::Waypoints;
use crate::intended::overshoot;
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_models::MAX_DOF;

/// How the duration optimiser starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Init {
    /// Start at rest: rest-to-rest durations, and every iterate scales exactly.
    Rest,
    /// Moving start, from the rest-to-rest durations.
    Cold,
    /// Moving start, from durations at the start's own pace (see `pace_search`).
    Warm,
    /// Moving start, from the from-rest durations' shape (see `shaped_search`).
    Shaped,
    /// Moving start, from equal durations (the policy's clock: every action takes the same
    /// time, so the demonstrated velocity profile keeps its shape), scanned like `Warm`.
    Uniform,
}

/// Knot whose position is an unknown of the linear system (not a waypoint).
const FREE: usize = usize::MAX;

/// Relative slack accepted on the limit ratios of the optimiser (the exact check allows 1e-9).
const RATIO_TOL: f64 = 1e-10;

/// Ringing past the waypoints (rad, [`overshoot`]) a shaped plan may have where the other starts
/// found no plan or ring less.
const SHAPED_OVERSHOOT: f64 = 1e-4;

/// Smallest segment duration the optimiser uses (s): zero-length segments (repeated waypoints)
/// still get a piece.
const MIN_SEGMENT: f64 = 1e-3;

/// Scratch space and state of the spline optimiser (reused across plans; no allocation once warm).
#[derive(Debug, Default, Clone)]
pub(crate) struct SplineSolver {
    /// Segment durations of the current iterate (s).
    seg_t: Vec<f64>,
    /// Best feasible segment durations found so far.
    best_t: Vec<f64>,
    /// Per-segment limit ratios (max over pieces and joints of |j|/J, |a|/A, |v|/V).
    rj: Vec<f64>,
    ra: Vec<f64>,
    rv: Vec<f64>,
    /// Pieces per segment.
    split: Vec<usize>,
    /// Piece durations and the segment of each piece.
    tau: Vec<f64>,
    seg_of: Vec<usize>,
    /// Per knot: waypoint index or [`FREE`]; and the unknown index of a free knot's position.
    knot_wp: Vec<usize>,
    knot_var: Vec<usize>,
    /// Per knot: the unknown index of its acceleration ([`FREE`] for the known M_0 and M_p).
    acc_var: Vec<usize>,
    /// Dense system (row-major), right-hand sides (one column per joint).
    mat: Vec<f64>,
    /// Right-hand sides, row-major with stride `n` (one column per joint).
    rhs: Vec<f64>,
    /// Lower and upper bandwidth of the system (from its sparsity pattern).
    band: (usize, usize),
    /// Cached scale-normalised ratio per segment.
    rs: Vec<f64>,
    /// Knot positions and accelerations per joint.
    y: Vec<[f64; MAX_DOF]>,
    acc: Vec<[f64; MAX_DOF]>,
    /// End velocity per joint.
    v_end: [f64; MAX_DOF],
    /// Duration of the first piece of a two-piece first segment (s; 0: half the segment).
    first_ramp: f64,
    /// Segment durations of the same waypoints planned from rest (the shape of `Init::Shaped`).
    shape: Vec<f64>,
}

impl SplineSolver {
    /// Time-optimised spline trajectory through the waypoints, or `None` if the optimiser found no
    /// spline within the limits (by its own ratios; the caller still runs the exact check).
    ///
    /// From a moving start the first piece is given the time to swing the start acceleration
    /// across the acceleration range at the jerk limit, τ_r = max_i (|q̈_0,i| + a_i)/j_i (clamped
    /// to [0.1, 0.5] of the first segment); if no spline is found, τ_r/2 and 2τ_r are tried.
    pub(crate) fn plan(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        iterations: usize,
    ) -> Option<Trajectory> {
        let n = lim.dof;
        let h = wp.segments();
        if h == 0 {
            return None;
        }
        self.layout(h);
        if start.is_at_rest(n) {
            self.first_ramp = 0.0;
            return self.optimise(lim, start, wp, end, iterations, Init::Rest);
        }
        let ramp = (0..n)
            .map(|i| (start.ddq[i].abs() + lim.a[i]) / lim.j[i])
            .fold(0.0, f64::max);
        let mut best: Option<Trajectory> = None;
        // The shape of the third start: the same waypoints planned from rest here.
        {
            self.first_ramp = 0.0;
            let rest = JointState::at_rest(&start.q[..n]);
            if self
                .optimise(lim, &rest, wp, end, iterations, Init::Rest)
                .is_some()
            {
                let mut shape = std::mem::take(&mut self.shape);
                shape.clear();
                shape.extend_from_slice(&self.best_t);
                self.shape = shape;
            } else {
                self.shape.clear();
            }
        }
        // Three starts of the optimiser (rest-to-rest, warm and shaped durations); the shortest
        // plan wins, but the shaped one only if it rings past its waypoints no more than the
        // others (at most SHAPED_OVERSHOOT where there are none): where a demonstration pauses
        // its waypoints bunch up, and a short plan that runs through them rings; replaced by
        // the next chunk before it comes back, it makes the robot creep past the pause.
        let inits: &[Init] = if self.shape.is_empty() {
            &[Init::Cold, Init::Warm]
        } else {
            &[Init::Cold, Init::Warm, Init::Shaped, Init::Uniform]
        };
        for &init in inits {
            // (The shaped start scans the first segment itself: one ramp is enough.)
            let ramps: &[f64] = if init == Init::Shaped {
                &[1.0]
            } else {
                &[1.0, 0.5, 2.0]
            };
            for &c in ramps {
                self.first_ramp = c * ramp;
                if let Some(t) = self.optimise(lim, start, wp, end, iterations, init) {
                    let better = match &best {
                        None => init != Init::Shaped || overshoot(&t, wp) <= SHAPED_OVERSHOOT,
                        Some(b) => {
                            t.duration() < b.duration()
                                && (init != Init::Shaped
                                    || overshoot(&t, wp) <= overshoot(b, wp).max(SHAPED_OVERSHOOT))
                        }
                    };
                    if better {
                        best = Some(t);
                    }
                    break;
                }
            }
        }
        best
    }
}
