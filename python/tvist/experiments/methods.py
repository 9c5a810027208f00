"""The rows of the experiment: how each method turns the planned move into the sent reference.

A :class:`Method` builds the reference of one motion from a :class:`MotionContext`. The
default rows are :func:`default_methods`; more rows are added by appending to that list, for
example a map identified on the twin with :func:`fd_tvist_map` (the CLI's ``--map`` option)::

    identified = DynamicMap.load("map.json")
    methods = [*default_methods(), fd_tvist_map("my-map", "FD-TVIST ZV, my map", identified)]
    run_demo(methods=methods)

``run_demo()`` (``tvist demo``) adds such a row itself from a reduced mapping campaign on the
twin (:mod:`tvist.experiments.identified`) unless ``identify=False`` (``--no-identify``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

import tvist
from tvist.experiments.fixed import fixed_robust_row, fixed_start_row
from tvist.experiments.method_row import Method, MotionContext, Reference
from tvist.maps.modal import ModalMap
from tvist.maps.paper10 import DynamicMap, MapDynamics
from tvist.robots import Robot

#: Shaper of the FD-TVIST rows: one ZV filter per mode, base then shoulder, like the paper.
TVIST_SHAPER = "zv"
#: Shaper of the zero-delay rows: the same two-mode ZV, so that they remove exactly the delay
#: the FD-TVIST rows add and differ from them only in how (see the report).
ZERO_DELAY_SHAPER = "zv"
#: Delay lines of a callable provider hold this multiple of the longest one-mode ZV delay seen
#: along the motion (the spec's SF ≈ 1.5).
DELAY_SAFETY_FACTOR = 1.5


def _unshaped(ctx: MotionContext) -> Reference:
    return Reference(np.array(ctx.trajectory.q), {"shaper": None})


def _run_tv_shaper(
    shaper: Any, ctx: MotionContext, provider_name: str, provider: Any = None
) -> Reference:
    """Shapes the motion with ``shaper``; with ``provider`` (the shaper's) a frequency-ranked
    modal map shapes the modes this move needs, following the pose or holding the stop's
    modes (:func:`tvist.maps.set_modes_for_move`)."""
    from tvist.maps import set_modes_for_move

    q = np.ascontiguousarray(ctx.trajectory.q)
    set_modes_for_move(shaper, provider, ctx.trajectory)
    shaper.reset(np.ascontiguousarray(q[0]))
    shaped = np.array(shaper.shape(q))
    counts = dict(shaper.status_counts)
    # Clamped delays, held modes or unshaped samples would make the row meaningless. A clamped
    # ζ and a bound slew limit (the modes followed at the limit's rate: still shaped, with
    # the filter a few cycles behind the provider) do not; both stay in ``status_counts``.
    tolerated = ("zeta_clamped", "mode_slew_limited")
    trouble = {k: n for k, n in counts.items() if n and k not in tolerated}
    if trouble:
        raise RuntimeError(
            f"{provider_name} on {ctx.motion.name}: the shaper reported {trouble} "
            "(delay lines too short, or invalid modes from the provider)"
        )
    return Reference(
        shaped,
        {
            "shaper": f"{TVIST_SHAPER} x {shaper.n_modes} modes (FD-TVIST cascade)",
            "provider": provider_name,
            "delay_at_end_pose_s": float(shaper.delay_s),
            # The modes shaped at the end pose (the shaper is at rest there): their delay.
            "end_modes": [(float(w), float(z)) for w, z in shaper.current_modes],
            # The stop pose's modes held over the move (set_modes_for_move) or followed.
            "held_at_end_pose": shaper.held_pose is not None,
            "status_counts": counts,
        },
    )


def _fd_tvist_truth(ctx: MotionContext) -> Reference:
    # The twin's eigen-analysis as a per-cycle provider: the best any map could do.
    shaper = tvist.TvShaper(
        ctx.twin.modes,
        ctx.trajectory.dt_s,
        ctx.trajectory.n_dof,
        shaper=TVIST_SHAPER,
        max_delay_s=DELAY_SAFETY_FACTOR * ctx.max_mode_delay_s,
    )
    return _run_tv_shaper(shaper, ctx, "twin eigen-analysis (ground truth)")


def fd_tvist_map(key: str, label: str, dynmap: DynamicMap) -> Method:
    """A two-mode ZV FD-TVIST row driven by ``dynmap`` through :class:`tvist.MapDynamics`.

    This is the real-time path: every cycle the Rust robot model evaluates ``J_0, J_1`` at the
    previous shaped output and the map turns them into modes.
    """

    def build(ctx: MotionContext) -> Reference:
        provider = MapDynamics(ctx.robot, dynmap)
        shaper = tvist.TvShaper(
            provider, ctx.trajectory.dt_s, ctx.trajectory.n_dof, shaper=TVIST_SHAPER
        )
        source = dynmap.metadata.get("source") or "dynamic map"
        ref = _run_tv_shaper(shaper, ctx, f"MapDynamics: {source}", provider)
        return Reference(ref.q, {**ref.details, "map_use": map_use(dynmap, ctx.robot, ref.q)})

    return Method(key=key, label=label, build=build, dynmap=dynmap)


def fd_tvist_modal(key: str, label: str, modal: ModalMap) -> Method:
    """A ZV FD-TVIST row driven by ``modal`` through :class:`tvist.ModalDynamics` (a
    frequency-ranked map shapes the modes each move needs)."""

    def build(ctx: MotionContext) -> Reference:
        provider = tvist.ModalDynamics(ctx.robot, modal)
        shaper = tvist.TvShaper(
            provider, ctx.trajectory.dt_s, ctx.trajectory.n_dof, shaper=TVIST_SHAPER
        )
        source = modal.metadata.get("source") or "modal map"
        return _run_tv_shaper(shaper, ctx, f"MapDynamics (modal): {source}", provider)

    # ``dynmap`` only needs ``modes(robot, q)`` (the mode tracks of the report).
    return Method(key=key, label=label, build=build, dynmap=modal)  # type: ignore[arg-type]


def map_use(dynmap: DynamicMap, robot: Robot, q: np.ndarray) -> dict[str, list]:
    """How a map is evaluated along the reference ``q`` ``(n_samples, n_dof)`` it shaped.

    Returns, per mode: ``inertia_clamped_percent``, the share of samples at which an inertia
    it reads lies outside its identified range (the map then holds the value at the bound),
    and ``gravity_sign_changes``, how often the gravity torque its ``k_g |τ|`` term reads
    changes sign (``0`` without that term). Both put a kink into the modes along the move.
    """
    q = np.ascontiguousarray(q, dtype=float)
    inertia = robot.joint_inertia_many(q)
    tau = robot.gravity_torque_many(q) if dynmap.uses_gravity else None
    clamped = [float(v) for v in 100.0 * np.mean(dynmap.outside_range(inertia), axis=0)]
    sign_changes = []
    for mode in dynmap.mode_maps:
        changes = 0
        if tau is not None and mode["k_g"] != 0.0:
            sign = np.sign(tau[:, mode["frequency_joint"]])
            sign = sign[sign != 0]
            changes = int(np.count_nonzero(np.diff(sign)))
        sign_changes.append(changes)
    return {"inertia_clamped_percent": clamped, "gravity_sign_changes": sign_changes}


#: Why the rows on the twin's exact modes cannot run on a robot.
ORACLE_TRUE_MODES = "reads the twin's exact modes every cycle (no robot offers them)"
ORACLE_END_POSE_MODES = (
    "is designed on the twin's exact modes at the end pose, before the arm gets there "
    "(on a robot they come from a map)"
)


def zero_delay_row(
    key: str,
    label: str,
    method: str,
    motions: Sequence[str] | None,
    dynmap: DynamicMap | None = None,
) -> Method:
    """A zero-delay row (``method`` ``"modified"`` or ``"ztdis"``) with two modes at the end
    pose, :data:`ZERO_DELAY_SHAPER`: the twin's exact modes (an oracle row), or those of
    ``dynmap`` (anything with ``modes(robot, q)``, e.g. an identified map: a row a user can
    run). ``motions=None`` runs it on every motion.

    Only the move itself (without the rest padding) is compressed; the rest before and after
    is kept, so the reference stops when the planned one does.
    """

    def build(ctx: MotionContext) -> Reference:
        traj = ctx.trajectory
        first = int(round(traj.t_motion_start_s / traj.dt_s))
        last = int(round(traj.t_motion_end_s / traj.dt_s))
        if dynmap is None:
            modes = ctx.twin.modes(ctx.motion.q_end)
            provider = "twin eigen-analysis at the end pose (time-invariant)"
        else:
            modes = dynmap.modes(ctx.robot, ctx.motion.q_end)
            source = dynmap.metadata.get("source") or "dynamic map"
            provider = f"{source}, at the end pose (time-invariant)"
        result = tvist.zero_delay(
            traj.q[first : last + 1], traj.dt_s, modes, shaper=ZERO_DELAY_SHAPER, method=method
        )
        q = np.array(traj.q)
        q[first : last + 1] = result.Q
        # The rest after the move is the end pose itself; what truncation at T leaves out is
        # result.tail_error (reported), a few nanoradians.
        q[last + 1 :] = ctx.motion.q_end
        return Reference(
            q,
            {
                "shaper": f"{ZERO_DELAY_SHAPER} x {len(modes)} modes ({method})",
                "provider": provider,
                "alpha": result.alpha,
                "shaper_delay_removed_s": result.delay_s,
                "tail_error_rad": result.tail_error,
                "modes": [list(m) for m in modes],
            },
        )

    return Method(
        key=key,
        label=label,
        build=build,
        motions=None if motions is None else tuple(motions),
        oracle=ORACLE_END_POSE_MODES if dynmap is None else None,
    )


#: Motions with zero-delay rows: the two that end in the low-frequency pose Q1/Q2.
ZERO_DELAY_MOTIONS = ("Q1->Q2", "Q3->Q1")


def default_methods() -> list[Method]:
    """The rows of the experiment, unshaped first (the baseline of the reduction)."""
    return [
        Method("unshaped", "Unshaped", _unshaped),
        Method(
            "fd-tvist-truth",
            "FD-TVIST ZV, true modes",
            _fd_tvist_truth,
            oracle=ORACLE_TRUE_MODES,
        ),
        fd_tvist_map("fd-tvist-paper-map", "FD-TVIST ZV, paper map", DynamicMap.paper_ur5e()),
        zero_delay_row(
            "modified",
            "Modified ZTDIS ZV, end-pose modes",
            "modified",
            ZERO_DELAY_MOTIONS,
        ),
        zero_delay_row("ztdis", "ZTDIS ZV, end-pose modes", "ztdis", ZERO_DELAY_MOTIONS),
        *_fixed_rows(),
    ]


def _fixed_rows() -> list[Method]:
    """The time-invariant baselines (:mod:`tvist.experiments.fixed`)."""
    return [fixed_start_row(), fixed_robust_row()]
