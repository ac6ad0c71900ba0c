//! Models from Python arguments: a robot is a built-in name, an inline spec (dict), or a URDF
//! (a path, or `{"urdf": path, "side": path}`); humans, constraints and objects are built-in
//! names or inline specs — the same forms as a log header, resolved by the same code
//! ([`LogModels::from_header`]), so that a log written from Python is audited against exactly
//! the models the shield used.

use crate::convert::{Given, from_py, show, to_py};
use crate::errors::{input, type_err};
use pacs_log::{Header, LogModels, ModelRef, ObjectEntry};
use pacs_models::ConstraintSpec;
use pacs_models::human::{HumanModel, HumanSpec};
use pacs_models::robot::{RobotModel, RobotSpec};
use pacs_models::shape::CapsuleSpec;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::path::PathBuf;

/// A path argument (str or os.PathLike).
fn path_of(obj: &Bound<'_, PyAny>) -> Option<PathBuf> {
    obj.extract::<PathBuf>().ok()
}

/// The robot as a header reference (URDF robots become their converted inline spec).
pub fn robot_ref(
    robot: &Bound<'_, PyAny>,
    side: Option<&Bound<'_, PyAny>>,
) -> PyResult<ModelRef<RobotSpec>> {
    let side_path = match side {
        None => None,
        Some(s) if s.is_none() => None,
        Some(s) => Some(path_of(s).ok_or_else(|| {
            type_err(format!(
                "side: expected a path to a side file, got {}",
                show(s)
            ))
        })?),
    };
    let urdf = |p: PathBuf, side: Option<PathBuf>| -> PyResult<ModelRef<RobotSpec>> {
        let model = pacs_models::urdf::load_urdf_files(&p, side.as_deref())
            .map_err(|e| input(format!("robot (URDF `{}`): {e}", p.display())))?;
        Ok(ModelRef::Spec(Box::new(model.spec().clone())))
    };
    if let Ok(d) = robot.cast::<PyDict>() {
        if let Some(u) = d.get_item("urdf")? {
            let p = path_of(&u).ok_or_else(|| {
                type_err(format!(
                    "robot[\"urdf\"]: expected a path, got {}",
                    show(&u)
                ))
            })?;
            let side = match d.get_item("side")? {
                Some(s) if !s.is_none() => Some(path_of(&s).ok_or_else(|| {
                    type_err(format!(
                        "robot[\"side\"]: expected a path, got {}",
                        show(&s)
                    ))
                })?),
                _ => side_path,
            };
            if let Some(k) = d
                .keys()
                .iter()
                .map(|k| k.to_string())
                .find(|k| k != "urdf" && k != "side")
            {
                return Err(input(format!(
                    "robot[\"{k}\"]: unknown field (a URDF robot has `urdf` and `side`)"
                )));
            }
            return urdf(p, side);
        }
        let spec: RobotSpec = from_py(robot, "robot")?;
        return Ok(ModelRef::Spec(Box::new(spec)));
    }
    if robot.is_instance_of::<PyString>() {
        let s: String = robot.extract()?;
        if RobotModel::builtin(&s).is_ok() && side_path.is_none() {
            return Ok(ModelRef::Name(s));
        }
        let p = PathBuf::from(&s);
        if p.is_file() || s.ends_with(".urdf") {
            return urdf(p, side_path);
        }
        return Err(input(format!(
            "robot: `{s}` is neither a built-in robot (fr3) nor an existing URDF file"
        )));
    }
    if let Some(p) = path_of(robot) {
        return urdf(p, side_path);
    }
    Err(type_err(format!(
        "robot: expected a built-in name, a spec dict, a URDF path or {{\"urdf\": ..., \"side\": ...}}, got {}",
        show(robot)
    )))
}

