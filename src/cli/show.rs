//! `pacs robot show`, `pacs human show` and `pacs object show`: built-in models as JSON.

use super::CliError;
use pacs_models::RobotSpec;
use serde_json::Value;
use std::path::Path;

/// Print a robot's spec: a built-in by name, or a URDF converted with its side file; with both,
/// the URDF's differences from the built-in go to stderr.
pub fn robot(
    name: Option<&str>,
    urdf: Option<&Path>,
    side: Option<&Path>,
) -> Result<Value, CliError> {
    let m = match (name, urdf) {
        (None, None) => {
            return Err(CliError::Input(
                "robot show: give a built-in name (fr3) or --urdf FILE [--side FILE]".into(),
            ));
        }
        (Some(n), None) => pacs_models::RobotModel::builtin(n)?,
        (_, Some(u)) => {
            let m = pacs_models::urdf::load_urdf_files(u, side)?;
            if let Some(n) = name {
                let b = pacs_models::RobotModel::builtin(n)?;
                let diffs = differences(b.spec(), m.spec());
                if diffs.is_empty() {
                    eprintln!(
                        "{}: the same joint limits as the built-in `{n}`",
                        u.display()
                    );
                } else {
                    eprintln!(
                        "{} differs from the built-in `{n}` ({} differences):",
                        u.display(),
                        diffs.len()
                    );
                    for d in &diffs {
                        eprintln!("  {d}");
                    }
                }
            }
            m
        }
    };
    serde_json::to_value(m.spec()).map_err(|e| CliError::Internal(e.to_string()))
}

/// Where a URDF model differs from a built-in: joint count, joint limits, link count (relative
/// differences above 1e-9).
pub fn differences(builtin: &RobotSpec, urdf: &RobotSpec) -> Vec<String> {
    let mut out = Vec::new();
    if builtin.joints.len() != urdf.joints.len() {
        out.push(format!(
            "joints: {} in the URDF, {} in the built-in",
            urdf.joints.len(),
            builtin.joints.len()
        ));
    }
    for (i, (b, u)) in builtin.joints.iter().zip(&urdf.joints).enumerate() {
        let (bl, ul) = (&b.limits, &u.limits);
        for (what, x, y, unit) in [
            ("q_min", ul.q_min, bl.q_min, "rad"),
            ("q_max", ul.q_max, bl.q_max, "rad"),
            ("v_max", ul.v_max, bl.v_max, "rad/s"),
            ("a_max", ul.a_max, bl.a_max, "rad/s²"),
            ("j_max", ul.j_max, bl.j_max, "rad/s³"),
        ] {
            if (x - y).abs() > 1e-9 * x.abs().max(y.abs()).max(1.0) {
                out.push(format!(
                    "joints[{i}] ({}).{what}: {x} {unit} in the URDF, {y} {unit} in the built-in",
                    u.name
                ));
            }
        }
    }
    let moving = |s: &RobotSpec| s.links.iter().filter(|l| !l.capsules.is_empty()).count();
    if moving(builtin) != moving(urdf) {
        out.push(format!(
            "links with capsules: {} in the URDF, {} in the built-in",
            moving(urdf),
            moving(builtin)
        ));
    }
    out
}

/// Print a built-in human model's spec.
pub fn human(name: &str) -> Result<Value, CliError> {
    let m = pacs_models::HumanModel::builtin(name)?;
    serde_json::to_value(m.spec()).map_err(|e| CliError::Internal(e.to_string()))
}

/// Print a built-in object's spec.
pub fn object(name: &str) -> Result<Value, CliError> {
    let spec = pacs_models::object::builtin_object(name).ok_or_else(|| {
        CliError::Input(format!(
            "unknown built-in object `{name}` (built-in: {})",
            pacs_models::object::BUILTIN_OBJECTS.join(", ")
        ))
    })?;
    serde_json::to_value(spec).map_err(|e| CliError::Internal(e.to_string()))
}
