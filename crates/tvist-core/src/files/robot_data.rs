//! Robot parameters from robot-data files (feature `json`).
//!
//! The UR e-Series parameters live in exactly one place, `data/ur_e_series.json` in this crate
//! (schema in its `conventions` field). This module embeds that file, parses it once, and
//! turns one of its `robots` entries into a [`RobotEntry`] (every field) or into the joints
//! and links of a [`Robot`]. The Python package reads the same parsed entries through its
//! bindings. A robot file ([`robot_file`]) is a document of the same schema holding one
//! robot. Setup-time only: parsing allocates.
//!
//! An entry places its joints either by standard DH parameters (`"dh": {"d", "a",
//! "alpha"}`, links in DH frame `i + 1`) or as URDF places them (`"joints": [{"origin_xyz_m",
//! "origin_rpy_rad", "axis"}, …]` and `"flange": {"origin_xyz_m", "origin_rpy_rad"}`, links in
//! the link frame after joint `i`), never both (see [`Chain`]).

use crate::error::Error;
use crate::robot::chain::{Chain, DhJoint};
use crate::robot::model::Robot;
use crate::robot::placement::{JointPlacement, Origin};
use crate::robot::rigid_body::RigidBody;
use serde_json::Value;
use std::sync::OnceLock;

/// The UR e-Series parameter file, embedded at build time.
pub const UR_E_SERIES_JSON: &str = include_str!("../../data/ur_e_series.json");

/// The `schema_version` this reader understands.
pub const SCHEMA_VERSION: u64 = 1;

fn invalid(msg: String) -> Error {
    Error::InvalidParameter(format!("robot data: {msg}"))
}

/// Parses a robot-data document and checks its schema version.
fn document(json: &str) -> Result<Value, Error> {
    let doc: Value = serde_json::from_str(json).map_err(|e| invalid(format!("{e}")))?;
    match doc.get("schema_version") {
        Some(Value::Number(n)) if n.as_u64() == Some(SCHEMA_VERSION) => Ok(doc),
        other => Err(invalid(format!(
            "schema_version {other:?}, expected {SCHEMA_VERSION}"
        ))),
    }
}

/// Every field of one robot entry (units in the names; per-joint lists have `n_dof` entries).
#[derive(Debug, Clone, PartialEq)]
pub struct RobotEntry {
    pub name: String,
    pub description: String,
    pub source: String,
    pub inertia_source: String,
    /// How the joints are placed.
    pub chain: Chain,
    /// Link `i` in the frame the chain names (mass, centre of mass, inertia about it).
    pub links: Vec<RigidBody>,
    /// `[lower, upper]` per joint, rad.
    pub joint_limits_rad: Vec<[f64; 2]>,
    pub max_velocity_rad_s: Vec<f64>,
    pub max_payload_kg: f64,
    /// Period of the robot controller's control loop, s (finite, > 0): the default sample
    /// period of what runs on the robot. `None` where the file does not state it (a robot
    /// file written from a URDF, which gives none).
    pub control_period_s: Option<f64>,
    /// The optional solid-cylinder model the inertias were derived from.
    pub inertia_cylinders: Option<InertiaCylinders>,
}

/// The `inertia_cylinders` block of an entry: one cylinder per link.
#[derive(Debug, Clone, PartialEq)]
pub struct InertiaCylinders {
    pub radius_m: Vec<f64>,
    pub length_m: Vec<f64>,
    /// `"x"`, `"y"` or `"z"`: the axis of DH frame `i` the cylinder lies along.
    pub axis: Vec<String>,
}

impl RobotEntry {
    /// Number of joints.
    pub fn n_dof(&self) -> usize {
        self.chain.n_dof()
    }

    /// The rigid-body model of this arm with `payload` on the flange, named after the entry.
    pub fn robot(&self, payload: RigidBody) -> Result<Robot, Error> {
        let robot = Robot::from_chain(self.chain.clone(), self.links.clone(), payload)?;
        Ok(robot.with_name(&self.name))
    }
}

