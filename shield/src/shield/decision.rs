//! The pure decision of one shield step (paper Algorithm 1): adopt a verified candidate or
//! continue the last verified failsafe.

use super::FilterMode;
use pacs_motion::scaling::{PathState, SpeedProfile};

/// The last verified failsafe: braking profile `profile` on trajectory slot `slot`, started at
/// absolute time `t0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifiedFailsafe {
    /// Trajectory slot the failsafe lives on.
    pub slot: usize,
    /// Braking path-speed profile (ṡ → 0).
    pub profile: SpeedProfile,
    /// Absolute time of the profile start.
    pub t0: f64,
}

/// A candidate of one shield step: the go-profile for α_s, then `brake`, on `slot`, and whether
/// the monitored trajectory was verified.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Trajectory slot of the candidate.
    pub slot: usize,
    /// Intended step (ṡ → 1) for α_s.
    pub go: SpeedProfile,
    /// Failsafe after the step (ṡ → 0).
    pub brake: SpeedProfile,
    /// The monitored trajectory (go, then brake) was verified.
    pub verified: bool,
}

/// The outcome of [`decide`]: the executed slot and path state at `t + α_s` and the (possibly
/// new) last verified failsafe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// Slot of the executed command.
    pub slot: usize,
    /// Executed path state at `t + α_s`.
    pub path: PathState,
    /// The last verified failsafe after this step.
    pub failsafe: VerifiedFailsafe,
    /// The candidate was adopted (verified, or OFF mode).
    pub adopted: bool,
}

/// What one shield step executes, before it is evaluated: the slot, the profile and the time on
/// it whose state is commanded at `t + α_s`, and the (possibly new) last verified failsafe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Choice {
    /// Slot of the executed command.
    pub slot: usize,
    /// The profile the executed state is read from (the candidate's go step, or the failsafe).
    pub profile: SpeedProfile,
    /// The time on `profile` (s after its start) of the executed state.
    pub tau: f64,
    /// The last verified failsafe after this step.
    pub failsafe: VerifiedFailsafe,
    /// The candidate was adopted (verified, or OFF mode).
    pub adopted: bool,
}

/// The selection of one shield step (paper Algorithm 1): a verified candidate (or any candidate
/// in OFF mode) is executed — its go step at α_s — and its brake profile becomes the stored
/// failsafe (starting at `t + α_s`); otherwise (no candidate, or not verified) the stored
/// failsafe is continued to `t + α_s`. [`decide`] evaluates the choice.
///
/// # Soundness
/// Claim C8 (induction): the stored failsafe changes only on a verified candidate, and the
/// executed state is read from the verified go step or from the stored failsafe. Harness
/// `f1_shield_decision_induction` (property test; Kani: `f1_decision_adopted`, `f1_decision_kept` — any finite profiles, full-width times with
/// `t ∈ [0, 100]` s, `α ∈ [1e-4, 0.01]` s, the failsafe started up to 1 s before); mutant `x2`
/// caught. Its Kani contract is [`chosen_by_rule`] (proven by `f3_choose_contract_adopted` and
/// `f3_choose_contract_kept`; used in place of `choose` by `f3_shield_step_induction`).
#[cfg_attr(kani, kani::requires(choose_in_proven_range(&stored, t, alpha)))]
#[cfg_attr(kani, kani::ensures(|c: &Choice| chosen_by_rule(&stored, &candidate, mode, t, alpha, c)))]
pub fn choose(
    stored: VerifiedFailsafe,
    candidate: Option<Candidate>,
    mode: FilterMode,
    t: f64,
    alpha: f64,
) -> Choice {
    match candidate {
        Some(c) if c.verified || mode == FilterMode::Off => Choice {
            slot: c.slot,
            profile: c.go,
            tau: alpha,
            failsafe: VerifiedFailsafe {
                slot: c.slot,
                profile: c.brake,
                t0: t + alpha,
            },
            adopted: true,
        },
        _ => Choice {
            slot: stored.slot,
            profile: stored.profile,
            tau: t + alpha - stored.t0,
            failsafe: stored,
            adopted: false,
        },
    }
}

/// The precondition of [`choose`]'s contract: finite times `t`, `α` and failsafe start (its
/// proofs `f3_choose_contract_adopted`, `f3_choose_contract_kept` draw any finite times and
/// finite profiles). A harness that puts the contract in `choose`'s place (`stub_verified`)
/// must call it with such times, which Kani checks at each call.
pub fn choose_in_proven_range(stored: &VerifiedFailsafe, t: f64, alpha: f64) -> bool {
    t.is_finite() && alpha.is_finite() && stored.t0.is_finite()
}

/// The selection rule of [`choose`] as a predicate on its result (its Kani contract): a verified
/// candidate (any candidate in OFF mode) is executed — its go step at α, its brake the new
/// failsafe from `t + α`, its slot — otherwise the stored failsafe is kept and continued to
/// `t + α`. Profiles and times compare bit for bit.
pub fn chosen_by_rule(
    stored: &VerifiedFailsafe,
    candidate: &Option<Candidate>,
    mode: FilterMode,
    t: f64,
    alpha: f64,
    c: &Choice,
) -> bool {
    match candidate {
        Some(k) if k.verified || mode == FilterMode::Off => {
            c.adopted
                && c.slot == k.slot
                && c.profile.same_bits(&k.go)
                && c.tau.to_bits() == alpha.to_bits()
                && c.failsafe.slot == k.slot
                && c.failsafe.profile.same_bits(&k.brake)
                && c.failsafe.t0.to_bits() == (t + alpha).to_bits()
        }
        _ => {
            !c.adopted
                && c.slot == stored.slot
                && c.profile.same_bits(&stored.profile)
                && c.tau.to_bits() == (t + alpha - stored.t0).to_bits()
                && c.failsafe.slot == stored.slot
                && c.failsafe.profile.same_bits(&stored.profile)
                && c.failsafe.t0.to_bits() == stored.t0.to_bits()
        }
    }
}

/// The pure decision of one shield step (paper Algorithm 1), as used by [`Shield::step`]: the
/// [`choose`]n profile evaluated at the chosen time.
///
/// [`Shield::step`]: super::Shield::step
///
/// # Soundness
/// Claim C8 (induction): the robot is always on a verified monitored trajectory; the stored
/// failsafe changes only on a verified candidate. Harness `f1_shield_decision_induction` (property test; Kani, split by outcome: `f1_decision_adopted`, `f1_decision_kept`;
/// [`choose`]; the twin: `decide` as a whole, three steps from the start), property test
/// `f3_real_shield_commands_on_verified_failsafe`; mutant `x2` caught.
pub fn decide(
    stored: VerifiedFailsafe,
    candidate: Option<Candidate>,
    mode: FilterMode,
    t: f64,
    alpha: f64,
) -> Decision {
    let c = choose(stored, candidate, mode, t, alpha);
    Decision {
        slot: c.slot,
        path: c.profile.eval(c.tau),
        failsafe: c.failsafe,
        adopted: c.adopted,
    }
}
