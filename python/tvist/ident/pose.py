"""One pose of a mapping campaign: its excitation logs → the per-pose record.

:func:`identify_pose` turns the base and the shoulder excitation logged at one pose (and those
of further excited joints, e.g. the elbow) into the record the campaign writes and
:func:`~tvist.ident.map_fit.fit_map` reads (:class:`PoseRecord`, one JSON line per pose)::

    {"key": "...",                      # name of the pose
     "q": [q_0, ..., q_5],              # pose, rad
     "payload_kg": m, "payload_com_m": [x, y, z],
     "inertia_kg_m2": [J_0, ..., J_5],  # joint-axis inertias at q (robot model + payload)
     "gravity_torque_nm": [τ_0, ..., τ_5],
     "modes": [{"joint": 0, "wn_rad_s": ..., "zeta": ..., "wn_se_rad_s": ..., "zeta_se": ...,
                "low_confidence": false, "reasons": [], "method": "two-mode",
                "ringing_index": 0, ...},
               {"joint": 1, ...}],       # or {"joint": j, "error": "..."} if it failed
     "ringing": [{"log_joint": 0, "wn_rad_s": ..., "zeta": ..., "wn_se_rad_s": ...,
                  "zeta_se": ..., "amplitude_m_s2": ..., "flange_direction": [x, y, z],
                  "low_confidence": false, "reasons": [], "tangent_share": ...}, ...],
     "error": null}

``ringing`` lists every mode that rings in each log (1-3 per log,
:mod:`tvist.ident.ringing`), with its direction at the flange in the base frame; a log of a
further excited joint (``log_joint`` 2 for the elbow, 3 for wrist 1) adds ``ringing`` entries
only: it rings the modes a base or shoulder excitation barely moves (an elbow-dominated mode
at folded poses). ``modes`` keeps one mode per identified joint
(:data:`IDENTIFIED_JOINTS`) for the paper's map: **the base mode** (``modes`` joint 0)
is the base log's mode that moves the flange along the base joint's tangent, separated from
the shoulder mode (:mod:`tvist.ident.base_mode`); the shoulder mode likewise from the
shoulder log. ``ringing_index`` names the ``ringing`` entry of the same log that is that mode
(the one closest in frequency, within :data:`SAME_MODE_RATIO`); ``None`` if none is (the
entry is then flagged: the mode is not among those that ring).

Checks across the logs (:func:`cross_check_logs`): a mode found in any two logs of the pose
must agree, within :data:`AGREEMENT_SE` combined standard errors and at
least :data:`AGREEMENT_FLOOR`; otherwise both entries are flagged (only the one a third log
does not confirm, where one is confirmed). Checks across poses are
in :mod:`tvist.ident.pose_checks`.

plus whatever the producer adds (the campaign: ``angle_rad``, ``radius_m``, ``wrist_joint``,
``true_modes`` on the twin).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tvist.ident.base_mode import separate_base_mode, separated_base_mode
from tvist.ident.local_fit import FitOptions, LocalFit
from tvist.ident.local_identification import identify_local
from tvist.ident.logs import Record, is_uniform, resample_uniform
from tvist.ident.preprocess import quiet_samples
from tvist.ident.ringing import RingingMode, at_rest_reason, ringing_from_log

__all__ = [
    "IDENTIFIED_JOINTS",
    "LOG_NAMES",
    "PoseRecord",
    "cross_check_logs",
    "identify_pose",
    "pose_of",
]

#: Joints whose single-mode ``modes`` entries are identified at every pose (base, shoulder):
#: the paper's map reads these. Which joints a campaign excites is
#: :func:`tvist.ident.excited.default_excited_joints`; the logs of the others add ``ringing``
#: entries only.
IDENTIFIED_JOINTS = (0, 1)
#: Two logs are of the same pose if their starting poses agree to this, rad.
SAME_POSE_TOL_RAD = 0.02
#: Modes of two logs closer than this frequency ratio are taken for the same mode; a
#: ``modes`` entry is the ``ringing`` entry within this ratio.
SAME_MODE_RATIO = 1.15
#: The same mode in two logs agrees if the frequencies differ by at most this many combined
#: standard errors (sqrt(se_a² + se_b²), relative) ... (two, not three: on arms unlike the
#: twin the standard errors leave out the model's mismatch, and at three a merged pair of
#: modes 2.5-3.5 % off passed as agreeing)
AGREEMENT_SE = 2.0
#: ... or by at most this fraction (the two logs' fits differ in the input and the noise,
#: not in the mode: a floor under standard errors that come out very small).
AGREEMENT_FLOOR = 0.01
_CORE_KEYS = (
    "key",
    "q",
    "payload_kg",
    "payload_com_m",
    "inertia_kg_m2",
    "gravity_torque_nm",
    "modes",
    "ringing",
    "error",
)


@dataclass(frozen=True)
class PoseRecord:
    """Identified modes of one pose, with what the map fit needs (see the module docstring).

    Attributes
    ----------
    key
        Name of the pose.
    q
        Joint angles, rad, shape (6,) (``None``: unreachable pose).
    payload_kg, payload_com_m
        Payload mass (kg) and centre of mass in the flange frame (m).
    inertia_kg_m2, gravity_torque_nm
        Joint-axis inertias (kg m²) and gravity torques (N m) of the model at ``q``.
    modes
        Per identified joint: the :class:`LocalFit` or the error message (str).
    error
        Why the pose has no result at all (e.g. ``"unreachable"``).
    ringing
        Every mode that rings in each log (:class:`~tvist.ident.ringing.RingingMode`),
        by excited joint (base log first), each log's lowest frequency first.
    extra
        Further fields kept as they are (the campaign's plan coordinates, a twin's true
        modes).
    """

    key: str
    q: tuple[float, ...] | None
    payload_kg: float = 0.0
    payload_com_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia_kg_m2: tuple[float, ...] | None = None
    gravity_torque_nm: tuple[float, ...] | None = None
    modes: dict[int, LocalFit | str] = field(default_factory=dict)
    error: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    ringing: tuple[RingingMode, ...] = ()

    def mode(self, joint: int) -> LocalFit | None:
        """The fit of ``joint``'s mode, or ``None`` if it failed or is missing."""
        fit = self.modes.get(joint)
        return fit if isinstance(fit, LocalFit) else None

    def to_dict(self) -> dict[str, Any]:
        """The JSON-lines record (see the module docstring)."""
        out: dict[str, Any] = {
            "key": self.key,
            "q": None if self.q is None else [float(v) for v in self.q],
            "payload_kg": float(self.payload_kg),
            "payload_com_m": [float(v) for v in self.payload_com_m],
        }
        if self.inertia_kg_m2 is not None:
            out["inertia_kg_m2"] = [float(v) for v in self.inertia_kg_m2]
        if self.gravity_torque_nm is not None:
            out["gravity_torque_nm"] = [float(v) for v in self.gravity_torque_nm]
        modes = []
        for joint in sorted(self.modes):
            fit = self.modes[joint]
            if isinstance(fit, str):
                modes.append({"joint": joint, "error": fit})
                continue
            entry = fit.to_dict()
            if self.ringing:
                entry["ringing_index"] = _ringing_index(fit, joint, self.ringing)
            modes.append(entry)
        out["modes"] = modes
        out["ringing"] = [m.to_dict() for m in self.ringing]
        out["error"] = self.error
        out.update(self.extra)
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> PoseRecord:
        """A record from its dict form (what :meth:`to_dict` writes)."""
        if not isinstance(data, dict) or "key" not in data:
            raise ValueError("a pose record is a JSON object with a 'key'")
        modes: dict[int, LocalFit | str] = {}
        for entry in data.get("modes", []):
            joint = int(entry["joint"])
            modes[joint] = str(entry["error"]) if entry.get("error") else LocalFit.from_dict(entry)

        def vector(name: str) -> tuple[float, ...] | None:
            value = data.get(name)
            return None if value is None else tuple(float(v) for v in value)

        com = vector("payload_com_m") or (0.0, 0.0, 0.0)
        return cls(
            key=str(data["key"]),
            q=vector("q"),
            payload_kg=float(data.get("payload_kg", 0.0)),
            payload_com_m=(com[0], com[1], com[2]),
            inertia_kg_m2=vector("inertia_kg_m2"),
            gravity_torque_nm=vector("gravity_torque_nm"),
            modes=modes,
            error=data.get("error"),
            extra={k: v for k, v in data.items() if k not in _CORE_KEYS},
            ringing=tuple(RingingMode.from_dict(m) for m in data.get("ringing") or ()),
        )


