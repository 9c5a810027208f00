"""Checks of identified modes across the poses of a batch or a campaign.

A mode's frequency changes smoothly with the pose. A confident ``ringing`` entry (see
:mod:`tvist.ident.pose`) that none of the modes of its nearest poses comes close to is a
result to doubt (a merged pair, a fit caught on a disturbance): :func:`flag_jumps` marks it
low-confidence, "jumps against neighbouring poses", naming how far the neighbours' closest
modes are.

Neighbours are the :data:`N_NEIGHBOURS` nearest poses with the same payload, by the largest
difference of the angles of the joints from the base to the robot's elbow
(:attr:`tvist.robots.RobotParams.elbow_joint`; a UR's base, shoulder and elbow, an FR3's also
its upper-arm rotation; the wrist is drawn at random per pose and moves the modes little),
within :data:`MAX_NEIGHBOUR_RAD`. The check needs at least two
neighbours with confident modes; a mode jumps if, at every one of them, the closest confident
mode (from any log) differs by more than :data:`JUMP_RATIO`.

:func:`flag_jumps` works on the records' dict form and is idempotent (it drops its own
earlier flags first), so it can run again when poses are added.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["JUMP_REASON", "flag_jumps"]

#: Nearest poses compared.
N_NEIGHBOURS = 2
#: Poses farther apart than this (largest of the angle differences up to the elbow, rad)
#: are not neighbours.
MAX_NEIGHBOUR_RAD = 0.6
#: A mode farther than this frequency ratio from every mode of every neighbour jumps.
JUMP_RATIO = 1.12
#: Prefix of the reason :func:`flag_jumps` adds.
JUMP_REASON = "jumps against neighbouring poses"


def _confident(record: dict[str, Any]) -> list[float]:
    return [
        float(m["wn_rad_s"])
        for m in record.get("ringing") or ()
        if not m.get("low_confidence", False)
    ]


def flag_jumps(records: Sequence[dict[str, Any]], robot_name: str = "ur5e") -> list[dict[str, Any]]:
    """Copies of ``records`` (of a campaign on ``robot_name``) with every confident
    ``ringing`` entry that jumps against its neighbouring poses flagged (see the module
    docstring); records without ``ringing`` or ``q`` are returned unchanged."""
    from tvist.robots import params

    elbow = params(robot_name).elbow_joint
    out = []
    for r in records:
        r = dict(r)
        if r.get("ringing"):
            cleaned = []
            for m in r["ringing"]:
                reasons = [x for x in m.get("reasons", ()) if not x.startswith(JUMP_REASON)]
                cleaned.append({**m, "reasons": reasons, "low_confidence": bool(reasons)})
            r["ringing"] = cleaned
        out.append(r)
    usable = [i for i, r in enumerate(out) if r.get("q") is not None and r.get("ringing")]
    if len(usable) < N_NEIGHBOURS + 1:
        return out
    last = 2 if elbow is None else elbow
    q = np.array([np.asarray(out[i]["q"], dtype=float)[: last + 1] for i in usable])
    payload = np.array([float(out[i].get("payload_kg", 0.0)) for i in usable])
    confident = [_confident(out[i]) for i in usable]
    for a, i in enumerate(usable):
        distance = np.max(np.abs(q - q[a]), axis=1)
        distance[a] = np.inf
        distance[payload != payload[a]] = np.inf
        near = [
            b for b in np.argsort(distance) if distance[b] <= MAX_NEIGHBOUR_RAD and confident[b]
        ][:N_NEIGHBOURS]
        if len(near) < N_NEIGHBOURS:
            continue
        ringing = out[i]["ringing"]
        for k, m in enumerate(ringing):
            if m.get("low_confidence", False):
                continue
            w = float(m["wn_rad_s"])
            gaps = [min(abs(math.log(w / v)) for v in confident[b]) for b in near]
            if min(gaps) > math.log(JUMP_RATIO):
                text = " and ".join(f"{100 * (math.exp(g) - 1):.0f} %" for g in gaps)
                ringing[k] = {
                    **m,
                    "low_confidence": True,
                    "reasons": [
                        *m.get("reasons", ()),
                        f"{JUMP_REASON} (their closest modes are {text} away)",
                    ],
                }
    return out
