//! The occupancy time intervals over which a monitored trajectory is verified (they cover it up
//! to standstill).

/// The occupancy time intervals of a monitored trajectory, as used by the shield's verification:
/// items `(k, t_a, t_b)` relative to the step start: `[0, α_s]` (k = 0), then durations
/// `first·2^(k−1)` until `stop`, the interval `max_intervals − 1` extending to `stop`. For finite
/// `0 < α_s ≤ stop`, `first > 0`, the intervals are contiguous and cover `[0, stop]`.
///
/// # Soundness
/// Claim C7: a step is verified only if every interval of the whole monitored trajectory passed,
/// and these intervals cover it. Harness `f2_occupancy_intervals_cover`; mutant `m4` caught.
#[derive(Debug, Clone, Copy)]
pub struct OccupancyIntervals {
    alpha: f64,
    stop: f64,
    max: usize,
    ta: f64,
    k: usize,
    dur: f64,
    done: bool,
}

impl OccupancyIntervals {
    /// Intervals for step `alpha`, standstill at `stop`, first duration `first`, at most `max`.
    pub fn new(alpha: f64, stop: f64, first: f64, max: usize) -> Self {
        Self {
            alpha,
            stop,
            max,
            ta: 0.0,
            k: 0,
            dur: first,
            done: false,
        }
    }
}

impl Iterator for OccupancyIntervals {
    type Item = (usize, f64, f64);
    fn next(&mut self) -> Option<(usize, f64, f64)> {
        if self.done || !(self.ta < self.stop || self.k == 0) {
            return None;
        }
        let (k, ta, stop) = (self.k, self.ta, self.stop);
        let tb = if k == 0 {
            self.alpha.min(stop.max(self.alpha))
        } else if k + 1 >= self.max {
            stop
        } else {
            (ta + self.dur).min(stop)
        };
        if k > 0 {
            self.dur *= 2.0;
        }
        self.k += 1;
        self.ta = tb;
        if tb >= stop {
            self.done = true;
        }
        Some((k, ta, tb))
    }
}
