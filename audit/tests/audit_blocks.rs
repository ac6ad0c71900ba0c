//! The block fast path (one check over the hull of up to 32 spans, then halves, then span by
//! span; objects included) against the reference that checks every span on its own: over
//! random logs of an arm moving near a person and a ball (measured at different rates, so that
//! blocks close on either), both give the same verdict, the same violating and certain samples,
//! the same violation intervals and the same inconclusive spans. The fast path may only decide
//! faster; a stretch it calls clean that a span check flags would fail this test.

mod audit_common;

use audit_common::Q_READY;
use pacs_audit::{AuditConfig, Auditor, RunResult};
use pacs_log::LogModels;
use pacs_models::object::{ObjectContact, ObjectModel, builtin_object};
use pacs_models::{ConstraintSpec, HumanModel, RobotModel};

/// xorshift64*, uniform in [0, 1).
struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }
}

fn standing(x: f64, y: f64) -> Vec<[f64; 3]> {
    vec![
        [x, y + 0.2, 1.4],
        [x - 0.1, y + 0.25, 1.15],
        [x - 0.2, y + 0.25, 0.95],
        [x, y - 0.2, 1.4],
        [x - 0.1, y - 0.25, 1.15],
        [x - 0.2, y - 0.25, 0.95],
        [x, y, 1.45],
        [x, y, 0.95],
        [x, y, 1.65],
    ]
}

fn models(task: &str, contact: ObjectContact) -> LogModels {
    let ball = ObjectModel::new(&builtin_object("ball").unwrap()).unwrap();
    LogModels {
        robot: RobotModel::builtin("fr3").unwrap(),
        human: HumanModel::builtin("default").unwrap(),
        people: vec![("human".into(), HumanModel::builtin("default").unwrap())],
        constraints: ConstraintSpec::builtin(task).unwrap(),
        environment: vec![],
        objects: vec![("b1".into(), ball, contact)],
    }
}

/// One random log, fed to `a`: 600 samples at 1 kHz (a few jittered), every joint moving, the
/// person walking from `x0` toward or away from the arm (30 Hz), the ball drifting near the arm
/// (20 Hz).
fn feed(a: &mut Auditor, seed: u64) {
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let x0 = rng.range(0.5, 2.2);
    let walk = rng.range(-0.8, 0.4);
    let amp = rng.range(0.0, 0.3);
    let ball = [
        rng.range(0.2, 0.7),
        rng.range(-0.4, 0.4),
        rng.range(0.0, 0.8),
    ];
    let bv = [rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), 0.0];
    let mut t = 0.0;
    for k in 0..600 {
        t = if k == 0 {
            0.0
        } else {
            t + 1e-3 * rng.range(0.98, 1.02)
        };
        if k % 33 == 0 {
            let x = x0 + walk * t;
            a.push_human(t, t, &standing(x, 0.1)).unwrap();
        }
        if k % 50 == 0 {
            let p = [ball[0] + bv[0] * t, ball[1] + bv[1] * t, ball[2]];
            a.push_object(t, t, "b1", p, Some(bv)).unwrap();
        }
        let mut q = Q_READY;
        let mut dq = [0.0; 7];
        for j in 0..7 {
            // Within FR3's limits: |dq| ≤ 1.35 rad/s, |ddq| ≤ 6.1 rad/s².
            let w = 1.5 + 0.5 * j as f64;
            q[j] += amp * (w * t).sin();
            dq[j] = amp * w * (w * t).cos();
        }
        a.push_robot(t, &q, Some(&dq)).unwrap();
    }
}

fn run(seed: u64, task: &str, contact: ObjectContact, fast: bool) -> RunResult {
    let a = Auditor::new(models(task, contact), AuditConfig::default()).unwrap();
    let mut a = if fast { a } else { a.without_block_fast_path() };
    feed(&mut a, seed);
    a.finish("random.jsonl", Default::default())
}

#[test]
fn the_block_fast_path_decides_as_span_by_span() {
    let contacts = [
        ObjectContact::Ssm,
        ObjectContact::NoContact,
        ObjectContact::Pfl { threshold: 2.0 },
    ];
    let (mut fails, mut passes) = (0, 0);
    for seed in 0..120u64 {
        let task = ["ssm", "handover", "feeding"][seed as usize % 3];
        let contact = contacts[(seed / 3) as usize % 3];
        let fast = run(seed, task, contact, true);
        let slow = run(seed, task, contact, false);
        let ctx = format!("seed {seed}, {task}, {contact:?}");
        assert_eq!(fast.verdict, slow.verdict, "{ctx}");
        assert_eq!(
            fast.metrics.violating_samples, slow.metrics.violating_samples,
            "{ctx}"
        );
        assert_eq!(
            fast.metrics.certain_violating_samples, slow.metrics.certain_violating_samples,
            "{ctx}"
        );
        let key = |r: &RunResult| serde_json::to_string(&(&r.violations, &r.inconclusive)).unwrap();
        assert_eq!(key(&fast), key(&slow), "{ctx}");
        match fast.verdict {
            pacs_audit::Verdict::Fail => fails += 1,
            pacs_audit::Verdict::Pass => passes += 1,
            _ => {}
        }
    }
    // The cases cover both outcomes (a comparison of only clean or only violating logs would
    // not exercise the split).
    eprintln!("{fails} fail, {passes} pass of 120");
    assert!(fails >= 20 && passes >= 20, "{fails} fail, {passes} pass");
}
