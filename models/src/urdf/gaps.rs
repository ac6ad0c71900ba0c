//! What a side file still lacks for its URDF to load: the keys, and why each is needed
//! (`pacs robot capsules` reports them after writing a side file).

use super::joints::{MISSING_LIMIT, limit_values};
use super::tree::Tree;
use super::{SideFile, load_urdf};
use crate::error::ModelError;
use serde::Serialize;
use urdf_rs::JointType;

/// A side-file key still missing, with the reason the loader needs it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SideFileGap {
    /// The key as written in a TOML side file: `tip`, `a_max`, `joints.NAME.q_min`,
    /// `links.NAME.capsules`.
    pub key: String,
    /// Why it is needed and what to give.
    pub why: String,
}

/// The keys `side` still lacks for [`load_urdf`] to accept the URDF `urdf_text` with it (empty:
/// it loads). Errors that no key of the side file would fix (an unparsable URDF, two root links,
/// an invalid value) are returned as `Err`.
pub fn side_file_gaps(urdf_text: &str, side: &SideFile) -> Result<Vec<SideFileGap>, ModelError> {
    let robot = super::parse_urdf(urdf_text)?;
    if side.tip.is_none() {
        let leaves: Vec<&str> = robot
            .links
            .iter()
            .filter(|l| !robot.joints.iter().any(|j| j.parent.link == l.name))
            .map(|l| l.name.as_str())
            .collect();
        if leaves.len() > 1 {
            // Without the tip the chain is unknown, and so are the joints that need limits.
            return Ok(vec![SideFileGap {
                key: "tip".into(),
                why: format!(
                    "the URDF has {} leaf links ({}): name the chain's last link (the flange or \
                     tool link); the joints' limits can be checked only once the chain is known",
                    leaves.len(),
                    leaves.join(", ")
                ),
            }]);
        }
    }
    let tree = Tree::new(&robot, side)?;
    let mut gaps = Vec::new();
    let mut no_limit: [Vec<&str>; 5] = Default::default();
    for j in tree.chain_joints() {
        if !matches!(j.joint_type, JointType::Revolute | JointType::Continuous) {
            continue; // refused by the loader below, with its own message
        }
        let ov = side.joints.get(&j.name).copied().unwrap_or_default();
        for (k, v) in limit_values(j, &ov, side).iter().enumerate() {
            if v.is_none() {
                no_limit[k].push(&j.name);
            }
        }
    }
    for (k, joints) in no_limit.iter().enumerate() {
        let (what, _) = MISSING_LIMIT[k];
        match k {
            // Position and velocity limits: per joint (they differ between joints).
            0..=2 => gaps.extend(joints.iter().map(|j| {
                SideFileGap {
                key: format!("joints.{j}.{what}"),
                why: match k {
                    0 | 1 => "continuous joint (or no <limit>): the URDF gives no finite position \
                              limit; give the range (rad) the controller enforces"
                        .into(),
                    _ => "the URDF's velocity limit is missing or not > 0; give the limit (rad/s)"
                        .into(),
                },
            }
            })),
            _ if !joints.is_empty() => {
                let (quantity, unit) = if k == 3 {
                    ("acceleration", "rad/s²")
                } else {
                    ("jerk", "rad/s³")
                };
                gaps.push(SideFileGap {
                    key: what.into(),
                    why: format!(
                        "no {quantity} limit for {} {}: URDF before 1.2 has none and robot \
                         vendors often publish none; give the limit ({unit}) your controller \
                         enforces, uniform `{what}` or per joint `[joints.NAME] {what}` — it is \
                         your assumption, not the vendor's",
                        if joints.len() == 1 { "joint" } else { "joints" },
                        joints.join(", ")
                    ),
                });
            }
            _ => {}
        }
    }
    if !gaps.is_empty() {
        return Ok(gaps);
    }
    match load_urdf(urdf_text, side) {
        Ok(_) => Ok(gaps),
        Err(ModelError::UncoveredLinks { links, .. }) => Ok(links
            .into_iter()
            .map(|(name, mass)| SideFileGap {
                key: format!("links.{name}.capsules"),
                why: format!(
                    "moving link with mass ({mass} kg) and no collision geometry in the URDF: \
                     give capsules (link frame, m), or `frame = true` if it has no body outside \
                     other links' capsules"
                ),
            })
            .collect()),
        Err(ModelError::MeshCollision { links }) => Ok(links
            .into_iter()
            .map(|name| SideFileGap {
                key: format!("links.{name}.capsules"),
                why: "mesh collision geometry without capsules (no mesh could be read for it)"
                    .into(),
            })
            .collect()),
        Err(e) => Err(e),
    }
}