/// The embedded file, parsed on first use (every entry read in full).
pub fn ur_e_series_entries() -> Result<&'static [RobotEntry], Error> {
    static PARSED: OnceLock<Result<Vec<RobotEntry>, Error>> = OnceLock::new();
    PARSED
        .get_or_init(|| {
            robot_names(UR_E_SERIES_JSON)?
                .iter()
                .map(|name| robot_entry(UR_E_SERIES_JSON, name))
                .collect()
        })
        .as_ref()
        .map(Vec::as_slice)
        .map_err(Clone::clone)
}

/// Entry `name` of the embedded file.
pub fn ur_e_series_entry(name: &str) -> Result<&'static RobotEntry, Error> {
    let entries = ur_e_series_entries()?;
    entries.iter().find(|e| e.name == name).ok_or_else(|| {
        let known: Vec<&str> = entries.iter().map(|e| e.name.as_str()).collect();
        invalid(format!("unknown robot {name:?}; known: {known:?}"))
    })
}

fn text(value: Option<&Value>, what: &str) -> Result<String, Error> {
    value
        .and_then(Value::as_str)
        .map(str::to_string)
        .ok_or_else(|| invalid(format!("{what} must be a string")))
}

/// Every field of robot `name` in robot-data document `json` (see [`robot_chain`] for the
/// chain; the other fields are required too).
pub fn robot_entry(json: &str, name: &str) -> Result<RobotEntry, Error> {
    let (chain, links) = robot_links(json, name)?;
    let n = chain.n_dof();
    let doc = document(json)?;
    let entry = &doc["robots"][name];
    let field = |key: &str| entry.get(key);
    let what = |key: &str| format!("{name}: {key}");
    let max_payload_kg = field("max_payload_kg")
        .and_then(Value::as_f64)
        .ok_or_else(|| invalid(format!("{name}: max_payload_kg must be a number")))?;
    let control_period_s = control_period(field("control_period_s"), name)?;
    let inertia_cylinders = match field("inertia_cylinders") {
        None | Some(Value::Null) => None,
        Some(block) => {
            let axis = block
                .get("axis")
                .and_then(Value::as_array)
                .filter(|a| a.len() == n)
                .and_then(|a| a.iter().map(|v| v.as_str().map(str::to_string)).collect())
                .ok_or_else(|| {
                    invalid(format!(
                        "{name}: inertia_cylinders.axis must hold {n} strings"
                    ))
                })?;
            Some(InertiaCylinders {
                radius_m: numbers(
                    block.get("radius_m"),
                    n,
                    &what("inertia_cylinders.radius_m"),
                )?,
                length_m: numbers(
                    block.get("length_m"),
                    n,
                    &what("inertia_cylinders.length_m"),
                )?,
                axis,
            })
        }
    };
    Ok(RobotEntry {
        name: name.to_string(),
        description: text(field("description"), &what("description"))?,
        source: text(field("source"), &what("source"))?,
        inertia_source: text(field("inertia_source"), &what("inertia_source"))?,
        chain,
        links,
        joint_limits_rad: rows::<2>(field("joint_limits_rad"), n, &what("joint_limits_rad"))?,
        max_velocity_rad_s: numbers(field("max_velocity_rad_s"), n, &what("max_velocity_rad_s"))?,
        max_payload_kg,
        control_period_s,
        inertia_cylinders,
    })
}

/// The optional `control_period_s` of entry `name`: absent (or null) is `None`; present, a
/// finite number > 0 (s).
fn control_period(value: Option<&Value>, name: &str) -> Result<Option<f64>, Error> {
    match value {
        None | Some(Value::Null) => Ok(None),
        Some(v) => match v.as_f64() {
            Some(s) if s.is_finite() && s > 0.0 => Ok(Some(s)),
            _ => Err(invalid(format!(
                "{name}: control_period_s must be a finite number of seconds > 0, got {v}"
            ))),
        },
    }
}

