//! Validation errors name the field and the offending value.

use pacs_models::constraints::{Constraint, ConstraintSpec, RegionSpec};
use pacs_models::fr3::fr3;
use pacs_models::{HumanModel, ModelError, RobotModel, RobotSpec, default_human};

fn spec() -> RobotSpec {
    fr3().spec().clone()
}

#[track_caller]
fn invalid_value(r: Result<impl std::fmt::Debug, ModelError>, field: &str) -> f64 {
    match r {
        Err(ModelError::InvalidValue {
            field: f, value, ..
        }) => {
            assert_eq!(f, field);
            value
        }
        other => panic!("expected InvalidValue at {field}, got {other:?}"),
    }
}

#[test]
fn builtin_spec_is_valid() {
    assert!(RobotModel::new(spec()).is_ok());
}

#[test]
fn negative_v_max() {
    let mut s = spec();
    s.joints[2].limits.v_max = -1.0;
    assert_eq!(
        invalid_value(RobotModel::new(s), "joints[2].limits.v_max"),
        -1.0
    );
}

#[test]
fn zero_a_max_and_j_max() {
    let mut s = spec();
    s.joints[4].limits.a_max = 0.0;
    assert_eq!(
        invalid_value(RobotModel::new(s), "joints[4].limits.a_max"),
        0.0
    );
    let mut s = spec();
    s.joints[6].limits.j_max = f64::INFINITY;
    assert_eq!(
        invalid_value(RobotModel::new(s), "joints[6].limits.j_max"),
        f64::INFINITY
    );
}

#[test]
fn nan_q_min() {
    let mut s = spec();
    s.joints[0].limits.q_min = f64::NAN;
    assert!(invalid_value(RobotModel::new(s), "joints[0].limits.q_min").is_nan());
}

#[test]
fn q_min_above_q_max() {
    let mut s = spec();
    s.joints[1].limits.q_min = 1.0;
    s.joints[1].limits.q_max = 0.5;
    assert_eq!(
        invalid_value(RobotModel::new(s), "joints[1].limits.q_max"),
        0.5
    );
}

#[test]
fn zero_axis() {
    let mut s = spec();
    s.joints[3].axis = [0.0, 0.0, 0.0];
    assert_eq!(invalid_value(RobotModel::new(s), "joints[3].axis"), 0.0);
}

#[test]
fn non_finite_origin() {
    let mut s = spec();
    s.joints[5].origin.rpy[1] = f64::NAN;
    assert!(invalid_value(RobotModel::new(s), "joints[5].origin.rpy[1]").is_nan());
}

#[test]
fn non_psd_inertia() {
    let mut s = spec();
    s.links[2].inertial.as_mut().unwrap().inertia = [1.0, 0.0, 0.0, -0.5, 0.0, 1.0];
    let v = invalid_value(RobotModel::new(s), "links[2].inertial.inertia");
    assert_eq!(v, -0.5, "value = smallest eigenvalue");
    // Off-diagonal terms too large: eigenvalues of [[1,2],[2,1]] are 3 and −1.
    let mut s = spec();
    s.links[1].inertial.as_mut().unwrap().inertia = [1.0, 2.0, 0.0, 1.0, 0.0, 1.0];
    let v = invalid_value(RobotModel::new(s), "links[1].inertial.inertia");
    assert!((v + 1.0).abs() < 1e-12, "{v}");
}

#[test]
fn negative_mass_and_radius() {
    let mut s = spec();
    s.links[3].inertial.as_mut().unwrap().mass = -2.0;
    assert_eq!(
        invalid_value(RobotModel::new(s), "links[3].inertial.mass"),
        -2.0
    );
    let mut s = spec();
    s.links[5].capsules[1].radius = -0.01;
    assert_eq!(
        invalid_value(RobotModel::new(s), "links[5].capsules[1].radius"),
        -0.01
    );
}

#[test]
fn duplicate_names() {
    let mut s = spec();
    s.joints[1].name = s.joints[0].name.clone();
    assert_eq!(
        RobotModel::new(s).unwrap_err(),
        ModelError::DuplicateName {
            kind: "joint",
            name: "fr3_joint1".into()
        }
    );
    let mut s = spec();
    s.links[4].name = "fr3_link2".into();
    assert_eq!(
        RobotModel::new(s).unwrap_err(),
        ModelError::DuplicateName {
            kind: "link",
            name: "fr3_link2".into()
        }
    );
}

#[test]
fn unknown_parent() {
    let mut s = spec();
    s.links[3].parent = "elbow".into();
    assert_eq!(
        RobotModel::new(s).unwrap_err(),
        ModelError::UnknownName {
            kind: "joint",
            name: "elbow".into(),
            field: "links[3].parent".into()
        }
    );
}

