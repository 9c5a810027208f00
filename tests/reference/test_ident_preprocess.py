"""Accelerometer preprocessing (eqs. 12-13) against an analytic rigid-arm reference."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ident_reference import dh_frames as reference_dh_frames
from tvist.ident.excitation import random_excitation
from tvist.ident.logs import Record
from tvist.ident.preprocess import quiet_samples, standstill_length, tangential_acceleration
from tvist.robots import params, ur5e

#: The UR5e's control period, s (its robot data).
UR5E_DT_S = params("ur5e").control_period_s

G_UP = np.array([0.0, 0.0, 9.81])  # reading of an accelerometer at rest: reaction to gravity


def dh_frames(q: np.ndarray) -> list[np.ndarray]:
    """Base-frame transforms of the UR5e's DH frames 0..6 (the plain-numpy standard-DH
    reference), each shaped like ``q``: (4, 4) for ``q`` of shape (6,), else (n_samples, 4, 4).
    """
    q = np.asarray(q, dtype=float)
    return [f.reshape(q.shape[:-1] + (4, 4)) for f in reference_dh_frames(q, "ur5e")]


class NumpyUR5e:
    """Independent kinematics: FK by DH products, Jacobian by central differences."""

    def flange_pose_many(self, q: np.ndarray) -> np.ndarray:
        return dh_frames(q)[-1]

    def jacobian_many(self, q: np.ndarray) -> np.ndarray:
        out = np.zeros((len(q), 6, 6))
        h = 1e-6
        for j in range(6):
            dq = np.zeros(6)
            dq[j] = h
            p_plus = dh_frames(q + dq)[-1][:, :3, 3]
            p_minus = dh_frames(q - dq)[-1][:, :3, 3]
            out[:, :3, j] = (p_plus - p_minus) / (2 * h)
        return out


def robots():
    return [pytest.param(NumpyUR5e(), id="numpy-dh"), pytest.param(ur5e(), id="tvist-core")]


def rigid_record(joint: int, q0: np.ndarray, seed: int, tilt_offset=(0.0, 0.0, 0.0)):
    """A rigid arm following an excitation exactly; the sensor reads Rᵀ (a + g_up) + offset.

    For a rotation about a fixed axis z through o, the flange acceleration is
    ``q̈ z×(p-o) + q̇² z×(z×(p-o))``; its tangential part is ``|z×(p-o)| q̈``.
    """
    ex = random_excitation(q0, joint, seed=seed, duration_s=2.0, dt_s=UR5E_DT_S)
    n = ex.t_s.size
    accel = np.zeros((n, 3))
    radius = np.zeros(n)
    for k in range(n):
        frames = dh_frames(ex.q[k])
        z, o = frames[joint][:3, 2], frames[joint][:3, 3]
        r_vec = np.cross(z, frames[-1][:3, 3] - o)
        radius[k] = np.linalg.norm(r_vec)
        a_base = ex.qdd[k, joint] * r_vec + ex.qd[k, joint] ** 2 * np.cross(z, r_vec)
        accel[k] = frames[-1][:3, :3].T @ (a_base + G_UP) + np.asarray(tilt_offset)
    rec = Record(
        t_s=ex.t_s,
        target_q=ex.q,
        target_qd=ex.qd,
        target_qdd=ex.qdd,
        actual_q=ex.q,
        tool_accel=accel,
    )
    return rec, radius * ex.qdd[:, joint], radius


@pytest.mark.parametrize("robot", robots())
@pytest.mark.parametrize("joint", [0, 1])
def test_rigid_arm_gives_radius_times_joint_acceleration(robot, joint):
    q0 = np.array([0.4, -1.9, 1.2, -0.8, 1.3, 0.5])
    rec, expected, radius = rigid_record(joint, q0, seed=joint)
    out = tangential_acceleration(rec, joint, robot)
    # Every wait between moves is used for gravity, not only the leading 250 samples.
    quiet = quiet_samples(rec)
    assert standstill_length(rec) == 250 and quiet[:250].all()
    assert out.standstill_samples == np.count_nonzero(quiet) > 250
    still = np.all(rec.target_qd == 0.0, axis=1) & np.all(rec.target_qdd == 0.0, axis=1)
    assert np.all(quiet[still])  # every exact standstill (all waits here are >= 0.1 s) ...
    peak_v, peak_a = np.max(np.abs(rec.target_qd)), np.max(np.abs(rec.target_qdd))
    # ... and nothing faster than 2 % of the log's peak speed and acceleration
    assert np.all(np.abs(rec.target_qd[quiet]) <= 0.02 * peak_v)
    assert np.all(np.abs(rec.target_qdd[quiet]) <= 0.02 * peak_a)
    np.testing.assert_allclose(out.gravity_base, G_UP, atol=1e-9)
    np.testing.assert_allclose(out.radius_m, radius, rtol=1e-6)
    # Finite-difference Jacobian (1e-6 step) limits agreement to ~1e-8 relative.
    np.testing.assert_allclose(out.psi, expected, atol=1e-6 * np.max(np.abs(expected)))
    np.testing.assert_array_equal(out.target_qdd, rec.target_qdd[:, joint])


def test_sensor_offset_is_removed_with_gravity():
    q0 = np.array([0.0, -1.2, 1.0, -1.4, 1.57, 0.0])
    rec, expected, _ = rigid_record(0, q0, seed=3, tilt_offset=(0.0, 0.0, 0.0))
    # A constant offset in the *base* frame (e.g. a tilted mounting) is removed exactly;
    # emulate it by adding a base-frame offset rotated into the sensor frame.
    offset_base = np.array([0.3, -0.2, 0.1])
    rot = NumpyUR5e().flange_pose_many(rec.actual_q)[:, :3, :3]
    shifted = replace(rec, tool_accel=rec.tool_accel + np.einsum("nji,j->ni", rot, offset_base))
    out = tangential_acceleration(shifted, 0, NumpyUR5e())
    np.testing.assert_allclose(out.gravity_base, G_UP + offset_base, atol=1e-9)
    np.testing.assert_allclose(out.psi, expected, atol=1e-6 * np.max(np.abs(expected)))


def test_base_frame_readings_are_not_rotated():
    q0 = np.array([0.0, -1.2, 1.0, -1.4, 1.57, 0.0])
    rec, expected, _ = rigid_record(1, q0, seed=4)
    rot = NumpyUR5e().flange_pose_many(rec.actual_q)[:, :3, :3]
    in_base = np.einsum("nij,nj->ni", rot, rec.tool_accel)
    rec_base = replace(rec, tool_accel=in_base)
    out = tangential_acceleration(rec_base, 1, NumpyUR5e(), accel_frame="base")
    np.testing.assert_allclose(out.psi, expected, atol=1e-6 * np.max(np.abs(expected)))


def test_missing_standstill_is_an_error():
    q0 = np.array([0.0, -1.2, 1.0, -1.4, 1.57, 0.0])
    rec, _, _ = rigid_record(0, q0, seed=5)
    # A joint that never stops: a slow sine on the wrist over the whole log.
    t = rec.t_s
    qd = rec.target_qd.copy()
    qdd = rec.target_qdd.copy()
    qd[:, 5] = 0.5 * np.cos(2 * np.pi * t)
    qdd[:, 5] = -np.pi * np.sin(2 * np.pi * t)
    moving = replace(rec, target_qd=qd, target_qdd=qdd)
    with pytest.raises(ValueError, match="at least 10 samples of standstill.*found [0-9]"):
        tangential_acceleration(moving, 0, NumpyUR5e())


def test_a_flange_frame_sensor_bias_is_separated_from_gravity():
    """A bias fixed in the sensor does not rotate with the flange; the quiet samples at the
    different shoulder angles between moves separate it from gravity."""
    q0 = np.array([0.0, -1.2, 1.0, -1.4, 1.57, 0.0])
    bias = np.array([0.2, -0.15, 0.3])
    rec, expected, _ = rigid_record(1, q0, seed=3, tilt_offset=bias)
    out = tangential_acceleration(rec, 1, NumpyUR5e())
    # Only the bias across the shoulder axis is separable: along the axis it reads the same
    # at every shoulder angle, like a horizontal gravity component along that axis would.
    axis = (dh_frames(q0)[1][:3, :3].T @ dh_frames(q0)[-1][:3, :3]).T @ np.array([0, 0, 1.0])
    across = bias - (bias @ axis) * axis
    found = out.sensor_bias - (out.sensor_bias @ axis) * axis
    # Exact data; the ridge (1e-6 per sample) against the small spread of orientations
    # (±10°, (0.17 rad)² ≈ 3e-2) shrinks the bias by ~1e-4 of itself.
    np.testing.assert_allclose(found, across, atol=1e-4)
    # Either split removes the bias from ψ exactly.
    np.testing.assert_allclose(out.psi, expected, atol=1e-6 * np.max(np.abs(expected)))


def test_flange_on_the_joint_axis_is_an_error():
    class OnAxis(NumpyUR5e):
        """Flange 1 mm from joint 1's axis (tangent of length 1 mm)."""

        def jacobian_many(self, q):
            jac = super().jacobian_many(q)
            jac[:, :3, 1] *= 1e-3 / np.linalg.norm(jac[:, :3, 1], axis=1)[:, None]
            return jac

    q0 = np.array([0.0, -1.2, 1.0, -1.4, 1.57, 0.0])
    rec, _, _ = rigid_record(1, q0, seed=6)
    with pytest.raises(ValueError, match="1.0 mm from the axis of joint 1"):
        tangential_acceleration(rec, 1, OnAxis())
    with pytest.raises(ValueError, match="joint"):
        tangential_acceleration(rec, 7, NumpyUR5e())


