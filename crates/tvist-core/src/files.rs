//! Documents read and written at setup (feature `json`): the robot-data file and the map file.

pub mod map_file;
pub mod robot_data;