#[test]
fn no_joints() {
    let mut s = spec();
    s.joints.clear();
    s.links.retain(|l| l.parent == "base");
    assert!(
        matches!(RobotModel::new(s), Err(ModelError::Invalid(m)) if m.contains("joint count 0"))
    );
}

#[test]
fn unknown_builtin_names() {
    assert!(
        matches!(RobotModel::builtin("ur5"), Err(ModelError::UnknownName { name, .. }) if name == "ur5")
    );
    assert!(
        matches!(HumanModel::builtin("x"), Err(ModelError::UnknownName { name, .. }) if name == "x")
    );
    assert!(
        matches!(ConstraintSpec::builtin("y"), Err(ModelError::UnknownName { name, .. }) if name == "y")
    );
}

#[test]
fn human_v_max_count_mismatch() {
    let mut s = default_human().spec().clone();
    s.v_max.pop();
    assert_eq!(
        HumanModel::new(s).unwrap_err(),
        ModelError::LengthMismatch {
            field: "v_max".into(),
            expected: 9,
            found: 8
        }
    );
}

#[test]
fn human_value_errors() {
    let mut s = default_human().spec().clone();
    s.a_max[6] = 0.0;
    assert_eq!(invalid_value(HumanModel::new(s), "a_max[6]"), 0.0);
    let mut s = default_human().spec().clone();
    s.delay = -0.01;
    assert_eq!(invalid_value(HumanModel::new(s), "delay"), -0.01);
    let mut s = default_human().spec().clone();
    s.body_parts[6].thickness = f64::NAN;
    assert!(invalid_value(HumanModel::new(s), "body_parts[6].thickness").is_nan());
    let mut s = default_human().spec().clone();
    s.keypoints[3] = "lShldr".into();
    assert_eq!(
        HumanModel::new(s).unwrap_err(),
        ModelError::DuplicateName {
            kind: "keypoint",
            name: "lShldr".into()
        }
    );
}

#[test]
fn unknown_keypoint_in_body_part() {
    let mut s = default_human().spec().clone();
    s.body_parts[4].to = "rWrist".into();
    assert_eq!(
        HumanModel::new(s).unwrap_err(),
        ModelError::UnknownName {
            kind: "keypoint",
            name: "rWrist".into(),
            field: "body_parts[4].to".into()
        }
    );
}

#[test]
fn unknown_body_part_in_extremity_and_clamping_pair() {
    let mut s = default_human().spec().clone();
    s.extremities[1].body_parts[2] = "rFinger".into();
    assert_eq!(
        HumanModel::new(s).unwrap_err(),
        ModelError::UnknownName {
            kind: "body part",
            name: "rFinger".into(),
            field: "extremities[1].body_parts[2]".into()
        }
    );
    let mut s = default_human().spec().clone();
    s.clamping_pairs[0][1] = "leg".into();
    assert_eq!(
        HumanModel::new(s).unwrap_err(),
        ModelError::UnknownName {
            kind: "body part",
            name: "leg".into(),
            field: "clamping_pairs[0][1]".into()
        }
    );
}

#[test]
fn unknown_body_part_in_region() {
    let mut c = ConstraintSpec::preset("handover").unwrap();
    c.regions[2].body_parts[1] = "rPalm".into();
    assert_eq!(
        c.resolve(&default_human()).unwrap_err(),
        ModelError::UnknownName {
            kind: "body part",
            name: "rPalm".into(),
            field: "regions[2].body_parts[1]".into()
        }
    );
}

#[test]
fn negative_threshold() {
    let mut c = ConstraintSpec::preset("feeding").unwrap();
    c.regions[4].constraint = Constraint::Pfl {
        unconstrained: 0.1,
        constrained: -0.001,
    };
    assert_eq!(
        invalid_value(
            c.resolve(&default_human()),
            "regions[4].constraint.constrained"
        ),
        -0.001
    );
    let c = ConstraintSpec {
        name: "x".into(),
        default: Constraint::Pfl {
            unconstrained: -1.0,
            constrained: 0.0,
        },
        regions: vec![],
    };
    assert_eq!(
        invalid_value(c.resolve(&default_human()), "default.unconstrained"),
        -1.0
    );
}

#[test]
fn body_part_in_two_regions() {
    let mut c = ConstraintSpec::preset("handover").unwrap();
    c.regions.push(RegionSpec {
        name: "again".into(),
        body_parts: vec!["torso".into()],
        constraint: Constraint::Ssm,
    });
    assert_eq!(
        c.resolve(&default_human()).unwrap_err(),
        ModelError::DuplicateName {
            kind: "body part in regions",
            name: "torso".into()
        }
    );
}

