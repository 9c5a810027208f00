"""Exact sampled responses of a second-order mode to a piecewise-constant input.

The mode is ``ÿ + 2ζω ẏ + ω² y = u(t)`` with state ``x = [y, ẏ]``. The input ``u`` is held
constant over each sample interval: sample ``k`` holds ``u[k]`` on ``[t_k, t_{k+1})`` (the
interval-mean acceleration of a log, ``(qd[k+1] - qd[k]) / dt_s``, is exactly such an input
for the velocity it came from). The input may reach the mode late or early by any real
``delay_s``, positive or negative: with ``delay_s = d dt_s + ε`` (``d`` whole samples,
``0 <= ε < dt_s``), the interval ``[t_k, t_{k+1})`` sees ``u[k-d-1]`` on its first ``ε`` and
``u[k-d]`` on the rest, so

``x[k+1] = A_d x[k] + Γ(dt-ε) u[k-d] + e^{A(dt-ε)} Γ(ε) u[k-d-1]``,

with ``A_d = e^{A dt}`` and ``Γ(h) = ∫_0^h e^{Aσ} dσ B``. This is exact (no discretisation
error) for every delay; at ``ε = 0`` it is the ordinary zero-order-hold discretisation.
"""

from __future__ import annotations

import numpy as np
from scipy import linalg, signal

__all__ = ["expm_and_gamma", "least_squares_fit", "shifted", "zoh_matrices", "zoh_responses"]


def expm_and_gamma(wn: float, zeta: float, h_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(e^{A h}, Γ(h))`` of ``ÿ + 2ζω ẏ + ω² y = u`` over ``h_s >= 0``; state ``[y, ẏ]``.

    Sylvester's formula with the eigenvalues ``λ_1,2 = -ζω ± ω√(ζ²-1)`` (complex for ζ < 1):
    ``e^{At} = c_0 I + c_1 A`` with ``c_0 = (λ_1 e^{λ_2 t} - λ_2 e^{λ_1 t})/(λ_1 - λ_2)`` and
    ``c_1 = (e^{λ_1 t} - e^{λ_2 t})/(λ_1 - λ_2)``, and ``Γ = A⁻¹ (e^{Ah} - I) B``. Near
    critical damping the eigenvalues merge and the augmented matrix exponential is used.
    """
    a = np.array([[0.0, 1.0], [-(wn**2), -2.0 * zeta * wn]])
    if h_s == 0.0:
        return np.eye(2), np.zeros(2)
    root = wn * np.sqrt(complex(zeta * zeta - 1.0))
    if abs(root) < 1e-4 * wn:
        m = np.zeros((3, 3))
        m[:2, :2] = a
        m[1, 2] = 1.0
        e = linalg.expm(m * h_s)
        return e[:2, :2], e[:2, 2]
    l1, l2 = -zeta * wn + root, -zeta * wn - root
    e1, e2 = np.exp(l1 * h_s), np.exp(l2 * h_s)
    c0 = ((l1 * e2 - l2 * e1) / (l1 - l2)).real
    c1 = ((e1 - e2) / (l1 - l2)).real
    ad = c0 * np.eye(2) + c1 * a
    # A⁻¹ (e^{Ah} - I) [0, 1]ᵀ with A⁻¹ = [[-2ζ/ω, -1/ω²], [1, 0]]
    col = (ad - np.eye(2))[:, 1]
    gamma = np.array([-2.0 * zeta / wn * col[0] - col[1] / wn**2, col[0]])
    return ad, gamma


def zoh_matrices(wn: float, zeta: float, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``(A_d, B_d)`` of the mode with its input held over ``dt_s`` (no delay)."""
    return expm_and_gamma(wn, zeta, dt_s)


def shifted(u: np.ndarray, d: int) -> np.ndarray:
    """``u[k - d]`` for every ``k`` (``d`` may be negative); the ends are held at the nearest
    value of ``u`` (a log starts and ends at rest, so this is zero acceleration there)."""
    n = u.size
    if d == 0:
        return u
    if abs(d) >= n:
        return np.full(n, u[0] if d > 0 else u[-1])
    if d > 0:
        return np.concatenate([np.full(d, u[0]), u[:-d]])
    return np.concatenate([u[-d:], np.full(-d, u[-1])])


def _filter(ad: np.ndarray, b: np.ndarray, u: np.ndarray) -> np.ndarray:
    """States ``x[k]`` of ``x[k+1] = A_d x[k] + b u[k]`` from rest, shape (n_samples, 2).

    Run by ``lfilter`` on the equivalent transfer functions: denominator the characteristic
    polynomial of ``A_d``, numerators ``C adj(zI - A_d) b`` with ``C = [1, 0]`` or ``[0, 1]``
    (strictly proper: ``x[k]`` depends on ``u`` up to ``k - 1``).
    """
    a1 = -(ad[0, 0] + ad[1, 1])
    a2 = ad[0, 0] * ad[1, 1] - ad[0, 1] * ad[1, 0]
    den = np.array([1.0, a1, a2])
    num0 = np.array([0.0, b[0], ad[0, 1] * b[1] - ad[1, 1] * b[0]])
    num1 = np.array([0.0, b[1], ad[1, 0] * b[0] - ad[0, 0] * b[1]])
    return np.column_stack([signal.lfilter(num0, den, u), signal.lfilter(num1, den, u)])


def zoh_responses(
    wn: float, zeta: float, u: np.ndarray, dt_s: float, delay_s: float = 0.0
) -> np.ndarray:
    """Exact responses of ``1/den`` and ``s/den`` to the held input ``u`` delayed by
    ``delay_s`` (s, any sign), sampled at the log's instants; shape (n_samples, 2).

    Column 0 is ``y`` and column 1 is ``ẏ`` of ``ÿ + 2ζω ẏ + ω² y = u(t - delay_s)``.
    """
    u = np.asarray(u, dtype=float)
    d = int(np.floor(delay_s / dt_s + 1e-12))
    eps = delay_s - d * dt_s
    if eps < 1e-12 * dt_s:
        eps = 0.0
    ad, b_late = expm_and_gamma(wn, zeta, dt_s - eps)
    full_ad, _ = expm_and_gamma(wn, zeta, dt_s)
    out = _filter(full_ad, b_late, shifted(u, d))
    if eps > 0.0:
        _, gamma_eps = expm_and_gamma(wn, zeta, eps)
        out += _filter(full_ad, ad @ gamma_eps, shifted(u, d + 1))
    return out


def least_squares_fit(phi: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Linear least-squares coefficients of ``y ≈ phi @ beta`` (a few columns, many rows),
    for a signal ``y`` (n,) or for every column of ``y`` (n, n_channels).

    Normal equations on unit-norm columns: a small dense solve, far cheaper than an SVD of
    the tall matrix in the inner loop of the nonlinear searches; falls back to ``lstsq`` when
    the columns are (numerically) dependent.
    """
    scale = np.linalg.norm(phi, axis=0)
    scale[scale == 0.0] = 1.0
    phi_n = phi / scale
    gram = phi_n.T @ phi_n
    try:
        if np.linalg.cond(gram) > 1e12:
            raise np.linalg.LinAlgError
        return np.linalg.solve(gram, phi_n.T @ y) / (scale if y.ndim == 1 else scale[:, None])
    except np.linalg.LinAlgError:
        beta, *_ = np.linalg.lstsq(phi, y, rcond=None)
        return beta
