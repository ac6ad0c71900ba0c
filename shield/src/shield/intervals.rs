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
        let tb = interval_end(k, ta, self.dur, self.alpha, stop, self.max);
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

/// The end (s, relative to the step start) of occupancy interval `k`, which starts at `ta`:
/// the intended step `α_s` for `k = 0`, `stop` for the last allowed interval (`k + 1 ≥ max`),
/// else `ta + dur` capped at `stop`.
///
/// # Soundness
/// Contract (claim C7, [`interval_within`]): for `0 < α_s ≤ stop` finite, `ta ∈ [0, stop]` and
/// `dur > 0` ([`interval_inputs`]), interval 0 ends at `α_s`, every later one at some
/// `tb ∈ [ta, stop]`, and the last allowed one at `stop`. Proven on this function by
/// `f2_interval_end_contract` (`proof_for_contract`, any floats); the iterator's cover of
/// `[0, stop]` from the contract alone by `f2_intervals_cover_by_contract` (`stub_verified`),
/// and from the code itself by `f2_occupancy_intervals_cover`.
#[cfg_attr(kani, kani::requires(interval_inputs(ta, dur, alpha, stop)))]
#[cfg_attr(kani, kani::ensures(|tb: &f64| interval_within(k, ta, alpha, stop, max, *tb)))]
pub fn interval_end(k: usize, ta: f64, dur: f64, alpha: f64, stop: f64, max: usize) -> f64 {
    if k == 0 {
        alpha.min(stop.max(alpha))
    } else if k >= max.saturating_sub(1) {
        stop
    } else {
        (ta + dur).min(stop)
    }
}

/// [`interval_end`]'s precondition: `0 < α_s ≤ stop`, both finite, `ta ∈ [0, stop]` and
/// `dur > 0` (∞ included; the shield's `first_interval` is validated positive and finite, and
/// doubles from there).
pub fn interval_inputs(ta: f64, dur: f64, alpha: f64, stop: f64) -> bool {
    alpha > 0.0 && alpha <= stop && stop.is_finite() && ta >= 0.0 && ta <= stop && dur > 0.0
}

/// [`interval_end`]'s postcondition: interval 0 ends at `α_s`; interval `k > 0` ends at `tb` in
/// `[ta, stop]`, at `stop` itself when `k + 1 ≥ max`.
pub fn interval_within(k: usize, ta: f64, alpha: f64, stop: f64, max: usize, tb: f64) -> bool {
    if k == 0 {
        tb == alpha
    } else {
        ta <= tb && tb <= stop && (k < max.saturating_sub(1) || tb == stop)
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A positive float, often at the extremes (∞ only where `inf`).
    fn positive(inf: bool) -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(5e-324),
            Just(f64::MIN_POSITIVE),
            Just(f64::MAX),
            Just(if inf { f64::INFINITY } else { 1.0 }),
            1e-6f64..10.0,
            any::<f64>().prop_map(f64::abs),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 20_000,
            max_global_rejects: 200_000,
            ..ProptestConfig::default()
        })]
        /// The twin of `f2_interval_end_contract`: [`interval_end`] keeps its contract for any
        /// inputs its precondition admits (interval 0 at `α_s`, later ones within `[ta, stop]`,
        /// the last allowed one at `stop`).
        #[test]
        fn interval_end_keeps_its_contract(
            k in prop_oneof![Just(0usize), Just(1), 0usize..16, any::<usize>()],
            max in prop_oneof![Just(0usize), Just(1), 0usize..16, any::<usize>()],
            dur in positive(true),
            stop in positive(false),
            alpha_frac in prop_oneof![Just(1.0f64), 0.0f64..=1.0],
            ta_frac in prop_oneof![Just(0.0f64), Just(1.0), 0.0f64..=1.0],
        ) {
            let (alpha, ta) = (stop * alpha_frac, stop * ta_frac);
            prop_assume!(interval_inputs(ta, dur, alpha, stop));
            let tb = interval_end(k, ta, dur, alpha, stop, max);
            prop_assert!(
                interval_within(k, ta, alpha, stop, max, tb),
                "interval {k} (max {max}) from {ta}: ends at {tb}, α {alpha}, stop {stop}, dur {dur}"
            );
        }
    }
}