def _ringing_index(fit: LocalFit, joint: int, ringing: tuple[RingingMode, ...]) -> int | None:
    """Index of the ``ringing`` entry of ``joint``'s log that is ``fit``'s mode (closest in
    frequency within :data:`SAME_MODE_RATIO`), or ``None``."""
    best = None
    for i, mode in enumerate(ringing):
        if mode.log_joint != joint:
            continue
        distance = abs(math.log(mode.wn_rad_s / fit.wn_rad_s))
        if distance < math.log(SAME_MODE_RATIO) and (best is None or distance < best[0]):
            best = (distance, i)
    return None if best is None else best[1]


def _relative_se(mode: RingingMode) -> float:
    return mode.wn_se_rad_s / mode.wn_rad_s


def _rings(mode: RingingMode) -> bool:
    """Whether the mode rings clearly (not flagged weak or below noise)."""
    return not any(r.startswith(("weak ringing", "below noise")) for r in mode.reasons)


#: Names of the excited joints' logs on a UR (elbow 2), for reasons and messages.
LOG_NAMES = {0: "base", 1: "shoulder", 2: "elbow", 3: "wrist 1", 4: "wrist 2", 5: "wrist 3"}


def _log_name(joint: int, elbow: int | None = 2) -> str:
    """A UR's names (:data:`LOG_NAMES`); on an arm whose elbow is not joint 2, base,
    shoulder, elbow and ``joint j``."""
    if joint == elbow:
        return "elbow"
    if elbow == 2 or joint in (0, 1):
        return LOG_NAMES.get(joint, f"joint {joint}")
    return f"joint {joint}"


