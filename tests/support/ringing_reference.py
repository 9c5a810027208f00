"""Independent generator of excitation logs in which several modes ring.

Built on :mod:`ident_reference` (off-grid ``movej``-like profile, exact integration, plain-numpy
DH kinematics, ur_rtde CSV writer) and more exact than the multi-mode estimator in what it
does not assume:

- each mode ``i`` is its own spring-damper ``ë_i + 2ζ_i ω_i ė_i + ω_i² e_i = -q̈(t)``,
  integrated exactly from every off-grid switch of the profile; a mode whose spring stiffens
  with deflection (a strain-wave gear, :class:`TrueRinging` ``stiffening``) by DOP853 at a
  relative tolerance of 1e-11;
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

#: A stiffening mode's deflection is "rated" where it carries this acceleration of the joint
#: (rad/s²): about a UR5e base gear's rated torque over a stretched arm's inertia.
RATED_ACCEL_RAD_S2 = 25.0


@dataclass(frozen=True)
class TrueRinging:
    """A mode of the generator: natural frequency (Hz, small signal), damping ratio, flange
    direction at the pose (unit, base frame), gain ``g`` (m/s² of flange acceleration per
    m/s² of modal deflection acceleration) and ``stiffening``: the factor by which the
    spring's tangent stiffness has grown at the deflection carrying
    :data:`RATED_ACCEL_RAD_S2` (1: a linear spring; a strain-wave gear 2-3)."""

    freq_hz: float
    zeta: float
    direction: tuple[float, float, float]
    gain: float
    stiffening: float = 1.0


def integrate_stiffening_mode(
    profile, wn: float, zeta: float, stiffening: float, t_out: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Deflection ``e`` and its rate at ``t_out`` for the hardening spring ``ë + 2ζω ė +
    ω² (e + κ e³) = -q̈(t)``, ``κ = (stiffening − 1) / (3 e_r²)``, ``e_r = a_r / ω²``
    (tangent stiffness ``ω² (1 + 3 κ e²)``): DOP853 at 1e-11 relative tolerance, restarted
    at every switch of the profile (the forcing is constant between switches)."""
    from scipy.integrate import solve_ivp

    e_r = RATED_ACCEL_RAD_S2 / wn**2
    kappa = (stiffening - 1.0) / (3.0 * e_r**2)
    origin = min(profile.times[0], t_out[0])
    switches, samples = profile.times - origin, t_out - origin
    _, _, u_after = profile.sample(profile.times)
    bounds = [0.0, *switches, max(samples[-1], switches[-1]) + 1e-9]
    forcing = [0.0, *u_after]
    out = np.zeros((t_out.size, 2))
    x = np.zeros(2)
    for k in range(len(bounds) - 1):
        lo, hi, u = bounds[k], bounds[k + 1], float(forcing[k])
        if hi <= lo:
            continue

        def rhs(_t, s, u=u):
            e, v = s
            return [v, -u - 2.0 * zeta * wn * v - wn**2 * (e + kappa * e**3)]

        sol = solve_ivp(
            rhs, (lo, hi), x, method="DOP853", rtol=1e-11, atol=1e-14, dense_output=True
        )
        inside = (samples >= lo) & (samples < hi)
        if inside.any():
            out[inside] = sol.sol(samples[inside]).T
        x = sol.y[:, -1]
    return out[:, 0], out[:, 1]


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
        if mode is None or mode.stiffening == 1.0:
            e, e_dot = integrate_mode(profile, wn, zeta, t_sensor)
            e_ddot = -qdd_s - 2.0 * zeta * wn * e_dot - wn**2 * e
        else:
            e, e_dot = integrate_stiffening_mode(profile, wn, zeta, mode.stiffening, t_sensor)
            kappa = (mode.stiffening - 1.0) / (3.0 * (RATED_ACCEL_RAD_S2 / wn**2) ** 2)
            e_ddot = -qdd_s - 2.0 * zeta * wn * e_dot - wn**2 * (e + kappa * e**3)
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
