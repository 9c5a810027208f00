"""How many of a twin campaign's identifications agree with the twin's true modes.

A campaign on the twin (``tvist campaign --sim``) stores in every pose record the identified
``modes`` and the twin's ``true_modes`` (:mod:`tvist.ident.campaign`). Per identified joint,
:func:`within_tolerance` counts the poses whose identified natural frequency is within a
relative tolerance of the true mode of the same joint: what ``tvist campaign`` prints after a
campaign on the twin, and what the README's results table reads from the records file.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

#: Relative tolerance on the natural frequency ω_n (0.03: within 3 %).
TOLERANCE = 0.03
#: The joints counted, with the names the summary gives them.
JOINT_NAMES = {0: "base", 1: "shoulder"}


@dataclass(frozen=True)
class JointAgreement:
    """One joint's identifications over a twin campaign, against the twin's true modes.

    Attributes
    ----------
    within
        Poses whose identified ω_n is within the tolerance of the true mode.
    compared
        Poses with both an identified and a true mode of the joint.
    confident
        Of ``compared``: identifications not flagged ``low_confidence``.
    confident_outside
        Of ``confident``: outside the tolerance (a confident identification that is wrong).
    """

    within: int
    compared: int
    confident: int
    confident_outside: int


def agreement(
    records: Iterable[Mapping[str, Any]], tolerance: float = TOLERANCE
) -> dict[str, JointAgreement]:
    """Per joint name of :data:`JOINT_NAMES`, how its identifications agree with the twin's
    true mode of that joint (relative ω_n error below ``tolerance``); records without
    ``true_modes`` (a real robot's) are left out, and a joint no pose could compare is left
    out of the result."""
    truth = [r for r in records if "true_modes" in r]
    out = {}
    for joint, name in JOINT_NAMES.items():
        inside, confident = [], []
        for r in truth:
            fit = next((m for m in r["modes"] if m.get("joint") == joint), None)
            true = next(m for m in r["true_modes"] if m["joint"] == joint)
            if fit is not None and "wn_rad_s" in fit:
                inside.append(abs(fit["wn_rad_s"] / true["wn_rad_s"] - 1.0) < tolerance)
                confident.append(not fit.get("low_confidence", False))
        if inside:
            out[name] = JointAgreement(
                within=sum(inside),
                compared=len(inside),
                confident=sum(confident),
                confident_outside=sum(c and not i for c, i in zip(confident, inside, strict=True)),
            )
    return out


def within_tolerance(
    records: Iterable[Mapping[str, Any]], tolerance: float = TOLERANCE
) -> dict[str, tuple[int, int]]:
    """Per joint name of :data:`JOINT_NAMES`: ``(within, compared)`` of :func:`agreement`."""
    return {
        name: (joint.within, joint.compared)
        for name, joint in agreement(records, tolerance).items()
    }
