"""Every identified mode of a campaign's poses, with what the robot model says of each pose.

A pose record (:mod:`tvist.ident.pose`) lists in ``ringing`` every mode that rang after the
base and the shoulder excitation, each with its flange direction (base frame) where the log
had three axes. Older records have only ``modes`` (one per excitation log, no direction):
those are read as ringing entries without a direction. Entries flagged ``low_confidence`` are
left out unless asked for.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tvist.robots import Robot, params

__all__ = ["ObservedModes", "observed_modes"]


#: Where along a bending link its model hinge pair sits (fraction of its length): the middle.
HINGE_AT_FRACTION = 0.5


@dataclass(frozen=True)
class ObservedModes:
    """Poses (``n``) and their identified modes (``k``, flattened over poses).

    Attributes
    ----------
    q, mass_kg_m2, gravity_torque_nm, jacobian
        Per pose ``(n, n_robot)``, ``(n, n_dof, n_dof)``, ``(n, n_dof)``, ``(n, 6, n_dof)``
        (robot model, payload included; with ``hinged_links`` the hinged arm's
        (:meth:`tvist.Robot.with_link_hinges`) with straight hinges, ``n_dof = n_robot + 2 ×``
        the number of hinged links).
    keys
        Pose keys.
    pose, log_joint
        ``(k,)`` pose index and excitation log (0 base, 1 shoulder, 2 elbow, 3 wrist 1) of
        each mode.
    wn_rad_s, zeta, wn_se_rad_s, zeta_se
        ``(k,)``; standard errors NaN where the record states none.
    direction
        ``(k, 3)`` unit flange direction, NaN where unknown.
    true_modes
        Per pose, the record's ``true_modes`` list (a twin's campaign) or ``None``.
    hinged_links
        Links with a hinge pair at :data:`HINGE_AT_FRACTION` of their length (none: the
        robot's own model).
    elbow_joint
        The robot's elbow (:attr:`tvist.robots.RobotParams.elbow_joint`; a UR's 2), ``None``
        for an arm without one.
    """

    q: np.ndarray
    mass_kg_m2: np.ndarray
    gravity_torque_nm: np.ndarray
    jacobian: np.ndarray
    keys: tuple[str, ...]
    pose: np.ndarray
    log_joint: np.ndarray
    wn_rad_s: np.ndarray
    zeta: np.ndarray
    wn_se_rad_s: np.ndarray
    zeta_se: np.ndarray
    direction: np.ndarray
    true_modes: tuple[Any, ...]
    hinged_links: tuple[int, ...] = ()
    elbow_joint: int | None = 2

    def column(self, joint: int) -> int:
        """Index of the robot's joint ``joint`` in the model arrays."""
        return joint + 2 * sum(1 for link in self.hinged_links if link < joint)

    def hinge_columns(self, link: int) -> tuple[int, int]:
        """Indices of the two hinge coordinates of hinged link ``link``."""
        first = self.column(link) + 1
        return first, first + 1

    @property
    def n_poses(self) -> int:
        return int(self.q.shape[0])

    def subset(self, index: Sequence[int] | np.ndarray) -> ObservedModes:
        """The poses at ``index`` (and their modes), renumbered."""
        index = np.asarray(index, dtype=int)
        new = np.full(self.n_poses, -1)
        new[index] = np.arange(index.size)
        keep = new[self.pose] >= 0
        return ObservedModes(
            self.q[index],
            self.mass_kg_m2[index],
            self.gravity_torque_nm[index],
            self.jacobian[index],
            tuple(self.keys[i] for i in index),
            new[self.pose[keep]],
            self.log_joint[keep],
            self.wn_rad_s[keep],
            self.zeta[keep],
            self.wn_se_rad_s[keep],
            self.zeta_se[keep],
            self.direction[keep],
            tuple(self.true_modes[i] for i in index),
            self.hinged_links,
            self.elbow_joint,
        )


def _number(value: Any) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        return math.nan
    return value if math.isfinite(value) and value > 0 else math.nan


def _entries(record: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    """The record's ringing entries, or its ``modes`` read as such (no direction)."""
    ringing = record.get("ringing")
    if ringing is not None:
        return list(ringing)
    return [
        {**m, "log_joint": m.get("joint"), "flange_direction": None}
        for m in record.get("modes", [])
        if m.get("joint") in (0, 1) and not m.get("error")
    ]


def observed_modes(
    records: Sequence[Mapping[str, Any]],
    robot_name: str,
    *,
    include_low_confidence: bool = False,
    hinged_links: Sequence[int] = (),
) -> ObservedModes:
    """The identified modes of every campaign record with a configuration ``q``, with the
    model arrays of the robot, or of the arm with a hinge pair in each of ``hinged_links``
    at :data:`HINGE_AT_FRACTION` of its length.

    Raises
    ------
    ValueError
        No usable record, a malformed ``q`` or payload, or stored joint inertias that are not
        this robot's (the campaign ran with another robot or payload).
    """
    from tvist.ident.modal_fit.poses import checked_poses

    robot_params = params(robot_name)
    robots: dict[tuple, Robot] = {}
    qs, keys, truth = [], [], []
    payload_of: list[tuple] = []
    pose, log, wn, zeta, wn_se, zeta_se, direction = [], [], [], [], [], [], []
    for i, r, q, key, model in checked_poses(records, robot_name):
        robots[key] = model
        p = len(qs)
        for m in _entries(r):
            if m.get("low_confidence", False) and not include_low_confidence:
                continue
            w, z = _number(m.get("wn_rad_s")), _number(m.get("zeta"))
            if not (math.isfinite(w) and math.isfinite(z)):
                continue
            d = m.get("flange_direction")
            d = np.full(3, np.nan) if d is None else np.asarray(d, dtype=float)
            norm = float(np.linalg.norm(d)) if d.shape == (3,) else math.nan
            pose.append(p)
            log.append(int(m.get("log_joint", -1)))
            wn.append(w)
            zeta.append(z)
            wn_se.append(_number(m.get("wn_se_rad_s")))
            zeta_se.append(_number(m.get("zeta_se")))
            direction.append(d / norm if norm > 0 else np.full(3, np.nan))
        qs.append(q)
        payload_of.append(key)
        keys.append(str(r.get("key", i)))
        truth.append(r.get("true_modes"))
    if not qs:
        raise ValueError(f"no campaign record with a configuration 'q' among {len(records)}")
    q_all = np.array(qs)
    hinged_links = tuple(sorted(int(link) for link in hinged_links))
    n_model = robot_params.n_dof + 2 * len(hinged_links)
    mass = np.empty((len(qs), n_model, n_model))
    tau = np.empty((len(qs), n_model))
    jac = np.empty((len(qs), 6, n_model))
    for key, robot in robots.items():
        model = (
            robot.with_link_hinges([(link, HINGE_AT_FRACTION) for link in hinged_links])
            if hinged_links
            else robot
        )
        rows = [i for i, k in enumerate(payload_of) if k == key]
        mass[rows] = model.mass_matrix_many(q_all[rows])
        tau[rows] = model.gravity_torque_many(q_all[rows])
        jac[rows] = model.jacobian_many(q_all[rows])
    return ObservedModes(
        q_all,
        mass,
        tau,
        jac,
        tuple(keys),
        np.array(pose, dtype=int),
        np.array(log, dtype=int),
        np.array(wn),
        np.array(zeta),
        np.array(wn_se),
        np.array(zeta_se),
        np.array(direction).reshape(-1, 3),
        tuple(truth),
        hinged_links,
        robot_params.elbow_joint,
    )
