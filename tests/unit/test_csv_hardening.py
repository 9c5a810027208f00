"""Malformed RTDE logs are refused with a ``ValueError`` naming the file and the row, or
repaired with a warning only when asked; none is read as silently wrong numbers.

Every log is written to a real file: a clean one by :meth:`Record.to_csv` (the format both
UR recorders write), then edited as text the way a broken recorder or a hand edit would.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from tvist.ident.csv_table import LogFormatError
from tvist.ident.logs import LogWarning, Record
from tvist.ident.logs import read_rtde_csv as read_rtde_log
from tvist.robots import params


def read_rtde_csv(path, **kwargs) -> Record:
    """The reader's format layer: these records are random numbers, not a physical log, so
    the unit check (tested in test_log_units.py) is off."""
    return read_rtde_log(path, check_units=False, **kwargs)


DT_S = params("ur5e").control_period_s  # e-Series RTDE period (the robot data)
ATOL_6DP = 5.01e-7  # "ur_rtde" writes 6 decimals: rounding error at most 0.5e-6


def make_record(n: int = 20, seed: int = 0) -> Record:
    rng = np.random.default_rng(seed)
    t = 1000.0 + DT_S * np.arange(n)

    def block(width: int) -> np.ndarray:
        return rng.uniform(-3.0, 3.0, size=(n, width))

    return Record(
        t_s=t,
        target_q=block(6),
        target_qd=block(6),
        target_qdd=block(6),
        actual_q=block(6),
        tool_accel=block(3),
        actual_TCP_pose=block(6),
    )


def write_edited(tmp_path, rec: Record, edit, fmt: str = "ur_rtde", name: str = "log.csv"):
    """``rec`` written by ``to_csv``, then ``edit(lines) -> lines`` applied to its text."""
    path = rec.to_csv(tmp_path / name, fmt=fmt)
    lines = edit(path.read_text().splitlines())
    path.write_text("\n".join(lines) + "\n")
    return path


def assert_same(a: Record, b: Record, atol: float) -> None:
    for name in (
        "t_s",
        "target_q",
        "target_qd",
        "target_qdd",
        "actual_q",
        "tool_accel",
        "actual_TCP_pose",
    ):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), atol=atol, rtol=0)


# --------------------------------------------------------------------------- field counts


def insert_field_in_row(lines, data_row: int, after_field: int, value: str = "9.99"):
    fields = lines[1 + data_row].split(",")
    fields.insert(after_field + 1, value)
    lines[1 + data_row] = ",".join(fields)
    return lines


def test_an_extra_field_in_one_row_is_refused_naming_the_row(tmp_path):
    # The shifted row would read target_q = [.., 9.99, ..] and move every later column by one.
    rec = make_record()
    path = write_edited(tmp_path, rec, lambda lines: insert_field_in_row(lines, 7, 2))
    with pytest.raises(
        LogFormatError,
        match=r"data row 7 \(line 9\) has 35 fields, the header "
        r"has 34",
    ) as caught:
        read_rtde_csv(path)
    assert str(path) in str(caught.value)
    assert isinstance(caught.value, ValueError)
    assert "repair='drop-bad-rows'" in str(caught.value)


def test_a_missing_field_is_refused_in_the_space_separated_format(tmp_path):
    rec = make_record()

    def drop_field(lines):
        fields = lines[1 + 4].split()
        del fields[10]
        lines[1 + 4] = " ".join(fields)
        return lines

    path = write_edited(tmp_path, rec, drop_field, fmt="ur_client")
    with pytest.raises(LogFormatError, match=r"data row 4 \(line 6\) has 33 fields"):
        read_rtde_csv(path)


def test_drop_bad_rows_drops_them_with_a_warning_naming_them(tmp_path):
    rec = make_record(n=30)

    def edit(lines):
        lines = insert_field_in_row(lines, 7, 2)
        lines[1 + 12] = lines[1 + 12].replace(",", ",abc,", 1)  # extra non-number field
        lines[1 + 20] = lines[1 + 20].rsplit(",", 1)[0]  # a field short
        return lines

    path = write_edited(tmp_path, rec, edit)
    with pytest.warns(LogWarning) as caught:
        back = read_rtde_csv(path, repair="drop-bad-rows", resample=False)
    messages = [str(w.message) for w in caught]
    dropped = next(m for m in messages if "malformed" in m)
    assert "dropped 3 malformed row(s)" in dropped
    for row, line in ((7, 9), (12, 14), (20, 22)):
        assert f"data row {row} (line {line})" in dropped
    # The rows left are exactly the untouched ones, values unshifted.
    kept = np.setdiff1d(np.arange(30), [7, 12, 20])
    assert_same(back, rec.select(kept), ATOL_6DP)
    # The holes are reported with the original data-row numbers.
    assert any("before data row(s) 8, 13, 21" in m for m in messages)


def test_row_numbers_after_a_repair_are_those_of_the_file(tmp_path):
    rec = make_record(n=30)

    def edit(lines):
        lines = insert_field_in_row(lines, 3, 0)
        lines[1 + 10], lines[1 + 11] = lines[1 + 11], lines[1 + 10]
        return lines

    path = write_edited(tmp_path, rec, edit)
    with pytest.warns(LogWarning), pytest.raises(LogFormatError, match="backwards at data row 11"):
        read_rtde_csv(path, repair="drop-bad-rows")


def test_a_cell_that_is_not_a_number_is_named(tmp_path):
    rec = make_record()

    def edit(lines):
        fields = lines[1 + 5].split(",")
        fields[3] = "1_000"  # Python's float() would read 1000.0
        lines[1 + 5] = ",".join(fields)
        return lines

    path = write_edited(tmp_path, rec, edit)
    with pytest.raises(
        LogFormatError,
        match=r"data row 5 \(line 7\) column 'target_q_2' holds "
        r"'1_000', not a number",
    ):
        read_rtde_csv(path)


def test_an_unknown_repair_is_refused():
    with pytest.raises(ValueError, match="unknown repair 'fix-everything'"):
        read_rtde_csv("unused.csv", repair="fix-everything")


# --------------------------------------------------------------------------- duplicated columns


def duplicate_column(lines, name: str, values: str):
    """Append a second column called ``name``; ``values`` "same" or "other"."""
    names = lines[0].split(",")
    k = names.index(name)
    out = [lines[0] + "," + name]
    for line in lines[1:]:
        fields = line.split(",")
        extra = fields[k] if values == "same" else "0.123456"
        out.append(line + "," + extra)
    return out


def test_a_duplicated_column_is_refused_naming_it(tmp_path):
    rec = make_record()
    path = write_edited(tmp_path, rec, lambda lines: duplicate_column(lines, "actual_q_3", "other"))
    with pytest.raises(
        LogFormatError, match=r"column 'actual_q_3' appears 2 times \(fields 23, 35\)"
    ) as caught:
        read_rtde_csv(path)
    assert str(path) in str(caught.value)
    assert "line 1 (the header)" in str(caught.value)


def test_keep_first_duplicate_uses_the_first_with_a_warning(tmp_path):
    rec = make_record()
    path = write_edited(tmp_path, rec, lambda lines: duplicate_column(lines, "actual_q_3", "other"))
    with pytest.warns(LogWarning, match="actual_q_3 appear more than once; the first"):
        back = read_rtde_csv(path, repair="keep-first-duplicate")
    assert_same(back, rec, ATOL_6DP)  # the first column holds the record's values


def test_a_duplicated_unused_column_is_ignored_like_any_unused_column(tmp_path):
    rec = make_record()

    def edit(lines):
        return [
            line + (",robot_mode,robot_mode" if i == 0 else ",7,8") for i, line in enumerate(lines)
        ]

    path = write_edited(tmp_path, rec, edit)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = read_rtde_csv(path)
    assert_same(back, rec, ATOL_6DP)


# --------------------------------------------------------------------------- encodings


def test_a_utf8_byte_order_mark_is_skipped(tmp_path):
    rec = make_record()
    path = rec.to_csv(tmp_path / "bom.csv")
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = read_rtde_csv(path)
    assert_same(back, rec, ATOL_6DP)


def test_a_utf16_file_is_decoded(tmp_path):
    rec = make_record()
    path = rec.to_csv(tmp_path / "wide.csv", fmt="ur_client")
    path.write_bytes(path.read_text().encode("utf-16"))  # with its byte-order mark
    back = read_rtde_csv(path)
    assert_same(back, rec, 0.0)  # %.17g: exact


def test_crlf_line_ends_are_read(tmp_path):
    rec = make_record()
    path = rec.to_csv(tmp_path / "dos.csv")
    path.write_bytes(path.read_bytes().replace(b"\n", b"\r\n"))
    assert_same(read_rtde_csv(path), rec, ATOL_6DP)


def test_a_byte_that_is_not_text_is_named_with_file_and_row(tmp_path):
    rec = make_record()
    path = rec.to_csv(tmp_path / "latin.csv")
    lines = path.read_bytes().split(b"\n")
    lines[1 + 6] = lines[1 + 6][:10] + b"\xe9" + lines[1 + 6][10:]
    path.write_bytes(b"\n".join(lines))
    with pytest.raises(LogFormatError) as caught:
        read_rtde_csv(path)
    message = str(caught.value)
    assert str(path) in message
    assert "data row 6 (line 8)" in message
    assert "byte 0xe9 at character 11 is not ASCII" in message
    with pytest.warns(LogWarning) as caught:
        back = read_rtde_csv(path, repair="drop-bad-rows", resample=False)
    messages = [str(w.message) for w in caught]
    assert any("dropped 1 malformed row(s): data row 6 (line 8)" in m for m in messages)
    assert any("skipped sample(s) before data row(s) 7" in m for m in messages)  # its hole
    assert_same(back, rec.select(np.delete(np.arange(rec.n_samples), 6)), ATOL_6DP)


def test_a_header_that_is_not_utf8_is_named(tmp_path):
    path = make_record().to_csv(tmp_path / "h.csv")
    path.write_bytes(b"\xff" + path.read_bytes())
    with pytest.raises(LogFormatError, match=r"line 1 \(the header\): byte 0xff"):
        read_rtde_csv(path)


def test_an_empty_file_is_a_format_error(tmp_path):
    path = tmp_path / "empty.csv"
    path.write_bytes(b"")
    with pytest.raises(LogFormatError, match="empty"):
        read_rtde_csv(path)


# --------------------------------------------------------------------------- timestamps, grids


def with_times(rec: Record, t_s: np.ndarray) -> Record:
    return Record(
        t_s=t_s,
        target_q=rec.target_q,
        target_qd=rec.target_qd,
        target_qdd=rec.target_qdd,
        actual_q=rec.actual_q,
        tool_accel=rec.tool_accel,
        actual_TCP_pose=rec.actual_TCP_pose,
    )


def test_a_last_timestamp_of_1e308_is_a_value_error(tmp_path):
    rec = make_record(n=50)
    t = rec.t_s.copy()
    t[-1] = 1e308
    path = with_times(rec, t).to_csv(tmp_path / "huge_t.csv", fmt="ur_client")
    for resample in (False, True):
        with pytest.raises(LogFormatError, match=r"more than 2\^53 periods.*data row 49"):
            read_rtde_csv(path, resample=resample)


def test_resampling_a_time_jump_is_refused_above_the_grid_cap(tmp_path):
    # A 1e6 s jump at 2 ms would be a 5e8-sample grid (4 GB per channel).
    rec = make_record(n=40)
    t = np.r_[rec.t_s[:20], rec.t_s[20:] + 1e6]
    path = with_times(rec, t).to_csv(tmp_path / "jump.csv", fmt="ur_client")
    with pytest.raises(
        ValueError,
        match=r"resampling would build 500000040 samples .*limit "
        r"10000000.*before data row 20.*split the log at its time jump",
    ):
        read_rtde_csv(path, resample=True)
    with pytest.warns(LogWarning, match="left as is"):  # without resampling: only reported
        assert read_rtde_csv(path, resample=False).n_samples == 40


def test_all_equal_timestamps_are_a_value_error(tmp_path):
    rec = make_record(n=10)
    path = with_times(rec, np.full(10, 5.0)).to_csv(tmp_path / "flat.csv", fmt="ur_client")
    with pytest.warns(LogWarning, match="repeated timestamp"):
        with pytest.raises(LogFormatError, match="timestamps do not advance"):
            read_rtde_csv(path)


def test_resampling_cells_too_large_to_interpolate_is_refused(tmp_path):
    rec = make_record(n=40)
    q = rec.actual_q.copy()
    q[9, 2], q[13, 2] = -1.7e308, 1.7e308
    gappy = Record(
        t_s=rec.t_s,
        target_q=rec.target_q,
        target_qd=rec.target_qd,
        target_qdd=rec.target_qdd,
        actual_q=q,
        tool_accel=rec.tool_accel,
        actual_TCP_pose=rec.actual_TCP_pose,
    ).select(np.r_[0:10, 13:40])  # 3 samples skipped between ±1.7e308
    path = gappy.to_csv(tmp_path / "big.csv", fmt="ur_client")
    with pytest.raises(
        ValueError, match=r"cannot resample: actual_q_2 is -1.7e\+308 at data row 9"
    ):
        read_rtde_csv(path, resample=True)
    # Read without resampling, the cells come back exactly as written.
    with pytest.warns(LogWarning, match="left as is"):
        back = read_rtde_csv(path, resample=False)
    assert back.actual_q[9, 2] == -1.7e308 and back.actual_q[10, 2] == 1.7e308


# --------------------------------------------------------------------------- command line


def test_identify_reports_a_malformed_row_on_one_line(tmp_path, capsys):
    from tvist.cli import main

    rec = make_record()
    path = write_edited(tmp_path, rec, lambda lines: insert_field_in_row(lines, 3, 5))
    assert main(["identify", str(path), "--joint", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("tvist identify: error: ")
    assert f"{path}: data row 3 (line 5) has 35 fields" in err[0]


def test_text_in_an_unused_column_is_ignored(tmp_path):
    rec = make_record()

    def edit(lines):
        return [
            line + (",robot_state" if i == 0 else ",RUNNING_NORMAL") for i, line in enumerate(lines)
        ]

    path = write_edited(tmp_path, rec, edit)
    assert_same(read_rtde_csv(path), rec, ATOL_6DP)


def test_identify_repairs_a_malformed_row_when_asked(tmp_path, capsys):
    from ident_reference import generate_log
    from tvist.cli import main

    # A physical log (the command also checks its units), with one row of 29 fields.
    path = tmp_path / "log.csv"
    q0 = np.array([0.3, -1.4, 1.2, -1.3, 1.5, 0.1])
    generate_log(path, seed=5, joint=0, wn_rad_s=2 * np.pi * 15.0, zeta=0.05, q0=q0)
    path.write_text("\n".join(insert_field_in_row(path.read_text().splitlines(), 3, 5)) + "\n")
    main(["identify", str(path), "--joint", "0"])
    assert "--repair drop-bad-rows" in capsys.readouterr().err  # the hint names the flag
    main(["identify", str(path), "--joint", "0", "--repair", "drop-bad-rows", "--json"])
    err = capsys.readouterr().err
    assert "has 29 fields" not in err.split("warning")[0]  # no longer refused for the row
    assert "tvist identify: warning:" in err and "data row 3" in err  # repaired, with a warning
