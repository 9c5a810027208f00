"""Which modes a move makes ring: predicted residual vibration per eigenmode, and the number
of lowest-frequency modes worth shaping (:func:`modes_to_shape`).

**Model** (the modal map's, :mod:`tvist.maps.modal`). The motors follow the reference ``q_r(t)``
rigidly; the deflections ``δ`` of the flexible joints obey

    M_ff(q) δ'' + C(q) δ' + K(q) δ = −M_f·(q) q_r''(t) − h_f(q, q_r')

with ``M_f·`` the rows of the link-side mass matrix on the flexible joints (the reference
acceleration of every joint drives them through the inertial coupling), ``h_f`` the same rows of the
Coriolis and centrifugal torques ``h = C(q, q_r') q_r'`` of the reference (a base rotation swings
the upper arm outwards and so rings the shoulder, which the accelerations alone do not couple at
every pose), ``K`` and ``C`` the map's laws at the pose's gravity torques. Gravity stiffness and the
slow change of the static deflection under gravity along the move are neglected, as in the map.
``h`` comes from the mass matrix alone (Christoffel form, :func:`velocity_torque_many`).
With bending links (``link_hinges``) ``δ`` also holds the hinge angles (two per hinge, after
the joints: :func:`flex_coordinates`), the matrices are the hinged arm's with straight hinges
(:meth:`ModalMap.evaluated_arm`), ``M_f·`` its flexible rows on the robot's joints and ``h_f``
its Coriolis and centrifugal torques on the flexible coordinates with the hinges at rest; each
hinge is its map spring and damper on both axes. Along the
move the matrices are taken at each sample of the reference and held over the sample period; the
drive is interpolated linearly between samples (its acceleration part exactly so for the
jerk-limited profiles of :func:`tvist.trajectory.double_s`). Each period is integrated exactly
(matrix exponential), so the prediction has no step-size error beyond holding the pose over 2 ms.

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

**Rule.** A mode is significant if its residual exceeds ``threshold`` (1 %) of the unshaped total,
or if its frequency is within :data:`NEAR_RATIO` (10 %) of a significant mode's: how the model
splits a move's ringing between two such close modes turns on coupling a map a few per cent off does
not hold (on the twin a learned map put a base move's ringing wholly into its 7.8 Hz base mode and
none into the 8.2 Hz shoulder mode; shaping the lowest alone left 95.5 %, both 99.4 %), and a second
filter that close widens the first one's notch. ``K`` is the smallest number of lowest-frequency
modes that contains every significant mode (at least 1), raised where the map's own uncertainty
asks for more (below): the ``shaped_modes`` of a frequency-ranked map or
``TvShaper.set_shaped_modes(K)`` for that move.

**Robustness.** A mode is shaped at the map's frequency and damping, which are off by about the
map's fit error: the ZV filter then leaves part of the mode's ringing, and for a heavily damped
mode the part is large (a damping ratio 0.35 off by 9 % leaves 2.7 % of it). The filter of a
neighbouring mode widens the notch around it (two ZV filters 11 % apart leave 0.3 %). So with
``K`` lowest modes shaped the *expected residual* is ``E(K) = Σ_i fraction_i · V_K(i)``, where
``V_K(i)`` is the percentage residual vibration (:func:`tvist.prv`) of the convolved ZV filters of
the ``K`` lowest modes on mode ``i`` with its frequency and damping ratio moved by one standard
error of the map, the worst of the four corners; the standard errors are the map fit's relative
RMS errors (``fit_statistics`` ``frequency_error_matched`` and ``damping_error_matched`` of
:func:`tvist.ident.fit_all_modes`), or :data:`DEFAULT_UNCERTAINTY` for a map without them.
``K`` is at least the smallest with ``E(K) <= threshold``; where no ``K`` reaches it, the smallest
within ``threshold`` of the lowest ``E`` (a further mode must lower it by more than that to be
worth its delay).

**Following the pose or holding the stop's modes** (:func:`set_modes_for_move`). The
time-varying shaper designs each cycle's filters for the modes where the arm is. Where the
modes change fast in a move's final deceleration (two modes veering near the stop), the
ringing left after the stop can exceed what the stop pose's modes, held over the move, leave:
on a variant arm a move kept 92.8 % with the modes followed and 99.5 % with them held. The
same exact integration predicts both: the move is shaped offline both ways
(``TvShaper.fresh_copy``), the map's model is driven with each shaped reference, and the
residual at the stop is summed over the modes as above. The stop pose's modes are held
(``TvShaper.hold_modes_at``) where following the pose is predicted to leave more than
``threshold`` of the unshaped total beyond what holding leaves; otherwise the shaper follows
the pose, as the published method does. Both shape the same ``K`` modes, so the delay at the
stop is the same. A reference that stops inside (several moves in one file) follows the pose:
holding one stop's modes would mistune the others.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg

from tvist.robots import Robot
from tvist.robots._robot import HingedArm
from tvist.trajectory._types import Trajectory
from tvist.trajectory.double_s import double_s

if TYPE_CHECKING:
    from tvist.maps.modal import ModalMap

__all__ = [
    "DEFAULT_THRESHOLD",
    "DEFAULT_UNCERTAINTY",
    "NEAR_RATIO",
    "ModeResidual",
    "ShapingChoice",
    "modes_to_shape",
    "set_modes_for_move",
    "flex_coordinates",
    "map_uncertainty",
    "velocity_torque_many",
]

#: Share of the unshaped total above which a mode's residual vibration is significant.
DEFAULT_THRESHOLD = 0.01
#: A mode within this relative frequency distance of a significant mode is significant too.
NEAR_RATIO = 0.10
#: Relative standard errors (natural frequency, damping ratio) of a map that does not state its
#: own: the largest a confident local identification has (``max_wn_rel_se`` and
#: ``max_zeta_rel_se`` of :class:`tvist.ident.local_fit.FitOptions`).
DEFAULT_UNCERTAINTY = (0.01, 0.10)
#: The shaper the robustness rule assumes for every mode (the time-varying shaper's default).
ROBUST_SHAPER = "zv"


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
        Share of the mode's strain energy per flexible coordinate (the map's joints in map
        order, then two per link hinge: :func:`flex_coordinates`), summing to 1.
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
    expected
        ``E(K)`` for ``K = 1 … len(modes)``: the expected residual with the ``K`` lowest modes
        shaped, a fraction of the unshaped total (module docs, robustness).
    uncertainty
        The map's relative standard errors (frequency, damping ratio) ``expected`` assumes.
    hold_end_pose
        True if the shaper holds the end pose's modes over the move instead of following
        the pose (:func:`set_modes_for_move`; module docs).
    predicted
        ``(following, holding)``: the residual the map predicts after the move shaped with the
        modes followed and with the end pose's modes held, fractions of ``total_m_s2``
        (``None`` where :func:`set_modes_for_move` did not compare them).
    """

    n_modes: int
    modes: tuple[ModeResidual, ...]
    total_m_s2: float
    threshold: float
    expected: tuple[float, ...] = ()
    uncertainty: tuple[float, float] = DEFAULT_UNCERTAINTY
    hold_end_pose: bool = False
    predicted: tuple[float, float] | None = None

    @property
    def significant(self) -> tuple[ModeResidual, ...]:
        """The significant modes: above the threshold, or within :data:`NEAR_RATIO` in
        frequency of a mode above it (module docs)."""
        above = [m.wn_rad_s for m in self.modes if m.fraction > self.threshold]
        return tuple(
            m for m in self.modes if any(abs(m.wn_rad_s / w - 1.0) <= NEAR_RATIO for w in above)
        )

    @property
    def n_significant(self) -> int:
        """The smallest number of lowest modes that holds every significant mode (at least
        1): ``K`` before the robustness rule raises it (module docs)."""
        return max((m.rank for m in self.significant), default=0) + 1


