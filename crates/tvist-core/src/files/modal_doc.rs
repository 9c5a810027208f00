//! The `modal` form of the map file: `flex_joints` (a joint and its load laws each),
//! `link_hinges` and the shaped modes (`mode_joints` or `shaped_modes`) of a [`ModalMap`],
//! read and written.

use crate::error::Error;
use crate::files::strict_json::{float, joint_index, number, object_with_fields, reason};
use crate::modes::modal::modal_map::{FlexJoint, LinkHinge, LoadLaw, ModalMap, ShapedModes};
use serde_json::{Map, Value};

/// Fields of one link hinge of a `modal` map, in the order they are written.
pub const LINK_HINGE_FIELDS: [&str; 4] = [
    "link",
    "at_fraction",
    "stiffness_nm_per_rad",
    "damping_nms_per_rad",
];

/// Fields of one flexible joint of a `modal` map, in the order they are written.
pub const FLEX_JOINT_FIELDS: [&str; 4] = [
    "joint",
    "stiffness_nm_per_rad",
    "damping_nms_per_rad",
    "damping_load_joint",
];

/// The `modal` form's fields of a map document: `flex_joints`, `link_hinges` (optional) and
/// one of `mode_joints` and `shaped_modes`; errors name the field.
pub fn modal_from(doc: &Map<String, Value>) -> Result<ModalMap, Error> {
    let mode_joints = match (doc.get("mode_joints"), doc.get("shaped_modes")) {
        (None, None) => {
            return Err(Error::document(
                "mode_joints",
                "missing: name the shaped modes by joint (mode_joints: [0, 1, ...]) or by \
                 number (shaped_modes: K, the K lowest-frequency modes)",
            ))
        }
        (Some(_), Some(_)) => {
            return Err(Error::document(
                "shaped_modes",
                "give either mode_joints or shaped_modes, not both",
            ))
        }
        (None, Some(k)) => Err(k),
        (Some(Value::Array(joints)), None) => Ok(joints
            .iter()
            .enumerate()
            .map(|(i, j)| joint_index(Some(j), &format!("mode_joints[{i}]")))
            .collect::<Result<Vec<_>, _>>()?),
        (Some(other), None) => {
            return Err(Error::document(
                "mode_joints",
                format!("must be a list of joint indices, got {other}"),
            ))
        }
    };
    let flex = match doc.get("flex_joints") {
        None => return Err(Error::document("flex_joints", "missing")),
        Some(Value::Array(entries)) => entries
            .iter()
            .enumerate()
            .map(|(i, e)| flex_from(e, &format!("flex_joints[{i}]")))
            .collect::<Result<Vec<_>, _>>()?,
        Some(other) => {
            return Err(Error::document(
                "flex_joints",
                format!("must be a list of flexible-joint objects, got {other}"),
            ))
        }
    };
    let hinges = match doc.get("link_hinges") {
        None => Vec::new(),
        Some(Value::Array(entries)) => entries
            .iter()
            .enumerate()
            .map(|(i, e)| hinge_from(e, &format!("link_hinges[{i}]")))
            .collect::<Result<Vec<_>, _>>()?,
        Some(other) => {
            return Err(Error::document(
                "link_hinges",
                format!("must be a list of link-hinge objects, got {other}"),
            ))
        }
    };
    // The flexible joints first (count, duplicates, signs: the map's own checks, whose
    // messages name the joint), with a mode they certainly have; then the hinges; then the
    // mode joints.
    let first = flex.first().map_or(0, |f| f.joint);
    ModalMap::new(flex.clone(), &[first])
        .map_err(|e| Error::document("flex_joints", reason(e)))?
        .with_link_hinges(hinges.clone())
        .map_err(|e| Error::document("link_hinges", reason(e)))?;
    let mode_joints = match mode_joints {
        Ok(joints) => joints,
        Err(k) => {
            let n = flex.len() + 2 * hinges.len();
            let k = k
                .as_u64()
                .filter(|&k| k >= 1 && k <= n as u64)
                .ok_or_else(|| {
                    Error::document(
                        "shaped_modes",
                        format!(
                            "must be an integer from 1 to {n} (the number of flexible \
                             coordinates: joints plus two per link hinge), got {k}"
                        ),
                    )
                })?;
            return ModalMap::shaping_hinged(flex, hinges, ShapedModes::Lowest(k as usize))
                .map_err(|e| Error::document("shaped_modes", reason(e)));
        }
    };
    if mode_joints.is_empty() {
        return Err(Error::document(
            "mode_joints",
            "must name at least one mode",
        ));
    }
    for (i, joint) in mode_joints.iter().enumerate() {
        if !flex.iter().any(|f| f.joint == *joint) || mode_joints[..i].contains(joint) {
            return Err(Error::document(
                format!("mode_joints[{i}]"),
                format!(
                    "joint {joint} must be one of the flexible joints {:?}, named once",
                    flex.iter().map(|f| f.joint).collect::<Vec<_>>()
                ),
            ));
        }
    }
    ModalMap::shaping_hinged(flex, hinges, ShapedModes::ByJoint(mode_joints))
        .map_err(|e| Error::document("mode_joints", reason(e)))
}

