//! Python values to Rust: float arrays (numpy or anything `numpy.asarray` accepts), JSON-like
//! dicts to serde types. Errors name the argument, the index and the value.

use crate::errors::{input, type_err};
use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use serde::de::DeserializeOwned;

/// Short `repr` of a value for messages.
pub fn show(obj: &Bound<'_, PyAny>) -> String {
    let r = obj
        .repr()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "<unprintable>".into());
    if r.chars().count() > 80 {
        let head: String = r.chars().take(77).collect();
        format!("{head}...")
    } else {
        r
    }
}

/// A float64 array view of `obj`: the array itself if it is a C-contiguous float64 ndarray
/// (no copy), else `numpy.ascontiguousarray(obj, dtype=float64)`.
fn float_array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'py, f64>>()
        && a.is_c_contiguous()
    {
        return Ok(a);
    }
    let py = obj.py();
    let converted = py
        .import("numpy")
        .and_then(|np| np.call_method1("ascontiguousarray", (obj, "float64")))
        .map_err(|_| {
            type_err(format!(
                "{name}: expected an array of numbers, got {} {}",
                obj.get_type()
                    .name()
                    .map(|n| n.to_string())
                    .unwrap_or_default(),
                show(obj)
            ))
        })?;
    converted
        .extract::<PyReadonlyArrayDyn<'py, f64>>()
        .map_err(|_| {
            type_err(format!(
                "{name}: expected an array of numbers, got {}",
                show(obj)
            ))
        })
}

/// Row-major values of a float array of `shape` (`None`: any length in that axis); every value
/// finite. Errors: `pacs.ArgumentTypeError` (not numbers), `pacs.InputError` (shape, NaN/inf,
/// naming the index).
pub fn floats(
    obj: &Bound<'_, PyAny>,
    name: &str,
    shape: &[Option<usize>],
) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let a = float_array(obj, name)?;
    let got = a.shape().to_vec();
    let want: Vec<String> = shape
        .iter()
        .map(|d| d.map_or("any".to_string(), |n| n.to_string()))
        .collect();
    if got.len() != shape.len()
        || got
            .iter()
            .zip(shape)
            .any(|(g, w)| w.is_some_and(|w| w != *g))
    {
        return Err(input(format!(
            "{name}: shape {got:?}, expected ({})",
            want.join(", ")
        )));
    }
    let values = a
        .as_slice()
        .map_err(|e| input(format!("{name}: {e}")))?
        .to_vec();
    if let Some(k) = values.iter().position(|x| !x.is_finite()) {
        let mut idx = Vec::with_capacity(got.len());
        let mut rest = k;
        for d in (0..got.len()).rev() {
            idx.push(rest % got[d].max(1));
            rest /= got[d].max(1);
        }
        idx.reverse();
        let idx: Vec<String> = idx.iter().map(|i| i.to_string()).collect();
        return Err(input(format!(
            "{name}[{}]: value {} is not finite",
            idx.join(", "),
            values[k]
        )));
    }
    Ok((got, values))
}

/// A 1-d float vector of `len` finite values.
pub fn vector(obj: &Bound<'_, PyAny>, name: &str, len: usize) -> PyResult<Vec<f64>> {
    Ok(floats(obj, name, &[Some(len)])?.1)
}

/// A 3-vector (a position in m, a velocity in m/s, …), shape (3,).
pub fn vec3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; 3]> {
    let v = vector(obj, name, 3)?;
    Ok([v[0], v[1], v[2]])
}

/// An optional 3-vector: `None` where absent or Python `None`.
pub fn optional_vec3(obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<Option<[f64; 3]>> {
    match obj {
        Some(v) if !v.is_none() => vec3(v, name).map(Some),
        _ => Ok(None),
    }
}

/// An (n, 3) array of points (m).
pub fn points(obj: &Bound<'_, PyAny>, name: &str, n: Option<usize>) -> PyResult<Vec<[f64; 3]>> {
    let (_, v) = floats(obj, name, &[n, Some(3)])?;
    Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// A finite float.
pub fn finite(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<f64> {
    let v: f64 = obj
        .extract()
        .map_err(|_| type_err(format!("{name}: expected a number, got {}", show(obj))))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(input(format!("{name}: value {v} is not finite")))
    }
}

/// JSON text of a JSON-like Python value (dicts, lists, str, numbers, bools, None; numpy
/// arrays and os.PathLike values are converted).
pub fn to_json(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    let py = obj.py();
    let helper = py
        .import("pacs._convert")
        .and_then(|m| m.getattr("to_json"));
    let text = match helper {
        Ok(f) => match f.call1((obj, name)) {
            Err(e) if e.is_instance_of::<pyo3::exceptions::PyValueError>(py) => return Err(e),
            r => r,
        },
        Err(_) => py
            .import("json")
            .and_then(|j| j.call_method1("dumps", (obj,))),
    };
    text.and_then(|t| t.extract::<String>()).map_err(|e| {
        type_err(format!(
            "{name}: not a JSON-like value ({e}): {}",
            show(obj)
        ))
    })
}

/// A serde value from a JSON-like Python value; errors name `name` and the field.
pub fn from_py<T: DeserializeOwned>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<T> {
    let text = to_json(obj, name)?;
    serde_json::from_str(&text).map_err(|e| {
        // Name the field inside the argument (`config.mode`), where serde_json points at one.
        let inner = (e.line() > 0)
            .then(|| pacs_models::json_path_at(&text, e.line(), e.column()))
            .flatten();
        match inner {
            Some(p) => input(format!("{name}.{p}: {e}")),
            None => input(format!("{name}: {e}")),
        }
    })
}

/// The JSON value as a Python object (`json.loads`).
pub fn to_py<'py>(py: Python<'py>, v: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| input(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// An optional argument whose absence differs from an explicit `None` (e.g. `humans`: absent
/// means the default human, `None` means no human).
pub enum Given<'py> {
    /// Not passed.
    Missing,
    /// Passed (possibly `None`).
    Value(Bound<'py, PyAny>),
}

impl<'a, 'py> FromPyObject<'a, 'py> for Given<'py> {
    type Error = PyErr;
    fn extract(obj: pyo3::Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        Ok(Given::Value(obj.to_owned()))
    }
}

/// A non-negative integer argument.
pub fn index(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<usize> {
    if obj.is_instance_of::<pyo3::types::PyBool>() {
        return Err(type_err(format!(
            "{name}: expected an int, got {}",
            show(obj)
        )));
    }
    let v: i64 = obj
        .extract()
        .map_err(|_| type_err(format!("{name}: expected an int, got {}", show(obj))))?;
    usize::try_from(v).map_err(|_| input(format!("{name}: value {v} is negative")))
}

/// A bool argument.
pub fn flag(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<bool> {
    obj.extract::<bool>()
        .map_err(|_| type_err(format!("{name}: expected True or False, got {}", show(obj))))
}

/// A path argument (str or os.PathLike).
pub fn path(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<std::path::PathBuf> {
    obj.extract::<std::path::PathBuf>()
        .map_err(|_| type_err(format!("{name}: expected a path, got {}", show(obj))))
}

/// A str argument.
pub fn text(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    obj.extract::<String>()
        .map_err(|_| type_err(format!("{name}: expected a str, got {}", show(obj))))
}
