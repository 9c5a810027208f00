"""Which mode of a base excitation is the base mode.

A base excitation may ring the shoulder mode too: strongly where the base mode is heavily
damped or moves the flange little (the paper's Fig. 22 situation), so that a single-mode fit
returns the shoulder frequency or a blend. Two ways to tell the modes apart:

- **from the base log alone** (:func:`separate_base_mode`, the default of
  :func:`~tvist.ident.local_identification.identify_local` for joint 0): each mode moves the flange
  in its own direction, the base mode along the base joint's tangent ``t_0``, the shoulder mode
  along the shoulder's tangent ``t_1``. Every mode of the fit (one, or two when the two-mode fit is
  significant) is fitted to the base-frame acceleration along ``t_0`` and along ``t_1`` of the same
  log; the mode with the larger share along ``t_0`` is the base mode. Where the two tangents are
  nearly parallel (flange over the base axis) or the shares do not differ clearly, the modes cannot
  be told apart and the result is flagged;
- **with the shoulder excitation of the same pose** (:func:`separated_base_mode`, used by
  :func:`~tvist.ident.pose.identify_pose` and the campaign): the component of the base log's
  two-mode fit at the shoulder log's frequency is the shoulder mode.

The result is never the shoulder mode reported unflagged as the base mode.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from tvist.ident.mode_estimates import ModeEstimate
from tvist.ident.zoh import least_squares_fit, shifted, zoh_responses

if TYPE_CHECKING:
    from tvist.ident.local_fit import FitOptions, LocalFit

__all__ = [
    "CLEAR_SHARE",
    "SAME_MODE_RATIO",
    "direction_shares",
    "separate_base_mode",
    "separated_base_mode",
]

#: Modes closer than this frequency ratio are taken for the same mode (twice the 1 % accuracy
#: of a local fit, plus margin).
SAME_MODE_RATIO = 1.03
#: A base component with less than this share of the response is flagged low-confidence.
CLEAR_SHARE = 0.3
#: Tangents of base and shoulder closer than this angle cannot separate the modes.
MIN_TANGENT_ANGLE_RAD = math.radians(30.0)
#: The base mode's share along ``t_0`` must exceed the other mode's by this much.
MIN_SHARE_MARGIN = 0.2


def direction_shares(
    modes: Sequence[tuple[float, float]],
    u: np.ndarray,
    accel_base: np.ndarray,
    directions: Sequence[np.ndarray],
    dt_s: float,
    delay_s: float,
    mask: np.ndarray,
) -> np.ndarray:
    """Energy of each mode's fitted response along each direction, shape (n_modes, n_dirs).

    For each direction ``d`` (unit vectors per sample, shape (n_samples, 3)), the base-frame
    acceleration along ``d`` is fitted by all ``modes`` together (numerators, a feedthrough
    and an offset by linear least squares); entry ``[i, j]`` is the energy of mode ``i``'s
    part of that fit along direction ``j``.
    """
    blocks = [zoh_responses(wn, zeta, u, dt_s, delay_s)[mask] for wn, zeta in modes]
    fed = shifted(u, int(round(delay_s / dt_s)))[mask]
    phi = np.column_stack([*blocks, fed, np.ones(fed.size)])
    out = np.zeros((len(modes), len(directions)))
    for j, d in enumerate(directions):
        y = np.einsum("ni,ni->n", accel_base, d)[mask]
        beta = least_squares_fit(phi, y)
        for i, block in enumerate(blocks):
            part = block @ beta[2 * i : 2 * i + 2]
            out[i, j] = float(part @ part)
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def separate_base_mode(
    fit: LocalFit,
    u: np.ndarray,
    accel_base: np.ndarray,
    base_tangent: np.ndarray,
    shoulder_tangent: np.ndarray,
    dt_s: float,
    mask: np.ndarray,
    *,
    max_wn_rel_se: float = 0.01,
) -> LocalFit:
    """The base mode of a base-joint fit (with ``fit.two_mode`` set), from the log alone.

    Parameters
    ----------
    fit
        Single-mode fit of the base log, with its two-mode fit attached.
    u, dt_s, mask
        The fit's input, sampling period and used samples.
    accel_base
        Gravity-free base-frame flange acceleration, m/s², shape (n_samples, 3).
    base_tangent, shoulder_tangent
        Linear Jacobian columns of joints 0 and 1 at the flange, shape (n_samples, 3).
    max_wn_rel_se
        A separated mode with a larger relative standard error of ``ω_n`` is flagged.
    """
    t0, t1 = _unit(base_tangent), _unit(shoulder_tangent)
    cos = float(np.median(np.abs(np.einsum("ni,ni->n", t0, t1))))
    if cos > math.cos(MIN_TANGENT_ANGLE_RAD):
        return _flagged(
            fit,
            f"the base and the shoulder move the flange in nearly the same direction here "
            f"({math.degrees(math.acos(cos)):.0f}° apart): the base mode cannot be told from "
            "the shoulder mode in a base log alone; identify the pose with its shoulder log "
            "(identify_pose)",
        )
    split = fit.two_mode
    if split is None or not split.significant:
        share = direction_shares(
            [(fit.wn_rad_s, fit.zeta)], u, accel_base, (t0, t1), dt_s, fit.delay_s, mask
        )[0]
        along_base = share[0] / max(share.sum(), 1e-300)
        if along_base < 0.5:
            return _flagged(
                fit,
                f"the mode found moves the flange mostly along the shoulder's direction "
                f"({100 * along_base:.0f} % along the base's): it is the shoulder mode, the "
                "base mode is hidden",
            )
        return fit
    modes = split.modes
    shares = direction_shares(
        [(m.wn_rad_s, m.zeta) for m in modes], u, accel_base, (t0, t1), dt_s, fit.delay_s, mask
    )
    along_base = shares[:, 0] / np.maximum(shares.sum(axis=1), 1e-300)
    order = np.argsort(-along_base)
    base, other = modes[int(order[0])], modes[int(order[1])]
    if along_base[order[0]] - along_base[order[1]] < MIN_SHARE_MARGIN:
        return _flagged(
            fit,
            f"the two modes ({modes[0].fn_hz:.2f} and {modes[1].fn_hz:.2f} Hz) move the flange "
            "in similar directions: the base mode cannot be told from the shoulder mode",
        )
    reasons = [r for r in fit.reasons if not r.startswith(("uncertain", "overdamped"))]
    if base.energy_share < CLEAR_SHARE:
        reasons.append(
            f"base mode weak next to the {other.fn_hz:.2f} Hz mode "
            f"({100 * base.energy_share:.0f} % of the response)"
        )
    return _as_base_mode(fit, base, reasons, max_wn_rel_se)


def _flagged(fit: LocalFit, reason: str) -> LocalFit:
    return replace(fit, low_confidence=True, reasons=(*fit.reasons, reason))


def _two_mode_fields(
    mode: ModeEstimate, reasons: list[str], max_wn_rel_se: float
) -> dict[str, Any]:
    """The result fields of ``mode`` of the two-mode fit (all but ``reasons`` and ``apparent``).

    Appends the uncertain-frequency reason to ``reasons`` (in place) when the relative
    standard error of ``ω_n`` exceeds ``max_wn_rel_se``; ``low_confidence`` is set from
    ``reasons`` after that. ``k_c = 2ζω_n`` (rad/s) and ``k_d = ω_n²`` (rad²/s²).
    """
    if mode.wn_se_rad_s > max_wn_rel_se * mode.wn_rad_s:
        reasons.append(
            f"uncertain frequency: standard error {100 * mode.wn_se_rad_s / mode.wn_rad_s:.2f}"
            " % of ω_n (two-mode fit)"
        )
    return {
        "wn_rad_s": mode.wn_rad_s,
        "zeta": mode.zeta,
        "wn_se_rad_s": mode.wn_se_rad_s,
        "zeta_se": mode.zeta_se,
        "k_a": mode.k_a,
        "k_b": mode.k_b,
        "k_c": 2.0 * mode.zeta * mode.wn_rad_s,
        "k_d": mode.wn_rad_s**2,
        "method": "two-mode",
        "low_confidence": bool(reasons),
    }


def _as_base_mode(
    fit: LocalFit, mode: ModeEstimate, reasons: list[str], max_wn_rel_se: float
) -> LocalFit:
    """``fit`` with its mode replaced by ``mode`` of the two-mode fit."""
    fields = _two_mode_fields(mode, reasons, max_wn_rel_se)  # may append to reasons
    return replace(
        fit,
        **fields,
        apparent={
            "wn_rad_s": fit.wn_rad_s,
            "zeta": fit.zeta,
            "low_confidence": float(fit.low_confidence),
        },
        reasons=tuple(reasons),
    )


def separated_base_mode(base: LocalFit, shoulder: LocalFit, options: FitOptions) -> dict[str, Any]:
    """The base record, with the base mode separated from the shoulder mode where needed.

    ``base`` is the single-mode fit of the base log with its two-mode fit attached;
    ``shoulder`` the fit of the shoulder log of the same pose. From the two-mode fit:

    - if its dominant component (largest share of the response) is not at the shoulder
      frequency identified from the shoulder excitation (within :data:`SAME_MODE_RATIO`),
      it is the base mode (the single-mode fit if the other component is no real mode);
    - if the dominant component is at the shoulder frequency, the base mode is the other
      component when that one is significant and well determined; with less than
      :data:`CLEAR_SHARE` of the response it is flagged low-confidence (it is still the best
      estimate of the base mode: the single-mode value would be the shoulder mode's);
    - otherwise the base and shoulder modes cannot be told apart (hidden or coincident
      modes): the single-mode fit is kept, flagged.

    The single-mode result is kept under ``apparent`` whenever it is replaced.
    """
    entry = base.to_dict()
    entry["method"] = "single-mode"
    split = base.two_mode
    if split is None or shoulder.low_confidence:
        return entry
    limit = math.log(SAME_MODE_RATIO)

    def shoulder_like(m: ModeEstimate) -> bool:
        return abs(math.log(m.wn_rad_s / shoulder.wn_rad_s)) < limit

    dominant, other = sorted(split.modes, key=lambda m: -m.energy_share)
    reasons = [r for r in base.reasons if not r.startswith(("uncertain", "overdamped"))]
    if not shoulder_like(dominant):
        # Even a weak second mode biases the single-mode fit, so the two-mode value is used
        # unless the second component is no mode at all (overdamped or unresolved).
        if other.zeta >= 0.9 or not other.wn_se_rad_s < 0.5 * other.wn_rad_s:
            return entry
        chosen = dominant
    elif split.significant and other.wn_se_rad_s <= options.max_wn_rel_se * 5 * other.wn_rad_s:
        chosen = other
        if other.energy_share < CLEAR_SHARE:
            reasons.append(
                f"base mode weak next to the shoulder mode ({100 * other.energy_share:.0f} % "
                "of the response)"
            )
    else:
        entry.update(
            low_confidence=True,
            reasons=[
                *base.reasons,
                "base excitation rings at the shoulder frequency: the base mode is hidden "
                "behind (or coincides with) the shoulder mode",
            ],
        )
        return entry
    fields = _two_mode_fields(chosen, reasons, options.max_wn_rel_se)  # may append to reasons
    entry.update(
        fields,
        apparent={"wn_rad_s": base.wn_rad_s, "zeta": base.zeta},
        reasons=reasons,
    )
    return entry
