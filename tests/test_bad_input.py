"""Every construction error of the shaping API raises a clear exception naming the problem."""

from __future__ import annotations

import numpy as np
import pytest

import tvist

MODES = tvist.ConstantModes([(40.0, 0.1)])


def good_provider(q: np.ndarray) -> list[tuple[float, float]]:
    return [(40.0, 0.1)]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"shaper": "zvx"}, "unknown shaper 'zvx'|unknown shaper \"zvx\""),
        ({"interp": "quintic"}, "unknown interpolation"),
        ({"dt_s": 0.0}, "dt_s"),
        ({"dt_s": -0.002}, "dt_s"),
        ({"dt_s": float("nan")}, "dt_s"),
        ({"dt_s": float("inf")}, "dt_s"),
        ({"n_dof": 0}, "n_dof"),
        ({"shaper": "ei", "tolerance": 0.0}, "tolerance"),
        ({"shaper": "ei", "tolerance": 0.5}, "tolerance"),
        ({"shaper": "ei", "tolerance": float("nan")}, "tolerance"),
        ({"shaper": "zv", "tolerance": 0.05}, '"ei" only'),
        ({"max_delay_s": -0.1}, "max_delay_s"),
        ({"max_delay_s": float("nan")}, "max_delay_s"),
        ({"max_delay_s": 1e9}, "unreasonably long"),
        ({"safety_factor": 0.5}, "safety_factor"),
        ({"safety_factor": float("nan")}, "safety_factor"),
    ],
)
def test_tvshaper_setup_errors(kwargs: dict, message: str) -> None:
    args = {"dynamics": MODES, "dt_s": 0.002, "n_dof": 2, **kwargs}
    with pytest.raises(ValueError, match=message):
        tvist.TvShaper(**args)


@pytest.mark.parametrize(
    "modes, message",
    [
        ([], "at least one mode"),
        ([(0.0, 0.1)], "invalid mode 0"),
        ([(40.0, 0.1), (-5.0, 0.1)], "invalid mode 1"),
        ([(np.nan, 0.1)], "invalid mode 0"),
        ([(np.inf, 0.1)], "invalid mode 0"),
        ([(40.0, -0.01)], "invalid mode 0"),
        ([(40.0, 1.0)], "invalid mode 0"),
        ([(40.0, np.nan)], "invalid mode 0"),
    ],
)
def test_constant_modes_errors(modes: list, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        tvist.ConstantModes(modes)


def test_damping_beyond_the_shaper_fit_is_rejected_at_setup() -> None:
    with pytest.raises(ValueError, match="3hump_ei"):
        tvist.TvShaper(tvist.ConstantModes([(40.0, 0.3)]), 0.002, 1, shaper="3hump_ei")
    with pytest.raises(ValueError, match="beyond the range"):
        tvist.shaper("ei", 40.0, 0.45)
    tvist.TvShaper(tvist.ConstantModes([(40.0, 0.3)]), 0.002, 1, shaper="zvd")  # closed form


@pytest.mark.parametrize(
    "args, message",
    [
        (("zvx", 40.0, 0.1), "unknown shaper"),
        (("zv", 0.0, 0.1), "invalid mode"),
        (("zv", 40.0, 1.0), "invalid mode"),
        (("zv", np.nan, 0.1), "invalid mode"),
    ],
)
def test_shaper_design_errors(args: tuple, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        tvist.shaper(*args)


def test_callable_needs_a_delay_bound() -> None:
    with pytest.raises(ValueError, match="max_delay_s"):
        tvist.TvShaper(good_provider, 0.002, 2)


def test_callable_is_probed_at_setup_and_its_exception_propagates() -> None:
    def wants_six(q: np.ndarray) -> list[tuple[float, float]]:
        if q.shape != (6,):
            raise ValueError(f"expected 6 joints, got {q.shape}")
        return [(40.0, 0.1)]

    # An n_dof the callable does not accept fails at construction, with its own message.
    with pytest.raises(ValueError, match="expected 6 joints"):
        tvist.TvShaper(wants_six, 0.002, 3, max_delay_s=0.5)
    tvist.TvShaper(wants_six, 0.002, 6, max_delay_s=0.5)

    with pytest.raises(ValueError, match="returned no modes"):
        tvist.TvShaper(lambda q: [], 0.002, 2, max_delay_s=0.5)
    with pytest.raises(TypeError, match="sequence of"):
        tvist.TvShaper(lambda q: 3.0, 0.002, 2, max_delay_s=0.5)
    with pytest.raises(TypeError, match="dynamics must be"):
        tvist.TvShaper("zv", 0.002, 2)


class Boom(RuntimeError):
    pass


def test_callable_raising_during_steps_propagates() -> None:
    calls = {"n": 0}

    def fails_later(q: np.ndarray) -> list[tuple[float, float]]:
        calls["n"] += 1
        if calls["n"] > 5:
            raise Boom("map evaluation failed")
        return [(40.0, 0.1)]

    shaper = tvist.TvShaper(fails_later, 0.002, 1, max_delay_s=0.5)
    for _ in range(4):
        shaper.step(np.array([0.0]))
    with pytest.raises(Boom, match="map evaluation failed"):
        shaper.step(np.array([0.0]))
    # In a block, the first failure ends the block (the callable is not called again),
    # also past the first of the chunks the block is processed in.
    for fail_after in (5, 1500):
        calls["n"] = 5 - fail_after
        shaper = tvist.TvShaper(fails_later, 0.002, 1, max_delay_s=0.5)
        with pytest.raises(Boom):
            shaper.shape(np.zeros((3000, 1)))
        assert calls["n"] == 6


def test_callable_returning_the_wrong_count_raises() -> None:
    calls = {"n": 0}

    def grows(q: np.ndarray) -> list[tuple[float, float]]:
        calls["n"] += 1
        return [(40.0, 0.1)] * (1 if calls["n"] < 3 else 2)

    shaper = tvist.TvShaper(grows, 0.002, 1, max_delay_s=0.5)
    shaper.step(np.array([0.0]))
    with pytest.raises(ValueError, match="returned 2 modes, expected 1"):
        shaper.step(np.array([0.0]))


def test_wrong_shapes_at_run_time() -> None:
    shaper = tvist.TvShaper(MODES, 0.002, 2)
    with pytest.raises(ValueError, match="n_dof = 2"):
        shaper.step(np.zeros(3))
    with pytest.raises(ValueError, match=r"expected \(n_samples, 2\)"):
        shaper.shape(np.zeros((10, 3)))
    with pytest.raises(ValueError, match="n_dof = 2"):
        shaper.reset(np.zeros(3))
    with pytest.raises(ValueError, match="finite"):
        shaper.reset(np.array([0.0, np.nan]))
