"""``tvist shape``: offline shaping of a trajectory file, checked against the library calls."""

from __future__ import annotations

import numpy as np
import pytest

import tvist
from tvist.cli import main
from tvist.shape_command import parse_modes, read_joint_csv
from tvist.trajectory import PAPER_POSES, double_s

DT = 0.002


@pytest.fixture
def move_csv(tmp_path):
    traj = double_s(PAPER_POSES["Q1"], PAPER_POSES["Q3"], dt_s=DT, t_pre_s=0.02, t_post_s=0.02)
    path = tmp_path / "move.csv"
    header = ",".join(f"q{j}" for j in range(6))
    np.savetxt(path, traj.q, delimiter=",", header=header, comments="", fmt="%.12f")
    return path, np.loadtxt(path, delimiter=",", skiprows=1)


def test_parse_modes_converts_hz_to_rad_s():
    assert parse_modes("8:0.2,7.5:0.3") == [(2 * np.pi * 8, 0.2), (2 * np.pi * 7.5, 0.3)]
    with pytest.raises(ValueError, match="FREQ_HZ:ZETA"):
        parse_modes("8")


def test_tvist_method_equals_the_shaper_and_ends_at_the_end_pose(move_csv, tmp_path):
    path, q = move_csv
    out = tmp_path / "shaped.csv"
    assert (
        main(["shape", str(path), "--out", str(out), "--modes", "8:0.2,7:0.3", "--shaper", "zvd"])
        == 0
    )
    shaped, header = read_joint_csv(out)
    assert header == [f"q{j}" for j in range(6)]
    modes = [(2 * np.pi * 8, 0.2), (2 * np.pi * 7, 0.3)]
    reference = tvist.TvShaper(tvist.ConstantModes(modes), DT, 6, shaper="zvd")
    padded = np.vstack([q, np.repeat(q[-1:], shaped.shape[0] - q.shape[0], axis=0)])
    # The file stores 9 decimals: equal to the library's output within 5e-10 rad.
    np.testing.assert_allclose(shaped, reference.shape(padded), atol=5e-10)
    # The padding holds the end pose long enough for the filter to settle on it.
    np.testing.assert_allclose(shaped[-1], q[-1], atol=5e-10)


def test_map_source_and_zero_delay_method_keep_the_length(move_csv, tmp_path):
    path, q = move_csv
    out = tmp_path / "zd.csv"
    args = ["shape", str(path), "--out", str(out), "--paper-map", "--payload-kg", "5"]
    assert main([*args, "--payload-com", "0,0,0.05", "--method", "mztdis"]) == 0
    shaped, _ = read_joint_csv(out)
    assert shaped.shape == q.shape
    np.testing.assert_allclose(shaped[-1], q[-1], atol=1e-6)


def test_rtde_logs_are_read_through_target_q(tmp_path):
    path = tmp_path / "log.csv"
    cols = ["timestamp"] + [f"target_q_{j}" for j in range(6)] + ["actual_q_0"]
    rows = np.column_stack([np.arange(4) * DT, np.ones((4, 6)) * 0.5, np.zeros(4)])
    np.savetxt(path, rows, delimiter=",", header=",".join(cols), comments="")
    q, header = read_joint_csv(path)
    assert header == cols[1:7] and q.shape == (4, 6) and np.all(q == 0.5)


def test_bad_files_and_arguments_are_refused(tmp_path):
    nan = tmp_path / "nan.csv"
    nan.write_text("0,0\n0,nan\n")
    with pytest.raises(ValueError, match="row 2"):
        read_joint_csv(nan)
    short = tmp_path / "short.csv"
    short.write_text("0,0\n")
    with pytest.raises(ValueError, match="at least 2"):
        read_joint_csv(short)
    ok = tmp_path / "ok.csv"
    ok.write_text("0,0\n0.1,0.1\n0.1,0.1\n")
    with pytest.raises(ValueError, match="--modes, --map"):
        main(["shape", str(ok), "--out", str(tmp_path / "o.csv")])
    with pytest.raises(ValueError, match="6"):
        main(["shape", str(ok), "--out", str(tmp_path / "o.csv"), "--paper-map"])
