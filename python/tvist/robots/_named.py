"""Arms by name: the parameters of a robot of the core's robot data or of an arm shipped as
URDF data (:func:`params`), and the UR e-Series models with a payload (:func:`ur5e`, ...)."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

from tvist import _core
from tvist.robots._params import Payload, RobotParams, _from_core, names
from tvist.robots._robot import Robot
from tvist.robots.urdf import SHIPPED_URDFS, shipped_params


@cache
def params(name: str) -> RobotParams:
    """Parameters of robot ``name``: one of :func:`names` (the core's robot data) or an arm
    shipped as URDF data (:data:`tvist.robots.SHIPPED_URDFS`, e.g. ``"fr3"``)."""
    if name in SHIPPED_URDFS:
        return shipped_params(name)
    if name not in names():
        known = ", ".join((*names(), *SHIPPED_URDFS))
        raise ValueError(f"unknown robot {name!r}; known: {known}")
    return _from_core(_core.robot_params(name))


def _named(
    name: str,
    payload_kg: float,
    payload_com_m: Sequence[float],
    payload_inertia_kg_m2: Sequence[float] | None,
) -> Robot:
    payload = Payload(payload_kg, tuple(payload_com_m), payload_inertia_kg_m2)
    return Robot(params(name), payload)


def ur3e(
    payload_kg: float = 0.0,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.0),
    payload_inertia_kg_m2: Sequence[float] | None = None,
) -> Robot:
    """UR3e with a payload (centre of mass and inertia in the flange frame)."""
    return _named("ur3e", payload_kg, payload_com_m, payload_inertia_kg_m2)


def ur5e(
    payload_kg: float = 0.0,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.0),
    payload_inertia_kg_m2: Sequence[float] | None = None,
) -> Robot:
    """UR5e with a payload (centre of mass and inertia in the flange frame)."""
    return _named("ur5e", payload_kg, payload_com_m, payload_inertia_kg_m2)


def ur10e(
    payload_kg: float = 0.0,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.0),
    payload_inertia_kg_m2: Sequence[float] | None = None,
) -> Robot:
    """UR10e with a payload (centre of mass and inertia in the flange frame)."""
    return _named("ur10e", payload_kg, payload_com_m, payload_inertia_kg_m2)


def ur16e(
    payload_kg: float = 0.0,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.0),
    payload_inertia_kg_m2: Sequence[float] | None = None,
) -> Robot:
    """UR16e with a payload (centre of mass and inertia in the flange frame)."""
    return _named("ur16e", payload_kg, payload_com_m, payload_inertia_kg_m2)


def ur20(
    payload_kg: float = 0.0,
    payload_com_m: Sequence[float] = (0.0, 0.0, 0.0),
    payload_inertia_kg_m2: Sequence[float] | None = None,
) -> Robot:
    """UR20 with a payload (centre of mass and inertia in the flange frame)."""
    return _named("ur20", payload_kg, payload_com_m, payload_inertia_kg_m2)
