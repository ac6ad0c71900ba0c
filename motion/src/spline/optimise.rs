//! The duration optimiser: a fixed-point iteration on the segment durations from one of the
//! starts ([`Init`]), keeping the best feasible iterate.

use super::{Init, MIN_SEGMENT, RATIO_TOL, SplineSolver};
use crate::chunk::Waypoints;
use crate::intended::rest_to_rest_time;
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};

/// Duration factor of the damped update for moving starts: r^MOVING_STEP_EXPONENT, at most ±15 %
/// a step (r: a segment's ratio over the target).
pub(super) fn damped_factor(r: f64) -> f64 {
    r.powf(MOVING_STEP_EXPONENT)
        .clamp(MOVING_STEP_CLAMP, 1.0 / MOVING_STEP_CLAMP)
}

/// Ratio the optimiser aims at for starts that are not at rest.
pub(super) const MOVING_TARGET: f64 = 0.97;

/// Exponent of the duration update t_k ← t_k · r_k^e (r_k: segment k's scale-normalised ratio).
const STEP_EXPONENT: f64 = 0.6;

/// Exponent and per-iteration clamp of the duration update for moving starts.
const MOVING_STEP_EXPONENT: f64 = 0.3;
const MOVING_STEP_CLAMP: f64 = 0.85;

impl SplineSolver {
    /// One run of the duration optimiser from `init`: the trajectory of the shortest iterate
    /// within the limits (by the optimiser's own ratios), or `None` if there was none.
    pub(super) fn optimise(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        iterations: usize,
        init: Init,
    ) -> Option<Trajectory> {
        let at_rest = init == Init::Rest;
        let warm = init == Init::Warm || init == Init::Shaped || init == Init::Uniform;
        let n = lim.dof;
        let h = wp.segments();
        // Start: synchronized rest-to-rest durations (closed form).
        let mut seg_t = std::mem::take(&mut self.seg_t);
        let mut best_t = std::mem::take(&mut self.best_t);
        rest_to_rest_durations(lim, wp, &mut seg_t);
        best_t.clear();
        let mut best = f64::INFINITY;
        if init == Init::Warm || init == Init::Uniform {
            let uniform = init == Init::Uniform;
            self.pace_search(
                lim,
                start,
                wp,
                end,
                uniform,
                &mut seg_t,
                &mut best,
                &mut best_t,
            );
        }
        if init == Init::Shaped {
            self.shaped_search(
                lim,
                start,
                wp,
                end,
                iterations,
                &mut seg_t,
                &mut best,
                &mut best_t,
            );
        }
        // Moving starts do not scale exactly: aim slightly inside the limits.
        let target = if at_rest { 1.0 } else { MOVING_TARGET };
        let generic = if init == Init::Shaped {
            0
        } else {
            iterations.max(1)
        };
        for _ in 0..generic {
            if !self.solve(lim, n, start, wp, end, &seg_t) {
                break;
            }
            self.ratios(n, lim, h);
            let lam = (0..h).map(|k| self.seg_ratio(k)).fold(0.0, f64::max);
            let total: f64 = seg_t.iter().sum();
            // At rest, λ·durations is exactly feasible; otherwise only an iterate within the
            // limits (λ ≤ 1) is a candidate as it stands.
            let (cand, scale) = if at_rest {
                (lam * total, lam)
            } else if lam <= 1.0 + RATIO_TOL {
                (total, 1.0)
            } else {
                (f64::INFINITY, 1.0)
            };
            if cand < best {
                best = cand;
                best_t.clear();
                best_t.extend(seg_t.iter().map(|t| t * scale));
            }
            for k in 0..h {
                let r = self.seg_ratio(k) / target;
                if r > 0.0 {
                    let f = if !warm {
                        r.powf(STEP_EXPONENT)
                    } else {
                        // Warm (moving) starts: the ratios couple through the fixed start
                        // state, so the update is damped (a smaller exponent, at most ±15 % a
                        // step).
                        damped_factor(r)
                    };
                    seg_t[k] = (seg_t[k] * f).max(MIN_SEGMENT);
                }
            }
        }
        let result = if best_t.is_empty() {
            None
        } else {
            (self.lambda(lim, start, wp, end, &best_t) <= 1.0 + RATIO_TOL)
                .then(|| self.assemble(n, start, wp, end))
        };
        self.seg_t = seg_t;
        self.best_t = best_t;
        result
    }