def cross_check_logs(ringing: list[RingingMode], elbow_joint: int | None = 2) -> list[RingingMode]:
    """``ringing`` with the modes found in two logs of the pose checked against each other
    (logs named as on an arm whose elbow is ``elbow_joint``).

    For every two logs (e.g. base and shoulder, shoulder and elbow), their modes closer than
    :data:`SAME_MODE_RATIO`, at least one of them confident and neither weak (a weak mode may
    be no mode), are paired, closest first (a mode at most once per other log). A pair whose
    frequencies differ by more than ``max(AGREEMENT_SE · sqrt(se_a² + se_b²),
    AGREEMENT_FLOOR)`` (relative) disagrees (a doubtful partner widens the tolerance by its
    larger standard error, but still counts); both are flagged, naming the difference and the
    other log -- except where a third log settles it: a mode that agrees with a confident
    mode of a third log is confirmed, and of a disagreeing pair only the unconfirmed mode is
    flagged (with two logs nothing is confirmed).
    """
    out = list(ringing)
    joints = sorted({m.log_joint for m in out})
    pairs = []
    for n, first in enumerate(joints):
        for second in joints[n + 1 :]:
            pairs += _paired(out, first, second)
    confirmed = {
        i
        for a, b, distance, tolerance in pairs
        if distance <= tolerance
        for i, partner in ((a, b), (b, a))
        if not ringing[partner].low_confidence
    }
    for a, b, distance, tolerance in pairs:
        if distance <= tolerance:
            continue
        diff = 100.0 * (math.exp(distance) - 1.0)
        allowed = f"more than the {100 * tolerance:.1f} % the standard errors allow"
        settled = (a in confirmed) != (b in confirmed)
        for i, other in ((a, b), (b, a)):
            if settled and i in confirmed:
                continue
            log = _log_name(out[other].log_joint, elbow_joint)
            out[i] = out[i].flagged(f"disagrees with the {log} log ({diff:.1f} %, {allowed})")
    return out


