//! The audit's claims in one list beside the code that makes them: which checks it performs and
//! the tests and harnesses that back each, and the modelling assumptions its verdicts rest on.
//! Reports print these lists; nothing else restates them.

use serde::Serialize;

/// One check the audit performs and what backs it (paths in the repository).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Check {
    /// What is checked.
    pub check: &'static str,
    /// Tests, harnesses and mutants that back it.
    pub backed_by: &'static [&'static str],
}

/// The checks of the audit.
pub const CHECKS: &[Check] = &[
    Check {
        check: "robot occupancy over a span (joint box from v_max, outward-rounded)",
        backed_by: &[
            "reach/tests/robot_occupancy.rs (proptest: sampled link points stay in the box occupancy)",
            "audit/tests/audit_checks.rs::violation_only_between_samples_is_caught",
        ],
    },
    Check {
        check: "human occupancy since the measurement (vel/pos/combined models)",
        backed_by: &["reach/tests/human_occupancy.rs (proptest soundness of every model)"],
    },
    Check {
        check: "conservative capsule separation / intersection",
        backed_by: &[
            "reach/tests/geometry.rs (lower bound never above exact distance; touching never disjoint)",
        ],
    },
    Check {
        check: "span enclosures and consistency of logged positions, velocities and accelerations",
        backed_by: &[
            "proofs: h2_span_enclosure_sound (property test of the whole claim; Kani on one corner of the limits, both modes' extreme motions and their contradiction)",
            "proofs: h2_contradiction_inconsistent (Kani: contradicting positions judged inconsistent, one corner of the limits and one span)",
            "proofs: h2_bang_bang_enclosed (Kani: one extreme bang-bang motion enclosed at any instant)",
            "proofs: h2_jerk_enclosed (Kani: one extreme jerk-limited motion enclosed at any instant)",
            "audit/tests/audit_consistency.rs",
        ],
    },
    Check {
        check: "whole-robot kinetic-energy upper bound over the boxes",
        backed_by: &[
            "reach/tests/energy.rs (proptest: bound covers every sampled state)",
            "audit/tests/audit_checks.rs::pfl_energy_just_above_and_below_threshold",
            "audit/tests/audit_consistency.rs::pfl_uses_the_whole_robot_energy",
        ],
    },
    Check {
        check: "the one ISO/TS 15066 rule (SSM, PFL, clamping) shared with the shield",
        backed_by: &[
            "proofs: i1_rule_judgement_sound (Kani: the narrow phase for any contact masks containing the true contacts)",
            "proofs: i1_broad_phase_boxes_contain (Kani: the broad phase's boxes contain the capsules)",
            "proofs: i1_rule_sound (property test of the whole rule)",
            "proofs/mutants: x9, x10 caught (x10 also by Kani)",
        ],
    },
    Check {
        check: "SSM violation detection (first, last sample, one-sample spike, between samples)",
        backed_by: &["audit/tests/audit_checks.rs"],
    },
    Check {
        check: "PFL constrained vs unconstrained contact",
        backed_by: &["audit/tests/audit_checks.rs::pfl_constrained_vs_unconstrained"],
    },
    Check {
        check: "bad input rejected (exit 3), never pass",
        backed_by: &[
            "audit/tests/audit_input.rs",
            "tests/cli_audit.rs",
            "fuzz/ (cargo fuzz target jsonl)",
        ],
    },
];

/// The modelling assumptions the verdicts rest on (see `docs/audit.md`).
pub const ASSUMPTIONS: &[&str] = &[
    "Recorded joint positions, velocities and accelerations are exact at their time stamps (up to 1 ulp of decimal parsing).",
    "Between samples every joint obeys |dq| <= v_max, |ddq| <= a_max and |dddq| <= j_max of the robot model; samples contradicting this or each other (positions vs velocities under a_max, velocities vs accelerations under j_max) make the span inconclusive, with boxes covering what the positions imply.",
    "The human moves within the human model's speed bound since each measurement; positions are within measurement_error_pos of the truth; a measurement stamped t_meas describes the state at t_meas - delay.",
    "Robot link geometry is the model's capsules enlarged by tracking_error; human body parts are the model's capsules.",
    "SSM: any possible contact while the robot is not provably at rest (all joint speeds <= rest_speed) is a violation; contact with the fixed base link counts.",
    "PFL: a possible contact is a violation if the sound upper bound of the whole robot's kinetic energy (which bounds the energy transferable at any contact point) exceeds the threshold; constrained (the lower threshold) if clamping is possible: the environment, robot links on two different frames (adjacent links included), a clampable body part, or another person (with several people every PFL contact counts as possible clamping).",
    "With human_model = pos: each extremity's keypoints stay within its length + thickness/2 of its base keypoint; a measurement contradicting this by more than 2 measurement_error_pos is not trusted (that extremity uses the speed-bounded occupancy).",
    "Spans longer than max_gap, before the first human record, or with a human measurement older than max_human_age are inconclusive.",
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Every file a check names as its backing exists, and every harness it names is defined in
    /// `proofs/` or beside the code (a renamed test must not leave the report pointing nowhere).
    #[test]
    fn backing_paths_and_harnesses_exist() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        // Harnesses of compositions, and those beside the code they check.
        let mut proofs = String::new();
        for dir in [
            "proofs/src/harnesses",
            "reach/src/rounding",
            "reach/src/interval",
        ] {
            for e in std::fs::read_dir(root.join(dir)).expect(dir).flatten() {
                proofs += &std::fs::read_to_string(e.path()).unwrap_or_default();
            }
        }
        for c in CHECKS {
            assert!(!c.backed_by.is_empty(), "{}: nothing backs it", c.check);
            for b in c.backed_by {
                if let Some(h) = b.strip_prefix("proofs: ") {
                    let name = h.split_whitespace().next().unwrap_or("");
                    assert!(
                        proofs.contains(name),
                        "{}: harness `{name}` not found",
                        c.check
                    );
                } else if let Some(path) = b.split([':', ' ']).next()
                    && path.ends_with(".rs")
                {
                    assert!(
                        root.join(path).is_file(),
                        "{}: `{path}` does not exist",
                        c.check
                    );
                }
            }
        }
    }
}
