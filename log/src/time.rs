//! Time stamps: whether a clock's floats resolve a step. One rule for the shield (which refuses
//! to start on a clock that cannot resolve its safety step) and the audit (which checks no span
//! whose stamps cannot resolve it).

/// Whether `f64` time stamps near `t` (s) resolve a thousandth of the step `alpha` (s): the
/// spacing of doubles at `t` — at most `ε·|t|` for normal numbers, and never below the least
/// positive double `2⁻¹⁰⁷⁴` (≈ 4.9·10⁻³²⁴ s: the spacing of every subnormal and of 0) — is at
/// most `alpha / 1000`. Unix time (≈ 1.8·10⁹ s) resolves steps of 0.4 ms and longer; at
/// `t = 10¹⁶` s doubles are 2 s apart and resolve no step shorter than 2000 s; stamps
/// `k·2⁻¹⁰⁷⁴` resolve nothing (a thousandth of their step rounds to 0). False for non-finite `t`
/// or `alpha`.
///
/// Used by `Shield::start` (the clock must resolve α) and by the audit (a span `[t0, t1]` is
/// checked only where the stamps resolve its length, else it is inconclusive,
/// `unresolved_time`).
pub fn clock_resolves(t: f64, alpha: f64) -> bool {
    let spacing = (f64::EPSILON * t.abs()).max(f64::from_bits(1));
    t.is_finite() && alpha.is_finite() && spacing <= alpha / 1000.0
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

    /// Near 0 the spacing of doubles is the least subnormal, not `ε·|t|` (which underflows):
    /// stamps `k·2⁻¹⁰⁷⁴` resolve no step of theirs, and 0 resolves a step only down to
    /// 1000·2⁻¹⁰⁷⁴.
    #[test]
    fn subnormal_stamps_resolve_no_step_of_theirs() {
        let tiny = f64::from_bits(1);
        for k in [0.0, 1.0, 2.0, 1000.0] {
            assert!(!clock_resolves(k * tiny, tiny), "t = {k}·2⁻¹⁰⁷⁴");
            assert!(!clock_resolves(k * tiny, 400.0 * tiny));
        }
        assert!(clock_resolves(0.0, 1000.0 * tiny));
        assert!(!clock_resolves(0.0, f64::INFINITY));
        assert!(clock_resolves(1e-300, 1e-300));
    }
}
