"""The batched forward-difference Jacobian is scipy's ``"2-point"`` one, to the bit: the same
matrix (steps flipped or shortened at bounds included), and least_squares given it returns
the same solution as with its default."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize
from scipy.optimize._numdiff import approx_derivative

from tvist.ident.forward_difference import forward_difference_jacobian

T = np.linspace(0.0, 2.0, 25)


def _many(x: np.ndarray) -> np.ndarray:
    """A nonlinear residual of 3 parameters, for ``(b, 3)`` of them: ``(b, 25)``, column-major
    (the Jacobian's layout must not follow the residual's)."""
    a, w, c = x[:, 0, None], x[:, 1, None], x[:, 2, None]
    return np.asfortranarray(a * np.exp(-c * T) * np.sin(w * T) - np.sin(1.3 * T))


def _one(x: np.ndarray) -> np.ndarray:
    return _many(x[None, :])[0]


@pytest.mark.parametrize(
    ("x", "lb", "ub"),
    [
        ([0.7, 1.1, 0.2], [-np.inf, 0.0, 0.0], [np.inf, 2.0, 1.0]),
        ([-2.5, 0.0, 1e-9], [-np.inf, -1.0, 0.0], [np.inf, 1.0, 1.0]),
        # At the upper bounds of w and c: their steps flipped backward.
        ([1.0, 2.0, 1.0], [-np.inf, 0.0, 0.0], [np.inf, 2.0, 1.0]),
        # c within 1e-10 of both bounds, less than a step: the step shortened to the farther.
        ([0.0, -3.0, 0.5], [-1.0, -4.0, 0.5 - 1e-10], [1.0, 0.0, 0.5 + 2e-10]),
    ],
)
def test_the_matrix_is_scipys_2_point_one_to_the_bit(x, lb, ub):
    x = np.asarray(x, dtype=float)
    want = approx_derivative(_one, x, method="2-point", f0=_one(x), bounds=(lb, ub))
    got = forward_difference_jacobian(_many, x, (lb, ub))
    np.testing.assert_array_equal(got, want)
    assert got.strides == want.strides  # the solver's products then sum in the same order


def test_unbounded_steps_are_scipys():
    x = np.array([3.0, -0.4, 0.05])
    want = approx_derivative(_one, x, method="2-point", f0=_one(x))
    got = forward_difference_jacobian(_many, x, (-np.inf, np.inf))
    np.testing.assert_array_equal(got, want)


def test_least_squares_given_it_finds_what_its_default_finds():
    bounds = ([0.0, 0.5, 0.0], [5.0, 3.0, 2.0])
    options = {"bounds": bounds, "loss": "soft_l1", "xtol": 1e-12, "ftol": 1e-12}
    default = optimize.least_squares(_one, [0.5, 0.8, 0.5], **options)
    batched = optimize.least_squares(
        _one,
        [0.5, 0.8, 0.5],
        jac=lambda v: forward_difference_jacobian(_many, v, bounds),
        **options,
    )
    np.testing.assert_array_equal(batched.x, default.x)
    assert batched.nfev == default.nfev and batched.cost == default.cost
