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


# ---- setup limits: no request can abort the interpreter ----

TWO_MODES = tvist.ConstantModes([(50.0, 0.1), (40.0, 0.2)])


@pytest.mark.parametrize("n_dof", [tvist.MAX_DOF + 1, 10**9, 2**62, 2**63 + 5])
@pytest.mark.parametrize("provider", ["constant", "callable"])
def test_huge_n_dof_is_a_value_error_not_an_abort(n_dof: int, provider: str) -> None:
    # 10**9 channels used to abort the interpreter (a 400 GB allocation), 2**62 raised a
    # PanicException (a BaseException). Both come from the core's shared limit now.
    dynamics = TWO_MODES if provider == "constant" else good_provider
    kwargs = {"max_delay_s": 0.1} if provider == "callable" else {}
    with pytest.raises((ValueError, OverflowError), match="n_dof|too large|int"):
        tvist.TvShaper(dynamics, dt_s=0.002, n_dof=n_dof, **kwargs)


def test_the_dof_limit_itself_is_accepted() -> None:
    shaper = tvist.TvShaper(TWO_MODES, dt_s=0.002, n_dof=tvist.MAX_DOF)
    assert shaper.n_dof == tvist.MAX_DOF == 4096


@pytest.mark.parametrize("provider", ["constant", "callable"])
def test_delay_lines_beyond_the_memory_limit_are_refused(provider: str) -> None:
    # 0.1 rad/s undamped at 100 kHz over 4096 channels: ~154 GB of delay line (the C reproducer).
    if provider == "constant":
        dynamics, kwargs = tvist.ConstantModes([(0.1, 0.0)]), {}
    else:
        dynamics, kwargs = (lambda q: [(0.1, 0.0)]), {"max_delay_s": 47.0}
    with pytest.raises(ValueError, match="256 MiB"):
        tvist.TvShaper(dynamics, dt_s=1e-5, n_dof=4096, **kwargs)
    # The bound is on the total: the same line for one channel (~38 MB) is fine.
    tvist.TvShaper(dynamics, dt_s=1e-5, n_dof=1, **kwargs)
    assert tvist.MAX_DELAY_LINE_BYTES == 256 * 2**20


# ---- silently wrong inputs ----


@pytest.mark.parametrize("com", [(1e200, 0.0, 0.0), (0.0, -1e160, 0.0)])
def test_a_huge_finite_payload_com_is_refused(com: tuple) -> None:
    # It used to give all-NaN inertias (5 kg x (1e200 m)^2 overflows).
    with pytest.raises(ValueError, match="non-finite joint inertias"):
        tvist.robots.ur5e(5.0, com)


def test_a_mode_above_nyquist_is_reported() -> None:
    # 1e4 rad/s at 2 ms is above pi/dt = 1571 rad/s: it used to run with status 0.
    shaper = tvist.TvShaper(tvist.ConstantModes([(1e4, 0.0)]), dt_s=0.002, n_dof=1)
    shaper.step(np.zeros(1))
    assert shaper.last_status & tvist.Status.MODE_ABOVE_NYQUIST
    assert shaper.status_counts["mode_above_nyquist"] == 1
    # Just below Nyquist is not flagged.
    below = tvist.TvShaper(tvist.ConstantModes([(1500.0, 0.0)]), dt_s=0.002, n_dof=1)
    below.step(np.zeros(1))
    assert below.last_status == 0


def test_status_flags_are_the_cores() -> None:
    flags = {f.name: f.value for f in tvist.Status if f.value}
    assert flags == tvist._core.STATUS_FLAGS
    assert list(flags.values()) == [1 << k for k in range(len(flags))]


# ---- reset accepts what step accepts ----


def test_reset_accepts_non_contiguous_and_integer_arrays() -> None:
    shaper = tvist.TvShaper(MODES, dt_s=0.002, n_dof=3)
    wide = np.arange(6.0)[::2]  # non-contiguous view [0, 2, 4]
    assert not wide.flags.c_contiguous
    # At rest the output is the input times the amplitude sum 1: equal up to rounding.
    shaper.reset(wide)
    np.testing.assert_allclose(shaper.step(wide), [0.0, 2.0, 4.0], rtol=1e-15)
    integers = np.array([1, 2, 3])
    shaper.reset(integers)  # used to raise TypeError: type mismatch int64 -> float64
    np.testing.assert_allclose(shaper.step(integers), [1.0, 2.0, 3.0], rtol=1e-15)
    shaper.reset([1, 2, 3])
    np.testing.assert_allclose(shaper.step([1, 2, 3]), [1.0, 2.0, 3.0], rtol=1e-15)
    shaper.reset(np.ones(3, dtype=np.int32))
    out = shaper.shape(np.ones((4, 3), dtype=np.int32))
    np.testing.assert_allclose(out, np.ones((4, 3)), rtol=1e-15)
    with pytest.raises(ValueError, match="q0 has 2 values"):
        shaper.reset(np.zeros(2, dtype=int))


@pytest.mark.parametrize(
    "complex_input",
    [
        np.array([1.0 + 2.0j, 3.0 + 0.0j]),
        np.array([1.0, 2.0], dtype=np.complex64),  # zero imaginary part: still complex data
        [np.complex128(1.0 + 2.0j), 3.0],  # numpy would make this a complex array
        [1.0 + 2.0j, 3.0],
    ],
    ids=["complex128", "complex64", "list-of-numpy-complex", "list-of-python-complex"],
)
def test_complex_input_is_refused_not_truncated(complex_input) -> None:
    """Converting complex data to float64 drops the imaginary part (with only a numpy warning,
    or none); step, shape and reset refuse it, and the refused call leaves no trace."""
    shaper = tvist.TvShaper(MODES, dt_s=0.002, n_dof=2)
    reference = tvist.TvShaper(MODES, dt_s=0.002, n_dof=2)
    for call, arg, name in [
        (shaper.step, complex_input, "q"),
        (shaper.reset, complex_input, "q0"),
        (shaper.shape, [complex_input, complex_input], "Q"),
    ]:
        with pytest.raises(
            TypeError, match=rf"^{name} must hold real numbers, got complex\d+ values"
        ):
            call(arg)
    # Nothing was shaped: the next real samples come out as from a fresh shaper.
    q = np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]])
    np.testing.assert_array_equal(shaper.shape(q), reference.shape(q))
    np.testing.assert_array_equal(shaper.step([1.0, 2.0]), reference.step([1.0, 2.0]))