/// A human model reference: a built-in name or an inline spec.
pub fn human_ref(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<ModelRef<HumanSpec>> {
    if obj.is_instance_of::<PyString>() {
        let s: String = obj.extract()?;
        HumanModel::builtin(&s).map_err(|e| input(format!("{name}: {e}")))?;
        return Ok(ModelRef::Name(s));
    }
    if obj.cast::<PyDict>().is_ok() {
        return Ok(ModelRef::Spec(Box::new(from_py(obj, name)?)));
    }
    Err(type_err(format!(
        "{name}: expected a built-in human name or a spec dict, got {}",
        show(obj)
    )))
}

/// Task constraints: a built-in name (`"sorting"`, `"handover"`, `"ssm"`, ...) or a spec dict.
pub fn constraints_ref(obj: &Bound<'_, PyAny>) -> PyResult<ModelRef<ConstraintSpec>> {
    if obj.is_instance_of::<PyString>() {
        let s: String = obj.extract()?;
        ConstraintSpec::builtin(&s).map_err(|e| input(format!("constraints: {e}")))?;
        return Ok(ModelRef::Name(s));
    }
    if obj.cast::<PyDict>().is_ok() {
        return Ok(ModelRef::Spec(Box::new(from_py(obj, "constraints")?)));
    }
    Err(type_err(format!(
        "constraints: expected a built-in task name or a spec dict, got {}",
        show(obj)
    )))
}

/// A scene's models: the header they are logged with and the resolved models.
pub struct SceneModels {
    /// The log header naming every model (several people: a v2 header listing them).
    pub header: Header,
    /// Resolved robot, first human, constraints, environment, objects.
    pub models: LogModels,
    /// Every human (the first is `models.human`).
    pub humans: Vec<HumanModel>,
}

/// Resolve the models of a shield or log writer (absent arguments: the FR3, the default
/// human, the sorting task; `humans=None`: no human).
#[allow(clippy::too_many_arguments)]
pub fn scene(
    py: Python<'_>,
    robot: Option<&Bound<'_, PyAny>>,
    side: Option<&Bound<'_, PyAny>>,
    humans: Given<'_>,
    constraints: Option<&Bound<'_, PyAny>>,
    objects: Option<&Bound<'_, PyAny>>,
    environment: Option<&Bound<'_, PyAny>>,
) -> PyResult<SceneModels> {
    // The defaults: the FR3, the default human, the sorting task.
    let robot = match robot {
        Some(r) => robot_ref(r, side)?,
        None => robot_ref(&"fr3".into_pyobject(py)?.into_any(), side)?,
    };
    let constraints = match constraints {
        Some(c) => constraints_ref(c)?,
        None => ModelRef::Name("sorting".into()),
    };
    let humans = match humans {
        Given::Missing => "default".into_pyobject(py)?.into_any(),
        Given::Value(h) => h,
    };
    let humans = &humans;
    let mut human_refs = Vec::new();
    let mut ids: Vec<Option<String>> = Vec::new();
    if humans.is_none() {
        // No human in the scene: the header still names the default model (no measurements).
    } else {
        // One name, spec or person alone stands for a list of one.
        let one = humans.is_instance_of::<PyString>() || humans.cast::<PyDict>().is_ok();
        let list: Vec<Bound<'_, PyAny>> = if one {
            vec![humans.clone()]
        } else {
            humans.extract().map_err(|_| {
                type_err(format!(
                    "humans: expected a name, a spec dict, a person {{\"id\": str, \"human\": name or spec}}, a list of them or None, got {}",
                    show(humans)
                ))
            })?
        };
        if list.is_empty() {
            return Err(input(
                "humans: an empty list (give at least one person, or None for a scene without people)"
                    .to_string(),
            ));
        }
        for (i, h) in list.iter().enumerate() {
            let at = if one {
                "humans".to_string()
            } else {
                format!("humans[{i}]")
            };
            // A person with an id: {"id": ..., "human": name or spec} (a dict with `id` is one;
            // a human model spec has no `id`).
            if let Ok(d) = h.cast::<PyDict>()
                && d.contains("id")?
            {
                for key in d.keys() {
                    let k: String = key.extract().unwrap_or_default();
                    if k != "id" && k != "human" {
                        return Err(input(format!(
                            "{at}: unknown key `{k}` (a person is {{\"id\": str, \"human\": name or spec}})"
                        )));
                    }
                }
                let id: String = d
                    .get_item("id")?
                    .map(|v| v.extract())
                    .transpose()
                    .map_err(|_| {
                        type_err(format!(
                            "{at}.id: expected a string, got {}",
                            d.get_item("id")
                                .ok()
                                .flatten()
                                .map(|v| show(&v))
                                .unwrap_or_default()
                        ))
                    })?
                    .unwrap_or_default();
                let model = d.get_item("human")?.ok_or_else(|| {
                    input(format!(
                        "{at}.human: missing (a person is {{\"id\": str, \"human\": name or spec}})"
                    ))
                })?;
                ids.push(Some(id));
                human_refs.push(human_ref(&model, &format!("{at}.human"))?);
                continue;
            }
            ids.push(None);
            human_refs.push(human_ref(h, &at)?);
        }
    }
    let first = human_refs
        .first()
        .cloned()
        .unwrap_or_else(|| ModelRef::Name("default".into()));
    // One unnamed person: a v1-style header (writers make it v2 with person `human`); several,
    // or one with an id: v2, each with its id (given, else `human0`, `human1`, ...).
    let mut header = if human_refs.len() > 1 || ids.iter().any(Option::is_some) {
        // Unnamed people are `human{i}`, unless another person was given that id: then the next
        // free number.
        let given: Vec<&String> = ids.iter().flatten().collect();
        let mut taken: Vec<String> = Vec::new();
        let people = human_refs
            .iter()
            .zip(&ids)
            .enumerate()
            .map(|(i, (h, id))| {
                let id = id.clone().unwrap_or_else(|| {
                    let mut k = i;
                    while given.iter().any(|g| **g == format!("human{k}"))
                        || taken.contains(&format!("human{k}"))
                    {
                        k += 1;
                    }
                    format!("human{k}")
                });
                taken.push(id.clone());
                pacs_log::PersonEntry {
                    id,
                    human: h.clone(),
                }
            })
            .collect();
        let mut h = Header::with_people(robot, people, constraints);
        h.end_event = false;
        h.start_event = false;
        h.check()
            .map_err(|e| input(e.to_string().replace("header.", "")))?;
        h
    } else {
        Header::new(robot, first, constraints)
    };
    if let Some(o) = objects.filter(|o| !o.is_none()) {
        header.objects = from_py::<Vec<ObjectEntry>>(o, "objects")?;
    }
    if let Some(e) = environment.filter(|e| !e.is_none()) {
        header.environment = from_py::<Vec<CapsuleSpec>>(e, "environment")?;
    }
    let models =
        LogModels::from_header(&header).map_err(|e| input(e.to_string().replace("header.", "")))?;
    let mut resolved = Vec::with_capacity(human_refs.len());
    for (i, h) in human_refs.iter().enumerate() {
        let m = match h {
            ModelRef::Name(n) => HumanModel::builtin(n),
            ModelRef::Spec(s) => HumanModel::new((**s).clone()),
        }
        .map_err(|e| input(format!("humans[{i}]: {e}")))?;
        resolved.push(m);
    }
    header
        .meta
        .insert("filter".into(), "pacs-shield (python)".into());
    Ok(SceneModels {
        header,
        models,
        humans: resolved,
    })
}

/// The robot's spec as pacs uses it (links, capsules, masses, limits; units m, kg, rad, rad/s,
/// rad/s², rad/s³): a built-in name, a spec dict, or a URDF path (with `side`, the side file
/// giving what URDF lacks), converted and validated.
#[pyfunction]
#[pyo3(signature = (robot, side=None))]
pub fn robot_spec<'py>(
    robot: &Bound<'py, PyAny>,
    side: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let r = robot_ref(robot, side)?;
    let model = match &r {
        ModelRef::Name(n) => RobotModel::builtin(n),
        ModelRef::Spec(s) => RobotModel::new((**s).clone()),
    }
    .map_err(|e| input(format!("robot: {e}")))?;
    to_py(robot.py(), model.spec())
}