def flex_coordinates(modal_map: ModalMap, arm: Robot | HingedArm) -> list[int]:
    """Indices in ``arm`` (:meth:`ModalMap.evaluated_arm`) of the map's flexible coordinates,
    in the core's order: the map's flexible joints, then two per link hinge in link order."""
    joints = [int(f["joint"]) for f in modal_map.flex_joints]
    if not isinstance(arm, HingedArm):
        return joints
    return [int(arm.joint_index[j]) for j in joints] + [int(i) for i in arm.hinge_index]


def _flex_system(
    modal_map: ModalMap, robot: Robot, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per pose of ``q`` ``(n, n_robot)``: ``M_ff``, ``M_f·`` (the flexible rows on the
    robot's joints), ``K``, ``C`` (diagonals) and the flange's translational Jacobian on the
    flexible coordinates (:func:`flex_coordinates`), of the arm the map evaluates."""
    arm = modal_map.evaluated_arm(robot)
    coords = flex_coordinates(modal_map, arm)
    joints = arm.joint_index if isinstance(arm, HingedArm) else np.arange(robot.n_dof)
    mass = arm.mass_matrix_many(q)
    # The joint laws read the robot's gravity torques by joint (straight hinges leave them
    # as the rigid arm's); each hinge carries its constant spring and damper on both axes.
    laws = modal_map.core.joint_laws_many(np.ascontiguousarray(robot.gravity_torque_many(q)))
    hinges = modal_map.link_hinges
    k_h = np.repeat([float(h["stiffness_nm_per_rad"]) for h in hinges], 2)
    c_h = np.repeat([float(h["damping_nms_per_rad"]) for h in hinges], 2)
    n = q.shape[0]
    stiffness = np.concatenate([laws[:, :, 0], np.broadcast_to(k_h, (n, k_h.size))], axis=1)
    damping = np.concatenate([laws[:, :, 1], np.broadcast_to(c_h, (n, c_h.size))], axis=1)
    jac = arm.jacobian_many(q)[:, :3, coords]
    m_f = mass[:, coords, :]
    return m_f[:, :, coords], m_f[:, :, joints], stiffness, damping, jac


#: Step of the central differences of the mass matrix, rad. The truncation error is of order
#: the step squared (about 1e-12 relative), the rounding error 1e-16 / step (1e-10 relative).
_DIFF_STEP_RAD = 1e-6


def velocity_torque_many(
    robot: Robot | HingedArm, q: np.ndarray, qd: np.ndarray, rows: Sequence[int]
) -> np.ndarray:
    """Coriolis and centrifugal torques ``h = M'(q) q' − ½ ∂(q'ᵀ M q')/∂q`` (N m) in joints
    ``rows``, per pose of ``q``, ``qd`` ``(n, n_robot)``: ``(n, len(rows))``. Central
    differences of the mass matrix: along ``q'`` for ``M' q'``, along each joint of ``rows``
    for the gradient (:data:`_DIFF_STEP_RAD`). For a hinged arm
    (:meth:`tvist.Robot.with_link_hinges`), ``rows`` index its coordinates (hinges included)
    and the hinges are straight and at rest: the torques the robot's motion puts on the
    hinges, which bend them."""
    q = np.asarray(q, dtype=float)
    qd = np.asarray(qd, dtype=float)
    if isinstance(robot, HingedArm):
        q, qd = robot.coordinates(q), robot.coordinates(qd)
        mass = robot.mass_matrix_bent_many
    else:
        mass = robot.mass_matrix_many
    h = _DIFF_STEP_RAD
    rows = list(rows)

    def at(x: np.ndarray) -> np.ndarray:
        return mass(np.ascontiguousarray(x))

    m_dot = (at(q + h * qd) - at(q - h * qd)) / (2.0 * h)  # M' = Σ_k ∂M/∂q_k q'_k
    out = np.einsum("kij,kj->ki", m_dot[:, rows, :], qd)
    for col, i in enumerate(rows):
        step = np.zeros(q.shape[1])
        step[i] = h
        d_mass = (at(q + step) - at(q - step)) / (2.0 * h)
        out[:, col] -= 0.5 * np.einsum("ki,kij,kj->k", qd, d_mass, qd)
    return out


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
    arm = modal_map.evaluated_arm(robot)
    drive = np.einsum("kij,kj->ki", m_f, traj.qdd[: end + 1])
    drive += velocity_torque_many(arm, q, traj.qd[: end + 1], flex_coordinates(modal_map, arm))
    f0, f1 = -drive[:end], -drive[1 : end + 1]
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
    dt_s: float | None = None,
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
        jerk-limited move between them (:func:`tvist.trajectory.double_s` at ``dt_s``, s;
        ``None``: the robot's control period,
        :attr:`~tvist.robots.RobotParams.control_period_s`).
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
        trajectory = double_s(q_start, q_end, dt_s=robot.params.sample_period_s(dt_s))
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
    uncertainty = map_uncertainty(modal_map)
    robust, expected = _robust_n_modes(modes, uncertainty, threshold)
    n_modes = max(ShapingChoice(1, modes, total, threshold).n_significant, robust)
    return ShapingChoice(n_modes, modes, total, threshold, tuple(expected), uncertainty)


def map_uncertainty(modal_map: ModalMap) -> tuple[float, float]:
    """Relative standard errors (natural frequency, damping ratio) of ``modal_map``'s modes:
    the RMS errors its fit states (``metadata["fit_statistics"]``), or
    :data:`DEFAULT_UNCERTAINTY` where it states none."""
    stats = (modal_map.metadata or {}).get("fit_statistics") or {}
    out = []
    for key, default in zip(
        ("frequency_error_matched", "damping_error_matched"), DEFAULT_UNCERTAINTY, strict=True
    ):
        rms = (stats.get(key) or {}).get("rms")
        out.append(float(rms) if rms is not None and math.isfinite(rms) else default)
    return out[0], out[1]


def _robust_n_modes(
    modes: Sequence[ModeResidual], uncertainty: tuple[float, float], threshold: float
) -> tuple[int, list[float]]:
    """The ``K`` the robustness rule asks for (module docs; 1 without modes) and ``E(K)`` for
    ``K = 1 … len(modes)``."""
    expected = _expected_residuals(modes, uncertainty)
    if not expected:
        return 1, expected
    reached = [k for k, e in enumerate(expected, 1) if e <= threshold]
    if reached:
        return reached[0], expected
    best = min(expected)
    return next(k for k, e in enumerate(expected, 1) if e <= best + threshold), expected


def _expected_residuals(
    modes: Sequence[ModeResidual], uncertainty: tuple[float, float]
) -> list[float]:
    """``E(K)`` for ``K = 1 … len(modes)`` (module docs, robustness): fractions of the
    unshaped total."""
    import tvist

    if not modes:
        return []
    sigma_wn, sigma_zeta = uncertainty
    corners = np.array([(a, b) for a in (-1.0, 1.0) for b in (-1.0, 1.0)])
    out = []
    filters: list = []
    for k in range(len(modes)):
        filters.append(tvist.shaper(ROBUST_SHAPER, modes[k].wn_rad_s, min(modes[k].zeta, 0.99)))
        combined = tvist.convolve(*filters)
        total = 0.0
        for m in modes:
            wn = m.wn_rad_s * (1.0 + sigma_wn * corners[:, 0])
            zeta = np.clip(m.zeta * (1.0 + sigma_zeta * corners[:, 1]), 0.0, 0.99)
            total += m.fraction * float(np.nanmax(tvist.prv(combined, wn, zeta)))
        out.append(total)
    return out


def set_modes_for_move(
    shaper: Any, provider: Any, move: Trajectory | np.ndarray, dt_s: float | None = None
) -> ShapingChoice | None:
    """Before shaping ``move`` with ``shaper`` (between moves: at rest), shape the modes that
    move needs: for a shaper driven by a frequency-ranked modal map (``provider`` a
    :class:`tvist.ModalDynamics` whose map has ``shaped_modes``), ``shaper.set_shaped_modes(K)``
    with ``K`` from :func:`modes_to_shape` for the move, and ``shaper.hold_modes_at`` the move's
    end pose where the map predicts that holding its modes leaves less ringing than following
    the pose (module docs). The one place the commands (``tvist shape``, ``tvist run``) and the
    demo rows choose per move.

    ``move``: the move's :class:`~tvist.trajectory.Trajectory`, or its reference samples
    ``(n_samples, n_dof)`` on the grid ``dt_s`` (velocity and acceleration by differences, the
    move ending at its last change). Returns the choice, or ``None`` (nothing changed) for any
    other provider or map. ``K`` is at most the map's own ``shaped_modes``.
    """
    from tvist.maps.modal import ModalMap

    modal = getattr(provider, "dynmap", None)
    if not isinstance(modal, ModalMap) or modal.shaped_modes is None:
        return None
    if not isinstance(move, Trajectory):
        if dt_s is None:
            raise ValueError("give dt_s with a move given as samples")
        move = _trajectory_of_samples(np.asarray(move, dtype=float), dt_s)
    choice = modes_to_shape(modal, provider.robot, move)
    k = min(choice.n_modes, modal.shaped_modes)
    shaper.set_shaped_modes(k)
    total = choice.total_m_s2
    if total <= 0 or _stops_inside(move.q):
        # Nothing rings, or one stop's modes would mistune the others: follow the pose.
        return dataclasses.replace(choice, n_modes=k)
    end_pose = np.ascontiguousarray(move.q[-1])
    following = _predicted_residual(shaper.fresh_copy(), modal, provider.robot, move)
    trial = shaper.fresh_copy()
    trial.hold_modes_at(end_pose)
    holding = _predicted_residual(trial, modal, provider.robot, move)
    hold = following - holding > choice.threshold * total
    if hold:
        shaper.hold_modes_at(end_pose)
    predicted = (following / total, holding / total)
    return dataclasses.replace(choice, n_modes=k, hold_end_pose=hold, predicted=predicted)


def _stops_inside(q: np.ndarray) -> bool:
    """True if the reference ``q`` ``(n_samples, n_dof)`` stands still for
    :data:`~tvist.units.MIN_REST_SAMPLES` samples or more between its first and last change:
    several moves, each stopping at its own pose."""
    from tvist.units import MIN_REST_SAMPLES

    moving = np.any(np.diff(q, axis=0) != 0.0, axis=1)
    changes = np.flatnonzero(moving)
    if changes.size == 0:
        return False
    inside = moving[changes[0] : changes[-1] + 1]
    still = np.flatnonzero(np.diff(np.concatenate([[1], inside.astype(int), [1]])))
    runs = still[1::2] - still[::2]  # lengths of the runs of unchanged samples
    return bool(runs.size) and int(runs.max()) >= MIN_REST_SAMPLES


def _predicted_residual(shaper: Any, modal_map: ModalMap, robot: Robot, move: Trajectory) -> float:
    """The residual acceleration (m/s², summed over the modes) the map predicts after ``move``
    shaped by ``shaper`` (unstarted; the move held at its end until every delay line can
    only read the end pose)."""
    q = np.ascontiguousarray(move.q)
    tail = math.ceil(sum(shaper.max_delay_s) / move.dt_s) + 3
    shaped = np.asarray(shaper.shape(np.vstack([q, np.repeat(q[-1:], tail, axis=0)])))
    reference = _trajectory_of_samples(shaped, move.dt_s)
    return sum(wn * wn * d for _, wn, _, d, _ in modal_residuals(modal_map, robot, reference))


def _trajectory_of_samples(q: np.ndarray, dt_s: float) -> Trajectory:
    """A :class:`~tvist.trajectory.Trajectory` of reference samples ``q`` on the grid ``dt_s``:
    central differences for velocity and acceleration, moving from the last sample within
    :data:`tvist.REST_TOLERANCE` of its first to the first from which every sample is within
    it of its last (as the experiments measure a stop, ``STOP_TOL_RAD``).

    Not the last change of any size: a shaper at rest may toggle the last bits of its output
    (about 1e-16 rad), which put the end of a shaped move at the end of its tail, and the
    ringing after it was judged there, after it had decayed (on development variant 2 of
    :mod:`tvist.sim.family`, Q3→Q1's following was predicted to leave 0.05 % instead of
    3.9 %, and the stop's modes were not held)."""
    from tvist import REST_TOLERANCE

    if q.ndim != 2 or q.shape[0] < 3:
        raise ValueError(f"a move needs samples (n_samples >= 3, n_dof), got {q.shape}")
    qd = np.gradient(q, dt_s, axis=0)
    qdd = np.gradient(qd, dt_s, axis=0)
    left = np.flatnonzero(np.max(np.abs(q - q[0]), axis=1) > REST_TOLERANCE)
    away = np.flatnonzero(np.max(np.abs(q - q[-1]), axis=1) > REST_TOLERANCE)
    first = int(left[0]) - 1 if left.size else 0
    last = int(away[-1]) + 1 if away.size else 0
    t = np.arange(q.shape[0]) * dt_s
    return Trajectory(
        t_s=t,
        q=q,
        qd=qd,
        qdd=qdd,
        dt_s=dt_s,
        t_motion_start_s=float(t[first]),
        t_motion_end_s=float(t[last]),
    )
