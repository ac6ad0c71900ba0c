//! The built-in Franka FR3 model.
//!
//! Kinematics, limits and inertials: franka_description (robots/fr3, franka_hand) and libfranka
//! rate limits, as gathered in `shared/reference/robot-and-human-facts.md` §1–3. Collision capsules:
//! franka_description's self-collision capsules with their 0.03 m safety distance included (§4b).
//! The two gripper fingers are lumped into one rigid body at the closed position (fingers' total
//! mass 0.058 kg); the gripper opening is not a joint of this model.

use crate::robot::{
    InertialSpec, JointLimitSpec, JointSpec, LinkSpec, PoseSpec, RobotModel, RobotSpec,
};
use crate::shape::CapsuleSpec;
use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2, FRAC_PI_4};

const Q_MIN: [f64; 7] = [-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159];
const Q_MAX: [f64; 7] = [2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159];
const V_MAX: [f64; 7] = [2.62, 2.62, 2.62, 2.62, 5.26, 4.18, 5.26];
/// libfranka kMaxJointAcceleration (rad/s²).
const A_MAX: f64 = 10.0;
/// libfranka kMaxJointJerk (rad/s³).
const J_MAX: f64 = 5000.0;

/// Joint origins (xyz, rpy) from franka_description kinematics.yaml.
const ORIGINS: [([f64; 3], [f64; 3]); 7] = [
    ([0.0, 0.0, 0.333], [0.0, 0.0, 0.0]),
    ([0.0, 0.0, 0.0], [-FRAC_PI_2, 0.0, 0.0]),
    ([0.0, -0.316, 0.0], [FRAC_PI_2, 0.0, 0.0]),
    ([0.0825, 0.0, 0.0], [FRAC_PI_2, 0.0, 0.0]),
    ([-0.0825, 0.384, 0.0], [-FRAC_PI_2, 0.0, 0.0]),
    ([0.0, 0.0, 0.0], [FRAC_PI_2, 0.0, 0.0]),
    ([0.088, 0.0, 0.0], [FRAC_PI_2, 0.0, 0.0]),
];

/// (mass, com, [ixx, ixy, ixz, iyy, iyz, izz]) of link0..link7.
const INERTIALS: [(f64, [f64; 3], [f64; 6]); 8] = [
    (
        2.3966,
        [-0.0172, 0.0004, 0.0745],
        [0.009, 0.0, 0.002, 0.0115, 0.0, 0.0085],
    ),
    (
        2.9274653454,
        [0.0000004128, -0.0181251324, -0.0386035970],
        [
            0.0239273,
            1.33179e-05,
            -0.000114048,
            0.0224822,
            -0.00199503,
            0.0063501,
        ],
    ),
    (
        2.9355370338,
        [0.0031828864, -0.0743221644, 0.0088146084],
        [
            0.0419389,
            0.000202573,
            0.00407778,
            0.0251451,
            -0.00422522,
            0.0617021,
        ],
    ),
    (
        2.2449013699,
        [0.0407015686, -0.0048200565, -0.0289730823],
        [
            0.0241014,
            0.00240469,
            -0.00285627,
            0.0197405,
            -0.00210421,
            0.0190445,
        ],
    ),
    (
        2.6155955791,
        [-0.0459100965, 0.0630492960, -0.0085187868],
        [
            0.03453,
            0.0132255,
            0.0101514,
            0.0288816,
            -0.000976283,
            0.0412547,
        ],
    ),
    (
        2.3271207594,
        [-0.0016039605, 0.0292536262, -0.0972965990],
        [
            0.0516103,
            -0.00571517,
            -0.00356732,
            0.0478773,
            0.010674,
            0.0164236,
        ],
    ),
    (
        1.8170376524,
        [0.0597131221, -0.0410294666, -0.0101692726],
        [
            0.00541233,
            0.00619346,
            0.00142193,
            0.0140583,
            -0.00131408,
            0.0160808,
        ],
    ),
    (
        0.6271432862,
        [0.0045225817, 0.0086261921, -0.0161633251],
        [
            0.000210924,
            -2.4333e-05,
            4.56448e-05,
            0.000177186,
            8.74407e-05,
            5.99319e-05,
        ],
    ),
];

/// Self-collision capsules (link frame) with radius r₀ + 0.03 m safety distance.
fn capsules(link: usize) -> Vec<CapsuleSpec> {
    let c = |p1: [f64; 3], p2: [f64; 3], radius: f64| CapsuleSpec { p1, p2, radius };
    match link {
        0 => vec![c([-0.09, 0.0, 0.06], [-0.06, 0.0, 0.06], 0.09)],
        1 => vec![c([0.0, 0.0, -0.333], [0.0, 0.0, -0.05], 0.09)],
        2 => vec![c([0.0, 0.0, -0.06], [0.0, 0.0, 0.06], 0.09)],
        3 => vec![c([0.0, 0.0, -0.22], [0.0, 0.0, -0.07], 0.09)],
        4 => vec![c([0.0, 0.0, -0.06], [0.0, 0.0, 0.06], 0.09)],
        5 => vec![
            c([0.0, 0.0, -0.31], [0.0, 0.0, -0.21], 0.09),
            c([0.0, 0.08, -0.20], [0.0, 0.08, -0.06], 0.055),
        ],
        6 => vec![c([0.0, 0.0, -0.07], [0.0, 0.0, 0.01], 0.08)],
        7 => {
            // (b) is given in link7_sc = link7 rotated +π/4 about z: (0.055..0.065, 0, 0.082).
            // libm's sin/cos of FRAC_PI_4 (one ulp apart), without a libm call in model
            // construction (which a model checker could not evaluate).
            let (s, co) = (FRAC_1_SQRT_2.next_down(), FRAC_1_SQRT_2);
            let rot = |x: f64| [co * x, s * x, 0.082];
            vec![
                c([0.0, 0.0, -0.06], [0.0, 0.0, 0.08], 0.07),
                c(rot(0.055), rot(0.065), 0.06),
            ]
        }
        _ => vec![],
    }
}

