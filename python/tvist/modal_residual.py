"""Which modes a move makes ring: predicted residual vibration per eigenmode, and the number
of lowest-frequency modes worth shaping (:func:`modes_to_shape`).

**Model** (the modal map's, :mod:`tvist.modal_map`). The motors follow the reference ``q_r(t)``
rigidly; the deflections ``δ`` of the flexible joints obey

    M_ff(q) δ'' + C(q) δ' + K(q) δ = −M_f·(q) q_r''(t)

with ``M_f·`` the rows of the link-side mass matrix on the flexible joints (the reference
acceleration of every joint drives them through the inertial coupling), ``K`` and ``C`` the
map's laws at the pose's gravity torques. Gravity-stiffness and velocity terms are neglected,
as in the map. Along the move the matrices are taken at each sample of the reference and held
over the sample period; the reference acceleration is interpolated linearly between samples
(exact for the jerk-limited profiles of :func:`tvist.trajectory.double_s`). Each period is
integrated exactly (matrix exponential), so the prediction has no step-size error beyond
holding the pose over 2 ms.

**Residual per mode.** At the end of the move the state ``(δ, δ')`` is split into the damped
eigenmodes of the end pose (eigenvectors of the first-order form): mode ``i`` contributes
``2 Re(c_i e^{λ_i t})`` to the flange's displacement, ``c_i = J_f ψ_i a_i`` with ``J_f`` the
translational flange Jacobian on the flexible joints, ``ψ_i`` the mode shape and ``a_i`` its
modal coordinate: a displacement amplitude ``2 |c_i|`` (m; the peak for motion along one
line, an upper bound of the peak otherwise). Its residual vibration is the acceleration
amplitude ``2 |λ_i|² |c_i|`` (m/s²), what a tool accelerometer measures and how tvist states
residual vibration (:mod:`tvist.analysis.residual`): it weighs a mode at twice the frequency
four times more than its displacement does. The unshaped total is the sum over modes, the
largest peak the superposition can reach. Overdamped (real) eigenvalues do not ring and are
left out.

**Rule.** A mode is significant if its residual exceeds ``threshold`` (1 %) of the unshaped
total; ``K`` is the smallest number of lowest-frequency modes that contains every significant
mode (at least 1): the ``shaped_modes`` of a frequency-ranked map or
``TvShaper.set_shaped_modes(K)`` for that move.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from tvist.robots import Robot
from tvist.trajectory import Trajectory, double_s

if TYPE_CHECKING:
    from tvist.modal_map import ModalMap

__all__ = ["DEFAULT_THRESHOLD", "ModeResidual", "ShapingChoice", "modes_to_shape"]

#: Share of the unshaped total above which a mode's residual vibration is significant.
DEFAULT_THRESHOLD = 0.01


@dataclass(frozen=True)
class ModeResidual:
    """One eigenmode of the flexible joints at the end pose and what the move leaves in it.

    Attributes
    ----------
    rank
        Position in frequency order (0: the lowest), as ``shaped_modes`` counts.
    wn_rad_s, zeta
        Natural frequency ``|λ|`` (rad/s) and damping ratio ``−Re λ / |λ|``.
    residual_m_s2
        Amplitude of the flange acceleration the mode rings with after the move, m/s².
    displacement_m
        The same as a flange displacement amplitude, m.
    fraction
        ``residual_m_s2`` over the unshaped total (the sum over modes).
    joint_shares
        Share of the mode's gear strain energy per flexible joint (map order), summing to 1.
    """

    rank: int
    wn_rad_s: float
    zeta: float
    residual_m_s2: float
    displacement_m: float
    fraction: float
    joint_shares: tuple[float, ...]

    @property
    def freq_hz(self) -> float:
        """Natural frequency, Hz."""
        return self.wn_rad_s / (2.0 * np.pi)


@dataclass(frozen=True)
class ShapingChoice:
    """The outcome of :func:`modes_to_shape`.

    Attributes
    ----------
    n_modes
        ``K``: shape the ``K`` lowest-frequency modes.
    modes
        Every oscillating eigenmode at the end pose, in frequency order.
    total_m_s2
        Unshaped total: the sum of the modes' residual acceleration amplitudes, m/s².
    threshold
        The significance threshold used (fraction of ``total_m``).
    """

    n_modes: int
    modes: tuple[ModeResidual, ...]
    total_m_s2: float
    threshold: float

    @property
    def significant(self) -> tuple[ModeResidual, ...]:
        """The modes above the threshold."""
        return tuple(m for m in self.modes if m.fraction > self.threshold)


def _flex_system(
    modal_map: ModalMap, robot: Robot, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per pose of ``q`` ``(n, n_dof)``: ``M_ff``, ``M_f·``, ``K``, ``C`` (diagonals) and
    the flange's translational Jacobian on the flexible joints."""
    joints = [int(f["joint"]) for f in modal_map.flex_joints]
    mass = robot.mass_matrix_many(q)
    laws = modal_map.core.joint_laws_many(np.ascontiguousarray(robot.gravity_torque_many(q)))
    jac = robot.jacobian_many(q)[:, :3, joints]
    m_f = mass[:, joints, :]
    return m_f[:, :, joints], m_f, laws[:, :, 0], laws[:, :, 1], jac


