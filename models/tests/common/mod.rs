//! Shared test helpers: a deterministic RNG, random configurations, data-file paths.
#![allow(dead_code)]

use pacs_models::RobotModel;
use std::path::PathBuf;

/// xorshift64* — deterministic, no dependencies.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.max(1))
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (x >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    /// A configuration uniformly inside the joint limits.
    pub fn config(&mut self, robot: &RobotModel) -> Vec<f64> {
        let l = robot.limits();
        (0..robot.dof())
            .map(|i| self.range(l.q_min()[i], l.q_max()[i]))
            .collect()
    }
    /// A velocity uniformly inside the velocity limits.
    pub fn velocity(&mut self, robot: &RobotModel) -> Vec<f64> {
        let l = robot.limits();
        (0..robot.dof())
            .map(|i| self.range(-l.v_max()[i], l.v_max()[i]))
            .collect()
    }
}

pub fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("data")
        .join(name)
}

pub fn read(name: &str) -> String {
    std::fs::read_to_string(data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// ½ q̇ᵀ M q̇.
pub fn quad(m: &nalgebra::DMatrix<f64>, dq: &[f64]) -> f64 {
    let v = nalgebra::DVector::from_column_slice(dq);
    0.5 * v.dot(&(m * &v))
}
