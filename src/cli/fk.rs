//! `pacs fk`: world-frame link capsules per configuration.

use super::reach::finite_capsule;
use super::{CliError, RobotRef, check_vec, read_json};
use serde::Deserialize;
use serde_json::{Value, json};
use std::path::Path;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Input {
    robot: RobotRef,
    q: Vec<Vec<f64>>,
}

/// Run `pacs fk --input F`.
pub fn run(path: &Path) -> Result<Value, CliError> {
    let input: Input = read_json(path)?;
    let robot = super::load_robot(&input.robot, Some(path))?;
    let mut configurations = Vec::with_capacity(input.q.len());
    for (i, q) in input.q.iter().enumerate() {
        check_vec(&format!("q[{i}]"), q, robot.dof())?;
        let frames = robot.frames(q);
        let mut links = Vec::with_capacity(robot.links().len());
        for l in robot.links() {
            let mut caps = Vec::with_capacity(l.capsules.len());
            for c in &l.capsules {
                let w = c.transformed(&frames[l.frame]);
                // Numbers as promised: never `null` (the model's reach bound keeps them finite).
                finite_capsule(&format!("q[{i}] (link `{}`)", l.name), &w)?;
                caps.push(json!({"p1": w.p1().coords.as_slice(), "p2": w.p2().coords.as_slice(), "radius": w.radius()}));
            }
            links.push(json!({"name": l.name, "capsules": caps}));
        }
        configurations.push(json!({"links": links}));
    }
    Ok(json!({"configurations": configurations}))
}
