"""Standard errors of least-squares parameters, per parameter: ``√diag(σ² (JᵀJ)⁺)``.

A parameter the data do not determine (its Jacobian column zero, or a combination of other
columns: two load terms of a joint no identified mode involves) makes ``J`` singular. That
parameter's standard error is infinite; the others keep the finite standard errors of the
problem reduced to the directions the data determine (for an estimable parameter
``e_iᵀ (JᵀJ)⁺ e_i`` is the same for every generalized inverse, so they equal those of the fit
with the undetermined parameters merged or removed).

Numerically: ``J``'s columns are scaled to unit length (the parameters' units then do not
matter) and its singular values at or below :data:`JACOBIAN_RTOL` times the largest are taken
for zero. A parameter is undetermined when more than :data:`JACOBIAN_RTOL` of its unit
vector's squared length lies in that null space.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["JACOBIAN_RTOL", "standard_errors"]

#: Relative accuracy of the least-squares Jacobians (finite differences: about √ε). Singular
#: values of the column-scaled Jacobian at or below this times the largest are not told from
#: zero; a parameter with more than this share (of its squared length) in their span is
#: undetermined.
JACOBIAN_RTOL = 1.5e-8


def standard_errors(jac: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Standard error of each parameter of a least-squares fit, shape (p,).

    ``jac`` is the Jacobian of the residuals at the solution, shape (n, p); ``residual`` the
    residuals, shape (n,). ``σ² = rᵀr / (n − rank J)``; the standard errors are
    ``√diag(σ² (JᵀJ)⁺)``, infinite for every parameter the data do not determine (see the
    module). All are infinite with fewer residuals than parameters.
    """
    n, p = jac.shape
    if p == 0:
        return np.zeros(0)
    out = np.full(p, math.inf)
    if n < p:
        return out
    norm = np.linalg.norm(jac, axis=0)
    seen = norm > 0
    if not seen.any():
        return out
    _, sv, vt = np.linalg.svd(jac[:, seen] / norm[seen], full_matrices=False)
    # Degrees of freedom: the residuals less the directions the data determine.
    rank = int(np.sum(sv > JACOBIAN_RTOL * sv[0]))
    s2 = float(residual @ residual) / max(n - rank, 1)
    # n >= p: vt is square, its rows from `rank` on span the null space of the seen columns.
    in_null_space = np.sum(vt[rank:] ** 2, axis=0)
    determined = in_null_space <= JACOBIAN_RTOL
    variance = np.einsum("ki,k->i", vt[:rank] ** 2, 1.0 / sv[:rank] ** 2) * s2
    se = np.sqrt(variance) / norm[seen]
    out[np.flatnonzero(seen)[determined]] = se[determined]
    return out
