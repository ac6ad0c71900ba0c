//! Loading robots from URDF plus a side file (TOML/JSON) with capsules and acceleration/jerk limits.
//!
//! The URDF gives the kinematic tree, position and velocity limits and inertials; the side file
//! ([`SideFile`]) picks the chain tip, gives what URDF lacks (acceleration and jerk limits,
//! collision capsules for mesh-only links, limits of continuous joints) and may override any limit,
//! capsule list or inertial. The format and every rule below are documented in `docs/models.md`.
//!
//! Rules:
//! - the chain runs from the URDF root link (the one link that is no joint's child) to the tip link
//!   (side file `tip`; default: the single leaf link, an error if there are several);
//! - revolute and continuous joints on that path become chain joints; fixed joints on it are merged
//!   (their child links become [`LinkSpec`]s carried by the last chain joint, or `"base"`);
//!   prismatic, floating, planar and spherical joints and `<mimic>` joints on it are rejected;
//! - joints off the path (gripper fingers, links beyond the tip) are frozen: fixed joints as they
//!   are, revolute/continuous/prismatic joints at `frozen_at` from the side file, default 0 clamped
//!   into their URDF position limits (so a Franka gripper is "closed"); their links keep their
//!   capsules and mass. Floating/planar/spherical joints off the path are rejected;
//! - capsules: a side-file `[links.NAME] capsules = [...]` list (link frame) replaces everything the
//!   URDF says about that link's collision geometry; otherwise URDF `<collision>` primitives are
//!   converted into capsules that contain them (sphere → ball; cylinder and URDF 1.2 capsule of
//!   length L, radius r → segment ±L/2 on the local z axis with radius r; box → segment along its
//!   longest edge with radius = half the diagonal of the other two edges); a link with a mesh
//!   collision and no side-file capsules is refused ([`ModelError::MeshCollision`]: a mesh cannot
//!   be bounded here, and dropping it would make SSM and PFL checks vacuous for that body);
//! - inertials: URDF `<inertial>` with its origin applied (centre of mass = origin xyz, inertia
//!   rotated into the link frame by the origin rpy); an all-zero `<inertial>` or none means
//!   massless; a side-file `inertial` (link frame) replaces the URDF one;
//! - limits: position and velocity from URDF `<limit>`, acceleration (min of URDF 1.2
//!   acceleration and deceleration) and jerk from URDF 1.2 if present; side-file values override:
//!   per-joint `[joints.NAME]` first, then the uniform `a_max` / `j_max`. A missing value is an error.
//!
//! [`LinkSpec`]: crate::robot::LinkSpec

mod gaps;
mod joints;
pub(crate) mod links;
mod pose;
mod side_file;
mod tree;

pub use gaps::{SideFileGap, side_file_gaps};
pub use links::collision_capsules;
pub use pose::rpy_of;
pub use side_file::{JointOverride, LinkOverride, SideFile};

use crate::error::ModelError;
use crate::robot::{RobotModel, RobotSpec};
use std::path::Path;
use tree::Tree;

/// Load a robot from URDF text and a side file, and validate it with [`RobotModel::new`].
/// Validation errors name the spec field and, in brackets, the URDF joint or link.
pub fn load_urdf(urdf_text: &str, side: &SideFile) -> Result<RobotModel, ModelError> {
    let spec = urdf_to_spec(urdf_text, side)?;
    RobotModel::new(spec.clone()).map_err(|e| with_names(e, &spec))
}

/// Load a robot from a URDF file and an optional side file (JSON or TOML).
pub fn load_urdf_files(
    urdf_path: &Path,
    side_path: Option<&Path>,
) -> Result<RobotModel, ModelError> {
    let read = |p: &Path| {
        std::fs::read_to_string(p)
            .map_err(|e| ModelError::Invalid(format!("cannot read `{}`: {e}", p.display())))
    };
    let urdf = read(urdf_path)?;
    let side = match side_path {
        Some(p) => SideFile::parse(&read(p)?)?,
        None => SideFile::default(),
    };
    load_urdf(&urdf, &side)
}

/// Convert URDF text plus a side file into a (not yet validated) [`RobotSpec`].
pub fn urdf_to_spec(urdf_text: &str, side: &SideFile) -> Result<RobotSpec, ModelError> {
    let robot = parse_urdf(urdf_text)?;
    Tree::new(&robot, side)?.to_spec(side)
}

