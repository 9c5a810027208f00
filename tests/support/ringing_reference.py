"""Independent generator of excitation logs in which several modes ring.

Built on :mod:`ident_reference` (off-grid ``movej``-like profile, exact integration, plain-numpy
DH kinematics, ur_rtde CSV writer) and more exact than the multi-mode estimator in what it
does not assume:

- each mode ``i`` is its own spring-damper ``ë_i + 2ζ_i ω_i ė_i + ω_i² e_i = -q̈(t)``,
  integrated exactly from every off-grid switch of the profile;
- the flange acceleration (base frame) is the rigid arm's (tangential ``q̈ z×(p-o)`` and
  centripetal ``q̇² z×(z×(p-o))`` at the motor angle) plus ``Σ_i g_i d_i(t) ë_i(t)``: mode ``i``
  moves the flange along ``d_i`` (unit, base frame at the pose), turned with the excited joint
  as it swings (rotation about the joint's axis). A stiff remainder mode beyond the band
  (``fast_hz``) carries the rest of the lever, ``z×(p-o) - Σ_i g_i d_i``, so that the flange
  acceleration is continuous where the motor's acceleration steps (a flexible arm's link
  does not follow a step of its motor at once);
- the accelerometer is sampled with timing jitter (uniform, each sample) around the log's
  timestamps, reads in the tool frame with the reaction to gravity, a constant bias and white
  noise, and is written as ur_rtde CSV.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ident_reference import G_UP, dh_frames, integrate_mode, random_profile, write_ur_rtde_csv


@dataclass(frozen=True)
class TrueRinging:
    """A mode of the generator: natural frequency (Hz), damping ratio, flange direction at
    the pose (unit, base frame) and gain ``g`` (m/s² of flange acceleration per m/s² of
    modal deflection acceleration)."""

    freq_hz: float
    zeta: float
    direction: tuple[float, float, float]
    gain: float


def _rotate(v: np.ndarray, axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """``v`` (3,) turned by ``angle`` (n,) about the unit ``axis`` (Rodrigues), (n, 3)."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return v * c + np.cross(axis, v) * s + np.outer(1.0 - c[:, 0], axis) * float(axis @ v)


def generate_ringing_log(
    path: Path,
    *,
    seed: int,
    joint: int,
    q0: np.ndarray,
    modes: list[TrueRinging],
    dt_s: float = 0.002,
    noise_m_s2: float = 0.03,
    jitter_s: float = 0.00002,
    duration_s: float = 8.0,
    robot_name: str = "ur5e",
    fast_hz: float = 250.0,
    fast_zeta: float = 0.7,
) -> Path:
    """Write one excitation log of ``joint`` at ``q0`` in which ``modes`` ring."""
    rng = np.random.default_rng(seed)
    q0 = np.asarray(q0, dtype=float)
    t0 = rng.uniform(1000.0, 2000.0)
    first_move = t0 + 0.5 + rng.uniform(0.0, dt_s)  # standstill, then an off-grid start
    profile = random_profile(rng, float(q0[joint]), first_move, duration_s)
    n = int(math.ceil((profile.times[-1] + 1.0 - t0) / dt_s)) + 1
    t_log = t0 + dt_s * np.arange(n)
    t_sensor = t_log + rng.uniform(-jitter_s, jitter_s, n)

    q_ref, qd_ref, qdd_ref = profile.sample(t_log)
    q_s, qd_s, qdd_s = profile.sample(t_sensor)
    q_motor = np.tile(q0, (n, 1))
    q_motor[:, joint] = q_s
    frames = dh_frames(q_motor, robot_name)
    z, o = frames[joint][:, :3, 2], frames[joint][:, :3, 3]
    p_flange, rot = frames[-1][:, :3, 3], frames[-1][:, :3, :3]
    lever = np.cross(z, p_flange - o)
    a_base = qdd_s[:, None] * lever + qd_s[:, None] ** 2 * np.cross(z, lever)
    axis = dh_frames(q0[None], robot_name)[joint][0, :3, 2]
    swing = q_s - q0[joint]
    remainder = lever.copy()
    for mode in [*modes, None]:
        freq, zeta = (fast_hz, fast_zeta) if mode is None else (mode.freq_hz, mode.zeta)
        wn = 2.0 * math.pi * freq
        e, e_dot = integrate_mode(profile, wn, zeta, t_sensor)
        e_ddot = -qdd_s - 2.0 * zeta * wn * e_dot - wn**2 * e
        if mode is None:
            a_base += e_ddot[:, None] * remainder
            continue
        d = np.asarray(mode.direction, dtype=float)
        path_dir = mode.gain * _rotate(d / np.linalg.norm(d), axis, swing)
        a_base += e_ddot[:, None] * path_dir
        remainder -= path_dir
    reading = np.einsum("nji,nj->ni", rot, a_base + G_UP)
    reading += rng.normal(0.0, 0.05, 3) + rng.normal(0.0, noise_m_s2, (n, 3))

    target_q = np.tile(q0, (n, 1))
    target_qd = np.zeros((n, 6))
    target_qdd = np.zeros((n, 6))
    target_q[:, joint], target_qd[:, joint], target_qdd[:, joint] = q_ref, qd_ref, qdd_ref
    return write_ur_rtde_csv(
        path,
        t_log,
        {
            "target_q": target_q,
            "target_qd": target_qd,
            "target_qdd": target_qdd,
            "actual_q": target_q.copy(),  # motor encoders
            "actual_tool_accelerometer": reading,
        },
    )