#[test]
fn huge_axis_whose_norm_overflows_is_rejected() {
    // |axis| overflows to +inf: normalising would give a NaN axis (and NaN FK) if accepted.
    let mut s = spec();
    s.joints[0].axis = [1e200, 1e200, 0.0];
    let v = invalid_value(RobotModel::new(s), "joints[0].axis");
    assert!(v.is_infinite());
}

/// A model that would make a PFL check vacuous is refused, naming the links.
#[test]
fn pfl_tasks_refuse_massless_moving_bodies() {
    use pacs_models::{ConstraintSpec, HumanModel, RobotModel};
    let human = HumanModel::builtin("default").unwrap();
    let pfl = ConstraintSpec::builtin("handover")
        .unwrap()
        .resolve(&human)
        .unwrap();
    let ssm = ConstraintSpec::builtin("ssm")
        .unwrap()
        .resolve(&human)
        .unwrap();
    let fr3 = RobotModel::builtin("fr3").unwrap();
    assert!(pfl.check_robot(&fr3).is_ok());
    let with = |edit: &dyn Fn(&mut pacs_models::RobotSpec)| {
        let mut spec = fr3.spec().clone();
        edit(&mut spec);
        RobotModel::new(spec).unwrap()
    };
    let link = |spec: &mut pacs_models::RobotSpec, name: &str| -> usize {
        spec.links.iter().position(|l| l.name == name).unwrap()
    };
    // A body with capsules and no inertial.
    let r = with(&|s| {
        let i = link(s, "fr3_link4");
        s.links[i].inertial = None;
    });
    let e = pfl.check_robot(&r).unwrap_err().to_string();
    assert!(
        e.contains("`fr3_link4`") && !e.contains("`fr3_link3`"),
        "{e}"
    );
    assert!(ssm.check_robot(&r).is_ok(), "SSM needs no masses");
    // Mass without inertia.
    let r = with(&|s| {
        let i = link(s, "fr3_link6");
        if let Some(inr) = s.links[i].inertial.as_mut() {
            inr.inertia = [0.0; 6];
        }
    });
    let e = pfl.check_robot(&r).unwrap_err().to_string();
    assert!(e.contains("`fr3_link6`"), "{e}");
    // A frame without capsules and without mass is not a body.
    let r = with(&|s| {
        let i = link(s, "fr3_fingers");
        s.links[i].inertial = None;
    });
    assert!(pfl.check_robot(&r).is_ok());
    // No moving mass at all: every moving link is named.
    let r = with(&|s| {
        for l in s.links.iter_mut() {
            l.inertial = None;
        }
    });
    let e = pfl.check_robot(&r).unwrap_err().to_string();
    assert!(
        e.contains("`fr3_fingers`") && e.contains("`fr3_link1`"),
        "{e}"
    );
    assert!(!e.contains("`fr3_link0`"), "the base does not move: {e}");
}

/// A finite but astronomical offset (a unit mistake, `1e300`) would overflow forward
/// kinematics and distances into `inf`/NaN (`pacs fk` printed `null`, the audit panicked or lost
/// its violations). The model is refused, naming the first offending field; the value is the
/// reach from the world origin up to it.
#[test]
fn astronomical_reach_is_refused_naming_the_field() {
    let mut s = spec();
    s.joints[1].origin.xyz = [1.7e308, 0.0, 0.0];
    s.joints[2].origin.xyz = [1.7e308, 0.0, 0.0];
    let e = RobotModel::new(s.clone()).unwrap_err();
    assert!(
        invalid_value(Err::<(), _>(e.clone()), "joints[1].origin.xyz") >= 1.7e308,
        "{e}"
    );
    assert!(
        e.to_string().starts_with(
            "invalid value for `joints[1].origin.xyz`: 170000000000000000000000000000"
        ) && e
            .to_string()
            .ends_with("(the robot's reach from the world origin must be at most 1e6 m)"),
        "{e}"
    );
    let mut s = spec();
    s.joints[3].origin.xyz = [0.0, 1e200, 0.0];
    invalid_value(RobotModel::new(s), "joints[3].origin.xyz");
    let mut s = spec();
    s.base.xyz = [0.0, 0.0, 2e6];
    assert_eq!(invalid_value(RobotModel::new(s), "base.xyz"), 2e6);
    let mut s = spec();
    s.links[5].capsules[1].radius = 1.7e308;
    invalid_value(RobotModel::new(s), "links[5].capsules[1]");
    let mut s = spec();
    s.links[4].origin.xyz = [3e6, 0.0, 0.0];
    invalid_value(RobotModel::new(s), "links[4].origin.xyz");
    let mut s = spec();
    let k = s.links.iter().position(|l| l.inertial.is_some()).unwrap();
    s.links[k].inertial.as_mut().unwrap().com = [0.0, 0.0, -1e7];
    invalid_value(RobotModel::new(s), &format!("links[{k}].inertial.com"));
    // Large but within the bound: accepted.
    let mut s = spec();
    s.base.xyz = [9e5, 0.0, 0.0];
    assert!(RobotModel::new(s).is_ok());
}

