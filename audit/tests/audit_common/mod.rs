//! Shared helpers of the audit tests: log construction through the public writer and an
//! independent exact geometry oracle (convex minimisation, not the code under test).
#![allow(dead_code)]

use nalgebra::{Point3, Vector3};
use pacs_audit::{AuditConfig, RunResult};
use pacs_log::{Header, LogWriter, ModelRef, jsonl::JsonlReader};
use pacs_models::{Capsule, HumanModel, RobotModel};

/// FR3 "ready" configuration (rad).
pub const Q_READY: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

/// Exact distance from point p to segment ab.
pub fn point_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let s = if l2 == 0.0 {
        0.0
    } else {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    };
    (p - (a + ab * s)).norm()
}

/// Exact distance between segments by ternary search over the first segment's parameter
/// (the distance to a segment is convex along a line).
pub fn segment_segment(
    a0: &Point3<f64>,
    a1: &Point3<f64>,
    b0: &Point3<f64>,
    b1: &Point3<f64>,
) -> f64 {
    let f = |s: f64| point_segment(&(a0 + (a1 - a0) * s), b0, b1);
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    f(0.5 * (lo + hi)).min(f(0.0)).min(f(1.0))
}

/// Signed distance between capsules (negative: overlap).
pub fn capsule_gap(a: &Capsule, b: &Capsule) -> f64 {
    segment_segment(&a.p1(), &a.p2(), &b.p1(), &b.p2()) - a.radius() - b.radius()
}

/// World capsules of the robot at q with their link names.
pub fn robot_capsules(robot: &RobotModel, q: &[f64]) -> Vec<(String, Capsule)> {
    robot
        .capsules_world(q)
        .into_iter()
        .map(|(l, c)| (robot.links()[l].name.clone(), c))
        .collect()
}

/// Body-part capsules of the human at the given keypoints.
pub fn human_capsules(human: &HumanModel, kp: &[[f64; 3]]) -> Vec<(String, Capsule)> {
    human
        .body_parts()
        .iter()
        .map(|b| {
            (
                b.name.clone(),
                Capsule::new(
                    Point3::from(kp[b.from]),
                    Point3::from(kp[b.to]),
                    b.thickness / 2.0,
                )
                .unwrap(),
            )
        })
        .collect()
}

/// Smallest exact signed distance between any robot capsule and any body part.
pub fn min_gap(robot: &RobotModel, q: &[f64], human: &HumanModel, kp: &[[f64; 3]]) -> f64 {
    let r = robot_capsules(robot, q);
    let h = human_capsules(human, kp);
    let mut m = f64::INFINITY;
    for (_, a) in &r {
        for (_, b) in &h {
            m = m.min(capsule_gap(a, b));
        }
    }
    m
}

/// A standing human: every keypoint near (x, y) (m).
pub fn standing(x: f64, y: f64) -> Vec<[f64; 3]> {
    vec![
        [x, y + 0.2, 1.4],
        [x, y + 0.25, 1.15],
        [x, y + 0.25, 0.9],
        [x, y - 0.2, 1.4],
        [x, y - 0.25, 1.15],
        [x, y - 0.25, 0.9],
        [x, y, 1.45],
        [x, y, 0.95],
        [x, y, 1.65],
    ]
}

/// Keypoint indices of the default human.
pub const L_HAND: usize = 2;
pub const R_HAND: usize = 5;
pub const R_FORE: usize = 4;
pub const L_FORE: usize = 1;

/// Log builder: header + records written through the public [`LogWriter`].
pub struct Log {
    pub w: LogWriter<Vec<u8>>,
}

impl Log {
    pub fn new(constraints: ModelRef<pacs_models::ConstraintSpec>) -> Self {
        Self::with_human(ModelRef::Name("default".into()), constraints)
    }
    pub fn with_human(
        human: ModelRef<pacs_models::HumanSpec>,
        constraints: ModelRef<pacs_models::ConstraintSpec>,
    ) -> Self {
        let mut w = LogWriter::new(Vec::new());
        let h = Header::new(ModelRef::Name("fr3".into()), human, constraints);
        w.write_header(&h).unwrap();
        Self { w }
    }
    pub fn robot(&mut self, t: f64, q: &[f64], dq: Option<&[f64]>) -> &mut Self {
        self.w.write_robot(t, q, dq).unwrap();
        self
    }
    pub fn human(&mut self, t: f64, kp: &[[f64; 3]]) -> &mut Self {
        self.w.write_human(t, t, kp).unwrap();
        self
    }
    pub fn text(self) -> String {
        String::from_utf8(self.w.finish().unwrap()).unwrap()
    }
}

/// Audit log text with a config.
pub fn run(text: &str, cfg: &AuditConfig) -> Result<RunResult, pacs_log::LogError> {
    let mut r = JsonlReader::new("test.jsonl", std::io::Cursor::new(text.as_bytes()))?;
    pacs_audit::audit_reader(&mut r, cfg)
}

pub fn ssm() -> ModelRef<pacs_models::ConstraintSpec> {
    ModelRef::Name("ssm".into())
}

/// A point moved from `c` by `d` along unit direction `u`.
pub fn offset(c: Point3<f64>, u: Vector3<f64>, d: f64) -> [f64; 3] {
    let p = c + u.normalize() * d;
    [p.x, p.y, p.z]
}

/// The built-in FR3.
pub fn fr3() -> RobotModel {
    RobotModel::builtin("fr3").unwrap()
}
pub fn human() -> HumanModel {
    HumanModel::builtin("default").unwrap()
}

/// Joint configuration with joint 1 at `a`.
pub fn q_at(a: f64) -> [f64; 7] {
    let mut q = Q_READY;
    q[0] = a;
    q
}

/// The world capsule of link `name` (first capsule) at q.
pub fn link_capsule(q: &[f64], name: &str) -> Capsule {
    robot_capsules(&fr3(), q)
        .into_iter()
        .find(|(n, _)| n == name)
        .unwrap()
        .1
}

/// Keypoints: the human standing far away, with the right hand moved to `hand`.
pub fn reaching(hand: [f64; 3]) -> Vec<[f64; 3]> {
    let mut kp = standing(2.5, 0.0);
    // The arm points away from the robot's base axis.
    let u = Vector3::new(hand[0], hand[1], 0.0).normalize();
    kp[R_HAND] = hand;
    kp[R_FORE] = offset(Point3::from(hand), u, 0.3);
    kp[3] = offset(Point3::from(hand), u, 0.6);
    kp
}

/// A right-hand position overlapping the `fr3_hand` capsule at q by `overlap` m, pushed away from
/// the robot base along the horizontal direction.
pub fn hand_contact(q: &[f64], overlap: f64) -> [f64; 3] {
    let c = link_capsule(q, "fr3_hand");
    let mid = nalgebra::center(&c.p1(), &c.p2());
    let u = Vector3::new(mid.x, mid.y, 0.0);
    let hand_r = human().body_parts()[5].thickness / 2.0;
    offset(mid, u, c.radius() + hand_r - overlap)
}