def _first_order(m_ff: np.ndarray, k: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``A`` of ``x' = A x`` for ``x = (δ, δ')`` (free vibration)."""
    n = m_ff.shape[0]
    m_inv = np.linalg.inv(m_ff)
    return np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv * k[None, :], -m_inv * c[None, :]]])


def _expm_many(m: np.ndarray) -> np.ndarray:
    """Matrix exponentials of a stack ``(n, d, d)``: scaling and squaring with a degree-16
    Taylor polynomial (for ``‖m / 2^s‖_1 <= 1/2`` its remainder is below 1e-20, far under
    rounding). Stacked products only: a few milliseconds for a thousand 12 × 12 matrices, where
    one library call per matrix can take milliseconds each on a machine whose cores are busy."""
    norm = np.abs(m).sum(axis=1).max(initial=0.0)
    s = max(0, int(np.ceil(np.log2(norm / 0.5))) if norm > 0 else 0)
    x = m / 2.0**s
    out = np.broadcast_to(np.eye(m.shape[1]), m.shape).copy()
    term = out.copy()
    for k in range(1, 17):
        term = term @ x / k
        out += term
    for _ in range(s):
        out = out @ out
    return out


def _state_after(traj: Trajectory, end: int, modal_map: ModalMap, robot: Robot) -> np.ndarray:
    """The state ``(δ, δ')`` at sample ``end`` of ``traj``, starting at rest at sample 0."""
    q = np.ascontiguousarray(traj.q[: end + 1])
    m_ff, m_f, k, c, _ = _flex_system(modal_map, robot, q)
    n = m_ff.shape[1]
    dt = traj.dt_s
    # z = (x, f, f') with f' constant over each period: the exact first-order hold of the
    # drive f, discretized per period with that period's matrices.
    m_inv = np.linalg.inv(m_ff[:end])
    big = np.zeros((end, 4 * n, 4 * n))
    big[:, :n, n : 2 * n] = np.eye(n)
    big[:, n : 2 * n, :n] = -m_inv * k[:end, None, :]
    big[:, n : 2 * n, n : 2 * n] = -m_inv * c[:end, None, :]
    big[:, n : 2 * n, 2 * n : 3 * n] = m_inv
    big[:, 2 * n : 3 * n, 3 * n :] = np.eye(n)
    phi = _expm_many(big * dt)
    f0 = -np.einsum("kij,kj->ki", m_f[:end], traj.qdd[:end])
    f1 = -np.einsum("kij,kj->ki", m_f[:end], traj.qdd[1 : end + 1])
    # What each period adds from its drive, then the free propagation, in order.
    forced = np.einsum("kij,kj->ki", phi[:, : 2 * n, 2 * n : 3 * n], f0)
    forced += np.einsum("kij,kj->ki", phi[:, : 2 * n, 3 * n :], (f1 - f0) / dt)
    x = np.zeros(2 * n)
    for i in range(end):
        x = phi[i, : 2 * n, : 2 * n] @ x + forced[i]
    return x


def modal_residuals(
    modal_map: ModalMap, robot: Robot, trajectory: Trajectory
) -> list[tuple[int, float, float, float, tuple[float, ...]]]:
    """Residual per oscillating eigenmode at the end of ``trajectory``'s motion:
    ``[(rank, wn_rad_s, zeta, displacement_m, joint_shares), ...]`` in frequency order (the
    flange displacement amplitude; its acceleration is ``wn_rad_s² ×`` that). See the module
    docs."""
    dt = trajectory.dt_s
    end = min(int(round(trajectory.t_motion_end_s / dt)), trajectory.n_samples - 1)
    x = _state_after(trajectory, end, modal_map, robot)
    m_ff, _, k, c, jac = _flex_system(modal_map, robot, trajectory.q[end][None, :])
    a = _first_order(m_ff[0], k[0], c[0])
    lam, vec = scipy.linalg.eig(a)
    coords = np.linalg.solve(vec, x.astype(complex))
    n = m_ff.shape[1]
    keep = np.flatnonzero(lam.imag > 1e-9 * np.abs(lam))
    keep = keep[np.argsort(np.abs(lam[keep]))]
    out = []
    for rank, i in enumerate(keep):
        shape = vec[:n, i]
        c_i = jac[0] @ shape * coords[i]
        energy = k[0] * np.abs(shape) ** 2
        out.append(
            (
                rank,
                float(abs(lam[i])),
                float(-lam[i].real / abs(lam[i])),
                float(2.0 * np.linalg.norm(c_i)),
                tuple(float(e) for e in energy / energy.sum()),
            )
        )
    return out


def modes_to_shape(
    modal_map: ModalMap,
    robot: Robot,
    trajectory: Trajectory | None = None,
    *,
    q_start: Sequence[float] | np.ndarray | None = None,
    q_end: Sequence[float] | np.ndarray | None = None,
    dt_s: float = 0.002,
    threshold: float = DEFAULT_THRESHOLD,
) -> ShapingChoice:
    """How many lowest-frequency modes to shape for one move (module docs).

    Parameters
    ----------
    modal_map
        The arm's modal map (its flexible joints and laws; how it names its modes is not read).
    robot
        The arm with its payload.
    trajectory
        The unshaped reference of the move; or ``q_start`` and ``q_end`` for the default
        jerk-limited move between them (:func:`tvist.trajectory.double_s` at ``dt_s``).
    threshold
        A mode is significant above this fraction of the unshaped total (default 1 %).

    Returns
    -------
    ShapingChoice
        ``n_modes`` (K) and the residual of every mode, for reporting.
    """
    if trajectory is None:
        if q_start is None or q_end is None:
            raise ValueError("give the move: a trajectory, or q_start and q_end")
        trajectory = double_s(q_start, q_end, dt_s=dt_s)
    elif q_start is not None or q_end is not None:
        raise ValueError("give the move once: a trajectory or q_start and q_end, not both")
    if not (0.0 <= threshold < 1.0):
        raise ValueError(f"threshold = {threshold}: must be a fraction in [0, 1)")
    if trajectory.n_dof != robot.n_dof:
        raise ValueError(f"the trajectory has {trajectory.n_dof} joints, the robot {robot.n_dof}")
    residuals = modal_residuals(modal_map, robot, trajectory)
    total = sum(wn * wn * d for _, wn, _, d, _ in residuals)
    modes = tuple(
        ModeResidual(
            rank, wn, zeta, wn * wn * d, d, wn * wn * d / total if total > 0 else 0.0, shares
        )
        for rank, wn, zeta, d, shares in residuals
    )
    significant = [m.rank for m in modes if m.fraction > threshold]
    n_modes = max(significant, default=0) + 1
    return ShapingChoice(n_modes, modes, total, threshold)
