"""The campaign's pose records as the modal fit reads them (:class:`ModalPoses`): per pose
the link-side mass matrix and gravity torques of the robot model with the record's payload,
and the identified (for a twin's campaign also the true) base and shoulder modes."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tvist.robots import Payload, Robot, params

#: The identified modes, in cascade order: base, shoulder.
MODE_JOINTS = (0, 1)


@dataclass(frozen=True)
class ModalPoses:
    """The campaign's poses with what the modal map needs, arrays over poses.

    Attributes
    ----------
    mass_kg_m2
        Link-side mass matrices, payload included, ``(n_poses, n_dof, n_dof)``.
    gravity_torque_nm
        ``(n_poses, n_dof)``.
    wn_rad_s, zeta
        Identified modes ``(n_poses, 2)`` (base, shoulder); NaN where not usable (missing,
        failed or flagged low-confidence).
    true_wn_rad_s, true_zeta
        The twin's true modes ``(n_poses, 2)``, NaN where unknown.
    inertia_kg_m2
        Joint inertias ``(n_poses, n_dof)`` (for the published form).
    keys
        Pose keys.
    wn_se_rad_s, zeta_se
        The local fits' stated standard errors of the identified modes ``(n_poses, 2)``, NaN
        where the record states none.
    """

    mass_kg_m2: np.ndarray
    gravity_torque_nm: np.ndarray
    wn_rad_s: np.ndarray
    zeta: np.ndarray
    true_wn_rad_s: np.ndarray
    true_zeta: np.ndarray
    inertia_kg_m2: np.ndarray
    keys: tuple[str, ...]
    wn_se_rad_s: np.ndarray | None = None
    zeta_se: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("wn_se_rad_s", "zeta_se"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.full(self.wn_rad_s.shape, np.nan))

    @property
    def n_poses(self) -> int:
        return int(self.mass_kg_m2.shape[0])

    def subset(self, index: np.ndarray) -> ModalPoses:
        """The poses at ``index``."""
        return ModalPoses(
            self.mass_kg_m2[index],
            self.gravity_torque_nm[index],
            self.wn_rad_s[index],
            self.zeta[index],
            self.true_wn_rad_s[index],
            self.true_zeta[index],
            self.inertia_kg_m2[index],
            tuple(self.keys[i] for i in np.asarray(index)),
            self.wn_se_rad_s[index],
            self.zeta_se[index],
        )


def modal_poses(
    records: Sequence[Mapping[str, Any]],
    robot_name: str,
    *,
    include_low_confidence: bool = False,
) -> ModalPoses:
    """Mass matrices, gravity torques and modes of every reachable campaign pose.

    Raises
    ------
    ValueError
        No record with a configuration ``q``, or a record whose stored joint inertias are not
        this robot model's (a campaign run with another robot or payload).
    """
    mass, tau, inertia, wn, zeta, twn, tzeta, keys = [], [], [], [], [], [], [], []
    wn_se, zeta_se = [], []
    for i, r, q, _, model in checked_poses(records, robot_name):
        mass.append(model.mass_matrix(q))
        tau.append(model.gravity_torque(q))
        inertia.append(model.joint_inertia(q))
        obs = np.full((2, 2), np.nan)
        obs_se = np.full((2, 2), np.nan)
        for mode in r.get("modes", []):
            j = mode.get("joint")
            if j not in MODE_JOINTS or "wn_rad_s" not in mode:
                continue
            if mode.get("low_confidence", False) and not include_low_confidence:
                continue
            w, z = float(mode.get("wn_rad_s", math.nan)), float(mode.get("zeta", math.nan))
            if math.isfinite(w) and math.isfinite(z) and w > 0 and z > 0:
                obs[MODE_JOINTS.index(j)] = (w, z)
                obs_se[MODE_JOINTS.index(j)] = (
                    _positive_or_nan(mode.get("wn_se_rad_s")),
                    _positive_or_nan(mode.get("zeta_se")),
                )
        truth = np.full((2, 2), np.nan)
        for mode in r.get("true_modes") or []:
            if mode.get("joint") in MODE_JOINTS:
                truth[MODE_JOINTS.index(mode["joint"])] = (mode["wn_rad_s"], mode["zeta"])
        wn.append(obs[:, 0])
        zeta.append(obs[:, 1])
        wn_se.append(obs_se[:, 0])
        zeta_se.append(obs_se[:, 1])
        twn.append(truth[:, 0])
        tzeta.append(truth[:, 1])
        keys.append(str(r.get("key", i)))
    if not mass:
        raise ValueError(f"no campaign record with a configuration 'q' among {len(records)}")
    return ModalPoses(
        np.array(mass),
        np.array(tau),
        np.array(wn),
        np.array(zeta),
        np.array(twn),
        np.array(tzeta),
        np.array(inertia),
        tuple(keys),
        np.array(wn_se),
        np.array(zeta_se),
    )


def checked_poses(
    records: Sequence[Mapping[str, Any]], robot_name: str
) -> Iterator[tuple[int, Mapping[str, Any], np.ndarray, tuple[float, tuple[float, ...]], Robot]]:
    """Every record with a configuration ``q`` and no error, checked, as ``(index, record,
    q, payload, model)``: ``payload`` is ``(mass_kg, com_m)``, ``model`` the robot with that
    payload (one model per payload, shared by its records).

    Raises
    ------
    ValueError
        A malformed ``q`` or payload, or stored joint inertias that are not this model's.
    """
    robot_params = params(robot_name)
    robots: dict[tuple, Robot] = {}
    for i, r in enumerate(records):
        q = r.get("q")
        if q is None or r.get("error"):
            continue
        q = np.asarray(q, dtype=float)
        if q.shape != (robot_params.n_dof,) or not np.all(np.isfinite(q)):
            raise ValueError(f"records[{i}]: 'q' must be {robot_params.n_dof} finite angles")
        payload = _record_payload(r, i)
        if payload not in robots:
            robots[payload] = Robot(robot_params, Payload(payload[0], payload[1]))
        _check_stored_inertia(r, i, robots[payload].joint_inertia(q), robot_name)
        yield i, r, q, payload, robots[payload]


#: Relative difference beyond which a record's stored joint inertias are not the robot
#: model's (the campaign writes the same model's values, equal to rounding).
INERTIA_MISMATCH = 1e-6


def _check_stored_inertia(
    record: Mapping[str, Any], index: int, model_inertia: np.ndarray, robot_name: str
) -> None:
    """Refuse a record whose stored joint inertias (``inertia_kg_m2``, written by the campaign
    from its robot model) are not ``robot_name``'s at its pose: the campaign ran with another
    robot or payload, and the fit would silently use the wrong mass matrices."""
    stored = record.get("inertia_kg_m2")
    if stored is None:
        return
    stored = np.asarray(stored, dtype=float)
    if stored.shape != model_inertia.shape:
        return
    rel = np.abs(stored - model_inertia) / np.maximum(np.abs(model_inertia), 1e-9)
    worst = float(np.max(rel)) if rel.size else 0.0
    if not worst <= INERTIA_MISMATCH:
        key = record.get("key", index)
        raise ValueError(
            f"records[{index}] ({key}): its joint inertias differ from the {robot_name} "
            f"model's by {100 * worst:.3g} %: the campaign ran with another robot or payload; "
            "pass the campaign's robot (--robot)"
        )


def _positive_or_nan(value: Any) -> float:
    """A stated standard error as a float, NaN if absent, not finite or not positive."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        return math.nan
    return value if math.isfinite(value) and value > 0 else math.nan


def _record_payload(record: Mapping[str, Any], i: int) -> tuple[float, tuple[float, ...]]:
    """``(payload_kg, payload_com_m)`` of pose record ``i``: both must be there (the mass
    matrices depend on them), except the centre of mass of a zero payload."""
    name = f"records[{i}] ({record.get('key', 'no key')})"
    if "payload_kg" not in record:
        raise ValueError(
            f"{name}: no payload_kg; a pose record names its payload (tvist identify "
            "--payload-kg, or logs recorded with it)"
        )
    mass = float(record["payload_kg"])
    com = record.get("payload_com_m")
    if com is None and mass != 0.0:
        raise ValueError(f"{name}: payload_kg {mass:g} without payload_com_m")
    return mass, tuple(float(v) for v in (com or (0.0, 0.0, 0.0)))