def flexible_record(joint: int, q0: np.ndarray, wn: float, zeta: float, seed: int, noise=0.1):
    """Like :func:`rigid_record`, but the tangential acceleration rings through a mode
    ``r (2ζω s + ω²)/(s² + 2ζω s + ω²)`` (eq. 16), plus 20 dB sensor noise on every axis."""
    from ident_reference import Profile, integrate_mode

    ex = random_excitation(q0, joint, seed=seed, dt_s=UR5E_DT_S)
    n = ex.t_s.size
    rng = np.random.default_rng(seed)
    radius = np.zeros(n)
    tangent = np.zeros((n, 3))
    normal = np.zeros((n, 3))
    rot = np.zeros((n, 3, 3))
    for k in range(n):
        frames = dh_frames(ex.q[k])
        z, o = frames[joint][:3, 2], frames[joint][:3, 3]
        r_vec = np.cross(z, frames[-1][:3, 3] - o)
        radius[k] = np.linalg.norm(r_vec)
        tangent[k] = r_vec / radius[k]
        normal[k] = ex.qd[k, joint] ** 2 * np.cross(z, r_vec)
        rot[k] = frames[-1][:3, :3]
    # The mode integrated exactly by the independent generator (ident_reference), from the
    # excitation's piecewise-constant acceleration: ψ = r θ̈ of the deflected link.
    profile = Profile(ex.t_s, ex.qdd[:-1, joint], float(ex.q[0, joint]))
    e, e_dot = integrate_mode(profile, wn, zeta, ex.t_s)
    psi = radius[0] * (-2 * zeta * wn * e_dot - wn**2 * e)
    a_base = psi[:, None] * tangent + normal
    accel = np.einsum("nji,nj->ni", rot, a_base + G_UP)
    accel += rng.normal(0.0, noise * np.sqrt(np.mean(psi**2)), accel.shape)
    rec = Record(
        t_s=ex.t_s,
        target_q=ex.q,
        target_qd=ex.qd,
        target_qdd=ex.qdd,
        actual_q=ex.q,
        tool_accel=accel,
    )
    return rec