/// Parse URDF text; a parser error gets the line of the first unbalanced element where the
/// XML is not well formed (the parser says only `No elements found` for a truncated file).
pub(crate) fn parse_urdf(urdf_text: &str) -> Result<urdf_rs::Robot, ModelError> {
    urdf_rs::read_from_string(urdf_text).map_err(|e| ModelError::Parse {
        format: "URDF",
        message: match xml_balance(urdf_text) {
            Some(where_) => format!("{e}: {where_}"),
            None => e.to_string(),
        },
    })
}

/// Where the elements of an XML text stop balancing: a closing tag that closes another element,
/// or elements still open where the text ends (a truncated file). `None` if they balance.
fn xml_balance(text: &str) -> Option<String> {
    let mut open: Vec<(String, usize)> = Vec::new();
    let line_at = |i: usize| 1 + text[..i].matches('\n').count();
    let mut i = 0;
    while let Some(k) = text[i..].find('<') {
        let start = i + k;
        let rest = &text[start..];
        let skip = |end: &str| rest.find(end).map(|e| start + e + end.len());
        let next = if rest.starts_with("<!--") {
            skip("-->")
        } else if rest.starts_with("<?") {
            skip("?>")
        } else if rest.starts_with("<![CDATA[") {
            skip("]]>")
        } else {
            // A tag: find its end outside quoted attribute values.
            let mut quote = None;
            let end = rest.char_indices().skip(1).find_map(|(j, c)| {
                match (quote, c) {
                    (None, '"' | '\'') => quote = Some(c),
                    (Some(q), c) if c == q => quote = None,
                    (None, '>') => return Some(j),
                    _ => {}
                }
                None
            });
            end.map(|end| {
                let tag = &rest[1..end];
                let name: String = tag
                    .trim_start_matches('/')
                    .chars()
                    .take_while(|c| !c.is_whitespace() && *c != '/')
                    .collect();
                if tag.starts_with('/') {
                    match open.pop() {
                        Some((o, _)) if o == name => {}
                        Some((o, l)) => {
                            return Err(format!(
                                "line {}: `</{name}>` closes `<{o}>` opened at line {l}",
                                line_at(start)
                            ));
                        }
                        None => {
                            return Err(format!(
                                "line {}: `</{name}>` closes no open element",
                                line_at(start)
                            ));
                        }
                    }
                } else if !tag.starts_with('!') && !tag.ends_with('/') {
                    open.push((name, line_at(start)));
                }
                Ok(start + end + 1)
            })
            .transpose()
            .unwrap_or_else(|e| {
                open.clear();
                open.push((e, 0));
                None
            })
        };
        match next {
            Some(n) => i = n,
            None => break,
        }
    }
    let lines = text.lines().count();
    match open.as_slice() {
        [] => None,
        [(msg, 0)] => Some(msg.clone()),
        [.., (name, l)] => Some(format!(
            "`<{name}>` opened at line {l} is not closed where the text ends (line {lines}): is the file truncated?"
        )),
    }
}

/// Add the URDF joint/link name to a validation error's `joints[i]` / `links[i]` field.
fn with_names(e: ModelError, spec: &RobotSpec) -> ModelError {
    let rename = |field: String| -> String {
        for (prefix, names) in [
            (
                "joints[",
                spec.joints
                    .iter()
                    .map(|j| j.name.as_str())
                    .collect::<Vec<_>>(),
            ),
            (
                "links[",
                spec.links
                    .iter()
                    .map(|l| l.name.as_str())
                    .collect::<Vec<_>>(),
            ),
        ] {
            if let Some(rest) = field.strip_prefix(prefix)
                && let Some(end) = rest.find(']')
                && let Ok(i) = rest[..end].parse::<usize>()
                && let Some(name) = names.get(i)
            {
                return format!("{prefix}{i}]{{{name}}}{}", &rest[end + 1..]);
            }
        }
        field
    };
    match e {
        ModelError::InvalidValue {
            field,
            value,
            reason,
        } => ModelError::InvalidValue {
            field: rename(field),
            value,
            reason,
        },
        ModelError::UnknownName { kind, name, field } => ModelError::UnknownName {
            kind,
            name,
            field: rename(field),
        },
        ModelError::LengthMismatch {
            field,
            expected,
            found,
        } => ModelError::LengthMismatch {
            field: rename(field),
            expected,
            found,
        },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_fields_get_urdf_names() {
        let spec = crate::fr3::fr3().spec().clone();
        let e = ModelError::InvalidValue {
            field: "joints[2].limits.v_max".into(),
            value: -1.0,
            reason: "x",
        };
        match with_names(e, &spec) {
            ModelError::InvalidValue { field, .. } => {
                assert_eq!(field, "joints[2]{fr3_joint3}.limits.v_max")
            }
            other => panic!("{other:?}"),
        }
    }
}
