"""How many of a twin campaign's identifications agree with the twin's true modes.

A campaign on the twin (``tvist campaign --sim``) stores in every pose record the identified
``modes`` and the twin's ``true_modes`` (:mod:`tvist.ident.campaign`). Per identified joint,
:func:`within_tolerance` counts the poses whose identified natural frequency is within a
relative tolerance of the true mode of the same joint: what ``tvist campaign`` prints after a
campaign on the twin, and what the README's results table reads from the records file.
:func:`ringing_agreement` does the same for every mode the logs show (the ``ringing`` lists).
"""

from __future__ import annotations

import math
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


@dataclass(frozen=True)
class RingingAgreement:
    """The ``ringing`` modes of a twin campaign's records (every mode each log shows,
    :mod:`tvist.ident.ringing`) against the twin's true modes.

    Attributes
    ----------
    modes
        Ringing modes in the records with true modes.
    confident
        Of ``modes``: not flagged ``low_confidence``.
    compared
        Of ``confident``: low enough that every true mode within the tolerance of it is in
        the band the records list (``f (1 + tolerance) <= band_hz``).
    outside
        Of ``compared``: farther than the tolerance from every true mode of the pose (a
        confident identification that is wrong).
    above_band
        Of ``confident``: the rest, near or above the band's top, where the true mode it may
        be is not listed (on the UR twins the stiff elbow's mode, 60-90 Hz, which the elbow
        log shows).
    """

    modes: int
    confident: int
    compared: int
    outside: int
    above_band: int


def ringing_agreement(
    records: Iterable[Mapping[str, Any]], band_hz: float, tolerance: float = TOLERANCE
) -> RingingAgreement:
    """How the records' confident ``ringing`` modes agree with their pose's true modes,
    ``band_hz`` being the frequency up to which the records list every true mode
    (:data:`tvist.ident.campaign_robots.TRUE_MODES_MAX_HZ` for a twin campaign). Records
    without ``true_modes`` (a real robot's) are left out."""
    modes = confident = compared = outside = above = 0
    for record in records:
        true_hz = [m["freq_hz"] for m in record.get("true_modes") or () if "freq_hz" in m]
        if not true_hz:
            continue
        for mode in record.get("ringing") or ():
            modes += 1
            if mode.get("low_confidence", True):
                continue
            confident += 1
            f_hz = mode["wn_rad_s"] / (2 * math.pi)
            if f_hz * (1.0 + tolerance) > band_hz:
                above += 1
                continue
            compared += 1
            outside += min(abs(f_hz / t - 1.0) for t in true_hz) > tolerance
    return RingingAgreement(modes, confident, compared, outside, above)
