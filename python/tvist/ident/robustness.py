"""Is the map good enough? Map errors against the shaper's robustness (paper section 5.4).

For every identified pose, the two-mode shaper is designed from the map's prediction (base
and shoulder ZV shapers convolved, eq. 53) and applied to the modes actually identified
there; the percent residual vibration (eqs. 52-55, :func:`tvist.prv`) of each identified mode
must stay at or below 10 %. The 10 % PRV *band* of a mode is the interval of actual frequency
(or damping) around the design value in which that holds, the other parameters fixed at their
design values; it is what Figs. 28-30 shade.

All shapers and PRVs come from :mod:`tvist` (the Rust core); all map predictions from
:class:`tvist.DynamicMap`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

import tvist

__all__ = [
    "PRV_LIMIT",
    "PoseRobustness",
    "evaluate_map",
    "pose_modes",
    "prv_band",
    "summarize",
    "two_mode_shaper",
    "usable_mode",
]

#: The paper's requirement: at most 10 % residual vibration.
PRV_LIMIT = 0.10


def two_mode_shaper(modes: Sequence[tuple[float, float]], shaper: str = "zv") -> tvist.Impulses:
    """Convolution of one ``shaper`` per mode ``(wn_rad_s, zeta)`` (eq. 53)."""
    return tvist.convolve(*(tvist.shaper(shaper, wn, zeta) for wn, zeta in modes))


def prv_band(
    impulses: tvist.Impulses,
    wn_rad_s: float,
    zeta: float,
    *,
    vary: str = "frequency",
    limit: float = PRV_LIMIT,
    span: float = 3.0,
    n: int = 3001,
) -> tuple[float, float]:
    """Interval of the actual ``ω_n`` (or ``ζ``) around the given one with PRV <= ``limit``.

    Parameters
    ----------
    impulses
        The shaper.
    wn_rad_s, zeta
        The mode as designed (the interval contains it when PRV there is <= ``limit``).
    vary
        ``"frequency"`` (scan ``ω_n`` over ``[ω/span, ω·span]``, ``ζ`` fixed) or
        ``"damping"`` (scan ``ζ`` over ``[0, min(1, ζ·span + 0.1)]``, ``ω_n`` fixed).
    limit
        PRV limit as a fraction.
    span, n
        Scan range and resolution.

    Returns
    -------
    (low, high)
        Bounds in rad/s (frequency) or in damping ratio; ``(nan, nan)`` if the design point
        itself exceeds ``limit``. A bound at the end of the scan means "at least this far".
    """
    if vary == "frequency":
        grid = np.geomspace(wn_rad_s / span, wn_rad_s * span, n)
        prv = tvist.prv(impulses, grid, zeta)
        centre = wn_rad_s
    elif vary == "damping":
        grid = np.linspace(0.0, min(0.999, zeta * span + 0.1), n)
        prv = tvist.prv(impulses, wn_rad_s, grid)
        centre = zeta
    else:
        raise ValueError(f"vary must be 'frequency' or 'damping', got {vary!r}")
    k = int(np.argmin(np.abs(grid - centre)))
    if not prv[k] <= limit:
        return (math.nan, math.nan)
    ok = prv <= limit
    lo = k
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    hi = k
    while hi < n - 1 and ok[hi + 1]:
        hi += 1
    return float(grid[lo]), float(grid[hi])


@dataclass(frozen=True)
class PoseRobustness:
    """Map prediction against identification at one pose.

    Attributes
    ----------
    key
        Pose name.
    inertia_kg_m2
        Joint inertias of the pose.
    predicted, identified
        ``[(wn_rad_s, zeta) base, shoulder]`` from the map and from the local fits.
    prv
        PRV of each identified mode under the shaper designed from the prediction.
    wn_band_rad_s, zeta_band
        Per mode, the 10 % PRV band of frequency and of damping around the prediction.
    """

    key: str
    inertia_kg_m2: tuple[float, ...]
    predicted: tuple[tuple[float, float], ...]
    identified: tuple[tuple[float, float], ...]
    prv: tuple[float, ...]
    wn_band_rad_s: tuple[tuple[float, float], ...]
    zeta_band: tuple[tuple[float, float], ...]

    @property
    def within_limit(self) -> bool:
        """True if every identified mode has PRV <= 10 %."""
        return all(p <= PRV_LIMIT for p in self.prv)

    @property
    def wn_error(self) -> tuple[float, ...]:
        """Relative map error of each frequency, ``predicted/identified - 1``."""
        return tuple(
            p[0] / i[0] - 1.0 for p, i in zip(self.predicted, self.identified, strict=True)
        )


def usable_mode(record: Mapping[str, Any], joint: int) -> Mapping[str, Any] | None:
    """The campaign record's identified mode of ``joint`` (the last one named so), or ``None``
    where it is missing, failed (``"error"``) or flagged low-confidence."""
    by_joint = {m.get("joint"): m for m in record.get("modes", [])}
    m = by_joint.get(joint)
    if m is None or "error" in m or m.get("low_confidence", False):
        return None
    return m


def _identified_modes(record: Mapping[str, Any], joints: Sequence[int]) -> list | None:
    out = []
    for j in joints:
        m = usable_mode(record, j)
        if m is None:
            return None
        out.append((float(m["wn_rad_s"]), float(m["zeta"])))
    return out


def pose_modes(
    dynmap: Any, record: Mapping[str, Any], robot: tvist.robots.Robot | None = None
) -> list[tuple[float, float]] | None:
    """The map's modes at a campaign pose: a :class:`tvist.DynamicMap` reads the record's
    joint inertias (and gravity torques), a :class:`tvist.ModalMap` the mass matrix of
    ``robot``'s model (default the map's ``metadata.robot``, else the UR5e) with the record's
    payload at its ``q``. ``None`` if the record lacks what the map reads."""
    if isinstance(dynmap, tvist.ModalMap):
        if record.get("q") is None:
            return None
        params = robot.params if robot is not None else tvist.robots.params(dynmap.robot or "ur5e")
        payload = tvist.robots.Payload(
            float(record.get("payload_kg", 0.0)),
            tuple(record.get("payload_com_m", (0.0, 0.0, 0.0))),
        )
        return dynmap.modes(tvist.robots.Robot(params, payload), record["q"])
    if "inertia_kg_m2" not in record:
        return None
    tau = record.get("gravity_torque_nm") if dynmap.uses_gravity else None
    return dynmap.modes_from_inertia(record["inertia_kg_m2"], tau)


def evaluate_map(
    results: Sequence[Mapping[str, Any]],
    dynmap: tvist.DynamicMap | tvist.ModalMap,
    *,
    shaper: str = "zv",
    joints: Sequence[int] = (0, 1),
    robot: tvist.robots.Robot | None = None,
) -> list[PoseRobustness]:
    """Robustness of ``dynmap`` at every confidently identified pose of a campaign.

    Parameters
    ----------
    results
        Campaign pose records (see :mod:`tvist.ident.campaign`).
    dynmap
        The map to judge (published or modal form); its modes are in cascade order
        ``joints`` (base, shoulder).
    shaper
        Shaper per mode (the paper: ZV).
    joints
        The excited joint of each map mode.
    robot
        For a modal map: the robot model (see :func:`pose_modes`).
    """
    out = []
    for record in results:
        identified = _identified_modes(record, joints)
        if identified is None or "inertia_kg_m2" not in record:
            continue
        predicted = pose_modes(dynmap, record, robot)
        if predicted is None:
            continue
        if not all(math.isfinite(w) and math.isfinite(z) and z < 1 for w, z in predicted):
            continue
        impulses = two_mode_shaper(predicted, shaper)
        prv = tuple(float(tvist.prv(impulses, w, z)) for w, z in identified)
        out.append(
            PoseRobustness(
                key=str(record.get("key", "")),
                inertia_kg_m2=tuple(float(v) for v in record["inertia_kg_m2"]),
                predicted=tuple((float(w), float(z)) for w, z in predicted),
                identified=tuple(identified),
                prv=prv,
                wn_band_rad_s=tuple(prv_band(impulses, w, z) for w, z in predicted),
                zeta_band=tuple(prv_band(impulses, w, z, vary="damping") for w, z in predicted),
            )
        )
    return out


def summarize(evaluations: Sequence[PoseRobustness]) -> dict[str, Any]:
    """Counts and error statistics of :func:`evaluate_map` (JSON-serialisable)."""
    n = len(evaluations)
    if n == 0:
        return {"n_poses": 0}
    errors = np.array([e.wn_error for e in evaluations])
    prv = np.array([e.prv for e in evaluations])
    return {
        "n_poses": n,
        "within_10_percent_prv": int(sum(e.within_limit for e in evaluations)),
        "fraction_within": float(np.mean([e.within_limit for e in evaluations])),
        "per_mode": [
            {
                "rms_wn_error": float(np.sqrt(np.mean(errors[:, m] ** 2))),
                "max_abs_wn_error": float(np.max(np.abs(errors[:, m]))),
                "median_prv": float(np.median(prv[:, m])),
                "max_prv": float(np.max(prv[:, m])),
            }
            for m in range(errors.shape[1])
        ],
    }
