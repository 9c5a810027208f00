"""Property tests: for any input in a broad class, the function either returns a result that
satisfies its documented invariants or raises ``ValueError`` — never another exception, a
crash or a silently wrong number.

Example counts are bounded (about 1,350 cases in all) and the search is derandomized, so a
run is reproducible and takes well under a minute.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

import tvist
from rtde_records import read_rtde_csv
from tvist.ident.logs import LogFormatError, Record

# Reproducible in CI: a fixed search (derandomize), no example database written to disk, no
# per-example time limit (the machine is shared; time is not what is tested).
PROPERTY = settings(
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

ATOL_6DP = 5.01e-7  # "ur_rtde" writes 6 decimals: rounding error at most 0.5e-6

# --------------------------------------------------------------------------- RTDE CSV reader

_WIDTHS = {
    "target_q": 6,
    "target_qd": 6,
    "target_qdd": 6,
    "actual_q": 6,
    "tool_accel": 3,
    "actual_TCP_pose": 6,
}


@st.composite
def records(draw, fmt: str) -> Record:
    """A clean record: uniform timestamps, finite values representable in format ``fmt``."""
    n = draw(st.integers(2, 30))
    if fmt == "ur_rtde":  # 6 decimals: keep steps far above the rounding and values moderate
        dt = draw(st.floats(1e-3, 0.1))
        t0 = draw(st.floats(-1e5, 1e5))
        value = st.floats(-1e6, 1e6, allow_nan=False)
    else:  # %.17g round-trips every double
        dt = draw(st.floats(1e-6, 10.0))
        t0 = draw(st.floats(-1e6, 1e6))
        value = st.floats(allow_nan=False, allow_infinity=False)
    t = t0 + dt * np.arange(n)
    with_pose = draw(st.booleans())
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    # A few drawn values (shrinkable, possibly extreme) among seeded moderate ones.
    blocks = {}
    for name, width in _WIDTHS.items():
        if name == "actual_TCP_pose" and not with_pose:
            blocks[name] = None
            continue
        block = rng.uniform(-4.0, 4.0, size=(n, width))
        k, j = draw(st.integers(0, n - 1)), draw(st.integers(0, width - 1))
        block[k, j] = draw(value)
        blocks[name] = block
    return Record(t_s=t, **blocks)


def _arrays(rec: Record) -> list[np.ndarray]:
    out = [rec.t_s, *(getattr(rec, name) for name in _WIDTHS if name != "actual_TCP_pose")]
    if rec.actual_TCP_pose is not None:
        out.append(rec.actual_TCP_pose)
    return out


def assert_same(expected: Record, got: Record, atol: float) -> None:
    assert got.n_samples == expected.n_samples
    assert (got.actual_TCP_pose is None) == (expected.actual_TCP_pose is None)
    for a, b in zip(_arrays(expected), _arrays(got), strict=True):
        if atol == 0.0:
            np.testing.assert_array_equal(b, a)
        else:
            np.testing.assert_allclose(b, a, atol=atol, rtol=1e-15)


def assert_names_the_file(error: ValueError, path) -> None:
    """Every refusal of a log is a :class:`LogFormatError` whose message starts with the file."""
    assert isinstance(error, LogFormatError), repr(error)
    assert str(error).startswith(f"{path}: "), str(error)


def _read_quietly(path, **kwargs) -> Record:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_rtde_csv(path, **kwargs)


@settings(PROPERTY, max_examples=150)
@given(data=st.data(), fmt=st.sampled_from(["ur_rtde", "ur_client"]))
def test_csv_round_trip(tmp_path, data, fmt):
    rec = data.draw(records(fmt))
    path = rec.to_csv(tmp_path / "log.csv", fmt=fmt)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a clean log reads without any warning
        back = read_rtde_csv(path)
    assert_same(rec, back, ATOL_6DP if fmt == "ur_rtde" else 0.0)


# Bytes that cannot be part of, or turn text into, a number (no digits, signs, '.', 'e', nor
# the letters of nan/inf/infinity), nor end a line.
_GARBAGE = st.sampled_from(
    [b"\x00", b"\x01", b"\x7f", b"\x80", b"\xc3", b"\xff", b"#", b";", b":", b"!", b"?", b"x",
     b"z", b"X", b"Z", b'"', b"'", b"_", b"|", b"@", b"\t", b"\xe2\x80\x8b"]
)  # fmt: skip


@st.composite
def mutations(draw, n_rows: int, n_fields: int, names: list[str]):
    """One textual defect: (kind, data row or column name, detail)."""
    kind = draw(
        st.sampled_from(["insert-field", "delete-field", "duplicate-column", "nan", "garbage"])
    )
    row = draw(st.integers(0, n_rows - 1))
    if kind == "insert-field":
        return kind, row, (draw(st.integers(0, n_fields)), draw(st.floats(-10, 10)))
    if kind == "delete-field":
        return kind, row, draw(st.integers(0, n_fields - 1))
    if kind == "duplicate-column":
        return kind, draw(st.sampled_from(names)), draw(st.booleans())
    if kind == "nan":
        return (
            kind,
            row,
            (draw(st.integers(0, n_fields - 1)), draw(st.sampled_from(["nan", "inf", "-inf"]))),
        )
    line = draw(st.integers(-1, n_rows - 1))  # -1: the header
    return kind, line, (draw(st.integers(0, 10**6)), draw(_GARBAGE))


def _apply(lines: list[bytes], sep: bytes, mutation) -> list[bytes]:
    kind, where, detail = mutation
    lines = list(lines)
    if kind in ("insert-field", "delete-field", "nan"):
        fields = lines[1 + where].split(sep)
        if kind == "insert-field":
            at, value = detail
            fields.insert(at, b"%.6f" % value)
        elif kind == "delete-field":
            del fields[detail]
        else:
            at, text = detail
            fields[at] = text.encode()
        lines[1 + where] = sep.join(fields)
    elif kind == "duplicate-column":
        k = lines[0].split(sep).index(where.encode())
        same = detail
        lines[0] += sep + where.encode()
        for i in range(1, len(lines)):
            lines[i] += sep + (lines[i].split(sep)[k] if same else b"0.5")
    else:
        line = lines[1 + where]
        at, junk = detail
        at %= len(line) + 1
        lines[1 + where] = line[:at] + junk + line[at:]
    return lines


@settings(PROPERTY, max_examples=250)
@given(
    data=st.data(),
    fmt=st.sampled_from(["ur_rtde", "ur_client"]),
    bom=st.booleans(),
)
def test_csv_mutations_are_refused_or_read_as_the_repaired_input(tmp_path, data, fmt, bom):
    rec = data.draw(records("ur_client" if fmt == "ur_client" else "ur_rtde"))
    path = rec.to_csv(tmp_path / "log.csv", fmt=fmt)
    text = path.read_bytes()
    sep = b"," if fmt == "ur_rtde" else b" "
    lines = text.rstrip(b"\n").split(b"\n")
    names = lines[0].decode().split(sep.decode())
    mutation = data.draw(mutations(rec.n_samples, len(names), names))
    mutated = _apply(lines, sep, mutation)
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + b"\n".join(mutated) + b"\n")
    atol = ATOL_6DP if fmt == "ur_rtde" else 0.0
    kind, where, _ = mutation

    # Without a repair option: a ValueError, or (the defect changed no number) the input.
    try:
        back = _read_quietly(path, resample=False)
    except ValueError as e:
        assert_names_the_file(e, path)
        event("refused without repair")
    else:
        # Only a garbage byte that changed no field can pass (e.g. a tab next to a separator).
        assert kind == "garbage", f"accepted without a repair: {mutation}"
        assert_same(rec, back, atol)

    # With the repair that fits the defect: the input without the damaged row, or all of it.
    repaired_input = rec
    if kind == "duplicate-column":
        kwargs = {"repair": "keep-first-duplicate"}
    elif kind == "nan":
        kwargs = {"drop_nan": True}
    else:
        kwargs = {"repair": "drop-bad-rows"}
    if kind in ("insert-field", "delete-field", "nan"):
        repaired_input = rec.select(np.delete(np.arange(rec.n_samples), where))
    try:
        back = _read_quietly(path, resample=False, **kwargs)  # a dropped row leaves a gap
    except ValueError as e:
        assert_names_the_file(e, path)
        # Only when no repair applies: fewer than 2 rows left, or a damaged header.
        assert (
            repaired_input.n_samples < 2
            or (kind == "garbage" and where == -1)
            or (kind == "garbage" and rec.n_samples <= 2)
        ), mutation
        return
    if back.n_samples == repaired_input.n_samples:
        assert_same(repaired_input, back, atol)
    else:  # a garbage byte broke its row, which was dropped
        assert kind == "garbage", mutation
        assert_same(rec.select(np.delete(np.arange(rec.n_samples), where)), back, atol)


@settings(PROPERTY, max_examples=150)
@given(
    t=st.lists(
        st.one_of(st.floats(allow_nan=False), st.floats(-1e9, 1e9)), min_size=2, max_size=30
    ),
    sort=st.booleans(),
    big=st.sampled_from([0.0, 1.7e308, -1.7e308, 1e300]),
    resample=st.booleans(),
)
def test_csv_extreme_numbers_never_give_other_errors_or_non_finite_output(
    tmp_path, t, sort, big, resample
):
    if sort:  # increasing timestamps (with the extremes), so the reader gets further
        t = sorted(t)
    n = len(t)
    rng = np.random.default_rng(n)
    q = rng.uniform(-1, 1, size=(n, 6))
    q[n // 2, 0] = big if big else q[n // 2, 0]
    rec = Record(
        t_s=np.asarray(t),
        target_q=q,
        target_qd=q,
        target_qdd=q,
        actual_q=q,
        tool_accel=q[:, :3],
    )
    path = rec.to_csv(tmp_path / "x.csv", fmt="ur_client")
    try:
        back = _read_quietly(path, resample=resample)
    except ValueError as _e:
        assert_names_the_file(_e, path)
        event("refused")
        return
    for a in _arrays(back):
        assert np.all(np.isfinite(a))
    assert np.all(np.diff(back.t_s) > 0)
    assert math.isfinite(back.dt_s)
    if not resample:  # every returned sample is one of the file's, unchanged
        idx = np.searchsorted(rec.t_s, back.t_s)
        np.testing.assert_array_equal(rec.actual_q[idx], back.actual_q)


# --------------------------------------------------------------------------- Impulses, shaper

_ANY_FLOAT = st.floats(allow_nan=True, allow_infinity=True)


def mostly(plausible: st.SearchStrategy, anything: st.SearchStrategy = _ANY_FLOAT):
    """Three draws in four from ``plausible``, so that valid inputs are well explored too."""
    return st.one_of(plausible, plausible, plausible, anything)


def _assert_valid_impulses(imp) -> None:
    a, t = np.asarray(imp.amplitudes), np.asarray(imp.times_s)
    assert a.shape == t.shape and a.size == len(imp) >= 1
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(t))
    # The sum is normalized to 1 in floating point: allow rounding of n terms.
    assert abs(a.sum() - 1.0) <= 1e-12 * max(1.0, np.abs(a).sum())
    assert t[0] >= 0.0 and np.all(np.diff(t) >= 0.0)
    assert imp.duration_s == t[-1]  # the delay: last impulse time, counted from 0


@settings(PROPERTY, max_examples=300)
@given(
    pairs=st.lists(
        st.tuples(st.one_of(_ANY_FLOAT, st.floats(-2, 2)), st.one_of(_ANY_FLOAT, st.floats(0, 1))),
        max_size=8,
    ),
    sort=st.booleans(),
)
def test_impulses_construct_valid_or_raise(pairs, sort):
    if sort:
        pairs = sorted(pairs, key=lambda p: p[1] if not math.isnan(p[1]) else 0.0)
    amplitudes, times = [p[0] for p in pairs], [p[1] for p in pairs]
    try:
        imp = tvist.Impulses(amplitudes, times)
    except ValueError as _e:
        event("refused")
        return
    _assert_valid_impulses(imp)


#: Shapers with zero residual vibration at the design point (EI: ``tolerance`` by design).
_EXACT = ("zv", "zvd", "zvdd", "mzv")


@settings(PROPERTY, max_examples=300)
@given(
    name=st.sampled_from([*tvist.SHAPERS, "nope", ""]),
    wn=mostly(st.floats(0.1, 1e4)),
    zeta=mostly(st.floats(0.0, 0.95)),
    tolerance=mostly(st.floats(0.005, 0.2)),
    misuse_tolerance=st.integers(0, 3),
)
def test_shaper_design_is_valid_or_raises(name, wn, zeta, tolerance, misuse_tolerance):
    if name != "ei" and misuse_tolerance != 3:  # a tolerance for a shaper without one: 1 in 4
        tolerance = None
    try:
        imp = tvist.shaper(name, wn, zeta, tolerance=tolerance)
    except ValueError as _e:
        event("refused")
        return
    _assert_valid_impulses(imp)
    if name in _EXACT and 0.1 <= wn <= 1e4 and zeta <= 0.95:
        # Residual vibration at the design point: zero up to rounding of the closed-form
        # impulse times (relative 1e-15 of ω_n·t over a few periods -> well under 1e-9).
        assert tvist.prv(imp, wn, zeta) <= 1e-9


# --------------------------------------------------------------------------- zero_delay


@st.composite
def quintic_moves(draw):
    """A rest-to-rest quintic move, optionally with rest padding, ``(n_samples, n_dof)``."""
    dt = draw(st.sampled_from([0.001, 0.002, 0.008]))
    n_move = draw(mostly(st.integers(100, 600), st.integers(4, 600)))
    n_dof = draw(st.integers(1, 3))
    dist = np.array(
        [draw(mostly(st.floats(0.05, 3.0), st.floats(-3.0, 3.0))) for _ in range(n_dof)]
    )
    start = np.array([draw(st.floats(-3.0, 3.0)) for _ in range(n_dof)])
    s = np.linspace(0.0, 1.0, n_move)
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = start + blend[:, None] * dist
    pad_before, pad_after = draw(st.integers(0, 50)), draw(st.integers(0, 50))
    q = np.vstack([np.repeat(q[:1], pad_before, 0), q, np.repeat(q[-1:], pad_after, 0)])
    return q, dt


@settings(PROPERTY, max_examples=100)
@given(
    move=quintic_moves(),
    modes=st.lists(
        st.tuples(
            mostly(st.floats(5.0, 300.0), st.one_of(_ANY_FLOAT, st.floats(1e-3, 2e3))),
            mostly(st.floats(0.0, 0.3), st.one_of(_ANY_FLOAT, st.floats(0.0, 0.99))),
        ),
        min_size=1,
        max_size=2,
    ),
    shaper=st.sampled_from(["zv", "zvd", "zvdd", "mzv", "ei"]),
    method=st.sampled_from(["modified", "ztdis"]),
)
def test_zero_delay_is_finite_and_keeps_the_end_points_or_raises(move, modes, shaper, method):
    q, dt = move
    try:
        r = tvist.zero_delay(q, dt, modes, shaper=shaper, method=method)
    except ValueError as _e:
        event("refused")
        return
    out = np.asarray(r.Q)
    assert out.shape == q.shape
    assert np.all(np.isfinite(out))
    # Starts where the input does (up to rounding in the filters: 1e-9 of the pose).
    np.testing.assert_allclose(out[0], q[0], rtol=0, atol=1e-9 * (1 + np.max(np.abs(q))))
    # Ends where the input ends, up to what cutting the reference at T leaves out; that
    # residual must be small against the move (a wrong reference was off by 1e3-1e7 times
    # the move), 1 % of the travel or 1e-9 rad for a move that barely moves.
    travel = float(np.max(np.abs(q[-1] - q[0])))
    assert np.max(np.abs(out[-1] - q[-1])) <= r.tail_error + 1e-12
    assert r.tail_error <= 0.01 * travel + 1e-9, (r.tail_error, travel)


# --------------------------------------------------------------------------- TvShaper setup


@settings(PROPERTY, max_examples=100)
@given(
    modes=st.lists(
        st.tuples(
            st.one_of(_ANY_FLOAT, st.floats(1.0, 1e3)), st.one_of(_ANY_FLOAT, st.floats(0, 0.9))
        ),
        max_size=3,
    ),
    dt_s=st.one_of(_ANY_FLOAT, st.floats(1e-3, 0.02)),
    n_dof=st.integers(0, 64),
    shaper=st.sampled_from([*tvist.SHAPERS, "nope"]),
    interp=st.sampled_from(["linear", "cubic", "nearest"]),
    max_delay_s=st.one_of(st.none(), _ANY_FLOAT, st.floats(0.0, 5.0)),
    safety_factor=st.one_of(_ANY_FLOAT, st.floats(1.0, 3.0)),
    provider=st.booleans(),
)
def test_tvshaper_setup_constructs_or_raises(
    modes, dt_s, n_dof, shaper, interp, max_delay_s, safety_factor, provider
):
    # Bounded setups only: every mode ≥ 1 rad/s with ζ ≤ 0.9 and dt ≥ 1 ms, or rejected by
    # validation before any allocation (a huge finite delay line is a separate memory cap).
    finite_modes = [(w, z) for w, z in modes if math.isfinite(w) and math.isfinite(z)]
    assume(all(w >= 1.0 and 0 <= z <= 0.9 for w, z in finite_modes) or not finite_modes)
    assume(not (math.isfinite(dt_s) and 0 < dt_s < 1e-3))
    assume(max_delay_s is None or not (math.isfinite(max_delay_s) and max_delay_s > 5.0))
    assume(not (math.isfinite(safety_factor) and safety_factor > 3.0))
    try:
        dynamics = (lambda _q: list(modes)) if provider else tvist.ConstantModes(modes)
        s = tvist.TvShaper(
            dynamics,
            dt_s,
            n_dof,
            shaper=shaper,
            interp=interp,
            max_delay_s=max_delay_s,
            safety_factor=safety_factor,
        )
    except ValueError as _e:
        event("refused")
        return
    assert s.n_dof == n_dof
    out = s.step(np.ones(n_dof))
    assert out.shape == (n_dof,)
    assert np.all(np.isfinite(out)) or s.last_status != 0


@pytest.mark.parametrize("provider", [False, True])
def test_a_negative_n_dof_is_a_value_error(provider):
    dynamics = (lambda _q: [(50.0, 0.1)]) if provider else tvist.ConstantModes([(50.0, 0.1)])
    with pytest.raises(ValueError, match="n_dof"):
        tvist.TvShaper(dynamics, 0.002, -1)
