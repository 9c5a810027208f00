//! Documents read and written at setup (feature `json`): the robot-data file and the map file
//! (its `paper10` and `modal` forms), in strict JSON.

pub mod map_file;
pub mod modal_doc;
pub mod paper10_doc;
pub mod robot_data;
mod strict_json;