    /// Warm start (moving starts): durations proportional to the segment lengths
    /// (limit-normalised joint-space norm), d_k = c·len_k (`uniform`: every len_k the first
    /// segment's, i.e. equal durations, the policy's clock), with the smallest feasible c found
    /// by a geometric scan around the start's own pace and a bisection. For a moving start the
    /// limit ratio is not monotone in c (too slow a pace must brake the start velocity first),
    /// hence the scan. A feasible pace becomes the best plan so far (`best`, `best_t`); `seg_t`
    /// is left at it, or at the least infeasible pace scanned.
    #[allow(clippy::too_many_arguments)]
    fn pace_search(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        uniform: bool,
        seg_t: &mut Vec<f64>,
        best: &mut f64,
        best_t: &mut Vec<f64>,
    ) {
        let n = lim.dof;
        let h = wp.segments();
        let norm = |d: &dyn Fn(usize) -> f64| {
            (0..n)
                .map(|i| (d(i) / lim.v[i]).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let pace = norm(&|i| start.dq[i]);
        let total_len: f64 = (1..=h)
            .map(|k| norm(&|i| wp.row(k)[i] - wp.row(k - 1)[i]))
            .sum();
        // Uniform: every segment the first one's length at the start's pace.
        let first_len = norm(&|i| wp.row(1)[i] - wp.row(0)[i]);
        // (Uniform needs a first segment to take its length from.)
        if pace > 0.0 && total_len > 0.0 && (!uniform || first_len > 0.0) {
            let c0 = 1.0 / pace;
            // λ(c): the largest limit ratio of the spline with durations c·len_k (∞ if
            // singular); leaves those durations in `seg_t`.
            let lam_at = |c: f64, this: &mut Self, seg_t: &mut Vec<f64>| -> f64 {
                seg_t.clear();
                for k in 1..=h {
                    let len = if uniform {
                        first_len
                    } else {
                        norm(&|i| wp.row(k)[i] - wp.row(k - 1)[i])
                    };
                    seg_t.push((c * len).max(MIN_SEGMENT));
                }
                this.lambda(lim, start, wp, end, seg_t)
            };
            let ok = |lam: f64| lam <= 1.0 + RATIO_TOL;
            let mut lo_infeasible = None;
            let mut found = None;
            let mut least = (f64::INFINITY, c0);
            for k in -8i32..=8 {
                let c = c0 * 2f64.powf(k as f64 / 4.0);
                let lam = lam_at(c, self, seg_t);
                if lam < least.0 {
                    least = (lam, c);
                }
                if ok(lam) {
                    found = Some(c);
                    break;
                }
                lo_infeasible = Some(c);
            }
            if let Some(mut hi) = found {
                if let Some(mut lo) = lo_infeasible {
                    for _ in 0..5 {
                        let mid = (lo * hi).sqrt();
                        if ok(lam_at(mid, self, seg_t)) {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                }
                let lam = lam_at(hi, self, seg_t);
                debug_assert!(ok(lam));
                *best = seg_t.iter().sum();
                best_t.extend_from_slice(seg_t);
            } else {
                // Nothing feasible at a uniform pace: refine from the least infeasible one.
                lam_at(least.1, self, seg_t);
            }
        }
    }
}

/// Synchronized rest-to-rest durations of the segments (closed form), into `seg_t`.
fn rest_to_rest_durations(lim: &Limits, wp: &Waypoints, seg_t: &mut Vec<f64>) {
    let n = lim.dof;
    let h = wp.segments();
    seg_t.clear();
    for k in 1..=h {
        let t = (0..n)
            .map(|i| {
                rest_to_rest_time(
                    (wp.row(k)[i] - wp.row(k - 1)[i]).abs(),
                    lim.v[i],
                    lim.a[i],
                    lim.j[i],
                )
            })
            .fold(0.0, f64::max);
        seg_t.push(t.max(MIN_SEGMENT));
    }
}
