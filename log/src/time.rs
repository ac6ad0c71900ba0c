//! Time stamps: whether a clock's floats resolve a step. One rule for the shield (which refuses
//! to start on a clock that cannot resolve its safety step) and the audit (which checks no span
//! whose stamps cannot resolve it).

/// Whether `f64` time stamps near `t` (s) resolve a thousandth of the step `alpha` (s): the
/// spacing of doubles at `t` (at most `ε·|t|`) is at most `alpha / 1000`. Unix time (≈ 1.8·10⁹ s)
/// resolves steps of 0.4 ms and longer; at `t = 10¹⁶` s doubles are 2 s apart and resolve no
/// step shorter than 2000 s. False for non-finite `t`.
///
/// Used by `Shield::start` (the clock must resolve α) and by the audit (a span `[t0, t1]` is
/// checked only where the stamps resolve its length, else it is inconclusive,
/// `unresolved_time`).
pub fn clock_resolves(t: f64, alpha: f64) -> bool {
    t.is_finite() && f64::EPSILON * t.abs() <= alpha / 1000.0
}

#[cfg(test)]
mod tests {
    use super::clock_resolves;

    #[test]
    fn unix_time_resolves_milliseconds_and_1e16_does_not_resolve_50_ms() {
        assert!(clock_resolves(1.8e9, 1e-3));
        assert!(!clock_resolves(1.8e9, 1e-4));
        assert!(!clock_resolves(1e16, 0.05));
        assert!(clock_resolves(0.0, 1e-6));
        assert!(!clock_resolves(f64::NAN, 1.0));
        // The boundary: ε·|t| = α/1000 resolves, one ulp more does not.
        // (Exact powers of two: ε·2²² = 2⁻³⁰ = α/1000 for α = 1000·2⁻³⁰.)
        let alpha = 1000.0 * 2f64.powi(-30);
        let t = 2f64.powi(22);
        assert!(clock_resolves(t, alpha));
        assert!(clock_resolves(-t, alpha));
        assert!(!clock_resolves(t * (1.0 + 2.0 * f64::EPSILON), alpha));
    }
}