/// Names of the robots in a robot-data document (in file order).
pub fn robot_names(json: &str) -> Result<Vec<String>, Error> {
    let doc = document(json)?;
    let robots = doc
        .get("robots")
        .and_then(Value::as_object)
        .ok_or_else(|| invalid("'robots' must be an object".into()))?;
    Ok(robots.keys().cloned().collect())
}

/// A list of `len` numbers at `value`, named `what` in errors.
fn numbers(value: Option<&Value>, len: usize, what: &str) -> Result<Vec<f64>, Error> {
    let list = value
        .and_then(Value::as_array)
        .ok_or_else(|| invalid(format!("{what} must be a list of numbers")))?;
    if list.len() != len {
        return Err(invalid(format!(
            "{what} has {} entries, expected {len}",
            list.len()
        )));
    }
    list.iter()
        .map(|v| {
            v.as_f64()
                .ok_or_else(|| invalid(format!("{what} must hold numbers only, found {v}")))
        })
        .collect()
}

/// `n` rows of `N` numbers at `value`.
fn rows<const N: usize>(
    value: Option<&Value>,
    n: usize,
    what: &str,
) -> Result<Vec<[f64; N]>, Error> {
    let list = value
        .and_then(Value::as_array)
        .ok_or_else(|| invalid(format!("{what} must be a list of rows")))?;
    if list.len() != n {
        return Err(invalid(format!(
            "{what} has {} rows, expected {n}",
            list.len()
        )));
    }
    list.iter()
        .enumerate()
        .map(|(i, row)| {
            let v = numbers(Some(row), N, &format!("{what}[{i}]"))?;
            let mut out = [0.0; N];
            out.copy_from_slice(&v);
            Ok(out)
        })
        .collect()
}

/// The one robot of robot file `path` (a robot-data document with exactly one entry), every
/// field read as for the embedded file.
pub fn robot_file(path: &std::path::Path) -> Result<RobotEntry, Error> {
    let shown = path.display();
    let json = std::fs::read_to_string(path)
        .map_err(|e| invalid(format!("cannot read robot file {shown}: {e}")))?;
    let names = robot_names(&json).map_err(|e| invalid(format!("{shown}: {e}")))?;
    match names.as_slice() {
        [name] => robot_entry(&json, name).map_err(|e| invalid(format!("{shown}: {e}"))),
        _ => Err(invalid(format!(
            "robot file {shown} must hold exactly one robot, found {names:?}"
        ))),
    }
}

/// DH joints and links of robot `name` in robot-data document `json` (an error for an entry
/// placed by `joints`: see [`robot_links`]).
pub fn robot_chain(json: &str, name: &str) -> Result<(Vec<DhJoint>, Vec<RigidBody>), Error> {
    match robot_links(json, name)? {
        (Chain::Dh(joints), links) => Ok((joints, links)),
        _ => Err(invalid(format!(
            "{name}: joints are placed by 'joints' (URDF form), not by DH parameters"
        ))),
    }
}

/// A list of `len` objects at `value`, named `what` in errors.
fn objects<'a>(value: Option<&'a Value>, what: &str) -> Result<&'a Vec<Value>, Error> {
    value
        .and_then(Value::as_array)
        .filter(|list| list.iter().all(Value::is_object))
        .ok_or_else(|| invalid(format!("{what} must be a list of objects")))
}

/// An `{"origin_xyz_m", "origin_rpy_rad"}` object.
fn origin(value: &Value, what: &str) -> Result<Origin, Error> {
    let three = |key: &str| -> Result<[f64; 3], Error> {
        let v = numbers(value.get(key), 3, &format!("{what}.{key}"))?;
        Ok([v[0], v[1], v[2]])
    };
    Ok(Origin::new(
        three("origin_xyz_m")?,
        three("origin_rpy_rad")?,
    ))
}

