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

/// One piece of the fine verification ([`verify_fine`]): a single occupancy interval, or the
/// union of the intervals before the last one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Piece {
    /// Occupancy interval `k` of [`OccupancyIntervals`].
    Interval(usize),
    /// Intervals `0..k` as one interval (its occupancy contains each of theirs).
    Before(usize),
}

/// The fine verification of a monitored trajectory over the occupancy intervals `leaves` (the
/// items of [`OccupancyIntervals`]: indices `0, 1, …` in order), with
/// `check(piece, t_a, t_b)` the verification of one time interval (`true`: verified). Order: the
/// last interval (where the human's reach is largest, the usual reason a step fails), then
/// everything before it as one interval, and only if that fails each interval before the last
/// in order, stopping at the first failure. At most `n + 1` calls for `n` intervals, two when
/// the merged piece verifies (the usual case when a step verifies: `docs/performance.md`).
///
/// # Soundness
/// Claim C7: `true` only if `check` returned `true` for pieces that cover `[0, stop]`: the last
/// interval `[t_a, stop]` and either `[0, t_a]` or every interval before it, which cover
/// `[0, t_a]` (contiguous intervals from 0, harness `f2_occupancy_intervals_cover`). A step
/// verified by the intervals one by one is verified here too (the same calls are made when
/// the merged piece fails). Harness `f2_fine_pieces_cover` (any `check` outcomes).
pub fn verify_fine<I>(leaves: I, mut check: impl FnMut(Piece, f64, f64) -> bool) -> bool
where
    I: Iterator<Item = (usize, f64, f64)> + Clone,
{
    let Some((last, last_ta, last_tb)) = leaves.clone().last() else {
        return false;
    };
    if !check(Piece::Interval(last), last_ta, last_tb) {
        return false;
    }
    if last == 0 || check(Piece::Before(last), 0.0, last_ta) {
        return true;
    }
    for (k, ta, tb) in leaves.take(last) {
        if !check(Piece::Interval(k), ta, tb) {
            return false;
        }
    }
    true
}
