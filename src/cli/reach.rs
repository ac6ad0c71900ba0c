//! `pacs reach robot`, `pacs reach human` and `pacs reach object`.

use super::{CliError, HumanRef, RobotRef, check_vec, parse_json, read_json};
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};
use pacs_reach::robot::RobotReach;
use serde::Deserialize;
use serde_json::{Value, json};
use std::path::Path;

/// A capsule's numbers as promised (finite): a bound that overflowed is an input error naming the
/// field, never `null` in the output.
pub(super) fn finite_capsule(field: &str, c: &pacs_models::Capsule) -> Result<(), CliError> {
    let (p1, p2, r) = (c.p1().coords, c.p2().coords, c.radius());
    let bad = p1
        .iter()
        .chain(p2.iter())
        .chain(std::iter::once(&r))
        .copied()
        .find(|x| !x.is_finite());
    match bad {
        None => Ok(()),
        Some(x) => Err(CliError::Input(format!(
            "{field}: the capsule overflows ({x}): the input is too large to bound in \
             floating point"
        ))),
    }
}

fn capsule_json(c: &pacs_models::Capsule) -> Value {
    json!({"p1": c.p1().coords.as_slice(), "p2": c.p2().coords.as_slice(), "radius": c.radius()})
}

/// One joint box of the input (rad).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxInput {
    q_lo: Vec<f64>,
    q_hi: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotInput {
    robot: RobotRef,
    boxes: Vec<BoxInput>,
    #[serde(default)]
    tracking_error: f64,
}

/// Built-in example input of `pacs reach robot`.
const ROBOT_EXAMPLE: &str = include_str!("../../examples/robot.json");
/// Built-in example input of `pacs reach human`.
const HUMAN_EXAMPLE: &str = include_str!("../../examples/human.json");

/// Read the input file, or parse the built-in example when no file is given.
fn input_or_example<T: serde::de::DeserializeOwned>(
    path: Option<&Path>,
    example: &str,
) -> Result<T, CliError> {
    match path {
        Some(p) => read_json(p),
        None => parse_json(Path::new("<built-in example>"), example),
    }
}