fn hinge_from(value: &Value, path: &str) -> Result<LinkHinge, Error> {
    let entry = object_with_fields(value, path, &LINK_HINGE_FIELDS, &[])?;
    let field = |key: &str| format!("{path}.{key}");
    let value = |key: &str| number(entry.get(key), &field(key));
    Ok(LinkHinge {
        link: joint_index(entry.get("link"), &field("link"))?,
        at_fraction: value("at_fraction")?,
        stiffness_nm_per_rad: value("stiffness_nm_per_rad")?,
        damping_nms_per_rad: value("damping_nms_per_rad")?,
    })
}

/// One link hinge of a `modal` map as written in a map file.
pub fn hinge_to_value(h: &LinkHinge) -> Value {
    let mut out = Map::new();
    out.insert("link".into(), Value::from(h.link));
    out.insert("at_fraction".into(), float(h.at_fraction));
    out.insert("stiffness_nm_per_rad".into(), float(h.stiffness_nm_per_rad));
    out.insert("damping_nms_per_rad".into(), float(h.damping_nms_per_rad));
    Value::Object(out)
}

fn flex_from(value: &Value, path: &str) -> Result<FlexJoint, Error> {
    let entry = object_with_fields(value, path, &FLEX_JOINT_FIELDS, &[])?;
    let field = |key: &str| format!("{path}.{key}");
    Ok(FlexJoint {
        joint: joint_index(entry.get("joint"), &field("joint"))?,
        stiffness_nm_per_rad: law_from(
            entry.get("stiffness_nm_per_rad"),
            &field("stiffness_nm_per_rad"),
        )?,
        damping_nms_per_rad: law_from(
            entry.get("damping_nms_per_rad"),
            &field("damping_nms_per_rad"),
        )?,
        damping_load_joint: joint_index(
            entry.get("damping_load_joint"),
            &field("damping_load_joint"),
        )?,
    })
}

/// A load law `[at_zero, per_nm, per_nm2]` (signs are checked by [`ModalMap::new`]).
fn law_from(value: Option<&Value>, path: &str) -> Result<LoadLaw, Error> {
    match value {
        None => Err(Error::document(path, "missing")),
        Some(Value::Array(v)) if v.len() == 3 => {
            let x = |i: usize| number(v.get(i), &format!("{path}[{i}]"));
            Ok(LoadLaw {
                at_zero: x(0)?,
                per_nm: x(1)?,
                per_nm2: x(2)?,
            })
        }
        Some(other) => Err(Error::document(
            path,
            format!("must be [at_zero, per_nm, per_nm2], got {other}"),
        )),
    }
}

