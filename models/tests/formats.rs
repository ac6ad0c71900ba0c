//! JSON/TOML round trips of the built-in specs and the constraint presets.

use pacs_models::constraints::{Constraint, ConstraintSpec};
use pacs_models::fr3::fr3;
use pacs_models::human::HumanSpec;
use pacs_models::{HumanModel, ModelError, RobotModel, default_human, parse_json_or_toml};

#[test]
fn fr3_spec_round_trips_through_json_and_toml() {
    let model = fr3();
    let spec = model.spec();
    let json = serde_json::to_string(spec).unwrap();
    let back = RobotModel::from_json(&json).unwrap();
    assert_eq!(back.spec(), spec);
    assert_eq!(back, model);
    let toml_text = toml::to_string(spec).unwrap();
    let back = RobotModel::from_toml(&toml_text).unwrap();
    assert_eq!(back.spec(), spec);
    assert_eq!(back, model);
    // parse_json_or_toml dispatches on the first character.
    let s1: pacs_models::RobotSpec = parse_json_or_toml(&json).unwrap();
    let s2: pacs_models::RobotSpec = parse_json_or_toml(&toml_text).unwrap();
    assert_eq!(&s1, spec);
    assert_eq!(&s2, spec);
}

#[test]
fn default_human_round_trips_through_json_and_toml() {
    let h = default_human();
    let json = serde_json::to_string(h.spec()).unwrap();
    assert_eq!(HumanModel::from_json(&json).unwrap(), h);
    let toml_text = toml::to_string(h.spec()).unwrap();
    assert_eq!(HumanModel::from_toml(&toml_text).unwrap(), h);
}

#[test]
fn presets_round_trip_through_json_and_toml() {
    for name in ["ssm", "sorting", "handover", "feeding"] {
        let c = ConstraintSpec::builtin(name).unwrap();
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(
            serde_json::from_str::<ConstraintSpec>(&json).unwrap(),
            c,
            "{name} JSON"
        );
        let toml_text = toml::to_string(&c).unwrap();
        assert_eq!(
            toml::from_str::<ConstraintSpec>(&toml_text).unwrap(),
            c,
            "{name} TOML"
        );
    }
}

#[test]
fn unknown_fields_are_rejected() {
    let json = serde_json::to_string(fr3().spec())
        .unwrap()
        .replacen("\"name\"", "\"nmae\"", 1);
    assert!(matches!(
        RobotModel::from_json(&json),
        Err(ModelError::Parse { format: "JSON", .. })
    ));
    let mut v: serde_json::Value = serde_json::to_value(default_human().spec()).unwrap();
    v["speed"] = 2.0.into();
    assert!(matches!(
        HumanModel::from_json(&v.to_string()),
        Err(ModelError::Parse { format: "JSON", .. })
    ));
}

fn resolved(name: &str) -> Vec<Constraint> {
    ConstraintSpec::preset(name)
        .unwrap()
        .resolve(&default_human())
        .unwrap()
        .per_part
}

#[test]
fn presets_resolve_with_documented_thresholds() {
    let h = default_human();
    let idx = |n: &str| h.body_part_index(n).unwrap();
    // Sorting / SSM: every part SSM, threshold 0.
    for name in ["ssm", "sorting"] {
        let t = ConstraintSpec::preset(name).unwrap().resolve(&h).unwrap();
        assert!(t.is_ssm_only());
        assert_eq!(t.per_part.len(), 8);
    }
    // Handover: hands 0.265 J free / 0.014 J clamped; others SaRA link values.
    let p = resolved("handover");
    for hand in ["lHand", "rHand"] {
        assert_eq!(p[idx(hand)].threshold(false), 0.265);
        assert_eq!(p[idx(hand)].threshold(true), 0.014);
    }
    assert_eq!(
        p[idx("lUpperArm")],
        Constraint::Pfl {
            unconstrained: 1.5,
            constrained: 0.01
        }
    );
    assert_eq!(
        p[idx("rLowerArm")],
        Constraint::Pfl {
            unconstrained: 1.3,
            constrained: 0.01
        }
    );
    assert_eq!(
        p[idx("torso")],
        Constraint::Pfl {
            unconstrained: 1.6,
            constrained: 0.01
        }
    );
    assert_eq!(
        p[idx("head")],
        Constraint::Pfl {
            unconstrained: 0.11,
            constrained: 0.01
        }
    );
    // Feeding: head 0.001 J both; hands 0.49 / 0.01.
    let p = resolved("feeding");
    assert_eq!(p[idx("head")].threshold(false), 0.001);
    assert_eq!(p[idx("head")].threshold(true), 0.001);
    assert_eq!(
        p[idx("rHand")],
        Constraint::Pfl {
            unconstrained: 0.49,
            constrained: 0.01
        }
    );
    assert!(
        !resolved("feeding")
            .iter()
            .any(|c| matches!(c, Constraint::Ssm)),
        "every default-human part is in a region"
    );
    assert!(ConstraintSpec::preset("unknown").is_none());
}

#[test]
fn human_spec_minimal_toml_uses_defaults() {
    let text = r#"
        keypoints = ["wrist"]
        v_max = [2.0]
        a_max = [50.0]
        body_parts = [{ name = "hand", from = "wrist", to = "wrist", thickness = 0.2 }]
    "#;
    let h = HumanModel::from_toml(text).unwrap();
    let s: &HumanSpec = h.spec();
    assert_eq!(s.name, "custom");
    assert_eq!(
        (s.measurement_error_pos, s.measurement_error_vel, s.delay),
        (0.0, 0.0, 0.0)
    );
    assert!(!h.clampable(0, 0));
}