/// Run `pacs reach robot [--input F]`.
pub fn run_robot(path: Option<&Path>) -> Result<Value, CliError> {
    let input: RobotInput = input_or_example(path, ROBOT_EXAMPLE)?;
    let robot = super::load_robot(&input.robot, path)?;
    let reach = RobotReach::try_new(&robot, input.tracking_error)
        .map_err(|e| CliError::Input(e.to_string()))?;
    let mut boxes = Vec::with_capacity(input.boxes.len());
    let mut caps =
        vec![
            pacs_models::Capsule::new_unchecked(Default::default(), Default::default(), 0.0);
            reach.capsule_count()
        ];
    for (i, b) in input.boxes.iter().enumerate() {
        check_vec(&format!("boxes[{i}].q_lo"), &b.q_lo, robot.dof())?;
        check_vec(&format!("boxes[{i}].q_hi"), &b.q_hi, robot.dof())?;
        let q = pacs_reach::JointBox::new(&b.q_lo, &b.q_hi).map_err(|e| {
            CliError::Input(match e {
                pacs_reach::JointBoxError::Invalid { joint, lo, hi } => format!(
                    "boxes[{i}]: joint {joint}: need q_lo <= q_hi, got q_lo[{joint}] = {lo}, q_hi[{joint}] = {hi}"
                ),
                other => format!("boxes[{i}]: {other}"),
            })
        })?;
        reach
            .occupancy_into(&q, &mut caps)
            .map_err(|e| CliError::Input(format!("boxes[{i}]: {e}")))?;
        for (l, &(s, e)) in robot.links().iter().zip(reach.link_ranges()) {
            for c in &caps[s..e] {
                finite_capsule(
                    &format!(
                        "boxes[{i}] (link `{}`, tracking_error {:?})",
                        l.name, input.tracking_error
                    ),
                    c,
                )?;
            }
        }
        let links: Vec<Value> = robot
            .links()
            .iter()
            .zip(reach.link_ranges())
            .map(|(l, &(s, e))| json!({"name": l.name, "capsules": caps[s..e].iter().map(capsule_json).collect::<Vec<_>>()}))
            .collect();
        boxes.push(json!({"links": links}));
    }
    Ok(json!({"boxes": boxes}))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeasurementInput {
    time: f64,
    positions: Vec<[f64; 3]>,
    #[serde(default)]
    velocities: Option<Vec<[f64; 3]>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HumanInput {
    human: HumanRef,
    #[serde(default = "default_model")]
    model: String,
    measurement: MeasurementInput,
    intervals: Vec<[f64; 2]>,
}

fn default_model() -> String {
    "combined".into()
}

/// Run `pacs reach human [--input F]`.
pub fn run_human(path: Option<&Path>) -> Result<Value, CliError> {
    let input: HumanInput = input_or_example(path, HUMAN_EXAMPLE)?;
    let human = input.human.load()?;
    let kind: HumanReachModel = input
        .model
        .parse()
        .map_err(|e: pacs_reach::ReachError| CliError::Input(format!("model: {e}")))?;
    let m = HumanMeasurement::new(
        &human,
        input.measurement.time,
        &input.measurement.positions,
        input.measurement.velocities.as_deref(),
    )
    .map_err(|e| CliError::Input(e.to_string()))?;
    let names: Vec<String> = human.body_parts().iter().map(|b| b.name.clone()).collect();
    let mut reach = HumanReach::new(human, kind);
    let mut out = Vec::with_capacity(input.intervals.len());
    for (i, [t_a, t_b]) in input.intervals.iter().enumerate() {
        let caps = reach
            .occupancy(&m, *t_a, *t_b)
            .map_err(|e| CliError::Input(format!("intervals[{i}]: {e}")))?;
        for (n, c) in names.iter().zip(&caps) {
            finite_capsule(
                &format!("intervals[{i}] = [{t_a:?}, {t_b:?}] (body part `{n}`)"),
                c,
            )?;
        }
        let parts: Vec<Value> = names
            .iter()
            .zip(&caps)
            .map(|(n, c)| json!({"name": n, "p1": c.p1().coords.as_slice(), "p2": c.p2().coords.as_slice(), "radius": c.radius()}))
            .collect();
        out.push(json!({"t": [t_a, t_b], "body_parts": parts}));
    }
    Ok(json!({"intervals": out}))
}

/// An object given by built-in name (`"ball"`) or inline spec: read from JSON by hand, so that a
/// bad inline spec reports its own field (no "untagged enum" message).
fn load_object(v: &Value) -> Result<pacs_models::object::ObjectModel, CliError> {
    let spec = match v {
        Value::String(name) => pacs_models::object::builtin_object(name).ok_or_else(|| {
            CliError::Input(format!(
                "object: unknown built-in object `{name}` (built-in: {})",
                pacs_models::object::BUILTIN_OBJECTS.join(", ")
            ))
        })?,
        Value::Object(_) => serde_json::from_value::<pacs_models::object::ObjectSpec>(v.clone())
            .map_err(|e| CliError::Input(format!("object: {e}")))?,
        other => {
            return Err(CliError::Input(format!(
                "object: expected a built-in name or an inline spec, found {other}"
            )));
        }
    };
    pacs_models::object::ObjectModel::new(&spec)
        .map_err(|e| CliError::Input(format!("object: {e}")))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectMeasurementInput {
    time: f64,
    position: [f64; 3],
    #[serde(default)]
    velocity: Option<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectInput {
    object: Value,
    measurement: ObjectMeasurementInput,
    intervals: Vec<[f64; 2]>,
}

/// Built-in example input of `pacs reach object`.
const OBJECT_EXAMPLE: &str = include_str!("../../examples/object.json");

fn zonotope_json<const N: usize>(z: &pacs_reach::zonotope::Zonotope3<N>, radius: f64) -> Value {
    json!({
        "centre": z.center(),
        "generators": z.generators(),
        "error_box": z.error_box(),
        "radius": radius,
    })
}

/// Run `pacs reach object [--input F]`.
pub fn run_object(path: Option<&Path>) -> Result<Value, CliError> {
    let input: ObjectInput = input_or_example(path, OBJECT_EXAMPLE)?;
    let model = load_object(&input.object)?;
    let m = &input.measurement;
    check_vec("measurement.time", &[m.time], 1)?;
    check_vec("measurement.position", &m.position, 3)?;
    if let Some(v) = &m.velocity {
        check_vec("measurement.velocity", v, 3)?;
    }
    let meas = pacs_reach::object::ObjectMeasurement {
        time: m.time,
        position: m.position,
        velocity: m.velocity,
    };
    let mut out = Vec::with_capacity(input.intervals.len());
    for (i, [t_a, t_b]) in input.intervals.iter().enumerate() {
        let field = format!("intervals[{i}] = [{t_a:?}, {t_b:?}]");
        let occ = pacs_reach::object::occupancy(&model, &meas, *t_a, *t_b)
            .map_err(|e| CliError::Input(format!("{field}: {e}")))?;
        let cap = occ.bounding_capsule().ok_or_else(|| {
            CliError::Input(format!(
                "{field}: the occupancy overflows: the input is too large to bound in floating point"
            ))
        })?;
        finite_capsule(&field, &cap)?;
        let mut entry = json!({
            "t": [t_a, t_b],
            "zonotope": zonotope_json(occ.zonotope(), occ.radius()),
            "bounding_capsule": capsule_json(&cap),
        });
        if let Some((z, r)) = occ.speed_set() {
            entry["speed_set"] = zonotope_json(z, r);
        }
        out.push(entry);
    }
    Ok(json!({"intervals": out}))
}