/// One flexible joint of a `modal` map as written in a map file.
pub fn flex_to_value(f: &FlexJoint) -> Value {
    let law = |l: &LoadLaw| Value::Array(vec![float(l.at_zero), float(l.per_nm), float(l.per_nm2)]);
    let mut out = Map::new();
    out.insert("joint".into(), Value::from(f.joint));
    out.insert("stiffness_nm_per_rad".into(), law(&f.stiffness_nm_per_rad));
    out.insert("damping_nms_per_rad".into(), law(&f.damping_nms_per_rad));
    out.insert(
        "damping_load_joint".into(),
        Value::from(f.damping_load_joint),
    );
    Value::Object(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::map_file::{MapFile, KIND_MODAL};

    fn reason_of(text: &str) -> String {
        match MapFile::parse(text) {
            Ok(_) => "accepted".into(),
            Err(e) => e.to_string(),
        }
    }

    /// A modal map file exactly as the Python package wrote it before the core read modal
    /// files (metadata without `payload`, fields in that order).
    const PYTHON_MODAL_FILE: &str = r#"{
  "schema_version": 1,
  "kind": "modal",
  "metadata": {
    "robot": "ur5e",
    "source": "gear laws of a flexible-joint twin (FlexParams)",
    "fit_statistics": null
  },
  "mode_joints": [
    0,
    1
  ],
  "flex_joints": [
    {
      "joint": 0,
      "stiffness_nm_per_rad": [
        26000.0,
        0.0,
        0.012
      ],
      "damping_nms_per_rad": [
        14.0,
        0.35,
        0.0
      ],
      "damping_load_joint": 1
    },
    {
      "joint": 1,
      "stiffness_nm_per_rad": [
        22000.0,
        0.0,
        0.0
      ],
      "damping_nms_per_rad": [
        21.0,
        0.0,
        0.0
      ],
      "damping_load_joint": 1
    }
  ]
}
"#;

    #[test]
    fn a_modal_file_written_by_python_reads_and_writes_back_identically() {
        let file = MapFile::parse(PYTHON_MODAL_FILE).expect("python modal file");
        assert_eq!(file.kind(), KIND_MODAL);
        assert_eq!(file.robot(), Some("ur5e"));
        let map = file.form().as_modal().expect("modal");
        assert_eq!(map.robot(), Some("ur5e"));
        assert_eq!(map.mode_joints(), Some(&[0, 1][..]));
        let base = map.flex_joints()[0];
        assert_eq!((base.joint, base.damping_load_joint), (0, 1));
        assert_eq!(base.stiffness_nm_per_rad.per_nm2, 0.012);
        assert_eq!(base.damping_nms_per_rad.per_nm, 0.35);
        // Written back: the same document plus `metadata.payload: null`.
        let back = MapFile::parse(&file.to_json()).expect("round trip");
        assert_eq!(back, file);
        let mut expected: Value = serde_json::from_str(PYTHON_MODAL_FILE).expect("json");
        expected["metadata"]["payload"] = Value::Null;
        assert_eq!(file.to_value(), expected);
    }

    #[test]
    fn modal_errors_name_the_field_and_the_reason() {
        let text = PYTHON_MODAL_FILE;
        let cases = [
            (
                text.replacen("26000.0", r#""stiff""#, 1),
                "flex_joints[0].stiffness_nm_per_rad[0]: must be a number",
            ),
            (
                text.replacen("26000.0,", "", 1),
                "flex_joints[0].stiffness_nm_per_rad: must be [at_zero, per_nm, per_nm2]",
            ),
            (
                text.replacen(
                    r#""damping_load_joint": 1"#,
                    r#""damping_load_joint": -1"#,
                    1,
                ),
                "flex_joints[0].damping_load_joint: must be a joint index",
            ),
            (
                text.replacen(r#""joint": 0"#, r#""joint": 0, "gear": 1"#, 1),
                "flex_joints[0]: unknown field(s) gear",
            ),
            (
                text.replacen("26000.0", "-1.0", 1),
                "flex_joints: stiffness of joint 0",
            ),
            (
                text.replacen(r#""joint": 1"#, r#""joint": 0"#, 1),
                "flex_joints: flexible joint 0 is listed twice",
            ),
            (
                text.replacen("\n    1\n", "\n    4\n", 1),
                "mode_joints[1]: joint 4 must be one of the flexible joints [0, 1], named once",
            ),
            (
                text.replacen("\n    1\n", "\n    0\n", 1),
                "mode_joints[1]: joint 0 must be one of the flexible joints [0, 1], named once",
            ),
            (
                text.replace(r#""mode_joints""#, r#""modes""#),
                "(document): unknown field(s) modes",
            ),
            (
                text.replacen("0.012", "NaN", 1),
                "(document): not valid JSON",
            ),
        ];
        for (doc, expected) in cases {
            assert_ne!(doc, text, "{expected}");
            let msg = reason_of(&doc);
            assert!(msg.contains(expected), "{msg:?} lacks {expected:?}");
        }
        let without = text.replace(r#""robot": "ur5e""#, r#""robot": null"#);
        let file = MapFile::parse(&without).expect("no robot");
        assert_eq!(file.form().robot(), None);
    }

    #[test]
    fn a_modal_file_shaping_its_lowest_modes_reads_and_writes_back() {
        let text = PYTHON_MODAL_FILE.replacen(
            "\"mode_joints\": [\n    0,\n    1\n  ]",
            "\"shaped_modes\": 2",
            1,
        );
        assert_ne!(text, PYTHON_MODAL_FILE);
        let file = MapFile::parse(&text).expect("shaped_modes file");
        let map = file.form().as_modal().expect("modal");
        assert_eq!(map.shaped_modes(), &ShapedModes::Lowest(2));
        assert_eq!(map.mode_joints(), None);
        assert_eq!(map.n_modes(), 2);
        let written = file.to_value();
        assert_eq!(written["shaped_modes"], Value::from(2));
        assert!(written.get("mode_joints").is_none());
        assert_eq!(MapFile::parse(&file.to_json()).expect("round trip"), file);
        let cases = [
            (text.replacen("\"shaped_modes\": 2", "\"shaped_modes\": 3", 1), "shaped_modes: must be an integer from 1 to 2 (the number of flexible coordinates: joints plus two per link hinge), got 3"),
            (text.replacen("\"shaped_modes\": 2", "\"shaped_modes\": 0", 1), "shaped_modes: must be an integer from 1 to 2"),
            (text.replacen("\"shaped_modes\": 2", "\"shaped_modes\": 1.5", 1), "shaped_modes: must be an integer from 1 to 2"),
            (text.replacen("\"shaped_modes\": 2", "\"shaped_modes\": [0]", 1), "shaped_modes: must be an integer from 1 to 2"),
            (text.replacen("\"shaped_modes\": 2", "\"shaped_modes\": 2, \"mode_joints\": [0]", 1), "shaped_modes: give either mode_joints or shaped_modes, not both"),
            (text.replacen("\"shaped_modes\": 2,", "", 1), "mode_joints: missing: name the shaped modes"),
        ];
        for (doc, expected) in cases {
            assert_ne!(doc, text, "{expected}");
            let msg = reason_of(&doc);
            assert!(msg.contains(expected), "{msg:?} lacks {expected:?}");
        }
    }
}