def _paired(out: list[RingingMode], first: int, second: int) -> list[tuple[int, int, float, float]]:
    """The pairs ``(a, b, distance, tolerance)`` of :func:`cross_check_logs` between the logs
    of joints ``first`` and ``second``: indices into ``out``, ``|log(ω_a / ω_b)|`` and its
    tolerance."""
    one = [i for i, m in enumerate(out) if m.log_joint == first]
    two = [i for i, m in enumerate(out) if m.log_joint == second]
    candidates = sorted(
        (abs(math.log(out[a].wn_rad_s / out[b].wn_rad_s)), a, b)
        for a in one
        for b in two
        if abs(math.log(out[a].wn_rad_s / out[b].wn_rad_s)) < math.log(SAME_MODE_RATIO)
        and not (out[a].low_confidence and out[b].low_confidence)
        and _rings(out[a])
        and _rings(out[b])
        and math.isfinite(_relative_se(out[a]) + _relative_se(out[b]))
    )
    used: set[int] = set()
    pairs = []
    for distance, a, b in candidates:
        if a in used or b in used:
            continue
        used |= {a, b}
        combined = math.hypot(_relative_se(out[a]), _relative_se(out[b]))
        pairs.append((a, b, distance, max(AGREEMENT_SE * combined, AGREEMENT_FLOOR)))
    return pairs


def pose_of(record: Record) -> np.ndarray:
    """The pose a log was taken at: the median measured joint angles over its first quiet
    stretch (an excitation starts standing at its pose and returns around it)."""
    quiet = quiet_samples(record)
    if not np.any(quiet):
        return np.median(record.actual_q, axis=0)
    start = int(np.argmax(quiet))
    stop = start + int(np.argmin(quiet[start:])) if not quiet[start:].all() else quiet.size
    return np.median(record.actual_q[start:stop], axis=0)


def _check_same_pose(poses: Mapping[int, np.ndarray], elbow: int | None = 2) -> None:
    """Raise if the logs' starting poses (by excited joint, rad) differ by more than
    :data:`SAME_POSE_TOL_RAD` (each log moves its own joint by up to ±10°, after its start)."""
    joints = sorted(poses)
    for n, first in enumerate(joints):
        for second in joints[n + 1 :]:
            worst = float(np.max(np.abs(poses[first] - poses[second])))
            if worst > SAME_POSE_TOL_RAD:
                raise ValueError(
                    f"the {_log_name(first, elbow)} and {_log_name(second, elbow)} logs are not "
                    f"of the same pose: their starting poses differ by up to {worst:.3f} rad"
                )


