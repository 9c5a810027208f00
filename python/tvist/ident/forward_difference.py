"""Forward-difference Jacobians from one batched evaluation of a residual.

``scipy.optimize.least_squares(..., jac="2-point")`` calls the residual once per parameter to
estimate the Jacobian; a residual that evaluates many parameter vectors in one call (stacked
eigenproblems) is many times faster. :func:`forward_difference_jacobian` takes the steps
scipy's ``"2-point"`` scheme takes (``scipy.optimize._numdiff.approx_derivative``: relative
step ``√ε``, flipped or shortened at a bound) with the same arithmetic, so passed as ``jac``
it gives the fit the matrix the ``"2-point"`` default gives, to the bit
(``tests/unit/test_forward_difference.py`` checks it against scipy's).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

__all__ = ["forward_difference_jacobian"]

#: Relative step of the forward difference: the square root of the float64 epsilon.
RELATIVE_STEP = np.finfo(np.float64).eps ** 0.5


def _steps(x: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> np.ndarray:
    """Step per parameter: ``√ε max(1, |x|)`` away from zero, reversed where it would cross a
    bound and fits on the other side, else the distance to the farther bound."""
    sign = (x >= 0).astype(float) * 2 - 1
    h = RELATIVE_STEP * sign * np.maximum(1.0, np.abs(x))
    if np.all((lb == -np.inf) & (ub == np.inf)):
        return h
    adjusted = h.copy()
    lower, upper = x - lb, ub - x
    violated = (x + h < lb) | (x + h > ub)
    fitting = np.abs(h) <= np.maximum(lower, upper)
    adjusted[violated & fitting] *= -1
    forward = (upper >= lower) & ~fitting
    adjusted[forward] = upper[forward]
    backward = (upper < lower) & ~fitting
    adjusted[backward] = -lower[backward]
    return adjusted


def forward_difference_jacobian(
    residual_many: Callable[[np.ndarray], np.ndarray],
    x: np.ndarray,
    bounds: tuple[Sequence[float] | np.ndarray, Sequence[float] | np.ndarray],
) -> np.ndarray:
    """``(m, n)`` Jacobian at ``x`` (``n`` parameters within ``bounds``) of a residual of
    ``m`` values, by forward differences.

    ``residual_many`` maps ``(b, n)`` parameter vectors to their ``(b, m)`` residuals, each
    row exactly what the residual of that vector alone is; it is called once, on ``x`` and
    its ``n`` steps."""
    x = np.asarray(x, dtype=float)
    lb, ub = (np.resize(np.asarray(b, dtype=float), x.shape) for b in bounds)
    h = _steps(x, lb, ub)
    stepped = np.repeat(x[None, :], x.size + 1, axis=0)
    diagonal = np.arange(x.size)
    stepped[diagonal + 1, diagonal] = x + h
    f = residual_many(stepped)
    dx = (x + h) - x
    # Built transposed in row-major order, as scipy builds it: the least-squares solver then
    # sees the same memory layout (its products sum in the same order).
    return np.ascontiguousarray((f[1:] - f[0]) / dx[:, None]).T