/// The chain and links of robot `name` in robot-data document `json`.
///
/// The joint count is that of `dh.d` (or of `joints`); every other per-joint field must match
/// it. Values are taken as written (the [`Robot`] constructor checks that they are physical).
pub fn robot_links(json: &str, name: &str) -> Result<(Chain, Vec<RigidBody>), Error> {
    let doc = document(json)?;
    let entry = doc.get("robots").and_then(|r| r.get(name)).ok_or_else(|| {
        invalid(format!(
            "unknown robot {name:?}; known: {:?}",
            robot_names(json).unwrap_or_default()
        ))
    })?;
    match (entry.get("dh"), entry.get("joints")) {
        (Some(_), Some(_)) => {
            return Err(invalid(format!(
                "{name}: give either 'dh' or 'joints', not both"
            )))
        }
        (None, Some(joints)) => {
            let list = objects(Some(joints), &format!("{name}: joints"))?;
            let placed = list
                .iter()
                .enumerate()
                .map(|(i, j)| {
                    let what = format!("{name}: joints[{i}]");
                    let axis = numbers(j.get("axis"), 3, &format!("{what}.axis"))?;
                    Ok(JointPlacement::new(
                        origin(j, &what)?,
                        [axis[0], axis[1], axis[2]],
                    ))
                })
                .collect::<Result<Vec<_>, Error>>()?;
            let flange = match entry.get("flange") {
                Some(f) if f.is_object() => origin(f, &format!("{name}: flange"))?,
                _ => {
                    return Err(invalid(format!(
                        "{name}: flange must be an object {{origin_xyz_m, origin_rpy_rad}}"
                    )))
                }
            };
            let links = links(entry, name, placed.len())?;
            return Ok((
                Chain::Urdf {
                    joints: placed,
                    flange,
                },
                links,
            ));
        }
        _ => {}
    }
    let dh = entry.get("dh");
    let n = dh
        .and_then(|d| d.get("d"))
        .and_then(Value::as_array)
        .map(Vec::len)
        .ok_or_else(|| invalid(format!("{name}: dh.d must be a list of numbers")))?;
    let d = numbers(dh.and_then(|d| d.get("d")), n, &format!("{name}: dh.d"))?;
    let a = numbers(dh.and_then(|d| d.get("a")), n, &format!("{name}: dh.a"))?;
    let alpha = numbers(
        dh.and_then(|d| d.get("alpha")),
        n,
        &format!("{name}: dh.alpha"),
    )?;
    let joints = (0..n).map(|i| DhJoint::new(d[i], a[i], alpha[i])).collect();
    Ok((Chain::Dh(joints), links(entry, name, n)?))
}

/// The `n` links of entry `name` (mass, centre of mass, inertia).
fn links(entry: &Value, name: &str, n: usize) -> Result<Vec<RigidBody>, Error> {
    let mass = numbers(entry.get("mass_kg"), n, &format!("{name}: mass_kg"))?;
    let com = rows::<3>(entry.get("com_m"), n, &format!("{name}: com_m"))?;
    let inertia = rows::<6>(
        entry.get("inertia_kg_m2"),
        n,
        &format!("{name}: inertia_kg_m2"),
    )?;
    Ok((0..n)
        .map(|i| RigidBody {
            mass_kg: mass[i],
            com_m: com[i],
            inertia_kg_m2: inertia[i],
        })
        .collect())
}

