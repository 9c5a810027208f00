"""Independent generator of identification logs, sharing none of the estimator's assumptions.

- The motion is a continuous-time bang-coast-bang profile (``movej``-like) whose acceleration
  switches at arbitrary real times, off the log's sampling grid; the log's clock starts at an
  arbitrary controller time.
- The mode is a spring-damper between motor and link, ``ë + 2ζω ė + ω² e = -q̈(t)`` for the link
  deflection ``e = θ - q``, integrated exactly (matrix exponential of the augmented system,
  ``scipy.linalg.expm``) from every switch to every sample instant.
- The flange acceleration comes from the robot's kinematics (standard DH in plain numpy, not
  the library's model) for the link angle ``θ``: tangential ``θ̈ z×(p-o)`` plus centripetal
  ``θ̇² z×(z×(p-o))``. The accelerometer reads it in the tool frame of the deflected link, with
  the reaction to gravity, a constant bias and white noise (20 dB below the tangential
  signal), sampled ``sensor_lag_s`` after (or before) the log's timestamp.
- The encoders (``actual_q``) see the motor, not the deflected link.
- The log is written by its own writer in the ur_rtde CSV format (comma-separated, 6 decimals,
  RTDE column names in recording order) to a real file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tvist.robots import params

G_UP = np.array([0.0, 0.0, 9.81])  # reading of an accelerometer at rest: reaction to gravity


def dh_frames(q: np.ndarray, robot_name: str = "ur5e") -> list[np.ndarray]:
    """Base-frame transforms of DH frames 0..6 (standard DH), shape (n, 4, 4) each."""
    p = params(robot_name)
    batch = np.asarray(q, dtype=float).reshape(-1, 6)
    frames = [np.broadcast_to(np.eye(4), (len(batch), 4, 4))]
    for i, (d, a, alpha) in enumerate(zip(p.d_m, p.a_m, p.alpha_rad, strict=True)):
        c, s = np.cos(batch[:, i]), np.sin(batch[:, i])
        ca, sa = math.cos(alpha), math.sin(alpha)
        step = np.zeros((len(batch), 4, 4))
        step[:, 0] = np.column_stack([c, -s * ca, s * sa, a * c])
        step[:, 1] = np.column_stack([s, c * ca, -c * sa, a * s])
        step[:, 2] = [0.0, sa, ca, d]
        step[:, 3] = [0.0, 0.0, 0.0, 1.0]
        frames.append(frames[-1] @ step)
    return frames


@dataclass(frozen=True)
class Profile:
    """Piecewise-constant acceleration: ``accel[i]`` on ``[times[i], times[i+1])``, zero
    before ``times[0]`` and after ``times[-1]``; starts at rest at ``q_start``."""

    times: np.ndarray
    accel: np.ndarray
    q_start: float

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Exact position, velocity and acceleration at times ``t``."""
        t = np.asarray(t, dtype=float)
        # velocity and position at each breakpoint
        dt = np.diff(self.times)
        v = np.concatenate([[0.0], np.cumsum(self.accel * dt)])
        x = self.q_start + np.concatenate(
            [[0.0], np.cumsum(v[:-1] * dt + 0.5 * self.accel * dt**2)]
        )
        i = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 1)
        inside = (t >= self.times[0]) & (t < self.times[-1])
        a = np.where(inside, np.append(self.accel, 0.0)[i], 0.0)
        tau = np.where(t >= self.times[0], t - self.times[i], 0.0)
        vel = np.where(t >= self.times[0], v[i] + a * tau, 0.0)
        pos = np.where(t >= self.times[0], x[i] + v[i] * tau + 0.5 * a * tau**2, self.q_start)
        return pos, vel, a


def random_profile(
    rng: np.random.Generator, q_start: float, t_first_s: float, duration_s: float
) -> Profile:
    """Random trapezoidal moves (±10°, 0.5-2 rad/s, 0.3-7 rad/s², waits 0.1-1 s), with the
    switch times wherever the drawn limits put them (no rounding to any grid)."""
    times, accel = [t_first_s], []
    t, q = t_first_s, q_start
    while t < t_first_s + duration_s:
        target = q_start + rng.uniform(-math.pi / 18, math.pi / 18)
        v, a = rng.uniform(0.5, 2.0), rng.uniform(0.3, 7.0)
        dist, sign = abs(target - q), math.copysign(1.0, target - q)
        if dist >= v * v / a:
            t_acc, t_coast = v / a, dist / v - v / a
        else:
            t_acc, t_coast = math.sqrt(dist / a), 0.0
        for length, value in ((t_acc, sign * a), (t_coast, 0.0), (t_acc, -sign * a)):
            t += length
            times.append(t)
            accel.append(value)
        wait = rng.uniform(0.1, 1.0)
        t += wait
        times.append(t)
        accel.append(0.0)
        q = target
    return Profile(np.array(times), np.array(accel), q_start)


