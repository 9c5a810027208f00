//! Thin PyO3 bindings of `tvist-core`: numpy in/out, errors mapped to `ValueError`.
//! No algorithm lives here: one module per core area, conversion only.

use pyo3::prelude::*;
use tvist_core as core;
use tvist_core::Status;

mod convert;
mod json;
mod map_file;
mod modal;
mod paper10;
mod providers;
mod robot;
mod robot_data;
mod robot_law;
mod shaping;
mod tv_shaper;
mod ztdis;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    shaping::register(m)?;
    providers::register(m)?;
    tv_shaper::register(m)?;
    robot::register(m)?;
    robot_data::register(m)?;
    paper10::register(m)?;
    map_file::register(m)?;
    modal::register(m)?;
    ztdis::register(m)?;
    let flags = pyo3::types::PyDict::new(m.py());
    for (name, flag) in Status::FLAGS {
        flags.set_item(name, flag.0)?;
    }
    m.add("STATUS_FLAGS", flags)?;
    m.add("MAX_DOF", core::limits::MAX_DOF)?;
    m.add("MAX_MODES", core::limits::MAX_MODES)?;
    m.add("MAX_MAP_FILE_BYTES", core::limits::MAX_MAP_FILE_BYTES)?;
    m.add("MAX_DELAY_LINE_BYTES", core::limits::MAX_DELAY_LINE_BYTES)?;
    Ok(())
}