/// UR e-Series robot `name` (`"ur3e"`, `"ur5e"`, …) from the embedded parameter file, with
/// `payload` on the flange; the robot carries its name.
pub fn ur_e_series(name: &str, payload: RigidBody) -> Result<Robot, Error> {
    ur_e_series_entry(name)?.robot(payload)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(result: Result<(Vec<DhJoint>, Vec<RigidBody>), Error>) -> String {
        match result {
            Ok(_) => String::from("accepted"),
            Err(e) => e.to_string(),
        }
    }

    const ONE_JOINT: &str = r#"{"schema_version": 1, "robots": {"arm": {
        "dh": {"d": [0.1], "a": [0.2], "alpha": [0.5]},
        "mass_kg": [2.0], "com_m": [[0.1, 0.0, 0.0]],
        "inertia_kg_m2": [[0.01, 0.02, 0.02, 0.0, 0.0, 0.0]]}}}"#;

    /// One joint with every field an entry needs, no control period.
    const ONE_ENTRY: &str = r#"{"schema_version": 1, "robots": {"arm": {
        "description": "one joint", "source": "test", "inertia_source": "test",
        "dh": {"d": [0.1], "a": [0.2], "alpha": [0.5]},
        "mass_kg": [2.0], "com_m": [[0.1, 0.0, 0.0]],
        "inertia_kg_m2": [[0.01, 0.02, 0.02, 0.0, 0.0, 0.0]],
        "joint_limits_rad": [[-3.0, 3.0]], "max_velocity_rad_s": [3.0],
        "max_payload_kg": 1.0}}}"#;

    #[test]
    fn reads_every_field_of_an_entry() -> Result<(), Error> {
        let (joints, links) = robot_chain(ONE_JOINT, "arm")?;
        assert_eq!(joints, vec![DhJoint::new(0.1, 0.2, 0.5)]);
        assert_eq!(
            links,
            vec![RigidBody {
                mass_kg: 2.0,
                com_m: [0.1, 0.0, 0.0],
                inertia_kg_m2: [0.01, 0.02, 0.02, 0.0, 0.0, 0.0],
            }]
        );
        Ok(())
    }

    const ONE_PLACED_JOINT: &str = r#"{"schema_version": 1, "robots": {"arm": {
        "joints": [{"origin_xyz_m": [0, 0, 0.1], "origin_rpy_rad": [0, 0, 0.3],
                    "axis": [0, 0, 1]}],
        "flange": {"origin_xyz_m": [0.2, 0, 0], "origin_rpy_rad": [0.5, 0, 0]},
        "mass_kg": [2.0], "com_m": [[0.1, 0.0, 0.0]],
        "inertia_kg_m2": [[0.01, 0.02, 0.02, 0.0, 0.0, 0.0]]}}}"#;

    #[test]
    fn reads_joints_placed_as_urdf_places_them() -> Result<(), Error> {
        let (chain, links) = robot_links(ONE_PLACED_JOINT, "arm")?;
        let joint = JointPlacement::new(
            Origin::new([0.0, 0.0, 0.1], [0.0, 0.0, 0.3]),
            [0.0, 0.0, 1.0],
        );
        let flange = Origin::new([0.2, 0.0, 0.0], [0.5, 0.0, 0.0]);
        assert_eq!(
            chain,
            Chain::Urdf {
                joints: vec![joint],
                flange
            }
        );
        assert_eq!(links[0].mass_kg, 2.0);
        let msg = |json: &str| match robot_links(json, "arm") {
            Ok(_) => String::from("accepted"),
            Err(e) => e.to_string(),
        };
        let both = ONE_PLACED_JOINT.replace(r#""joints""#, r#""dh": {}, "joints""#);
        assert!(
            msg(&both).contains("either 'dh' or 'joints'"),
            "{}",
            msg(&both)
        );
        let no_flange = ONE_PLACED_JOINT.replace(r#""flange""#, r#""tool""#);
        assert!(
            msg(&no_flange).contains("flange must be an object"),
            "{}",
            msg(&no_flange)
        );
        let bad_axis = ONE_PLACED_JOINT.replace("[0, 0, 1]", "[0, 1]");
        assert!(
            msg(&bad_axis).contains("joints[0].axis has 2 entries"),
            "{}",
            msg(&bad_axis)
        );
        assert!(
            robot_chain(ONE_PLACED_JOINT, "arm").is_err(),
            "not a DH chain"
        );
        Ok(())
    }

    #[test]
    fn the_embedded_file_holds_six_joint_ur_robots() -> Result<(), Error> {
        let names = robot_names(UR_E_SERIES_JSON)?;
        assert!(names.iter().any(|n| n == "ur5e"), "{names:?}");
        for name in &names {
            let robot = ur_e_series(name, RigidBody::NONE)?;
            assert_eq!(robot.n_dof(), 6, "{name}");
        }
        Ok(())
    }

    #[test]
    fn every_entry_is_read_in_full_once() -> Result<(), Error> {
        let entries = ur_e_series_entries()?;
        let names: Vec<&str> = entries.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(
            names,
            ["ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur3", "ur5", "ur10"]
        );
        let ur5e = ur_e_series_entry("ur5e")?;
        assert_eq!(ur5e.max_payload_kg, 5.0);
        assert_eq!(ur5e.joint_limits_rad.len(), 6);
        assert!(ur5e.inertia_cylinders.is_some());
        assert!(
            core::ptr::eq(ur5e, ur_e_series_entry("ur5e")?),
            "parsed once"
        );
        let robot = ur_e_series("ur10e", RigidBody::NONE)?;
        assert_eq!(robot.name(), Some("ur10e"));
        Ok(())
    }

    #[test]
    fn every_embedded_entry_states_its_control_period() -> Result<(), Error> {
        // The makers' specifications: the e-Series controller runs at 500 Hz, the CB-series
        // at 125 Hz.
        for entry in ur_e_series_entries()? {
            let expected = if entry.name.ends_with('e') || entry.name == "ur20" {
                0.002
            } else {
                0.008
            };
            assert_eq!(entry.control_period_s, Some(expected), "{}", entry.name);
        }
        Ok(())
    }

    #[test]
    fn the_control_period_is_optional_but_must_be_a_positive_time() -> Result<(), Error> {
        assert_eq!(robot_entry(ONE_ENTRY, "arm")?.control_period_s, None);
        let stated = ONE_ENTRY.replace(
            r#""max_payload_kg": 1.0"#,
            r#""max_payload_kg": 1.0, "control_period_s": 0.001"#,
        );
        assert_eq!(robot_entry(&stated, "arm")?.control_period_s, Some(0.001));
        for bad in ["0", "-0.002", "\"fast\"", "[0.002]"] {
            let json = ONE_ENTRY.replace(
                r#""max_payload_kg": 1.0"#,
                &format!(r#""max_payload_kg": 1.0, "control_period_s": {bad}"#),
            );
            let msg = match robot_entry(&json, "arm") {
                Ok(e) => format!("accepted as {:?}", e.control_period_s),
                Err(e) => e.to_string(),
            };
            assert!(
                msg.contains("arm: control_period_s must be"),
                "{bad}: {msg}"
            );
        }
        Ok(())
    }

    #[test]
    fn malformed_documents_name_the_problem() {
        let cases = [
            ("{", "robot data:"),
            (r#"{"schema_version": 2, "robots": {}}"#, "schema_version"),
            (
                &ONE_JOINT.replace(r#""a": [0.2]"#, r#""a": [0.2, 0.3]"#),
                "dh.a has 2 entries",
            ),
            (
                &ONE_JOINT.replace(r#""mass_kg": [2.0]"#, r#""mass_kg": ["x"]"#),
                "mass_kg must hold numbers",
            ),
            (
                &ONE_JOINT.replace("[[0.1, 0.0, 0.0]]", "[[0.1, 0.0]]"),
                "com_m[0] has 2 entries",
            ),
            (
                &ONE_JOINT.replace(r#""inertia_kg_m2""#, r#""inertia""#),
                "inertia_kg_m2 must be a list of rows",
            ),
        ];
        for (json, expected) in cases {
            let msg = message(robot_chain(json, "arm"));
            assert!(msg.contains(expected), "{msg:?} lacks {expected:?}");
        }
        let msg = message(robot_chain(ONE_JOINT, "ur99"));
        assert!(
            msg.contains("unknown robot \"ur99\"") && msg.contains("arm"),
            "{msg}"
        );
    }
}
