//! `pacs fk`: world-frame link capsules per configuration.

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
    let robot = input.robot.load()?;
    let mut configurations = Vec::with_capacity(input.q.len());
    for (i, q) in input.q.iter().enumerate() {
        check_vec(&format!("q[{i}]"), q, robot.dof())?;
        let frames = robot.frames(q);
        let links: Vec<Value> = robot
            .links()
            .iter()
            .map(|l| {
                let caps: Vec<Value> = l
                    .capsules
                    .iter()
                    .map(|c| {
                        let w = c.transformed(&frames[l.frame]);
                        json!({"p1": w.p1().coords.as_slice(), "p2": w.p2().coords.as_slice(), "radius": w.radius()})
                    })
                    .collect();
                json!({"name": l.name, "capsules": caps})
            })
            .collect();
        configurations.push(json!({"links": links}));
    }
    Ok(json!({"configurations": configurations}))
}
