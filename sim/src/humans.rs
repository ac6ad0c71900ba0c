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
    let elbow = [
        0.5 * (rs[0] + hand[0]),
        0.5 * (rs[1] + hand[1]),
        0.5 * (rs[2] + hand[2]) - 0.05,
    ];
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
pub(crate) fn ease(t: f64, a: f64, b: f64) -> f64 {
    let u = ((t - a) / (b - a)).clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

pub(crate) fn lerp(a: [f64; 3], b: [f64; 3], w: f64) -> [f64; 3] {
    [
        a[0] + w * (b[0] - a[0]),
        a[1] + w * (b[1] - a[1]),
        a[2] + w * (b[2] - a[2]),
    ]
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
    /// Arrival, reach, and leave times (s): walks 1.3 m in from 2.5 m over `[0, arrive]`, moves
    /// the right hand to `reach` over `[reach, reach + 1.2]`, back over `[leave, leave + 1.2]`,
    /// and walks away over `[leave + 1.3, leave + 2.8]`. The default human model's speed limit
    /// holds with `arrive ≥ 1.5` s.
    pub times: [f64; 3],
}

impl HumanScript for WalkIn {
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]> {
        let [t_arrive, t_reach, t_leave] = self.times;
        let walk_in = ease(t, 0.0, t_arrive);
        let walk_out = ease(t, t_leave + 1.3, t_leave + 2.8);
        let x = 2.5 - 1.3 * walk_in + 1.3 * walk_out;
        // The hand travels up to ≈ 1.15 m (table height, across the table) in 1.2 s: at most
        // 1.5·1.15/1.2 ≈ 1.45 m/s at the ease's peak, within the default model's 2 m/s.
        let arm = ease(t, t_reach, t_reach + 1.2) * (1.0 - ease(t, t_leave, t_leave + 1.2));
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
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }
    /// Uniform in the ball of radius `r`.
    pub fn in_ball(&mut self, r: f64) -> [f64; 3] {
        loop {
            let v = [
                2.0 * self.uniform() - 1.0,
                2.0 * self.uniform() - 1.0,
                2.0 * self.uniform() - 1.0,
            ];
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
        Self {
            period,
            rng: Rng::new(seed),
            next: 0.0,
        }
    }

    /// The measurement due at time `t`, if any.
    pub fn measure(
        &mut self,
        model: &HumanModel,
        script: &dyn HumanScript,
        t: f64,
    ) -> Option<HumanMeasurement> {
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

/// Height (m) of the floor below the robot base in the task scenarios: the FR3 stands on a table
/// top at z = 0 and people stand (or sit) on the floor at z = `FLOOR_Z`.
pub const FLOOR_Z: f64 = -0.75;

/// [`standing`] with the floor at height `z0` (m): keypoints of a person with the torso at
/// (x, y), the right hand at `hand`, the left arm hanging.
pub fn standing_on(x: f64, y: f64, z0: f64, hand: [f64; 3]) -> Vec<[f64; 3]> {
    let mut kp = standing(x, y, [hand[0], hand[1], hand[2] - z0]);
    for p in &mut kp {
        p[2] += z0;
    }
    kp
}

/// Keypoints of a person seated on a chair at (x, y) facing the robot (−x), floor at `z0`, the
/// head at `head` (the torso leans with it), both hands in the lap.
pub fn seated(x: f64, y: f64, z0: f64, head: [f64; 3]) -> Vec<[f64; 3]> {
    let hip = [x + 0.05, y, z0 + 0.55];
    let neck = [0.35 * hip[0] + 0.65 * head[0], head[1], head[2] - 0.15];
    let lap = |s: f64| [x - 0.2, y + s * 0.15, z0 + 0.65];
    let shoulder = |s: f64| [neck[0], neck[1] + s * 0.2, neck[2] - 0.05];
    let elbow = |s: f64| [x - 0.02, y + s * 0.22, z0 + 0.75];
    vec![
        shoulder(1.0),
        elbow(1.0),
        lap(1.0),
        shoulder(-1.0),
        elbow(-1.0),
        lap(-1.0),
        neck,
        hip,
        head,
    ]
}

/// Sorting: a person walks up to the far side of the table, reaches for blocks at `reach` (m), and
/// walks away. Times (s): arrival, reach start, leave start.
#[derive(Debug, Clone)]
pub struct Reacher {
    /// Where the person stands (x, y) when at the table (m).
    pub stand: [f64; 2],
    /// Point the right hand reaches for (m).
    pub reach: [f64; 3],
    /// Arrival, reach start and leave start (s); walking takes `times[0]`, the reach 0.8 s.
    pub times: [f64; 3],
}

impl HumanScript for Reacher {
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]> {
        let [t_arrive, t_reach, t_leave] = self.times;
        let far = self.stand[0] + 1.3;
        let w = ease(t, 0.0, t_arrive) - ease(t, t_leave + 0.8, t_leave + 0.8 + t_arrive);
        let x = far + w * (self.stand[0] - far);
        let y = self.stand[1];
        // The hand travels up to ≈ 1.15 m (table height, across the table) in 1.2 s: at most
        // 1.5·1.15/1.2 ≈ 1.45 m/s at the ease's peak, within the default model's 2 m/s.
        let arm = ease(t, t_reach, t_reach + 1.2) * (1.0 - ease(t, t_leave, t_leave + 1.2));
        let rest = [x - 0.05, y - 0.25, FLOOR_Z + 0.95];
        standing_on(x, y, FLOOR_Z, lerp(rest, self.reach, arm))
    }
    fn name(&self) -> &str {
        "reacher"
    }
}

/// Handover: a person at the table raises the right hand holding a block to `offer` (m) from
/// `t_offer` on (over 1 s) and keeps it there, moving it slowly by up to `sway` (m).
#[derive(Debug, Clone)]
pub struct Offerer {
    /// Where the person stands (x, y) (m).
    pub stand: [f64; 2],
    /// Where the hand holds the block (m).
    pub offer: [f64; 3],
    /// When the hand starts rising (s).
    pub t_offer: f64,
    /// Amplitude of the slow hand motion (m).
    pub sway: f64,
}

impl HumanScript for Offerer {
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]> {
        let [x, y] = self.stand;
        let rest = [x - 0.05, y - 0.25, FLOOR_Z + 0.95];
        let w = ease(t, self.t_offer, self.t_offer + 1.0);
        let mut hand = lerp(rest, self.offer, w);
        hand[1] += self.sway * w * (0.8 * t).sin();
        hand[2] += 0.5 * self.sway * w * (1.3 * t).sin();
        standing_on(x, y, FLOOR_Z, hand)
    }
    fn name(&self) -> &str {
        "offerer"
    }
}

/// Feeding: a seated person holds the head at `head` (m) and leans forward by `lean` (m) toward
/// the fork from `t_lean` on (over 1 s), back after `t_back`.
#[derive(Debug, Clone)]
pub struct Diner {
    /// Chair position (x, y) (m).
    pub seat: [f64; 2],
    /// Head keypoint at rest (m).
    pub head: [f64; 3],
    /// Lean displacement of the head (m).
    pub lean: [f64; 3],
    /// Lean start and lean-back start (s).
    pub times: [f64; 2],
}

impl HumanScript for Diner {
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]> {
        let w = ease(t, self.times[0], self.times[0] + 1.0)
            * (1.0 - ease(t, self.times[1], self.times[1] + 1.0));
        let head = [
            self.head[0] + w * self.lean[0],
            self.head[1] + w * self.lean[1],
            self.head[2] + w * self.lean[2],
        ];
        seated(self.seat[0], self.seat[1], FLOOR_Z, head)
    }
    fn name(&self) -> &str {
        "diner"
    }
}

/// A person standing still on the floor at (x, y) (m), arms down: a bystander outside the
/// workspace in the tasks whose hazards are objects.
#[derive(Debug, Clone)]
pub struct Bystander {
    /// Torso position (x, y) (m).
    pub at: [f64; 2],
}

impl HumanScript for Bystander {
    fn keypoints(&self, _t: f64) -> Vec<[f64; 3]> {
        let [x, y] = self.at;
        standing_on(x, y, FLOOR_Z, [x - 0.05, y - 0.25, FLOOR_Z + 0.95])
    }
    fn name(&self) -> &str {
        "bystander"
    }
}