def identify_pose(
    base_record: Record | None,
    shoulder_record: Record | None,
    robot: Any,
    *,
    key: str | None = None,
    q: np.ndarray | None = None,
    options: FitOptions | None = None,
    separate_modes: bool = True,
    accel_frame: str = "flange",
    other_records: Mapping[int, Record | None] | None = None,
) -> PoseRecord:
    """Identify the base and shoulder modes of one pose from its two excitation logs, and
    every mode that rings in them and in the logs of further excited joints.

    Parameters
    ----------
    base_record, shoulder_record
        Logs of the base (joint 0) and shoulder (joint 1) excitation at the same pose
        (``None``: that excitation is missing; its mode is then an error entry).
    robot
        Model with the payload, e.g. ``tvist.robots.ur5e(payload_kg, payload_com_m)``: the
        kinematics for preprocessing, the inertias and gravity torques for the map.
    key
        Name of the pose (default from the pose's joint angles).
    q
        The pose, rad (default: the median measured joint angles of the first log's quiet
        samples, :func:`pose_of`, base log first).
    options
        Local-fit settings.
    separate_modes
        Separate the base mode from the shoulder mode where the base log rings both:
        with the shoulder log's frequency (:func:`~tvist.ident.base_mode.separated_base_mode`),
        or, if the shoulder fit is not usable, from the base log alone
        (:func:`~tvist.ident.base_mode.separate_base_mode`). ``False``: the paper's
        single-mode fits.
    accel_frame
        Frame of the accelerometer columns (``"flange"`` or ``"base"``).
    other_records
        Logs of further excited joints at the same pose, by joint (e.g. ``{2: elbow_log}``;
        ``None`` entries are missing logs): each adds the modes that ring in it as
        ``ringing`` entries (``log_joint`` its joint), after a single-mode local fit of it
        for the input timing (:func:`~tvist.ident.local_identification.identify_local`). A log whose
        fits fail adds none (with a warning).

    Raises
    ------
    ValueError
        Every log missing, logs of different poses, or an ``other_records`` joint that is
        the base or the shoulder.
    """
    opts = options or FitOptions()
    others = {int(j): r for j, r in (other_records or {}).items()}
    if set(others) & set(IDENTIFIED_JOINTS):
        raise ValueError(
            "other_records holds further joints' logs; pass the base and shoulder logs as "
            "base_record and shoulder_record"
        )
    logs = {0: base_record, 1: shoulder_record, **others}
    present = {j: r for j, r in sorted(logs.items()) if r is not None}
    if not present:
        raise ValueError("identify_pose needs at least one excitation log")
    poses = {j: pose_of(r) for j, r in present.items()}
    params = getattr(robot, "params", None)
    elbow = getattr(params, "elbow_joint", 2) if params is not None else 2
    _check_same_pose(poses, elbow)
    if q is None:
        q = next(iter(poses.values()))
    q = np.asarray(q, dtype=float)
    payload = getattr(robot, "payload", None)
    fits: dict[int, LocalFit] = {}
    modes: dict[int, LocalFit | str] = {}
    for joint in (*IDENTIFIED_JOINTS, *sorted(others)):
        log = logs[joint]
        if log is None:
            if joint in IDENTIFIED_JOINTS:
                modes[joint] = "no log"
            continue
        try:
            fits[joint] = identify_local(
                log,
                joint,
                robot,
                options=opts,
                accel_frame=accel_frame,
                two_modes=separate_modes and joint == 0,
                base_mode=False,
            )
        except (ValueError, RuntimeError) as exc:
            if joint in IDENTIFIED_JOINTS:
                modes[joint] = str(exc)
            else:
                name = _log_name(joint, elbow)
                warnings.warn(f"{name} log: no local fit ({exc})", stacklevel=2)
            continue
        if joint in IDENTIFIED_JOINTS:
            modes[joint] = fits[joint]
    ringing: list[RingingMode] = []
    for joint, fit in fits.items():
        try:
            ringing += ringing_from_log(
                logs[joint], joint, robot, fit, q, options=opts, accel_frame=accel_frame
            )
        except (ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
            warnings.warn(f"joint {joint}: no multi-mode fit ({exc})", stacklevel=2)
    ringing = cross_check_logs(ringing, elbow)
    if separate_modes and 0 in fits:
        base = fits[0]
        shoulder = fits.get(1)
        if shoulder is not None and not shoulder.low_confidence:
            modes[0] = LocalFit.from_dict(separated_base_mode(base, shoulder, opts))
        elif base_record is not None and not base.no_ringing:
            modes[0] = _separate_alone(base, base_record, robot, opts, accel_frame)
    return PoseRecord(
        key=key or "q[" + ",".join(f"{v:.3f}" for v in q) + "]",
        q=tuple(float(v) for v in q),
        payload_kg=float(getattr(payload, "mass_kg", 0.0)),
        payload_com_m=tuple(float(v) for v in getattr(payload, "com_m", (0.0, 0.0, 0.0))),  # type: ignore[arg-type]
        inertia_kg_m2=tuple(float(v) for v in robot.joint_inertia(q)),
        gravity_torque_nm=tuple(float(v) for v in robot.gravity_torque(q)),
        modes=_linked(modes, ringing),
        ringing=tuple(ringing),
    )


#: Reasons of a ``ringing`` entry that leave its frequency unresolved (prefixes): an entry so
#: flagged cannot show another log's entry wrong (:func:`_seen_resolved_elsewhere`).
_UNRESOLVED_FREQUENCY = ("uncertain frequency", "merged neighbours", "next to an unresolved")
#: Two ``ringing`` entries of different logs are the same mode only if they also move the
#: flange in about the same direction: ``|cos|`` of the angle between their flange
#: directions at least this (45°). The same mode seen in two logs keeps its direction to a
#: few degrees (``|cos|`` >= 0.9 on the family variants' campaigns), two distinct modes of a
#: pose are close to perpendicular (``|cos|`` <= 0.06 where a base log's mode and a shoulder
#: log's other mode came within :data:`SAME_MODE_RATIO`); any threshold from 0.1 to 0.95
#: flagged the same entries there.
SAME_DIRECTION_COS = math.cos(math.radians(45.0))


def _frequency_unresolved(mode: RingingMode) -> bool:
    return any(r.startswith(_UNRESOLVED_FREQUENCY) for r in mode.reasons)


def _same_direction(a: RingingMode, b: RingingMode) -> bool:
    if a.flange_direction is None or b.flange_direction is None:
        return False
    cos = float(np.dot(a.flange_direction, b.flange_direction))
    norms = float(np.linalg.norm(a.flange_direction) * np.linalg.norm(b.flange_direction))
    return norms > 0.0 and abs(cos) >= SAME_DIRECTION_COS * norms


def _seen_resolved_elsewhere(
    fit: LocalFit, joint: int, mode: RingingMode, ringing: list[RingingMode]
) -> tuple[RingingMode, float] | None:
    """Where ``fit`` (``joint``'s ``modes`` entry, whose multi-mode fit ``mode`` flags merged
    neighbours) is contradicted by the same mode resolved in another log: the closest
    ``ringing`` entry of another log within :data:`SAME_MODE_RATIO` that moves the flange in
    the same direction (:data:`SAME_DIRECTION_COS`), rings clearly and has a resolved
    frequency (no uncertain frequency, merge or unresolved neighbour), if it differs from
    ``fit`` by more than the standard errors allow (as between two logs,
    :func:`cross_check_logs`); that entry and ``|log(ω / ω_fit)|``, else ``None``.

    The merged fit of the one log is then the one to doubt: the neighbour it could not
    separate pulls it, the other log's clean fit of the same mode is not pulled."""
    if not any(r.startswith("merged neighbours") for r in mode.reasons):
        return None
    same = [
        (abs(math.log(other.wn_rad_s / fit.wn_rad_s)), other)
        for other in ringing
        if other.log_joint != joint
        and _rings(other)
        and not _frequency_unresolved(other)
        and _same_direction(mode, other)
        and math.isfinite(_relative_se(other))
    ]
    same = [(d, other) for d, other in same if d < math.log(SAME_MODE_RATIO)]
    if not same:
        return None
    distance, other = min(same, key=lambda pair: pair[0])
    combined = math.hypot(_relative_se(other), fit.wn_se_rad_s / fit.wn_rad_s)
    if distance <= max(AGREEMENT_SE * combined, AGREEMENT_FLOOR):
        return None
    return other, distance


#: A ``modes`` entry agrees with its log's multi-mode fit within ``AGREEMENT_SE`` combined
#: standard errors or this fraction: the two estimators model the same log differently (the
#: paper map's entry has no feedthrough or a second mode only), so they differ by up to 1-2 %
#: on the twin where both are right.
LINK_FLOOR = 0.02


def _linked(
    modes: dict[int, LocalFit | str], ringing: list[RingingMode]
) -> dict[int, LocalFit | str]:
    """``modes`` with a confident entry flagged where its log's multi-mode fit does not
    confirm it:

    - no ringing mode near its frequency;
    - the nearest one's frequency is uncertain (its standard error above the limit): the
      entry's own small standard error only holds for its one- or two-mode model, on the
      family's variants such entries were 8-13 % off (a base mode pulled by a close
      shoulder mode);
    - the nearest one is flagged merged neighbours and another log resolves the same mode
      (same direction at the flange) at a frequency the standard errors do not allow
      (:func:`_seen_resolved_elsewhere`);
    - it differs from the nearest one by more than the standard errors allow (as between two
      logs, :func:`cross_check_logs`);
    - the nearest one's free decays ring slower than the entry by more than the standard
      errors allow: the entry is not the arm at rest
      (:func:`~tvist.ident.ringing.at_rest_reason`).

    The other doubts of the ``ringing`` entry (merged neighbours alone, a disagreement
    between two logs without a resolved same-direction partner, jumps across poses) are
    not inherited: on the twin's campaigns they flag mostly correct entries."""
    if not ringing:
        return modes
    out = dict(modes)
    for joint, fit in modes.items():
        if isinstance(fit, str) or fit.low_confidence or fit.no_ringing:
            continue
        if not any(m.log_joint == joint for m in ringing):
            continue
        index = _ringing_index(fit, joint, tuple(ringing))
        found = ", ".join(f"{m.fn_hz:.2f}" for m in ringing if m.log_joint == joint)
        reason = None
        if index is None:
            reason = (
                f"not among the modes that ring in the log ({fit.fn_hz:.2f} Hz; the multi-mode "
                f"fit finds {found} Hz)"
            )
            out[joint] = replace(fit, low_confidence=True, reasons=(*fit.reasons, reason))
            continue
        mode = ringing[index]
        elsewhere = _seen_resolved_elsewhere(fit, joint, mode, ringing)
        distance = abs(math.log(mode.wn_rad_s / fit.wn_rad_s))
        combined = math.hypot(_relative_se(mode), fit.wn_se_rad_s / fit.wn_rad_s)
        at_rest = at_rest_reason(fit.wn_rad_s, fit.wn_se_rad_s, mode)
        if at_rest is not None:
            reason = at_rest
        elif any(r.startswith("uncertain frequency") for r in mode.reasons):
            why = next(r for r in mode.reasons if r.startswith("uncertain frequency"))
            reason = f"the multi-mode fit of the same log doubts it ({mode.fn_hz:.2f} Hz: {why})"
        elif elsewhere is not None:
            other, apart = elsewhere
            reason = (
                f"merged in its log: the {_log_name(other.log_joint)} log resolves the same "
                f"mode at {other.fn_hz:.2f} Hz ({100 * (math.exp(apart) - 1):.1f} % away)"
            )
        elif distance > max(AGREEMENT_SE * combined, LINK_FLOOR):
            reason = (
                f"disagrees with the multi-mode fit of the same log "
                f"({100 * (math.exp(distance) - 1):.1f} %: {fit.fn_hz:.2f} Hz against "
                f"{found} Hz)"
            )
        if reason is not None:
            out[joint] = replace(fit, low_confidence=True, reasons=(*fit.reasons, reason))
    return out


def _separate_alone(
    base: LocalFit, record: Record, robot: Any, opts: FitOptions, accel_frame: str
) -> LocalFit:
    """The base-log-only separation (used when the shoulder fit is not usable)."""
    from tvist.ident.local_fit import interval_mean_acceleration, saturated_samples
    from tvist.ident.preprocess import tangential_acceleration

    if not is_uniform(record.t_s):
        record, _ = resample_uniform(record)  # as identify_local did (it warned)
    tangential = tangential_acceleration(record, 0, robot, accel_frame=accel_frame)  # type: ignore[arg-type]
    assert tangential.accel_base is not None
    jac = robot.jacobian_many(np.ascontiguousarray(record.actual_q))[:, :3, :2]
    return separate_base_mode(
        base,
        interval_mean_acceleration(record.target_qd[:, 0], record.dt_s),
        tangential.accel_base,
        jac[:, :, 0],
        jac[:, :, 1],
        record.dt_s,
        ~saturated_samples(record.tool_accel),
        max_wn_rel_se=opts.max_wn_rel_se,
    )
