//! The URDF link tree: its root, the chain from the root to the tip, and its walk into a
//! [`RobotSpec`] (chain joints, merged fixed joints, frozen off-chain joints, links).

use super::SideFile;
use super::joints::{chain_limits, frozen_motion};
use super::links::{collision_capsules, urdf_inertial};
use super::pose::{iso_to_pose, urdf_pose_iso};
use crate::error::ModelError;
use crate::robot::{JointSpec, LinkSpec, PoseSpec, RobotSpec};
use nalgebra::Isometry3;
use std::collections::HashMap;
use urdf_rs::JointType;

pub(super) struct Tree<'a> {
    robot: &'a urdf_rs::Robot,
    link_index: HashMap<&'a str, usize>,
    /// Joints whose parent is link i (URDF order).
    child_joints: Vec<Vec<usize>>,
    root: usize,
    /// Joints on the path root → tip.
    on_path: Vec<bool>,
}

impl<'a> Tree<'a> {
    pub(super) fn new(robot: &'a urdf_rs::Robot, side: &SideFile) -> Result<Self, ModelError> {
        let mut link_index = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if link_index.insert(l.name.as_str(), i).is_some() {
                return Err(ModelError::DuplicateName {
                    kind: "URDF link",
                    name: l.name.clone(),
                });
            }
        }
        if robot.links.is_empty() {
            return Err(ModelError::Invalid("URDF has no links".into()));
        }
        let mut joint_names = HashMap::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
        let mut child_joints = vec![Vec::new(); robot.links.len()];
        for (ji, j) in robot.joints.iter().enumerate() {
            if joint_names.insert(j.name.as_str(), ji).is_some() {
                return Err(ModelError::DuplicateName {
                    kind: "URDF joint",
                    name: j.name.clone(),
                });
            }
            let find = |name: &str, what: &str| {
                link_index
                    .get(name)
                    .copied()
                    .ok_or_else(|| ModelError::UnknownName {
                        kind: "link",
                        name: name.into(),
                        field: format!("joint `{}` {what}", j.name),
                    })
            };
            let p = find(&j.parent.link, "parent")?;
            let c = find(&j.child.link, "child")?;
            if let Some(other) = parent_joint[c] {
                return Err(ModelError::Invalid(format!(
                    "URDF link `{}` is the child of two joints (`{}` and `{}`)",
                    j.child.link, robot.joints[other].name, j.name
                )));
            }
            parent_joint[c] = Some(ji);
            child_joints[p].push(ji);
        }
        let roots: Vec<usize> = (0..robot.links.len())
            .filter(|&i| parent_joint[i].is_none())
            .collect();
        if roots.len() != 1 {
            let names: Vec<&str> = roots
                .iter()
                .map(|&i| robot.links[i].name.as_str())
                .collect();
            return Err(ModelError::Invalid(format!(
                "URDF must have exactly one root link (a link that is no joint's child); found {names:?}"
            )));
        }
        let root = roots[0];
        // Every link must hang below the root (rules out detached cycles).
        let mut seen = vec![false; robot.links.len()];
        let mut stack = vec![root];
        while let Some(l) = stack.pop() {
            seen[l] = true;
            stack.extend(
                child_joints[l]
                    .iter()
                    .map(|&j| link_index[robot.joints[j].child.link.as_str()]),
            );
        }
        if let Some(i) = seen.iter().position(|s| !s) {
            return Err(ModelError::Invalid(format!(
                "URDF link `{}` is not connected to the root link `{}`",
                robot.links[i].name, robot.links[root].name
            )));
        }
        for name in side.joints.keys() {
            if !joint_names.contains_key(name.as_str()) {
                return Err(ModelError::UnknownName {
                    kind: "URDF joint",
                    name: name.clone(),
                    field: "joints".into(),
                });
            }
        }
        for name in side.links.keys() {
            if !link_index.contains_key(name.as_str()) {
                return Err(ModelError::UnknownName {
                    kind: "URDF link",
                    name: name.clone(),
                    field: "links".into(),
                });
            }
        }
        let tip = match &side.tip {
            Some(t) => *link_index
                .get(t.as_str())
                .ok_or_else(|| ModelError::UnknownName {
                    kind: "URDF link",
                    name: t.clone(),
                    field: "tip".into(),
                })?,
            None => {
                let leaves: Vec<usize> = (0..robot.links.len())
                    .filter(|&i| child_joints[i].is_empty())
                    .collect();
                if leaves.len() != 1 {
                    let names: Vec<&str> = leaves
                        .iter()
                        .map(|&i| robot.links[i].name.as_str())
                        .collect();
                    return Err(ModelError::Invalid(format!(
                        "URDF has {} leaf links {names:?}; name the chain's last link with `tip` in the side file",
                        leaves.len()
                    )));
                }
                leaves[0]
            }
        };
        let mut on_path = vec![false; robot.joints.len()];
        let mut l = tip;
        while let Some(j) = parent_joint[l] {
            on_path[j] = true;
            l = link_index[robot.joints[j].parent.link.as_str()];
        }
        Ok(Self {
            robot,
            link_index,
            child_joints,
            root,
            on_path,
        })
    }

    /// The URDF joints on the chain from the root to the tip, root first.
    pub(super) fn chain_joints(&self) -> Vec<&'a urdf_rs::Joint> {
        let mut out = Vec::new();
        let mut stack = vec![self.root];
        while let Some(l) = stack.pop() {
            for &ji in &self.child_joints[l] {
                if self.on_path[ji] {
                    out.push(&self.robot.joints[ji]);
                    stack.push(self.link_index[self.robot.joints[ji].child.link.as_str()]);
                }
            }
        }
        out
    }

    pub(super) fn to_spec(&self, side: &SideFile) -> Result<RobotSpec, ModelError> {
        let robot = self.robot;
        let mut joints = Vec::new();
        let mut links = Vec::new();
        // (link, carrying frame name, pose of the link frame in the carrying frame; None = identity)
        let mut stack: Vec<(usize, String, Option<Isometry3<f64>>)> =
            vec![(self.root, "base".into(), None)];
        let mut mesh_links = Vec::new();
        while let Some((li, carrier, acc)) = stack.pop() {
            match self.link_spec(li, &carrier, acc, side) {
                Ok(l) => links.push(l),
                Err(ModelError::MeshCollision { links: l }) => mesh_links.extend(l),
                Err(e) => return Err(e),
            }
            // Push children in reverse so that they are visited in URDF order.
            for &ji in self.child_joints[li].iter().rev() {
                let j = &robot.joints[ji];
                let child = self.link_index[j.child.link.as_str()];
                let origin = urdf_pose_iso(&j.origin, || format!("joint `{}` origin", j.name))?;
                let to_joint = acc.map_or(origin, |a| a * origin);
                let ov = side.joints.get(&j.name).copied().unwrap_or_default();
                if self.on_path[ji] {
                    match j.joint_type {
                        JointType::Revolute | JointType::Continuous => {
                            if ov.frozen_at.is_some() {
                                return Err(ModelError::Invalid(format!(
                                    "side file `joints.{}.frozen_at`: joint is on the chain, only off-chain joints can be frozen",
                                    j.name
                                )));
                            }
                            if let Some(m) = &j.mimic {
                                return Err(ModelError::Invalid(format!(
                                    "URDF joint `{}` on the chain mimics `{}`; coupled (mimic) chain joints are not supported",
                                    j.name, m.joint
                                )));
                            }
                            let pose = match acc {
                                None => PoseSpec {
                                    xyz: *j.origin.xyz,
                                    rpy: *j.origin.rpy,
                                },
                                Some(_) => iso_to_pose(&to_joint),
                            };
                            joints.push(JointSpec {
                                name: j.name.clone(),
                                origin: pose,
                                axis: *j.axis.xyz,
                                limits: chain_limits(j, &ov, side)?,
                            });
                            stack.push((child, j.name.clone(), None));
                        }
                        JointType::Fixed => stack.push((child, carrier.clone(), Some(to_joint))),
                        ref t => {
                            return Err(ModelError::Invalid(format!(
                                "URDF joint `{}` of type {t:?} lies on the chain from `{}` to the tip; only revolute, \
                                 continuous and fixed joints are supported there",
                                j.name, robot.links[self.root].name
                            )));
                        }
                    }
                } else {
                    if ov.q_min.is_some()
                        || ov.q_max.is_some()
                        || ov.v_max.is_some()
                        || ov.a_max.is_some()
                        || ov.j_max.is_some()
                    {
                        return Err(ModelError::Invalid(format!(
                            "side file `joints.{}`: joint is not on the chain (it is frozen); only `frozen_at` applies",
                            j.name
                        )));
                    }
                    let motion = frozen_motion(j, ov.frozen_at)?;
                    stack.push((child, carrier.clone(), Some(to_joint * motion)));
                }
            }
        }
        if !mesh_links.is_empty() {
            return Err(ModelError::MeshCollision { links: mesh_links });
        }
        let user_values = self.user_values(side, &joints);
        Ok(RobotSpec {
            name: side.name.clone().unwrap_or_else(|| robot.name.clone()),
            base: side.base.unwrap_or_default(),
            joints,
            links,
            user_values,
        })
    }

    /// What the side file gave rather than the URDF, one line each (see
    /// [`RobotSpec::user_values`]); `joints` the chain joints with their resolved limits.
    fn user_values(&self, side: &SideFile, joints: &[JointSpec]) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(b) = &side.base {
            out.push(format!("base pose xyz {:?} m, rpy {:?} rad", b.xyz, b.rpy));
        }
        const UNITS: [&str; 5] = ["rad", "rad", "rad/s", "rad/s²", "rad/s³"];
        const NAMES: [&str; 5] = ["q_min", "q_max", "v_max", "a_max", "j_max"];
        // Uniform values: which chain joints took them.
        for (k, uniform) in [(3, side.a_max), (4, side.j_max)] {
            let Some(v) = uniform else { continue };
            let took: Vec<&str> = joints
                .iter()
                .filter(|j| {
                    let ov = side.joints.get(&j.name).copied().unwrap_or_default();
                    [ov.a_max, ov.j_max][k - 3].is_none()
                })
                .map(|j| j.name.as_str())
                .collect();
            if !took.is_empty() {
                let which = if took.len() == joints.len() {
                    "every joint".to_string()
                } else {
                    format!("joints {}", took.join(", "))
                };
                out.push(format!("{} = {v} {} for {which}", NAMES[k], UNITS[k]));
            }
        }
        for j in joints {
            let Some(ov) = side.joints.get(&j.name) else {
                continue;
            };
            for (k, v) in [ov.q_min, ov.q_max, ov.v_max, ov.a_max, ov.j_max]
                .into_iter()
                .enumerate()
            {
                if let Some(v) = v {
                    out.push(format!("joints.{}.{} = {v} {}", j.name, NAMES[k], UNITS[k]));
                }
            }
        }
        for (name, ov) in &side.joints {
            if let Some(x) = ov.frozen_at {
                out.push(format!(
                    "joints.{name}.frozen_at = {x} (joint frozen there)"
                ));
            }
        }
        for (name, l) in &side.links {
            if let Some(c) = &l.capsules {
                out.push(format!(
                    "links.{name}.capsules: {} capsule(s) from the side file (fitted to meshes or given), not the URDF's collision geometry",
                    c.len()
                ));
            }
            if l.frame == Some(true) {
                out.push(format!(
                    "links.{name}.frame = true: no capsules (the link is stated to have no body outside other links' capsules)"
                ));
            }
            if let Some(i) = &l.inertial {
                out.push(format!(
                    "links.{name}.inertial: mass {} kg from the side file",
                    i.mass
                ));
            }
        }
        out
    }

    fn link_spec(
        &self,
        li: usize,
        carrier: &str,
        acc: Option<Isometry3<f64>>,
        side: &SideFile,
    ) -> Result<LinkSpec, ModelError> {
        let link = &self.robot.links[li];
        let ov = side.links.get(&link.name);
        let frame = ov.and_then(|o| o.frame).unwrap_or(false);
        if frame && !link.collision.is_empty() {
            return Err(ModelError::Invalid(format!(
                "side file `links.{}.frame = true`, but the URDF gives the link {} <collision> element(s); \
                 a link with collision geometry is not a frame (give `capsules` instead)",
                link.name,
                link.collision.len()
            )));
        }
        let capsules = match ov.and_then(|o| o.capsules.clone()) {
            Some(c) => c,
            None if frame => Vec::new(),
            None => {
                // A mesh cannot be bounded here: a link whose collision geometry includes one
                // needs side-file capsules, else SSM/PFL would silently ignore that body.
                if link
                    .collision
                    .iter()
                    .any(|c| matches!(c.geometry, urdf_rs::Geometry::Mesh { .. }))
                {
                    return Err(ModelError::MeshCollision {
                        links: vec![link.name.clone()],
                    });
                }
                collision_capsules(link)?
            }
        };
        let inertial = match ov.and_then(|o| o.inertial) {
            Some(i) => Some(i),
            None => urdf_inertial(link)?,
        };
        Ok(LinkSpec {
            name: link.name.clone(),
            parent: carrier.into(),
            origin: acc.map_or_else(PoseSpec::default, |a| iso_to_pose(&a)),
            capsules,
            inertial,
            frame,
        })
    }
}
