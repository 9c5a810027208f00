//! The `paper10` form of the map file: its `modes`, each the ten coefficients, joints,
//! exponents and inertia ranges of one [`ModeMap`], read and written.

use crate::error::Error;
use crate::files::strict_json::{float, joint_index, number, object_with_fields, reason};
use crate::modes::paper10::dynamic_map::{DynamicMap, InertiaRange, MapCoefficients, ModeMap};
use serde_json::{Map, Value};

/// Required fields of one `paper10` mode, in the order they are written.
pub const MODE_FIELDS: [&str; 12] = [
    "k_0",
    "k_j",
    "k_g",
    "k_p",
    "c_0",
    "c_1",
    "c_2",
    "c_tau",
    "frequency_joint",
    "damping_joint",
    "damping_gain_exponent",
    "frequency_gain_exponent",
];

/// Optional fields of one `paper10` mode: `[min, max]` (kg m²) of the frequency joint's and
/// the damping joint's inertia the map was identified on; missing or `null` is unbounded.
pub const RANGE_FIELDS: [&str; 2] = [
    "frequency_inertia_range_kg_m2",
    "damping_inertia_range_kg_m2",
];

pub(crate) fn paper10_from(doc: &Map<String, Value>) -> Result<DynamicMap, Error> {
    let modes = match doc.get("modes") {
        None => return Err(Error::document("modes", "missing")),
        Some(Value::Array(modes)) if !modes.is_empty() => modes,
        Some(_) => {
            return Err(Error::document(
                "modes",
                "must be a non-empty list of mode objects",
            ))
        }
    };
    // The count first: nothing is parsed per mode beyond the limit.
    crate::limits::check_n_modes(modes.len(), "the map")
        .map_err(|e| Error::document("modes", reason(e)))?;
    let maps = modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let path = format!("modes[{i}]");
            let mode = mode_from(m, &path)?;
            // The map's own rule (checked again by `DynamicMap::new`), here to name the mode.
            mode.check_physical()
                .map_err(|why| Error::document(path, why))?;
            Ok(mode)
        })
        .collect::<Result<Vec<_>, Error>>()?;
    DynamicMap::new(maps).map_err(|e| Error::document("modes", reason(e)))
}

fn range(value: Option<&Value>, path: &str) -> Result<Option<InertiaRange>, Error> {
    match value {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Array(bounds)) if bounds.len() == 2 => {
            let lo = number(bounds.first(), &format!("{path}[0]"))?;
            let hi = number(bounds.get(1), &format!("{path}[1]"))?;
            InertiaRange::new(lo, hi)
                .map(Some)
                .map_err(|e| Error::document(path, reason(e)))
        }
        Some(other) => Err(Error::document(
            path,
            format!("must be [min, max] in kg m² or null, got {other}"),
        )),
    }
}

/// One `paper10` mode of a map document, checked for form (its fields, finite numbers, joint
/// indices, exponents, ranges); `path` names it in errors (`modes[1]`). The physical rules
/// are the map's ([`DynamicMap::new`]); a mode alone may break them (a trial point of a fit).
pub fn mode_from(value: &Value, path: &str) -> Result<ModeMap, Error> {
    let mode = object_with_fields(value, path, &MODE_FIELDS, &RANGE_FIELDS)?;
    let f = |key: &str| number(mode.get(key), &format!("{path}.{key}"));
    let coefficients = MapCoefficients {
        k_0: f("k_0")?,
        k_j: f("k_j")?,
        k_g: f("k_g")?,
        k_p: f("k_p")?,
        c_0: f("c_0")?,
        c_1: f("c_1")?,
        c_2: f("c_2")?,
        c_tau: f("c_tau")?,
    };
    let frequency_joint = joint_index(
        mode.get("frequency_joint"),
        &format!("{path}.frequency_joint"),
    )?;
    let damping_joint = joint_index(mode.get("damping_joint"), &format!("{path}.damping_joint"))?;
    let mut exponents = [0.0; 2];
    for (e, key) in exponents
        .iter_mut()
        .zip(["damping_gain_exponent", "frequency_gain_exponent"])
    {
        *e = f(key)?;
        let bound = crate::modes::paper10::dynamic_map::MAX_GAIN_EXPONENT;
        if e.abs() > bound {
            return Err(Error::document(
                format!("{path}.{key}"),
                format!(
                    "{e} is outside [-{bound}, {bound}] (the published forms use -0.5, 0, \
                     0.5 and 1)"
                ),
            ));
        }
    }
    let [frequency_range, damping_range] = [0, 1].map(|k| {
        range(
            mode.get(RANGE_FIELDS[k]),
            &format!("{path}.{}", RANGE_FIELDS[k]),
        )
    });
    let (frequency_range, damping_range) = (frequency_range?, damping_range?);
    if frequency_joint == damping_joint && frequency_range != damping_range {
        return Err(Error::document(
            path,
            format!(
                "frequency and damping both read joint {frequency_joint}, so {} and {} must \
                 be equal",
                RANGE_FIELDS[0], RANGE_FIELDS[1]
            ),
        ));
    }
    Ok(ModeMap {
        coefficients,
        frequency_joint,
        damping_joint,
        damping_gain_exponent: exponents[0],
        frequency_gain_exponent: exponents[1],
        frequency_range,
        damping_range,
    })
}

fn range_to_value(range: Option<InertiaRange>) -> Value {
    range.map_or(Value::Null, |r| {
        Value::Array(vec![float(r.min_kg_m2()), float(r.max_kg_m2())])
    })
}

/// One `paper10` mode as written in a map file.
pub fn mode_to_value(m: &ModeMap) -> Value {
    let c = &m.coefficients;
    let mut out = Map::new();
    for (key, x) in [
        ("k_0", c.k_0),
        ("k_j", c.k_j),
        ("k_g", c.k_g),
        ("k_p", c.k_p),
        ("c_0", c.c_0),
        ("c_1", c.c_1),
        ("c_2", c.c_2),
        ("c_tau", c.c_tau),
    ] {
        out.insert(key.into(), float(x));
    }
    out.insert("frequency_joint".into(), Value::from(m.frequency_joint));
    out.insert("damping_joint".into(), Value::from(m.damping_joint));
    out.insert(
        "damping_gain_exponent".into(),
        float(m.damping_gain_exponent),
    );
    out.insert(
        "frequency_gain_exponent".into(),
        float(m.frequency_gain_exponent),
    );
    out.insert(RANGE_FIELDS[0].into(), range_to_value(m.frequency_range));
    out.insert(RANGE_FIELDS[1].into(), range_to_value(m.damping_range));
    Value::Object(out)
}
