"""Setup errors of the zero-delay helpers: values outside their ranges are refused by name."""

from __future__ import annotations

import numpy as np
import pytest

import tvist
from tvist.trajectory import min_jerk
from tvist.ztdis import compress

DT_S = 0.002
MODES = [(2.0 * np.pi * 2.55, 0.04)]


@pytest.fixture(scope="module")
def move() -> np.ndarray:
    return min_jerk([0.0], [0.3], duration_s=0.734, dt_s=DT_S).q


def test_compress_needs_alpha_in_the_half_open_unit_interval(move):
    assert compress(move, DT_S, 1.0).shape == move.shape  # no compression: allowed
    for alpha in (0.0, 1.2, 1.5, -0.5, float("nan")):
        with pytest.raises(ValueError, match="alpha"):
            compress(move, DT_S, alpha)


def test_joint_limits_must_be_positive(move):
    # Only zero, negative or non-finite limits are refused. The compressed 0.3 rad move peaks
    # at 1.18 rad/s: a velocity limit of 0.9 (below 1, as real ones may be) is accepted as a
    # limit and then reported as exceeded, not refused as invalid.
    with pytest.raises(ValueError, match="v_max exceeded"):
        tvist.zero_delay(move, DT_S, MODES, shaper="zvd", v_max=0.9)
    for bad in (0.0, -1.0, float("inf")):
        with pytest.raises(ValueError, match="v_max"):
            tvist.zero_delay(move, DT_S, MODES, shaper="zvd", v_max=bad)
        with pytest.raises(ValueError, match="a_max"):
            tvist.zero_delay(move, DT_S, MODES, shaper="zvd", a_max=bad)
