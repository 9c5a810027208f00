//! Python objects <-> JSON values (`serde_json::Value`), for the map file of the core.
//!
//! Python side: `None`, `bool`, `int`, `float`, `str`, lists/tuples, dicts with string keys,
//! and anything with `tolist()` (numpy arrays and scalars). A non-finite float is either
//! refused (coefficients: the message names the field) or written as `null` (metadata, where
//! `null` means "not available"), as the caller chooses.
//!
//! [`map_file_from`] turns a map document (a Python dict) into the core's checked map file;
//! both the map-file functions and `DynamicMap`'s constructor read documents through it.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};
use tvist_core::files::map_file::MapFile;

use crate::convert::value_error;

/// Deepest nesting converted (the core's parser stops at 128 as well).
const MAX_DEPTH: usize = 64;

/// What to do with a NaN or infinite float.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum NonFinite {
    Refuse,
    AsNull,
}

/// `obj` as a JSON value; `path` names it in errors (`modes[0].k_0`).
pub fn to_value(obj: &Bound<'_, PyAny>, path: &str, non_finite: NonFinite) -> PyResult<Value> {
    convert(obj, path, non_finite, 0)
}

fn err(path: &str, reason: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{path}: {reason}"))
}

fn convert(obj: &Bound<'_, PyAny>, path: &str, nf: NonFinite, depth: usize) -> PyResult<Value> {
    if depth > MAX_DEPTH {
        return Err(err(path, format!("nested deeper than {MAX_DEPTH} levels")));
    }
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(i) = obj.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = obj.extract::<u64>() {
            return Ok(Value::from(u));
        }
        return Err(err(path, "integer out of the 64-bit range"));
    }
    if obj.is_instance_of::<PyFloat>() {
        let x: f64 = obj.extract()?;
        return match (Number::from_f64(x), nf) {
            (Some(n), _) => Ok(Value::Number(n)),
            (None, NonFinite::AsNull) => Ok(Value::Null),
            (None, NonFinite::Refuse) => Err(err(path, format!("must be finite, got {x}"))),
        };
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.to_str()?.to_owned()));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut out = Map::new();
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| err(path, format!("keys must be strings, got {k}")))?;
            let child = format!("{path}.{key}");
            out.insert(key, convert(&v, &child, nf, depth + 1)?);
        }
        return Ok(Value::Object(out));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let items = obj
            .try_iter()?
            .enumerate()
            .map(|(i, item)| convert(&item?, &format!("{path}[{i}]"), nf, depth + 1))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(Value::Array(items));
    }
    if obj.hasattr("tolist")? {
        // numpy arrays and scalars: plain Python values of the same content.
        let plain = obj.call_method0("tolist")?;
        if !plain.is(obj) {
            return convert(&plain, path, nf, depth + 1);
        }
    }
    Err(err(
        path,
        format!("cannot be written as JSON (a {})", obj.get_type().name()?),
    ))
}

/// A JSON value as a plain Python object (dicts keep the value's key order).
pub fn to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

/// A map document (Python object) checked by the core's map-file validation.
pub(crate) fn map_file_from(doc: &Bound<'_, PyAny>) -> PyResult<MapFile> {
    let value = match doc.cast::<PyDict>() {
        // Metadata may hold statistics that could not be computed (NaN): written as null.
        // Everything else must be finite, and the error names the field.
        Ok(d) => {
            let mut map = Map::new();
            for (k, v) in d.iter() {
                let key: String = k
                    .extract()
                    .map_err(|_| PyValueError::new_err("map document: keys must be strings"))?;
                let nf = if key == "metadata" {
                    NonFinite::AsNull
                } else {
                    NonFinite::Refuse
                };
                let value = to_value(&v, &key, nf)?;
                map.insert(key, value);
            }
            Value::Object(map)
        }
        Err(_) => to_value(doc, "(document)", NonFinite::Refuse)?,
    };
    MapFile::from_value(&value).map_err(value_error)
}