/// The Franka Research 3 arm with the Franka Hand (7 revolute joints; links `link0`…`link7`, `hand`,
/// `fingers`).
pub fn fr3() -> RobotModel {
    let joints = (0..7)
        .map(|i| JointSpec {
            name: format!("fr3_joint{}", i + 1),
            origin: PoseSpec {
                xyz: ORIGINS[i].0,
                rpy: ORIGINS[i].1,
            },
            axis: [0.0, 0.0, 1.0],
            limits: JointLimitSpec {
                q_min: Q_MIN[i],
                q_max: Q_MAX[i],
                v_max: V_MAX[i],
                a_max: A_MAX,
                j_max: J_MAX,
            },
        })
        .collect();
    let mut links: Vec<LinkSpec> = (0..8)
        .map(|i| LinkSpec {
            name: format!("fr3_link{i}"),
            parent: if i == 0 {
                "base".into()
            } else {
                format!("fr3_joint{i}")
            },
            origin: PoseSpec::default(),
            capsules: capsules(i),
            inertial: Some(InertialSpec {
                mass: INERTIALS[i].0,
                com: INERTIALS[i].1,
                inertia: INERTIALS[i].2,
            }),
            frame: false,
        })
        .collect();
    // Flange (link8) is 0.107 m along z of link7; the hand is rotated −π/4 about z.
    let hand_origin = PoseSpec {
        xyz: [0.0, 0.0, 0.107],
        rpy: [0.0, 0.0, -FRAC_PI_4],
    };
    links.push(LinkSpec {
        name: "fr3_hand".into(),
        parent: "fr3_joint7".into(),
        origin: hand_origin,
        capsules: vec![
            CapsuleSpec {
                p1: [0.0, -0.05, 0.04],
                p2: [0.0, 0.05, 0.04],
                radius: 0.07,
            },
            CapsuleSpec {
                p1: [0.0, -0.05, 0.10],
                p2: [0.0, 0.05, 0.10],
                radius: 0.05,
            },
        ],
        inertial: Some(InertialSpec {
            mass: 0.6544,
            com: [-0.0000376, 0.0119128, 0.0207260],
            inertia: [0.00186, 0.0, 0.0, 0.0003, -2e-05, 0.00174],
        }),
        frame: false,
    });
    // Two fingers (0.0291 kg each) closed: combined CoM on the hand axis, parallel-axis terms added.
    let m_f = 0.0291;
    let d_y: f64 = 0.015285;
    let par = 2.0 * m_f * d_y * d_y;
    links.push(LinkSpec {
        name: "fr3_fingers".into(),
        parent: "fr3_joint7".into(),
        origin: hand_origin,
        capsules: vec![],
        inertial: Some(InertialSpec {
            mass: 2.0 * m_f,
            com: [0.0, 0.0, 0.0584 + 0.0219675],
            inertia: [
                2.0 * 8.49e-06 + par,
                0.0,
                0.0,
                2.0 * 8.53e-06,
                0.0,
                2.0 * 1.77e-06 + par,
            ],
        }),
        // Closed, the fingers lie inside the hand's capsules (z 0.058..0.103 m, |y| < 0.03 m
        // in the hand frame; the hand's second capsule reaches 0.05 m around z = 0.10 m).
        frame: true,
    });
    let spec = RobotSpec {
        name: "fr3".into(),
        base: PoseSpec::default(),
        joints,
        links,
        user_values: Vec::new(),
    };
    RobotModel::new(spec).expect("built-in FR3 model is valid")
}

/// FR3 "ready" configuration (rad): (0, −π/4, 0, −3π/4, 0, π/2, π/4).
pub const Q_READY: [f64; 7] = [
    0.0,
    -FRAC_PI_4,
    0.0,
    -3.0 * FRAC_PI_4,
    0.0,
    FRAC_PI_2,
    FRAC_PI_4,
];

/// Pose of the tool centre point (between the fingertips) in the frame of joint 7.
pub fn tcp_in_joint7() -> nalgebra::Isometry3<f64> {
    nalgebra::Isometry3::from_parts(
        nalgebra::Translation3::new(0.0, 0.0, 0.107 + 0.1034),
        nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, -FRAC_PI_4),
    )
}