@pytest.mark.parametrize("joint", [0, 1])
def test_identify_local_end_to_end(joint):
    from tvist.ident.local_identification import identify_local

    q0 = np.array([0.3, -1.7, 1.4, -1.2, 1.57, 0.0])
    wn, zeta = 2 * np.pi * (9.0 + 6 * joint), 0.06 + 0.1 * joint
    rec = flexible_record(joint, q0, wn, zeta, seed=20 + joint)
    fit = identify_local(rec, joint, ur5e())
    # Same tolerances as the synthetic acceptance (1 % in ω_n, 5 % in ζ).
    assert fit.wn_rad_s == pytest.approx(wn, rel=0.01)
    assert fit.zeta == pytest.approx(zeta, rel=0.05)
    assert not fit.low_confidence, fit.reason
    assert fit.joint == joint


def test_identify_local_saturation_is_flagged_or_rejected():
    from tvist.ident.local_identification import identify_local

    q0 = np.array([0.3, -1.7, 1.4, -1.2, 1.57, 0.0])
    wn, zeta = 2 * np.pi * 12.0, 0.05
    rec = flexible_record(0, q0, wn, zeta, seed=30)

    def clipped(level_quantile: float) -> Record:
        accel = rec.tool_accel.copy()
        dev = accel[:, 0] - np.median(accel[:, 0])
        level = np.quantile(np.abs(dev), level_quantile)
        accel[:, 0] = np.median(accel[:, 0]) + np.clip(dev, -level, level)
        return replace(rec, tool_accel=accel)

    few = identify_local(clipped(0.995), 0, NumpyUR5e())  # 0.5 % of samples clipped
    assert few.low_confidence and "saturated" in few.reason
    assert few.n_used < few.n_samples
    assert few.wn_rad_s == pytest.approx(wn, rel=0.01)  # clipped samples were excluded
    with pytest.raises(ValueError, match="saturated"):
        identify_local(clipped(0.8), 0, NumpyUR5e())  # 20 % clipped: unusable


def test_identify_local_resamples_gappy_logs_with_a_warning():
    from tvist.ident.local_identification import identify_local
    from tvist.ident.logs import LogWarning

    q0 = np.array([0.3, -1.7, 1.4, -1.2, 1.57, 0.0])
    wn = 2 * np.pi * 12.0
    rec = flexible_record(0, q0, wn, 0.05, seed=31)
    gappy = rec.select(np.r_[0:1000, 1010 : rec.n_samples])
    with pytest.warns(LogWarning, match="10 of .* samples filled"):
        fit = identify_local(gappy, 0, NumpyUR5e())
    assert fit.wn_rad_s == pytest.approx(wn, rel=0.01)
