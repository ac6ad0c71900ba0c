//! The shaped start of moving starts: the later segments at a common multiple of their from-rest
//! durations, the first segment's duration searched on its own, then a damped refinement.

use super::optimise::{MOVING_TARGET, damped_factor};
use super::{MIN_SEGMENT, RATIO_TOL, SplineSolver};
use crate::chunk::Waypoints;
use crate::trajectory::{EndCondition, JointState, Limits};

/// Shaped moving starts ([`SplineSolver::shaped_search`]): the later segments' from-rest durations
/// are scaled by c = SHAPE_SCALE_STEP^±i, at most SHAPE_SCALES steps from 1 within
/// [SHAPE_SCALE_MIN, SHAPE_SCALE_MAX] (upwards the walk stops when the largest ratio has fallen
/// by less than 1 − STALL_RATIO after STALL_AFTER steps); the first segment's duration is
/// scanned over [FIRST_MIN, FIRST_MAX] times its from-rest duration at FIRST_POINTS geometric
/// points and refined by GOLDEN_STEPS golden-section steps, and within ±20 % at REFINE_POINTS
/// in each of REFINE_ITERATIONS refinement iterations.
const SHAPE_SCALES: usize = 8;
const SHAPE_SCALE_MIN: f64 = 0.6;
const SHAPE_SCALE_MAX: f64 = 1.9;
const SHAPE_SCALE_STEP: f64 = 1.08;
const FIRST_MIN: f64 = 0.02;
const FIRST_MAX: f64 = 3.0;
const FIRST_POINTS: usize = 40;
const REFINE_ITERATIONS: usize = 4;
const REFINE_POINTS: usize = 5;
const GOLDEN_STEPS: usize = 6;
const STALL_AFTER: usize = 2;
const STALL_RATIO: f64 = 0.97;

impl SplineSolver {
    /// The first segment's duration in [lo, hi] (s) that minimises the largest limit ratio, the
    /// other durations fixed: a geometric scan of `points` durations, then a golden-section
    /// refinement around the best. Leaves it in `seg_t[0]` and returns the ratio.
    #[allow(clippy::too_many_arguments)]
    fn best_first(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        seg_t: &mut [f64],
        lo: f64,
        hi: f64,
        points: usize,
    ) -> f64 {
        let (lo, hi) = (lo.max(MIN_SEGMENT), hi.max(MIN_SEGMENT));
        let step = (hi / lo).powf(1.0 / (points.max(2) - 1) as f64);
        let (mut best_i, mut best_l) = (0usize, f64::INFINITY);
        let mut t = lo;
        for i in 0..points {
            seg_t[0] = t;
            let l = self.lambda(lim, start, wp, end, seg_t);
            if l < best_l {
                (best_i, best_l) = (i, l);
            }
            t *= step;
        }
        let at = |i: f64| lo * step.powf(i);
        // Golden section on log t over the neighbouring grid points.
        let (mut a, mut b) = (best_i as f64 - 1.0, best_i as f64 + 1.0);
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let mut best_t = at(best_i as f64);
        for _ in 0..GOLDEN_STEPS {
            let (x1, x2) = (b - g * (b - a), a + g * (b - a));
            seg_t[0] = at(x1);
            let l1 = self.lambda(lim, start, wp, end, seg_t);
            seg_t[0] = at(x2);
            let l2 = self.lambda(lim, start, wp, end, seg_t);
            if l1 < best_l {
                (best_l, best_t) = (l1, at(x1));
            }
            if l2 < best_l {
                (best_l, best_t) = (l2, at(x2));
            }
            if l1 <= l2 {
                b = x2;
            } else {
                a = x1;
            }
        }
        seg_t[0] = best_t;
        best_l
    }

    /// Moving start from the from-rest shape (`self.shape`): the later segments at c times their
    /// from-rest durations, the first segment's duration optimised for each c (a moving start
    /// reaches the next waypoint within limits only in a narrow window of durations), then a
    /// damped fixed-point refinement of the later segments with the first re-optimised.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn shaped_search(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        iterations: usize,
        seg_t: &mut Vec<f64>,
        best: &mut f64,
        best_t: &mut Vec<f64>,
    ) {
        let shape = std::mem::take(&mut self.shape);
        let h = shape.len();
        let ok = |l: f64| l <= 1.0 + RATIO_TOL;
        let record = |seg_t: &[f64], best: &mut f64, best_t: &mut Vec<f64>| {
            let total: f64 = seg_t.iter().sum();
            if total < *best {
                *best = total;
                best_t.clear();
                best_t.extend_from_slice(seg_t);
            }
        };
        // The later segments at c times their from-rest durations (the first one's is then
        // searched by `best_first`).
        let fill = |seg_t: &mut Vec<f64>, c: f64| {
            seg_t.clear();
            seg_t.push(shape[0]);
            seg_t.extend(shape[1..].iter().map(|t| (c * t).max(MIN_SEGMENT)));
        };
        // The scale search starts at c = 1 (the later segments as from rest, where most plans
        // land) and walks down while c stays feasible, else up until it is (or the ratio stops
        // falling: the shape does not fit). The first segment's feasible durations form a
        // narrow valley that moves with the scale, so every scale scans the whole range.
        let tail: f64 = shape[1..].iter().sum();
        let wide = |this: &mut Self, seg_t: &mut Vec<f64>, c: f64| -> f64 {
            fill(seg_t, c);
            this.best_first(
                lim,
                start,
                wp,
                end,
                seg_t,
                FIRST_MIN * shape[0],
                FIRST_MAX * shape[0],
                FIRST_POINTS,
            )
        };
        let mut c = 1.0;
        if ok(wide(self, seg_t, c)) {
            record(seg_t, best, best_t);
            for _ in 0..SHAPE_SCALES {
                c /= SHAPE_SCALE_STEP;
                if c < SHAPE_SCALE_MIN || !ok(wide(self, seg_t, c)) {
                    break;
                }
                record(seg_t, best, best_t);
            }
        } else {
            let mut prev = f64::INFINITY;
            for i in 0..SHAPE_SCALES {
                c *= SHAPE_SCALE_STEP;
                if c > SHAPE_SCALE_MAX || c * tail >= *best {
                    // Slower than a plan already found.
                    break;
                }
                let l = wide(self, seg_t, c);
                if ok(l) {
                    record(seg_t, best, best_t);
                    break;
                }
                if i >= STALL_AFTER && l > STALL_RATIO * prev {
                    break;
                }
                prev = l;
            }
        }
        if best_t.is_empty() {
            self.shape = shape;
            return;
        }
        // Damped fixed-point refinement of the later segments from the best found, the first
        // segment re-optimised around its last duration at every iterate.
        if h > 1 {
            seg_t.clear();
            seg_t.extend_from_slice(best_t);
            for _ in 0..iterations.min(REFINE_ITERATIONS) {
                self.lambda(lim, start, wp, end, seg_t);
                for k in 1..h {
                    let r = self.seg_ratio(k) / MOVING_TARGET;
                    if r > 0.0 {
                        seg_t[k] = (seg_t[k] * damped_factor(r)).max(MIN_SEGMENT);
                    }
                }
                let t0 = seg_t[0];
                let l = self.best_first(
                    lim,
                    start,
                    wp,
                    end,
                    seg_t,
                    0.8 * t0,
                    1.25 * t0,
                    REFINE_POINTS,
                );
                if ok(l) {
                    record(seg_t, best, best_t);
                }
            }
        }
        self.shape = shape;
    }
}
