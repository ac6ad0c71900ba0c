//! The shield's inputs as Python hands them over (chunks, measurements of people and objects),
//! checked and converted, with errors naming the argument.

use crate::convert::{finite, floats, index, optional_vec3, points, show, vec3};
use crate::errors::{input, type_err};
use pacs_models::human::HumanModel;
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use pyo3::prelude::*;

pub fn chunk_rows(deltas: &Bound<'_, PyAny>, dof: usize) -> PyResult<Vec<Vec<f64>>> {
    let (shape, v) = floats(deltas, "deltas", &[None, Some(dof)])?;
    if shape[0] == 0 {
        return Err(input(
            "deltas: shape [0, _]: a chunk needs at least one action",
        ));
    }
    Ok(v.chunks_exact(dof).map(<[f64]>::to_vec).collect())
}

pub fn horizon(h: Option<&Bound<'_, PyAny>>, rows: usize) -> PyResult<usize> {
    match h {
        Some(h) if !h.is_none() => {
            let v = index(h, "h")?;
            if v < 1 || v > rows {
                return Err(input(format!(
                    "h: {v} is outside 1..={rows} (the number of actions in the chunk)"
                )));
            }
            Ok(v)
        }
        _ => Ok(rows),
    }
}

/// Parse measure arguments: the human index (default 0) and the measurement.
pub fn measurement(
    humans: &[HumanModel],
    ids: &[&str],
    human: Option<&Bound<'_, PyAny>>,
    t_meas: &Bound<'_, PyAny>,
    positions: &Bound<'_, PyAny>,
    velocities: Option<&Bound<'_, PyAny>>,
) -> PyResult<(usize, HumanMeasurement)> {
    let id = match human {
        Some(h) if !h.is_none() => {
            if let Ok(s) = h.extract::<String>() {
                ids.iter().position(|i| *i == s).ok_or_else(|| {
                    input(format!(
                        "human: no person `{s}` in this shield (people: {ids:?})"
                    ))
                })?
            } else if !h.is_instance_of::<pyo3::types::PyBool>() && h.extract::<i64>().is_ok() {
                // Any integer (numpy's too).
                index(h, "human")?
            } else {
                return Err(type_err(format!(
                    "human: expected a person's id (str) or index, got {}",
                    show(h)
                )));
            }
        }
        _ if humans.len() > 1 => {
            return Err(input(format!(
                "human: required with several people (an id or index; people: {ids:?})"
            )));
        }
        _ => 0,
    };
    let Some(model) = humans.get(id) else {
        return Err(input(format!(
            "human: {id} is not a human of this shield ({} humans)",
            humans.len()
        )));
    };
    let t = finite(t_meas, "t_meas")?;
    let k = model.keypoint_count();
    let p = points(positions, "positions", Some(k))?;
    let v = match velocities {
        Some(v) if !v.is_none() => Some(points(v, "velocities", Some(k))?),
        _ => None,
    };
    let m = HumanMeasurement::new(model, t, &p, v.as_deref()).map_err(|e| input(e.to_string()))?;
    Ok((id, m))
}

/// Parse measure_object arguments.
pub fn object_measurement(
    object_ids: &[String],
    id: &Bound<'_, PyAny>,
    t_meas: &Bound<'_, PyAny>,
    position: &Bound<'_, PyAny>,
    velocity: Option<&Bound<'_, PyAny>>,
) -> PyResult<(usize, ObjectMeasurement)> {
    let k = if let Ok(s) = id.extract::<String>() {
        object_ids.iter().position(|o| *o == s).ok_or_else(|| {
            input(format!(
                "id: no object `{s}` in this shield (objects: {object_ids:?})"
            ))
        })?
    } else if id.is_instance_of::<pyo3::types::PyInt>() {
        let i = index(id, "id")?;
        if i >= object_ids.len() {
            return Err(input(format!(
                "id: object {i} does not exist ({} objects)",
                object_ids.len()
            )));
        }
        i
    } else {
        return Err(type_err(format!(
            "id: expected an object id (str) or index, got {}",
            show(id)
        )));
    };
    let t = finite(t_meas, "t_meas")?;
    Ok((
        k,
        ObjectMeasurement {
            time: t,
            position: vec3(position, "position")?,
            velocity: optional_vec3(velocity, "velocity")?,
        },
    ))
}