def _expm(m: np.ndarray) -> np.ndarray:
    """Matrix exponential by eigendecomposition (the augmented matrix is diagonalisable for
    ζ < 1); checked against ``scipy.linalg.expm`` in the tests."""
    lam, vec = np.linalg.eig(m)
    return (vec @ np.diag(np.exp(lam)) @ np.linalg.inv(vec)).real


def integrate_mode(
    profile: Profile, wn: float, zeta: float, t_out: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Exact deflection ``e`` and its rate at ``t_out`` for ``ë + 2ζω ė + ω² e = -q̈(t)``."""
    a_mat = np.array([[0.0, 1.0], [-(wn**2), -2.0 * zeta * wn]])

    # Times relative to the first event, so equal steps compare equal (the log's clock is large).
    origin = min(profile.times[0], t_out[0])
    switches, samples = profile.times - origin, t_out - origin
    _, _, u_after = profile.sample(profile.times)  # the acceleration from each switch on
    events = sorted(
        [(t, 0, i) for i, t in enumerate(switches)] + [(t, 1, k) for k, t in enumerate(samples)]
    )
    x = np.zeros(3)
    x[2] = 1.0
    out = np.zeros((t_out.size, 2))
    u = 0.0
    t_prev = 0.0
    cache: dict[tuple[int, float], np.ndarray] = {}
    for t, kind, i in events:
        h = t - t_prev
        if h > 0:
            key = (round(h * 1e12), u)
            if key not in cache:
                m = np.zeros((3, 3))
                m[:2, :2] = a_mat
                m[1, 2] = -u  # forcing -q̈, constant over the step
                cache[key] = _expm(m * h)
            x = cache[key] @ x
            t_prev = t
        if kind == 0:
            u = float(u_after[i])
        else:
            out[i] = x[:2]
    return out[:, 0], out[:, 1]


@dataclass(frozen=True)
class GeneratedLog:
    path: Path
    joint: int
    q0: np.ndarray
    wn_rad_s: float
    zeta: float
    sensor_lag_s: float
    dt_s: float


RECORDED = (
    ("target_q", 6),
    ("target_qd", 6),
    ("target_qdd", 6),
    ("actual_q", 6),
    ("actual_tool_accelerometer", 3),
)


def write_ur_rtde_csv(
    path: Path, t_s: np.ndarray, columns: dict[str, np.ndarray], sep: str = ","
) -> Path:
    """ur_rtde ``startFileRecording`` layout: header of RTDE names, 6 decimals, commas
    (``sep=" "``: UR's own ``record.py`` client, space-separated)."""
    header = ["timestamp"]
    blocks = [t_s[:, None]]
    for name, width in RECORDED:
        header += [f"{name}_{i}" for i in range(width)]
        blocks.append(columns[name])
    table = np.hstack(blocks)
    with path.open("w", encoding="utf-8") as fh:
        fh.write(sep.join(header) + "\n")
        for row in table:
            fh.write(sep.join(f"{v:.6f}" for v in row) + "\n")
    return path


def generate_log(
    path: Path,
    *,
    seed: int,
    joint: int,
    wn_rad_s: float,
    zeta: float,
    q0: np.ndarray,
    dt_s: float = 0.002,
    snr_db: float = 20.0,
    sensor_lag_s: float = 0.0,
    duration_s: float = 8.0,
    robot_name: str = "ur5e",
    hover_rad_s: float = 0.0,
    skip_fraction: float = 0.0,
    sep: str = ",",
) -> GeneratedLog:
    """Write one excitation log of ``joint`` at pose ``q0`` (see the module docstring).

    ``hover_rad_s`` adds the slow hovering of a real controller's target velocities (every
    joint, amplitude in rad/s); ``skip_fraction`` drops that fraction of the rows at random
    (skipped samples); ``sep=" "`` writes UR's ``record.py`` format."""
    rng = np.random.default_rng(seed)
    t0 = rng.uniform(1000.0, 2000.0)  # controller clock at the first sample
    first_move = t0 + 0.5 + rng.uniform(0.0, dt_s)  # standstill, then an off-grid start
    profile = random_profile(rng, float(q0[joint]), first_move, duration_s)
    n = int(math.ceil((profile.times[-1] - t0) / dt_s)) + 1
    t_log = t0 + dt_s * np.arange(n)

    q_ref, qd_ref, qdd_ref = profile.sample(t_log)
    t_sensor = t_log - sensor_lag_s
    q_s, qd_s, qdd_s = profile.sample(t_sensor)
    e, e_dot = integrate_mode(profile, wn_rad_s, zeta, t_sensor)
    theta = q_s + e
    theta_dot = qd_s + e_dot
    theta_ddot = -2.0 * zeta * wn_rad_s * e_dot - wn_rad_s**2 * e  # = q̈ + ë

    q_link = np.tile(q0, (n, 1))
    q_link[:, joint] = theta
    frames = dh_frames(q_link, robot_name)
    z, o = frames[joint][:, :3, 2], frames[joint][:, :3, 3]
    p_flange, rot = frames[-1][:, :3, 3], frames[-1][:, :3, :3]
    lever = np.cross(z, p_flange - o)
    a_base = theta_ddot[:, None] * lever + theta_dot[:, None] ** 2 * np.cross(z, lever)
    reading = np.einsum("nji,nj->ni", rot, a_base + G_UP)
    tangential_rms = float(np.sqrt(np.mean((theta_ddot * np.linalg.norm(lever, axis=1)) ** 2)))
    noise = tangential_rms * 10.0 ** (-snr_db / 20.0)
    reading += rng.normal(0.0, 0.1, 3) + rng.normal(0.0, noise, (n, 3))

    target_q = np.tile(q0, (n, 1))
    target_qd = np.zeros((n, 6))
    target_qdd = np.zeros((n, 6))
    target_q[:, joint], target_qd[:, joint], target_qdd[:, joint] = q_ref, qd_ref, qdd_ref
    actual_q = target_q.copy()  # motor encoders: the reference, not the deflected link
    if hover_rad_s:
        phase = rng.uniform(0.0, 2 * math.pi, 6)
        slow = np.sin(2 * math.pi * 0.7 * (t_log - t0)[:, None] + phase)
        target_qd = target_qd + hover_rad_s * slow
        target_qdd = target_qdd + hover_rad_s * rng.normal(0.0, 1.0, target_qdd.shape)
    keep = np.ones(n, dtype=bool)
    if skip_fraction:
        keep[1:-1] = rng.uniform(size=n - 2) >= skip_fraction
    write_ur_rtde_csv(
        path,
        t_log[keep],
        {
            "target_q": target_q[keep],
            "target_qd": target_qd[keep],
            "target_qdd": target_qdd[keep],
            "actual_q": actual_q[keep],
            "actual_tool_accelerometer": reading[keep],
        },
        sep=sep,
    )
    return GeneratedLog(path, joint, np.asarray(q0, float), wn_rad_s, zeta, sensor_lag_s, dt_s)


def random_case(folder: Path, seed: int, dt_s: float = 0.002) -> GeneratedLog:
    """A seeded case: mode 5-40 Hz, ζ 0.02-0.4 (log-uniform), base or shoulder, a random
    pose, a sensor timing offset of -1 ... +3 ms, 20 dB."""
    rng = np.random.default_rng([77, seed])
    wn = 2 * math.pi * rng.uniform(5.0, 40.0)
    zeta = math.exp(rng.uniform(math.log(0.02), math.log(0.4)))
    joint = seed % 2
    q0 = np.array(
        [
            rng.uniform(-math.pi, math.pi),
            rng.uniform(-2.4, -0.7),
            rng.uniform(0.6, 2.2),
            rng.uniform(-2.0, -1.0),
            rng.uniform(1.0, 2.0),
            rng.uniform(-math.pi, math.pi),
        ]
    )
    return generate_log(
        folder / f"case_{seed:03d}.csv",
        seed=seed,
        joint=joint,
        wn_rad_s=wn,
        zeta=zeta,
        q0=q0,
        dt_s=dt_s,
        sensor_lag_s=rng.uniform(-0.001, 0.003),
    )


def mode_signals(
    seed: int,
    wn_rad_s: float,
    zeta: float,
    *,
    dt_s: float = 0.002,
    duration_s: float = 8.0,
    snr_db: float | None = 20.0,
    radius_m: float = 0.6,
    sensor_lag_s: float = 0.0,
    max_moves: int | None = None,
    point_samples: bool = False,
    tail_s: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Fit input and output without the kinematics: the interval-mean acceleration of the
    off-grid profile (``point_samples``: its value at each sample instant instead), and
    ``radius_m θ̈`` of the exactly integrated mode (plus white noise ``snr_db`` below it;
    ``None`` for none). ``max_moves`` limits the number of moves; ``tail_s`` adds standstill
    at the end."""
    rng = np.random.default_rng([91, seed])
    profile = random_profile(rng, 0.0, 0.5 + rng.uniform(0.0, dt_s), duration_s)
    if max_moves is not None:
        keep = 1 + 4 * max_moves  # each move: accelerate, coast, decelerate, wait
        profile = Profile(profile.times[:keep], profile.accel[: keep - 1], 0.0)
    n = int(math.ceil((profile.times[-1] + tail_s) / dt_s)) + 1
    t = dt_s * np.arange(n)
    _, qd, qdd = profile.sample(t)
    u = qdd if point_samples else np.append(np.diff(qd) / dt_s, 0.0)
    e, e_dot = integrate_mode(profile, wn_rad_s, zeta, t - sensor_lag_s)
    y = radius_m * (-2.0 * zeta * wn_rad_s * e_dot - wn_rad_s**2 * e)
    if snr_db is not None:
        y = y + rng.normal(0.0, float(np.sqrt(np.mean(y**2))) * 10.0 ** (-snr_db / 20.0), n)
    return u, y, dt_s
