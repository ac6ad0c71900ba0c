//! Scripted human motions (ground truth) and the measurement model.

use pacs_models::HumanModel;
use pacs_reach::human::HumanMeasurement;

/// A ground-truth human motion: keypoint positions (m) at time t (s), in the model's order.
pub trait HumanScript: Send + Sync {
    /// Keypoints at time `t`.
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]>;
    /// Short description.
    fn name(&self) -> &str;
}

/// Default human standing with the torso at (x, y), the right hand at `hand`, the left arm down.
pub fn standing(x: f64, y: f64, hand: [f64; 3]) -> Vec<[f64; 3]> {
    let rs = [x, y - 0.2, 1.4];
    let elbow = [0.5 * (rs[0] + hand[0]), 0.5 * (rs[1] + hand[1]), 0.5 * (rs[2] + hand[2]) - 0.05];
    vec![
        [x, y + 0.2, 1.4],
        [x, y + 0.25, 1.15],
        [x, y + 0.25, 0.9],
        rs,
        elbow,
        hand,
        [x, y, 1.5],
        [x, y, 1.0],
        [x, y, 1.65],
    ]
}

/// Smooth step 0 → 1 over [a, b] (cubic ease; |slope| ≤ 1.5/(b − a)).
fn ease(t: f64, a: f64, b: f64) -> f64 {
    let u = ((t - a) / (b - a)).clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

fn lerp(a: [f64; 3], b: [f64; 3], w: f64) -> [f64; 3] {
    [a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])]
}

/// Handover: the person stands in front of the robot and holds the right hand at `offer`
/// from `t_offer` on (raising it over 1 s), swaying it by ±1 cm.
#[derive(Debug, Clone)]
pub struct Handover {
    /// Where the hand is offered (m).
    pub offer: [f64; 3],
    /// When the hand starts rising (s).
    pub t_offer: f64,
}

impl HumanScript for Handover {
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]> {
        let rest = [1.05, -0.25, 0.95];
        let w = ease(t, self.t_offer, self.t_offer + 1.0);
        let mut hand = lerp(rest, self.offer, w);
        hand[1] += 0.01 * w * (2.0 * t).sin();
        standing(1.15, 0.0, hand)
    }
    fn name(&self) -> &str {
        "handover"
    }
}

/// A person walks from 2.5 m toward the table in front of the robot, reaches across it toward
/// `reach`, and walks away again.
#[derive(Debug, Clone)]
pub struct WalkIn {
    /// Point the hand reaches for (m).
    pub reach: [f64; 3],
    /// Arrival, reach, and leave times (s).
    pub times: [f64; 3],
}

impl HumanScript for WalkIn {
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]> {
        let [t_arrive, t_reach, t_leave] = self.times;
        let walk_in = ease(t, 0.0, t_arrive);
        let walk_out = ease(t, t_leave + 1.0, t_leave + 2.5);
        let x = 2.5 - 1.3 * walk_in + 1.3 * walk_out;
        let arm = ease(t, t_reach, t_reach + 0.8) * (1.0 - ease(t, t_leave, t_leave + 0.8));
        let rest = [x - 0.05, -0.25, 0.95];
        standing(x, 0.0, lerp(rest, self.reach, arm))
    }
    fn name(&self) -> &str {
        "walk-in"
    }
}

/// Nobody near the robot (2.5 m away, still).
#[derive(Debug, Clone, Default)]
pub struct Absent;

impl HumanScript for Absent {
    fn keypoints(&self, _t: f64) -> Vec<[f64; 3]> {
        standing(2.5, 0.0, [2.45, -0.25, 0.95])
    }
    fn name(&self) -> &str {
        "absent"
    }
}

/// Deterministic xorshift generator for reproducible noise.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// Seeded generator (seed 0 is mapped to a fixed non-zero state).
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in the ball of radius `r`.
    pub fn in_ball(&mut self, r: f64) -> [f64; 3] {
        loop {
            let v = [2.0 * self.uniform() - 1.0, 2.0 * self.uniform() - 1.0, 2.0 * self.uniform() - 1.0];
            if v[0] * v[0] + v[1] * v[1] + v[2] * v[2] <= 1.0 {
                return [v[0] * r, v[1] * r, v[2] * r];
            }
        }
    }
}

/// A camera: measures the true keypoints at t − delay, adds noise within the model's position
/// error bound, stamps the measurement t; one measurement per `period` (s).
#[derive(Debug, Clone)]
pub struct Camera {
    /// Measurement period (s).
    pub period: f64,
    rng: Rng,
    next: f64,
}

impl Camera {
    /// A camera with the given period and noise seed.
    pub fn new(period: f64, seed: u64) -> Self {
        Self { period, rng: Rng::new(seed), next: 0.0 }
    }

    /// The measurement due at time `t`, if any.
    pub fn measure(&mut self, model: &HumanModel, script: &dyn HumanScript, t: f64) -> Option<HumanMeasurement> {
        if t + 1e-12 < self.next {
            return None;
        }
        self.next = t + self.period;
        let e = model.measurement_error_pos();
        let kp: Vec<[f64; 3]> = script
            .keypoints(t - model.delay())
            .into_iter()
            .map(|p| {
                let n = self.rng.in_ball(e);
                [p[0] + n[0], p[1] + n[1], p[2] + n[2]]
            })
            .collect();
        HumanMeasurement::new(model, t, &kp, None).ok()
    }
}
