"""RTDE log reading/writing: round trips for both UR formats and one test per bad-log case."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from tvist.ident.logs import LogWarning, Record, find_gaps
from tvist.ident.logs import read_rtde_csv as read_rtde_log
from tvist.robots import params


def read_rtde_csv(path, **kwargs) -> Record:
    """The reader's format layer: these records are random numbers, not a physical log, so
    the unit check (tested in test_log_units.py) is off."""
    return read_rtde_log(path, check_units=False, **kwargs)


DT_S = params("ur5e").control_period_s  # e-Series RTDE period (the robot data)


def make_record(n: int = 50, with_pose: bool = True, seed: int = 0) -> Record:
    rng = np.random.default_rng(seed)
    t = 1000.0 + DT_S * np.arange(n)  # RTDE timestamps count from controller start

    def block(width: int) -> np.ndarray:
        return rng.uniform(-3.0, 3.0, size=(n, width))

    return Record(
        t_s=t,
        target_q=block(6),
        target_qd=block(6),
        target_qdd=block(6),
        actual_q=block(6),
        tool_accel=block(3) + np.array([0.0, 0.0, 9.81]),
        actual_TCP_pose=block(6) if with_pose else None,
    )


def assert_records_close(a: Record, b: Record, atol: float) -> None:
    for name in ("t_s", "target_q", "target_qd", "target_qdd", "actual_q", "tool_accel"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), atol=atol, rtol=0)
    if a.actual_TCP_pose is None:
        assert b.actual_TCP_pose is None
    else:
        np.testing.assert_allclose(a.actual_TCP_pose, b.actual_TCP_pose, atol=atol, rtol=0)


def test_round_trip_ur_rtde_six_decimals(tmp_path):
    rec = make_record()
    path = rec.to_csv(tmp_path / "log.csv", fmt="ur_rtde")
    header = path.read_text().splitlines()[0]
    assert header.startswith("timestamp,target_q_0,")
    assert "actual_tool_accelerometer_2" in header
    first_row = path.read_text().splitlines()[1].split(",")
    assert all(len(v.split(".")[1]) == 6 for v in first_row)
    back = read_rtde_csv(path)
    # 6 decimals: rounding error at most 0.5e-6 (plus float noise)
    assert_records_close(rec, back, atol=5.01e-7)


def test_round_trip_ur_client_space_separated(tmp_path):
    rec = make_record(with_pose=False)
    path = rec.to_csv(tmp_path / "log.csv", fmt="ur_client")
    assert path.read_text().splitlines()[0].startswith("timestamp target_q_0 target_q_1")
    back = read_rtde_csv(path)
    assert_records_close(rec, back, atol=0.0)  # %.17g round-trips doubles exactly
    assert back.dt_s == pytest.approx(DT_S)


def test_extra_columns_and_trailing_separator_are_ignored(tmp_path):
    rec = make_record(n=10, with_pose=False)
    cols = ["timestamp"]
    cols += [
        f"{f}_{i}" for f in ("target_q", "target_qd", "target_qdd", "actual_q") for i in range(6)
    ]
    cols += [f"actual_tool_accelerometer_{i}" for i in range(3)]
    values = np.hstack(
        [
            rec.t_s[:, None],
            rec.target_q,
            rec.target_qd,
            rec.target_qdd,
            rec.actual_q,
            rec.tool_accel,
        ]
    )
    # Put an unrelated field first and shuffle the order: lookup must be by name.
    order = np.random.default_rng(1).permutation(len(cols))
    extra = np.arange(10.0)[:, None]
    header = "robot_mode," + ",".join(cols[i] for i in order) + ","
    rows = [
        ",".join(f"{v:.6f}" for v in np.concatenate([extra[k], values[k, order]])) + ","
        for k in range(10)
    ]
    path = tmp_path / "extra.csv"
    path.write_text("\n".join([header, *rows]) + "\n")
    back = read_rtde_csv(path)
    assert_records_close(rec, back, atol=5.01e-7)


def test_missing_columns_are_named(tmp_path):
    rec = make_record(n=5)
    path = rec.to_csv(tmp_path / "log.csv", fmt="ur_client")
    lines = path.read_text().splitlines()
    names = lines[0].split()
    drop = [names.index("target_qdd_3"), names.index("actual_tool_accelerometer_1")]
    keep = [i for i in range(len(names)) if i not in drop]
    path.write_text("\n".join(" ".join(line.split()[i] for i in keep) for line in lines) + "\n")
    with pytest.raises(ValueError, match=r"target_qdd_3, actual_tool_accelerometer_1"):
        read_rtde_csv(path)


def test_not_an_rtde_file(tmp_path):
    path = tmp_path / "x.csv"
    path.write_text("time;a;b\n0;1;2\n")
    with pytest.raises(ValueError, match="timestamp"):
        read_rtde_csv(path)


def _write_with_rows(tmp_path, rec: Record, edit) -> object:
    path = rec.to_csv(tmp_path / "log.csv", fmt="ur_rtde")
    lines = path.read_text().splitlines()
    header, rows = lines[0], lines[1:]
    rows = edit(header, rows)
    path.write_text("\n".join([header, *rows]) + "\n")
    return path


def test_nan_row_is_named_or_dropped(tmp_path):
    rec = make_record(n=20)

    def put_nan(header, rows):
        cols = header.split(",")
        fields = rows[7].split(",")
        fields[cols.index("actual_q_2")] = "nan"
        rows[7] = ",".join(fields)
        return rows

    path = _write_with_rows(tmp_path, rec, put_nan)
    with pytest.raises(ValueError, match=r"row\(s\) 7 "):
        read_rtde_csv(path)
    with pytest.warns(LogWarning) as caught:
        back = read_rtde_csv(path, drop_nan=True, resample=False)
    messages = [str(w.message) for w in caught]
    assert any("dropped 1 row(s) with non-finite values: 7" in m for m in messages)
    # The dropped row leaves a one-sample hole, reported like any skipped sample.
    assert any("about 1 skipped sample(s) before data row(s) 8" in m for m in messages)
    assert back.n_samples == 19
    np.testing.assert_allclose(back.t_s, np.delete(rec.t_s, 7), atol=5.01e-7)


def test_duplicated_samples_are_dropped_with_a_warning(tmp_path):
    rec = make_record(n=20)

    def duplicate(header, rows):
        return rows[:5] + [rows[4]] + rows[5:12] + [rows[11], rows[11]] + rows[12:]

    path = _write_with_rows(tmp_path, rec, duplicate)
    with pytest.warns(LogWarning, match=r"dropped 3 sample\(s\).*row\(s\) 5, 13, 14"):
        back = read_rtde_csv(path)
    assert_records_close(rec, back, atol=5.01e-7)


def test_backwards_timestamp_is_an_error_naming_the_row(tmp_path):
    rec = make_record(n=20)

    def swap(header, rows):
        rows[9], rows[10] = rows[10], rows[9]
        return rows

    path = _write_with_rows(tmp_path, rec, swap)
    with pytest.raises(ValueError, match=r"backwards at data row 10"):
        read_rtde_csv(path)


def test_skipped_samples_are_resampled_by_default_or_reported(tmp_path):
    n = 40
    t = DT_S * np.arange(n)
    ramp = np.outer(t, np.arange(1, 7))  # linear in time: interpolation must be exact
    rec = Record(
        t_s=t,
        target_q=ramp,
        target_qd=ramp * 2,
        target_qdd=ramp * 3,
        actual_q=ramp * 4,
        tool_accel=ramp[:, :3],
    )
    skip = np.r_[np.arange(0, 10), np.arange(13, n)]  # 3 samples missing before data row 10
    gappy = rec.select(skip)
    assert list(find_gaps(gappy.t_s)) == [10]
    path = gappy.to_csv(tmp_path / "gap.csv", fmt="ur_client")
    with pytest.warns(LogWarning, match=r"about 3 skipped sample\(s\) before data row\(s\) 10"):
        kept = read_rtde_csv(path, resample=False)
    assert kept.n_samples == n - 3
    # Resampled by default, saying how much was filled.
    with pytest.warns(LogWarning, match=r"3 of 40 samples \(7.5 %\) filled"):
        fixed = read_rtde_csv(path)
    assert fixed.n_samples == n
    np.testing.assert_allclose(fixed.t_s, t, atol=1e-12)
    np.testing.assert_allclose(fixed.actual_q, rec.actual_q, atol=1e-12)
    np.testing.assert_allclose(fixed.tool_accel, rec.tool_accel, atol=1e-12)


def test_a_time_jump_is_refused_not_filled(tmp_path):
    rec = make_record(n=40)
    jumped = Record(
        t_s=np.r_[rec.t_s[:20], rec.t_s[20:] + 1e6],
        target_q=rec.target_q,
        target_qd=rec.target_qd,
        target_qdd=rec.target_qdd,
        actual_q=rec.actual_q,
        tool_accel=rec.tool_accel,
    )
    path = jumped.to_csv(tmp_path / "jump.csv", fmt="ur_client")
    with pytest.raises(ValueError, match="split the log at its time jump"):
        read_rtde_csv(path)


def test_clean_log_reads_without_warnings(tmp_path):
    path = make_record().to_csv(tmp_path / "ok.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_rtde_csv(path)


def test_record_validates_shapes():
    rec = make_record(n=5)
    # The joints are as many as target_q has columns (6 on a UR, 7 on an FR3): the other
    # joint fields must match it.
    with pytest.raises(ValueError, match=r"target_qd must have shape \(5, 5\)"):
        Record(
            t_s=rec.t_s,
            target_q=rec.target_q[:, :5],
            target_qd=rec.target_qd,
            target_qdd=rec.target_qdd,
            actual_q=rec.actual_q,
            tool_accel=rec.tool_accel,
        )
