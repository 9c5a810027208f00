//! Strict JSON for the setup documents: a bounded file read, a parse that refuses repeated
//! keys, readers of single fields whose errors name the field, and finite numbers written
//! (a non-finite one as `null`).

use crate::error::Error;
use crate::modes::paper10::dynamic_map::MAX_JOINT_INDEX;
use serde::de::{Deserialize, Deserializer, Error as _, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Number, Value};
use std::io::Read;
use std::path::Path;

/// The UTF-8 text of the file at `path`, at most [`crate::limits::MAX_MAP_FILE_BYTES`] long;
/// the error says why not. A regular file is judged by its size before anything is read;
/// anything else (a device, a pipe) is read up to one byte past the limit, never further.
pub(crate) fn read_limited(path: &Path) -> Result<String, String> {
    let limit = crate::limits::MAX_MAP_FILE_BYTES;
    let too_long = |size: &str| {
        format!(
            "{size} is more than the {} MiB a map file may have: not a map file",
            limit >> 20
        )
    };
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read: {e}"))?;
    if let Ok(meta) = file.metadata() {
        if meta.is_file() && meta.len() > limit {
            return Err(too_long(&format!("{} bytes", meta.len())));
        }
    }
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot read: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(too_long("its content"));
    }
    String::from_utf8(bytes).map_err(|e| format!("not UTF-8 text ({e})"))
}

/// A JSON value parsed as [`Value`] is, except that an object with a repeated key is an
/// error naming the key ([`Value`] silently keeps the last one, so a file could say two
/// things and mean one).
pub(crate) struct UniqueKeys(pub(crate) Value);

impl<'de> Deserialize<'de> for UniqueKeys {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer
            .deserialize_any(UniqueKeysVisitor)
            .map(UniqueKeys)
    }
}

pub(crate) struct UniqueKeysVisitor;

impl<'de> Visitor<'de> for UniqueKeysVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_bool<E>(self, b: bool) -> Result<Value, E> {
        Ok(Value::Bool(b))
    }

    fn visit_i64<E>(self, i: i64) -> Result<Value, E> {
        Ok(Value::from(i))
    }

    fn visit_u64<E>(self, u: u64) -> Result<Value, E> {
        Ok(Value::from(u))
    }

    fn visit_f64<E>(self, x: f64) -> Result<Value, E> {
        // The parser gives finite values only (overflow is its own error).
        Ok(float(x))
    }

    fn visit_str<E>(self, s: &str) -> Result<Value, E> {
        Ok(Value::String(s.to_owned()))
    }

    fn visit_string<E>(self, s: String) -> Result<Value, E> {
        Ok(Value::String(s))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::new();
        while let Some(UniqueKeys(item)) = seq.next_element()? {
            items.push(item);
        }
        Ok(Value::Array(items))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                return Err(A::Error::custom(format!(
                    "the key {key:?} appears twice in one object"
                )));
            }
            let UniqueKeys(value) = map.next_value()?;
            out.insert(key, value);
        }
        Ok(Value::Object(out))
    }
}

/// The text of a core error without its kind prefix ("invalid parameter: ").
pub(crate) fn reason(e: Error) -> String {
    match e {
        Error::InvalidParameter(msg) | Error::TooLarge(msg) => msg,
        other => other.to_string(),
    }
}

pub(crate) fn number(value: Option<&Value>, path: &str) -> Result<f64, Error> {
    match value {
        None => Err(Error::document(path, "missing")),
        Some(Value::Number(n)) => match n.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(Error::document(path, format!("must be finite, got {n}"))),
        },
        Some(other) => Err(Error::document(
            path,
            format!("must be a number, got {other}"),
        )),
    }
}

pub(crate) fn joint_index(value: Option<&Value>, path: &str) -> Result<usize, Error> {
    let bad = |v: &dyn std::fmt::Display| {
        Error::document(
            path,
            format!("must be a joint index 0..={MAX_JOINT_INDEX}, got {v}"),
        )
    };
    match value {
        None => Err(Error::document(path, "missing")),
        Some(Value::Number(n)) => match n.as_u64() {
            Some(j) if j <= MAX_JOINT_INDEX as u64 => Ok(j as usize),
            _ => Err(bad(n)),
        },
        Some(other) => Err(bad(other)),
    }
}

/// `value` as a JSON object whose every key is one of `fields` or `optional` (`path` names it
/// in errors; the message lists `fields`).
pub(crate) fn object_with_fields<'a>(
    value: &'a Value,
    path: &str,
    fields: &[&str],
    optional: &[&str],
) -> Result<&'a Map<String, Value>, Error> {
    let object = value.as_object().ok_or_else(|| {
        Error::document(
            path,
            format!("must be an object with fields {}", fields.join(", ")),
        )
    })?;
    let unknown: Vec<&str> = object
        .keys()
        .map(String::as_str)
        .filter(|k| !fields.contains(k) && !optional.contains(k))
        .collect();
    if !unknown.is_empty() {
        return Err(Error::document(
            path,
            format!("unknown field(s) {}", unknown.join(", ")),
        ));
    }
    Ok(object)
}

pub(crate) fn float(x: f64) -> Value {
    Number::from_f64(x).map_or(Value::Null, Value::Number)
}
