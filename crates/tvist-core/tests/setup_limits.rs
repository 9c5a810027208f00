//! Setup refuses what would abort the process or silently give wrong numbers: channel and
//! delay-line memory limits, overflowing payloads, maps of another robot; and a mode above the
//! Nyquist frequency is reported in every cycle.

use tvist_core::files::robot_data::ur_e_series;
use tvist_core::limits::{MAX_DELAY_LINE_BYTES, MAX_DOF};
use tvist_core::{
    ConstantModes, DynamicMap, Error, MapDynamics, Mode, RigidBody, ShaperKind, Status, TvShaper,
    TvShaperConfig,
};

fn constant(wn: f64, zeta: f64) -> ConstantModes {
    ConstantModes::new(vec![Mode::new(wn, zeta)]).expect("valid mode")
}

#[test]
fn channels_beyond_the_limit_are_refused() {
    let config = TvShaperConfig::new(0.002, MAX_DOF + 1, ShaperKind::Zv);
    let err = TvShaper::new(constant(40.0, 0.1), &config).expect_err("too many channels");
    assert!(matches!(err, Error::TooLarge(_)), "{err}");
    let config = TvShaperConfig::new(0.002, MAX_DOF, ShaperKind::Zv);
    assert!(TvShaper::new(constant(40.0, 0.1), &config).is_ok());
}

#[test]
fn delay_lines_beyond_the_memory_limit_are_refused() {
    // A ZV shaper for 0.1 rad/s undamped lasts pi/0.1 = 31.4 s; x 1.5 at 100 kHz that is
    // 4.7e6 samples per channel: 154 GB over 4096 channels, 38 MB for one.
    let config = TvShaperConfig::new(1e-5, 4096, ShaperKind::Zv);
    let err = TvShaper::new(constant(0.1, 0.0), &config).expect_err("154 GB");
    assert!(err.to_string().contains("256 MiB"), "{err}");
    let one = TvShaperConfig::new(1e-5, 1, ShaperKind::Zv);
    assert!(TvShaper::new(constant(0.1, 0.0), &one).is_ok());
    // The limit is on the sum over the cascade: 8 such modes on 1 channel are 300 MB.
    let eight = ConstantModes::new(vec![Mode::new(0.1, 0.0); 8]).expect("modes");
    let err = TvShaper::new(eight, &one).expect_err("300 MB");
    assert!(matches!(err, Error::TooLarge(_)), "{err}");
    assert_eq!(MAX_DELAY_LINE_BYTES, 1 << 28);
}

#[test]
fn a_mode_above_nyquist_is_flagged_every_cycle() {
    let dt_s = 0.002; // Nyquist: pi / dt = 1570.8 rad/s
    for (wn, flagged) in [(1e4, true), (1571.0, true), (1570.0, false), (40.0, false)] {
        let config = TvShaperConfig::new(dt_s, 1, ShaperKind::Zv);
        let mut shaper = TvShaper::new(constant(wn, 0.0), &config).expect("shaper");
        let mut y = [0.0];
        for k in 0..5 {
            let status = shaper.step(&[k as f64], &mut y);
            assert_eq!(status.contains(Status::MODE_ABOVE_NYQUIST), flagged, "{wn}");
            assert!(y[0].is_finite());
        }
    }
}

#[test]
fn a_payload_that_overflows_the_inertias_is_refused() {
    for com in [[1e200, 0.0, 0.0], [0.0, 0.0, -1e160]] {
        let err = ur_e_series("ur5e", RigidBody::point(5.0, com)).expect_err("overflow");
        assert!(err.to_string().contains("non-finite"), "{err}");
    }
    let mut robot = ur_e_series("ur5e", RigidBody::point(5.0, [0.0, 0.0, 0.05])).expect("robot");
    assert!(robot
        .set_payload(RigidBody::point(5.0, [1e200, 0.0, 0.0]))
        .is_err());
    assert_eq!(
        robot.payload().com_m,
        [0.0, 0.0, 0.05],
        "unchanged after a refusal"
    );
    let mut j = [0.0; 6];
    robot.joint_inertia(&[0.0; 6], &mut j);
    assert!(j.iter().all(|v| v.is_finite()));
}

#[test]
fn a_map_of_another_robot_is_refused_naming_both() {
    let ur10e = ur_e_series("ur10e", RigidBody::point(5.0, [0.0, 0.0, 0.05])).expect("robot");
    let err = MapDynamics::new(ur10e.clone(), DynamicMap::paper_ur5e()).expect_err("mismatch");
    assert_eq!(
        err,
        Error::RobotMismatch {
            map_robot: "ur5e".into(),
            robot: "ur10e".into()
        }
    );
    let msg = err.to_string();
    assert!(msg.contains("ur5e") && msg.contains("ur10e"), "{msg}");
    assert!(MapDynamics::new_allowing_other_robot(ur10e.clone(), DynamicMap::paper_ur5e()).is_ok());
    let ur10e_map = DynamicMap::new(DynamicMap::paper_ur5e().mode_maps().to_vec())
        .expect("map")
        .for_robot("ur10e");
    assert!(MapDynamics::new(ur10e, ur10e_map).is_ok());
}
