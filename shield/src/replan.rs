//! The one re-plan policy for a chunk whose hand-over failed: planned too late for its lead, or
//! offered but the commands left the predicted path (stale) or its first step was not verified.

/// When and how a chunk is planned again after a failed hand-over.
///
/// The schedule:
/// - **Asynchronous** ([`crate::worker::ChunkWorker`]): the `n`-th stale offer in a row is
///   planned again after [`ReplanPolicy::backoff`]`(n)` safety steps: 0, 1, 3, 7, 15, 31, 63,
///   63, … (2ⁿ⁻¹ − 1, at most [`ReplanPolicy::max_backoff`]), without limit, so that a loop whose
///   steps keep alternating between verified and not (an arm creeping past a person) does not
///   plan the chunk every few steps.
/// - **Blocking** (the Python binding's `set_chunk`, one caller waiting): at most
///   [`ReplanPolicy::attempts`] attempts, each planned at once; a plan that came too late
///   looks further ahead next time ([`ReplanPolicy::longer_lead`]: the lead doubled, at most
///   [`ReplanPolicy::max_lead`]).
///
/// Either way the robot keeps its verified motion meanwhile: re-planning only decides when the
/// new chunk can take over, never what is safe.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplanPolicy {
    /// Longest pause (safety steps) before planning again after offers went stale in a row.
    pub max_backoff: u64,
    /// Hand-over attempts of a blocking caller before it gives up.
    pub attempts: usize,
    /// Longest hand-over lead (safety steps).
    pub max_lead: usize,
}

impl ReplanPolicy {
    /// The policy every runner uses: pauses up to 63 steps, 5 blocking attempts, leads up to
    /// 200 steps.
    pub const DEFAULT: ReplanPolicy = ReplanPolicy {
        max_backoff: 63,
        attempts: 5,
        max_lead: 200,
    };

    /// Safety steps to wait before planning again after the `streak`-th stale offer in a row
    /// (`streak` ≥ 1; 0 is treated as 1): 2^(streak−1) − 1, at most
    /// [`ReplanPolicy::max_backoff`]. Never overflows.
    pub fn backoff(&self, streak: u32) -> u64 {
        let exp = streak.saturating_sub(1).min(16);
        ((1u64 << exp) - 1).min(self.max_backoff)
    }

    /// The lead (safety steps) after a plan came too late for `lead`: doubled, at most
    /// [`ReplanPolicy::max_lead`]. Never overflows.
    pub fn longer_lead(&self, lead: usize) -> usize {
        lead.saturating_mul(2).min(self.max_lead)
    }

    /// The lead (safety steps) for a planning time of `planning_s` (s) at `safety_step` (s):
    /// twice the planning time plus one step, at least 2 and at most
    /// [`ReplanPolicy::max_lead`].
    pub fn lead_for(&self, planning_s: f64, safety_step: f64) -> usize {
        ((2.0 * planning_s / safety_step).ceil() as usize + 1).clamp(2, self.max_lead)
    }
}

impl Default for ReplanPolicy {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backoff_schedule() {
        let p = ReplanPolicy::DEFAULT;
        let got: Vec<u64> = (1..=9).map(|n| p.backoff(n)).collect();
        assert_eq!(got, [0, 1, 3, 7, 15, 31, 63, 63, 63]);
        assert_eq!(p.backoff(0), 0);
        assert_eq!(p.backoff(u32::MAX), 63);
    }

    #[test]
    fn leads() {
        let p = ReplanPolicy::DEFAULT;
        assert_eq!(p.longer_lead(3), 6);
        assert_eq!(p.longer_lead(150), 200);
        assert_eq!(p.longer_lead(usize::MAX), 200);
        assert_eq!(p.lead_for(0.0, 0.001), 2);
        assert_eq!(p.lead_for(0.0012, 0.001), 4);
        assert_eq!(p.lead_for(1.0, 0.001), 200);
    }
}
