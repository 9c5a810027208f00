"""Per-parameter standard errors of a least-squares fit, against the textbook linear-regression
ones computed by hand (ordinary least squares, ``σ² (XᵀX)⁻¹`` as statsmodels reports them)."""

from __future__ import annotations

import numpy as np

from tvist.ident.standard_errors import standard_errors


def ols_standard_errors(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Residuals of the least-squares fit of ``y`` by full-rank ``x`` and the standard errors
    ``√diag(σ² (XᵀX)⁻¹)``, ``σ² = rᵀr / (n − p)``."""
    n, p = x.shape
    beta = np.linalg.solve(x.T @ x, x.T @ y)
    residual = y - x @ beta
    sigma2 = residual @ residual / (n - p)
    return residual, np.sqrt(sigma2 * np.diag(np.linalg.inv(x.T @ x)))


def regression(seed: int, n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Four regressors of different units (column norms about 6 to 6e3) and a noisy response."""
    rng = np.random.default_rng(seed)
    x = np.column_stack([np.ones(n), rng.normal(size=(n, 3)) * [1.0, 1e2, 1e3]])
    y = x @ [0.5, -2.0, 0.03, 1e-3] + 0.1 * rng.normal(size=n)
    return x, y


def test_full_rank_equals_sigma2_times_the_inverse_normal_matrix():
    for seed in range(3):
        x, y = regression(seed)
        # The Jacobian of the residuals y - X β is -X; its sign does not matter.
        residual, expected = ols_standard_errors(x, y)
        np.testing.assert_allclose(standard_errors(-x, residual), expected, rtol=1e-10, atol=0)


def test_two_identical_columns_are_undetermined_and_leave_the_others_as_without_one():
    x, y = regression(4)
    # Columns 2 and 4 are the same regressor: only their sum is determined by the data.
    doubled = np.column_stack([x, x[:, 2]])
    residual, reduced = ols_standard_errors(x, y)
    se = standard_errors(doubled, residual)
    assert se[2] == np.inf and se[4] == np.inf
    # The others are determined: the standard errors of the problem without the copy (the
    # same residuals and degrees of freedom, n - rank).
    np.testing.assert_allclose(se[[0, 1, 3]], reduced[[0, 1, 3]], rtol=1e-10, atol=0)


def test_a_column_of_zeros_is_undetermined_and_leaves_the_others():
    x, y = regression(5)
    residual, expected = ols_standard_errors(x, y)
    se = standard_errors(np.column_stack([x[:, :2], np.zeros(len(y)), x[:, 2:]]), residual)
    assert se[2] == np.inf
    np.testing.assert_allclose(se[[0, 1, 3, 4]], expected, rtol=1e-10, atol=0)


def test_fewer_residuals_than_parameters_determine_nothing():
    x, y = regression(6, n=3)
    assert np.all(standard_errors(x, y) == np.inf)
    assert standard_errors(np.zeros((5, 0)), np.zeros(5)).shape == (0,)
