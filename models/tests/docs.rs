//! Every fenced example in docs/models.md parses and validates (and JSON/TOML twins agree).

use pacs_models::constraints::ConstraintSpec;
use pacs_models::urdf::{SideFile, load_urdf};
use pacs_models::{HumanModel, RobotModel, default_human};

/// (info string, body) of every fenced block.
fn blocks() -> Vec<(String, String)> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/models.md");
    let text = std::fs::read_to_string(&path).expect("docs/models.md");
    let mut out = Vec::new();
    let mut cur: Option<(String, String)> = None;
    for line in text.lines() {
        if let Some(info) = line.strip_prefix("```") {
            match cur.take() {
                None => cur = Some((info.trim().to_string(), String::new())),
                Some(b) => out.push(b),
            }
        } else if let Some((_, body)) = cur.as_mut() {
            body.push_str(line);
            body.push('\n');
        }
    }
    assert!(cur.is_none(), "unterminated code block");
    out
}

fn of(kind: &str) -> Vec<String> {
    blocks()
        .into_iter()
        .filter(|(i, _)| i.ends_with(kind))
        .map(|(_, b)| b)
        .collect()
}

#[test]
fn robot_examples() {
    let b = of(" robot");
    assert_eq!(b.len(), 2);
    let t = RobotModel::from_toml(&b[0]).unwrap();
    let j = RobotModel::from_json(&b[1]).unwrap();
    assert_eq!(t, j);
    assert_eq!(t.dof(), 1);
}

#[test]
fn urdf_and_side_examples() {
    let u = of(" urdf");
    let s = of(" side");
    assert_eq!((u.len(), s.len()), (1, 2));
    let (st, sj) = (
        SideFile::parse(&s[0]).unwrap(),
        SideFile::parse(&s[1]).unwrap(),
    );
    assert_eq!(st, sj);
    let r = load_urdf(&u[0], &st).unwrap();
    assert_eq!(r.dof(), 2);
    assert_eq!(r.limits().j_max(), &[100.0, 50.0]);
    assert_eq!(
        r.capsule_count(),
        2,
        "cylinder of `upper` + side capsule of `fore` (its mesh replaced by the side file)"
    );
}

#[test]
fn human_examples() {
    let b = of(" human");
    assert_eq!(b.len(), 2);
    let t = HumanModel::from_toml(&b[0]).unwrap();
    let j = HumanModel::from_json(&b[1]).unwrap();
    assert_eq!(t.keypoint_count(), 3);
    assert_eq!(j.extremities().len(), 1);
    assert!(t.clampable(2, 1) && t.clampable(1, 2));
}

#[test]
fn constraint_examples() {
    let b = of(" constraints");
    assert_eq!(b.len(), 2);
    let t: ConstraintSpec = pacs_models::parse_json_or_toml(&b[0]).unwrap();
    let j: ConstraintSpec = pacs_models::parse_json_or_toml(&b[1]).unwrap();
    assert_eq!(t, j);
    let r = t.resolve(&default_human()).unwrap();
    let h = default_human().body_part_index("rHand").unwrap();
    assert_eq!(r.per_part[h].threshold(true), 0.014);
}
