//! Bindings of the core's map file: documents (Python objects) and files checked by the
//! core's parser, and maps written back; the map is a `DynamicMap` or a `ModalMap` by the
//! document's `kind`.

use pyo3::prelude::*;
use tvist_core::files::map_file::{self, MapFile, MapForm};

use crate::convert::value_error;
use crate::json::{self, map_file_from, NonFinite};
use crate::modal::PyModalMap;
use crate::paper10::PyDynamicMap;

/// A parsed map file as `(DynamicMap or ModalMap, metadata dict)`, by the file's kind.
fn map_parts(py: Python<'_>, file: MapFile) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyAny>)> {
    let metadata = json::to_py(py, &serde_json::Value::Object(file.metadata().clone()))?;
    let map = match file.into_form() {
        MapForm::Paper10(inner) => Bound::new(py, PyDynamicMap { inner })?.into_any(),
        MapForm::Modal(inner) => Bound::new(py, PyModalMap { inner })?.into_any(),
    };
    Ok((map, metadata))
}

/// The map form of a `DynamicMap` or `ModalMap`.
fn form_of(map: &Bound<'_, PyAny>) -> PyResult<MapForm> {
    if let Ok(m) = map.cast::<PyDynamicMap>() {
        Ok(MapForm::Paper10(m.borrow().inner.clone()))
    } else if let Ok(m) = map.cast::<PyModalMap>() {
        Ok(MapForm::Modal(m.get().inner.clone()))
    } else {
        Err(pyo3::exceptions::PyTypeError::new_err(
            "map must be a _core.DynamicMap or a _core.ModalMap",
        ))
    }
}

/// Validates a map document (a dict as read from JSON) with the core's map-file rules and
/// returns `(DynamicMap or ModalMap, metadata)` by its kind; errors name the field.
#[pyfunction]
fn map_from_document<'py>(
    py: Python<'py>,
    doc: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    map_parts(py, map_file_from(doc)?)
}

/// Reads and validates the map file at `path` (the core's reader: size limit, UTF-8, strict
/// JSON): `(DynamicMap or ModalMap, metadata)`; errors start with the path.
#[pyfunction]
fn load_map_file(
    py: Python<'_>,
    path: std::path::PathBuf,
) -> PyResult<(Bound<'_, PyAny>, Bound<'_, PyAny>)> {
    map_parts(py, MapFile::load(&path).map_err(value_error)?)
}

/// The map file of `map` (DynamicMap or ModalMap) with `metadata`, as strict JSON text
/// (non-finite metadata numbers written as null).
#[pyfunction]
fn write_map(map: &Bound<'_, PyAny>, metadata: &Bound<'_, PyAny>) -> PyResult<String> {
    let meta = json::to_value(metadata, "metadata", NonFinite::AsNull)?;
    let file = MapFile::new(form_of(map)?, &meta).map_err(value_error)?;
    Ok(file.to_json())
}

/// The map document of `map` with `metadata` as a dict (what `write_map` writes).
#[pyfunction]
fn map_document<'py>(
    py: Python<'py>,
    map: &Bound<'py, PyAny>,
    metadata: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let meta = json::to_value(metadata, "metadata", NonFinite::AsNull)?;
    let file = MapFile::new(form_of(map)?, &meta).map_err(value_error)?;
    json::to_py(py, &file.to_value())
}

/// Registers the functions and constants of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MAP_METADATA_FIELDS", map_file::METADATA_FIELDS.to_vec())?;
    m.add("MAP_SCHEMA_VERSION", map_file::SCHEMA_VERSION)?;
    m.add("MAP_KIND_PAPER10", map_file::KIND_PAPER10)?;
    m.add("MAP_KIND_MODAL", map_file::KIND_MODAL)?;
    m.add_function(wrap_pyfunction!(map_from_document, m)?)?;
    m.add_function(wrap_pyfunction!(load_map_file, m)?)?;
    m.add_function(wrap_pyfunction!(write_map, m)?)?;
    m.add_function(wrap_pyfunction!(map_document, m)?)?;
    Ok(())
}
