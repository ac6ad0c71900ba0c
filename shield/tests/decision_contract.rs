//! `choose`'s Kani contract (`chosen_by_rule`) as a property test: every choice `choose` makes
//! satisfies it, and a choice that differs from `choose`'s in any one field does not (so the
//! contract the step harness `f3_*step*` stands on pins the choice down, it is not vacuous).

use pacs_motion::scaling::{PathState, SpeedProfile};
use pacs_shield::shield::{
    Candidate, Choice, FilterMode, VerifiedFailsafe, choose, chosen_by_rule,
};

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn bool(&mut self) -> bool {
        self.next() & 1 == 1
    }
}

fn profile(r: &mut Rng) -> SpeedProfile {
    let start = PathState {
        s: 5.0 * r.unit(),
        sd: r.unit(),
        sdd: 0.0,
    };
    SpeedProfile::plan(
        start,
        if r.bool() { 1.0 } else { 0.0 },
        2.0 + 8.0 * r.unit(),
        50.0,
    )
}

#[test]
fn every_choice_satisfies_the_contract_and_no_other_does() {
    let mut r = Rng(0x5EED_C0DE_0000_0042);
    let (mut adopted, mut kept) = (0, 0);
    for _ in 0..5_000 {
        let t = 100.0 * r.unit();
        let alpha = 1e-4 + 0.0099 * r.unit();
        let stored = VerifiedFailsafe {
            slot: usize::from(r.bool()),
            profile: profile(&mut r),
            t0: t - r.unit(),
        };
        let candidate = r.bool().then(|| Candidate {
            slot: usize::from(r.bool()),
            go: profile(&mut r),
            brake: profile(&mut r),
            verified: r.bool(),
        });
        let mode =
            [FilterMode::Pacs, FilterMode::Off, FilterMode::SingleAction][(r.next() % 3) as usize];
        let c = choose(stored, candidate, mode, t, alpha);
        assert!(
            chosen_by_rule(&stored, &candidate, mode, t, alpha, &c),
            "{c:?}"
        );
        if c.adopted {
            adopted += 1;
        } else {
            kept += 1;
        }
        // One field changed: the contract refuses it.
        let other = profile(&mut r);
        let variants: [Choice; 6] = [
            Choice {
                adopted: !c.adopted,
                ..c
            },
            Choice {
                slot: 1 - c.slot,
                ..c
            },
            Choice {
                tau: c.tau + 1e-3,
                ..c
            },
            Choice {
                profile: other,
                ..c
            },
            Choice {
                failsafe: VerifiedFailsafe {
                    t0: c.failsafe.t0 + 1e-3,
                    ..c.failsafe
                },
                ..c
            },
            Choice {
                failsafe: VerifiedFailsafe {
                    profile: other,
                    ..c.failsafe
                },
                ..c
            },
        ];
        for (k, v) in variants.iter().enumerate() {
            let same_profile = |a: &SpeedProfile, b: &SpeedProfile| a.same_bits(b);
            if (k == 3 && same_profile(&other, &c.profile))
                || (k == 5 && same_profile(&other, &c.failsafe.profile))
            {
                continue;
            }
            assert!(
                !chosen_by_rule(&stored, &candidate, mode, t, alpha, v),
                "variant {k} accepted: {v:?}"
            );
        }
    }
    assert!(
        adopted > 1_000 && kept > 1_000,
        "{adopted} adopted, {kept} kept"
    );
}