/// A moving link with mass and no capsules can never be found touching anyone: refused, naming
/// the link and its mass, unless marked `frame` (which then must have no capsules, and its centre
/// of mass must lie in a capsule of another link on its joint).
#[test]
fn moving_link_with_mass_and_no_capsules_is_refused_unless_a_frame() {
    for name in ["fr3_link4", "fr3_hand"] {
        let mut s = spec();
        let l = s.links.iter_mut().find(|l| l.name == name).unwrap();
        l.capsules.clear();
        let mass = l.inertial.unwrap().mass;
        match RobotModel::new(s.clone()) {
            Err(ModelError::UncoveredLinks { robot, links }) => {
                assert_eq!(robot, "fr3");
                assert_eq!(links, vec![(name.to_string(), mass)]);
            }
            other => panic!("{name}: {other:?}"),
        }
        // Marked `frame`, it is refused all the same: its centre of mass lies outside every
        // capsule of the other links on its joint (the mark's claim is false).
        s.links.iter_mut().find(|l| l.name == name).unwrap().frame = true;
        let e = RobotModel::new(s.clone()).unwrap_err().to_string();
        // (For the hand, the fingers' mark fails too: their mass lay in the hand's capsules.)
        assert!(
            e.contains("`frame: true`") && e.contains("outside every capsule"),
            "{name}: {e}"
        );
        if name != "fr3_link4" {
            continue;
        }
        // With its mass moved into a capsule of another link on the same joint, the mark holds.
        let frame_of = |s: &pacs_models::RobotSpec, n: &str| {
            s.links.iter().find(|l| l.name == n).unwrap().parent.clone()
        };
        let parent = frame_of(&s, name);
        let host = s
            .links
            .iter()
            .find(|l| l.name != name && l.parent == parent && !l.capsules.is_empty())
            .map(|l| (l.origin.xyz, l.origin.rpy, l.capsules[0]));
        let unrotated = |rpy: [f64; 3]| rpy == [0.0; 3];
        if let Some((origin, rpy, c)) = host
            && unrotated(rpy)
            && unrotated(s.links.iter().find(|l| l.name == name).unwrap().origin.rpy)
        {
            // The host's first capsule end, in the joint frame (link origins here have no rotation).
            let l = s.links.iter_mut().find(|l| l.name == name).unwrap();
            let at = [
                origin[0] + c.p1[0] - l.origin.xyz[0],
                origin[1] + c.p1[1] - l.origin.xyz[1],
                origin[2] + c.p1[2] - l.origin.xyz[2],
            ];
            l.inertial.as_mut().unwrap().com = at;
            assert!(
                RobotModel::new(s).is_ok(),
                "{name} marked as a frame, mass inside"
            );
        }
    }
    // The built-in's fingers are marked (inside the hand's capsules); unmarked they are refused.
    let mut s = spec();
    let f = s
        .links
        .iter_mut()
        .find(|l| l.name == "fr3_fingers")
        .unwrap();
    assert!(f.frame);
    f.frame = false;
    assert!(matches!(
        RobotModel::new(s),
        Err(ModelError::UncoveredLinks { links, .. }) if links[0].0 == "fr3_fingers"
    ));
    // The base link does not move: mass without capsules is accepted there.
    let mut s = spec();
    s.links[0].capsules.clear();
    assert_eq!(s.links[0].parent, "base");
    assert!(RobotModel::new(s).is_ok());
    // A massless link without capsules (a tool frame) is accepted.
    let mut s = spec();
    s.links[4].capsules.clear();
    s.links[4].inertial = None;
    assert!(RobotModel::new(s).is_ok());
    // `frame` with capsules is a contradiction.
    let mut s = spec();
    s.links[4].frame = true;
    match RobotModel::new(s) {
        Err(ModelError::Invalid(m)) => assert_eq!(
            m,
            "links[4] (`fr3_link4`): `frame: true` marks a link without capsules, but it has 1"
        ),
        other => panic!("{other:?}"),
    }
    // In a JSON model the mark is `"frame": true`, and the error is the same.
    let mut v = serde_json::to_value(spec()).unwrap();
    v["links"][4]["capsules"] = serde_json::json!([]);
    let e = RobotModel::from_json(&v.to_string())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("robot `fr3`: moving links with mass and no capsules: `fr3_link4` (2.6155955791 kg) (no contact"),
        "{e}"
    );
    // Marked, its mass still lies outside the other links' capsules: refused.
    v["links"][4]["frame"] = serde_json::json!(true);
    let e = RobotModel::from_json(&v.to_string())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "links[4] (`fr3_link4`): `frame: true` states that the link has no body outside"
        ),
        "{e}"
    );
}
