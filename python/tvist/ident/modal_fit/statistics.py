"""Statistics of the modal fit: standard errors of the fitted parameters, the kept law
coefficients with their standard errors in physical units, and relative errors of predicted
modes against identified or true ones.

The standard errors are those of :func:`tvist.ident.standard_errors.standard_errors` (per
parameter: infinite only for the parameters the data do not determine), over the inliers of
a robust fit."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from tvist.ident.modal_fit.model import _Term
from tvist.ident.standard_errors import standard_errors

#: Residuals beyond this many robust standard deviations are outliers in the stiffness fit's
#: standard errors (they are down-weighted in the fit itself by the robust loss).
OUTLIER_SIGMAS = 4.0


def _standard_errors(
    jac: np.ndarray, residual: np.ndarray, outlier_sigmas: float | None = None
) -> np.ndarray:
    """Per-parameter standard errors ``√diag(σ² (JᵀJ)⁺)`` with ``σ² = rᵀr / (n − rank J)``,
    infinite for a parameter the data do not determine
    (:func:`tvist.ident.standard_errors.standard_errors`).

    With ``outlier_sigmas`` (for a fit with a robust loss), residuals beyond that many robust
    standard deviations (``1.4826 median|r|``) are left out of ``σ²`` and ``J``, as the robust
    loss leaves them out of the fit: a mode the local fit mistook for another (a 20 % residual
    among 0.5 % ones) would otherwise inflate every standard error and get determinable terms
    dropped as insignificant.
    """
    if outlier_sigmas is not None and residual.size:
        robust_sigma = 1.4826 * float(np.median(np.abs(residual)))
        inlier = np.abs(residual) <= outlier_sigmas * robust_sigma
        if robust_sigma > 0 and inlier.sum() > jac.shape[1]:
            jac, residual = jac[inlier], residual[inlier]
    return standard_errors(jac, residual)


def _json_number(value: float) -> float | None:
    """``value`` as a float, or ``None`` (JSON null) when it is not finite (an unidentifiable
    term's standard error)."""
    value = float(value)
    return value if math.isfinite(value) else None


def _coefficient_stats(
    stiff_terms: Sequence[_Term],
    damp_terms: Sequence[_Term],
    stiffness: Mapping[int, Sequence[float]],
    damping: Mapping[int, Sequence[float]],
    se: np.ndarray,
    two_stage: tuple[Mapping[int, Sequence[float]], Mapping[int, Sequence[float]]] | None,
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Every kept law coefficient with its standard error, in physical units (``se``: of the
    stiffness parameters ``log k_0, a_1, a_2``, then of the damping coefficients), and, after
    the joint refinement, the two-stage value it started from."""
    names = ("at_zero", "per_nm", "per_nm2")
    stiffness_stats, damping_stats = [], []
    for i, t in enumerate(stiff_terms):
        index = 0 if t.name == "k_0" else int(t.name[-1])
        # d k_0 = k_0 d(log k_0); k_i = k_0 a_i, d k_i ≈ k_0 d a_i.
        entry = {
            "joint": t.joint,
            "term": names[index],
            "value": float(stiffness[t.joint][index]),
            "se": _json_number(stiffness[t.joint][0] * se[i]),
        }
        if two_stage is not None:
            entry["two_stage"] = float(two_stage[0][t.joint][index])
        stiffness_stats.append(entry)
    for i, t in enumerate(damp_terms, start=len(stiff_terms)):
        index = int(t.name[-1])
        entry = {
            "joint": t.joint,
            "term": names[index],
            "value": float(damping[t.joint][index]),
            "se": _json_number(se[i]),
        }
        if two_stage is not None:
            entry["two_stage"] = float(two_stage[1][t.joint][index])
        damping_stats.append(entry)
    return stiffness_stats, damping_stats


def relative_errors(pred: np.ndarray, wn_rad_s: np.ndarray, zeta: np.ndarray) -> dict[str, Any]:
    """RMS and max relative errors of predictions ``(n, 2, 2)`` against modes ``(n, 2)``,
    per mode (base, shoulder), over the finite entries."""
    out: dict[str, Any] = {}
    for m, name in enumerate(("base", "shoulder")):
        entry: dict[str, Any] = {}
        for q, ref in (("frequency", wn_rad_s[:, m]), ("damping", zeta[:, m])):
            rel = pred[:, m, 0 if q == "frequency" else 1] / ref - 1.0
            rel = rel[np.isfinite(rel)]
            entry[q] = {
                "n": int(rel.size),
                "rms": float(np.sqrt(np.mean(rel**2))) if rel.size else math.nan,
                "max": float(np.max(np.abs(rel))) if rel.size else math.nan,
            }
        out[name] = entry
    return out
