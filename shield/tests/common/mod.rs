//! Helpers shared by the shield's integration tests (`handover.rs`, `worker.rs`): a seeded
//! generator, random chunks, the scene's shield, and command comparisons.
#![allow(dead_code)] // each test binary uses its own subset

use pacs_models::{ConstraintSpec, HumanModel, default_human, fr3};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_shield::ChunkMotion;
use pacs_shield::shield::{Command, Shield, ShieldConfig};

pub const Q0: [f64; 7] = fr3::Q_READY;

/// A small deterministic generator (the cases are reproducible without a dependency).
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

pub fn random_chunk(rng: &mut Lcg) -> Chunk {
    let dir: Vec<f64> = (0..7).map(|_| 0.03 * (2.0 * rng.next() - 1.0)).collect();
    Chunk {
        kind: ActionKind::Delta,
        actions: (0..16)
            .map(|k| dir.iter().map(|d| d * (1.0 + 0.05 * k as f64)).collect())
            .collect(),
        execute: 8,
        gripper: None,
    }
}

pub fn human() -> HumanModel {
    default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap()
}

pub fn shield(motion: ChunkMotion) -> Shield {
    let mut cfg = ShieldConfig::default();
    motion.apply(&mut cfg);
    let spec = ConstraintSpec::builtin("sorting").unwrap();
    let mut sh = Shield::new(fr3::fr3(), Some((human(), &spec)), vec![], cfg).unwrap();
    sh.start(0.0, &Q0).unwrap();
    sh
}

pub fn same(a: &Command, b: &Command) -> bool {
    a.t == b.t
        && a.q() == b.q()
        && a.dq() == b.dq()
        && a.ddq() == b.ddq()
        && a.diag.verified == b.diag.verified
}

/// Consecutive commands cannot be farther apart than the robot's limits allow in one step.
pub fn assert_continuous(prev: &Command, cmd: &Command) {
    let lim = fr3::fr3().limits().clone();
    let dt = cmd.t - prev.t;
    for i in 0..7 {
        let dq = (cmd.state.q[i] - prev.state.q[i]).abs();
        assert!(
            dq <= lim.v_max()[i] * dt * (1.0 + 1e-9) + 1e-12,
            "joint {i} jumped {dq} rad in one step at t = {}",
            cmd.t
        );
        let dv = (cmd.state.dq[i] - prev.state.dq[i]).abs();
        assert!(
            dv <= lim.a_max()[i] * dt * (1.0 + 1e-9) + 1e-12,
            "joint {i} velocity jumped {dv} rad/s in one step at t = {}",
            cmd.t
        );
    }
}
