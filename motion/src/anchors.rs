//! The deterministic FR3 chunk problem set of the trajectory anchors (benchmarks, docs, tests):
//! q0 uniform in [q_min + 0.6, q_max − 0.6] at rest; H = 16 delta actions with
//! d ← 0.8·d + 0.2·N(0, I) (d starts at N(0, I)), action = step·d, step ~ U(0.005, 0.04) per chunk.

use crate::chunk::{ActionKind, Chunk};
use pacs_models::JointLimits;

/// A small deterministic generator (SplitMix64) with uniform and normal draws.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// Seeded generator.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform(f64::MIN_POSITIVE, 1.0);
        let u2 = self.uniform(0.0, 1.0);
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// One problem: start configuration (at rest) and a chunk.
#[derive(Debug, Clone)]
pub struct Problem {
    /// Start configuration (rad).
    pub q0: Vec<f64>,
    /// The chunk (H = 16 delta actions, h executed).
    pub chunk: Chunk,
}

/// `count` problems with seed `seed`; h alternates between 8 (even index) and 6 (odd index).
pub fn anchor_set(limits: &JointLimits, count: usize, seed: u64) -> Vec<Problem> {
    let n = limits.dof();
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|c| {
            let q0: Vec<f64> = (0..n)
                .map(|i| rng.uniform(limits.q_min()[i] + 0.6, limits.q_max()[i] - 0.6))
                .collect();
            let step = rng.uniform(0.005, 0.04);
            let mut d: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
            let actions = (0..16)
                .map(|_| {
                    for x in d.iter_mut() {
                        *x = 0.8 * *x + 0.2 * rng.normal();
                    }
                    d.iter().map(|x| step * x).collect()
                })
                .collect();
            Problem {
                q0,
                chunk: Chunk {
                    kind: ActionKind::Delta,
                    actions,
                    execute: if c % 2 == 0 { 8 } else { 6 },
                    gripper: None,
                },
            }
        })
        .collect()
}

/// Lower bound on any trajectory through the waypoints: Σ_k max_i |Δq̂_ki| / v_max,i (s).
pub fn lower_bound(wp: &crate::chunk::Waypoints, v_max: &[f64]) -> f64 {
    (1..=wp.segments())
        .map(|k| {
            (0..wp.dof())
                .map(|i| (wp.row(k)[i] - wp.row(k - 1)[i]).abs() / v_max[i])
                .fold(0.0, f64::max)
        })
        .sum()
}
