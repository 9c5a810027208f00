"""``tvist shape``: offline shaping of trajectory files, each output compared with the library
calls it wraps (the shapers, zero_delay, and an independent scipy resampling)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import make_interp_spline

import tvist
from tvist.cli import main
from tvist.cli.shape import parse_modes, read_joint_csv, read_trajectory_csv
from tvist.sim.flex import UR5E_FLEX
from tvist.trajectory import PAPER_POSES
from tvist.trajectory.joint_names import UR_JOINT_NAMES

#: The default --dt-s: the --robot's (ur5e) control period, s (its robot data).
DT = tvist.robots.params("ur5e").control_period_s
# The files store 9 decimals: equal to the library's output within 5e-10 rad (rounding of
# the stored input and output, each at most 5e-10).
ATOL_FILE = 1.1e-9


def refused(args: list[str], match: str, capsys) -> None:
    """The command refuses: a ValueError naming the problem, or a one-line error, exit 2."""
    try:
        code = main(args)
    except ValueError as e:
        assert match in str(e), str(e)
        return
    except SystemExit as e:
        code = e.code
    assert code == 2
    assert match in capsys.readouterr().err


def test_parse_modes_converts_hz_to_rad_s():
    assert parse_modes("8:0.2,7.5:0.3") == [(2 * np.pi * 8, 0.2), (2 * np.pi * 7.5, 0.3)]
    with pytest.raises(ValueError, match="FREQ_HZ:ZETA"):
        parse_modes("8")


def test_tvist_method_equals_the_shaper_and_ends_at_the_end_pose(paper_move_csv, tmp_path, capsys):
    path, q = paper_move_csv
    out = tmp_path / "shaped.csv"
    assert (
        main(["shape", str(path), "--out", str(out), "--modes", "8:0.2,7:0.3", "--shaper", "zvd"])
        == 0
    )
    assert "no time column" in capsys.readouterr().out
    shaped, header = read_joint_csv(out)
    assert header == [f"q{j}" for j in range(6)]
    modes = [(2 * np.pi * 8, 0.2), (2 * np.pi * 7, 0.3)]
    reference = tvist.TvShaper(tvist.ConstantModes(modes), DT, 6, shaper="zvd")
    padded = np.vstack([q, np.repeat(q[-1:], shaped.shape[0] - q.shape[0], axis=0)])
    np.testing.assert_allclose(shaped, reference.shape(padded), atol=ATOL_FILE)
    # The padding holds the end pose long enough for the filter to settle on it.
    np.testing.assert_allclose(shaped[-1], q[-1], atol=5e-10)
    # The added delay is the ZVD cascade's plus at most two samples.
    delay = sum(tvist.shaper("zvd", w, z).duration_s for w, z in modes)
    assert 0.0 <= (shaped.shape[0] - q.shape[0]) * DT - delay <= 2 * DT


@pytest.mark.parametrize(("method", "zd_method"), [("modified", "modified"), ("ztdis", "ztdis")])
def test_map_source_zero_delay_equals_zero_delay_with_the_end_pose_modes(
    paper_move_csv, tmp_path, method, zd_method
):
    path, q = paper_move_csv
    out = tmp_path / "zd.csv"
    args = ["shape", str(path), "--out", str(out), "--paper-map", "--payload-kg", "5"]
    assert main([*args, "--payload-com", "0", "0", "0.05", "--method", method]) == 0
    shaped, _ = read_joint_csv(out)
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    modes = tvist.DynamicMap.paper_ur5e().modes(robot, q[-1])
    ref = tvist.zero_delay(q, DT, modes, shaper="zv", method=zd_method, interp="linear")
    assert shaped.shape == q.shape
    np.testing.assert_allclose(shaped, ref.Q, atol=ATOL_FILE)


def test_map_source_fd_tvist_equals_the_map_driven_shaper(paper_move_csv, tmp_path):
    path, q = paper_move_csv
    out = tmp_path / "map.csv"
    assert main(["shape", str(path), "--out", str(out), "--paper-map", "--payload-kg", "3"]) == 0
    shaped, _ = read_joint_csv(out)
    robot = tvist.robots.ur5e(3.0, (0.0, 0.0, 0.05))  # the default CoM of every command
    ref = tvist.TvShaper(tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e()), DT, 6)
    padded = np.vstack([q, np.repeat(q[-1:], shaped.shape[0] - q.shape[0], axis=0)])
    np.testing.assert_allclose(shaped, ref.shape(padded), atol=ATOL_FILE)


def test_modal_map_file_fd_tvist_equals_the_modal_map_driven_shaper(paper_move_csv, tmp_path):
    # --map dispatches on the file's kind: a modal map file drives the modal provider.
    path, q = paper_move_csv
    entries = [
        {
            "joint": j,
            "stiffness_nm_per_rad": [UR5E_FLEX.k1_nm_per_rad[j], 0.0, 0.0],
            "damping_nms_per_rad": [UR5E_FLEX.c0_nms_per_rad[j], 0.0, 0.0],
            "damping_load_joint": j,
        }
        for j in (0, 1)  # the twin's base and shoulder gears, without load terms
    ]
    modal = tvist.ModalMap(entries, (0, 1), {"robot": "ur5e"})
    map_path = tmp_path / "modal.json"
    modal.save(map_path)
    out = tmp_path / "modal.csv"
    args = ["shape", str(path), "--out", str(out), "--map", str(map_path), "--payload-kg", "3"]
    assert main(args) == 0
    shaped, _ = read_joint_csv(out)
    robot = tvist.robots.ur5e(3.0, (0.0, 0.0, 0.05))  # the default CoM of every command
    ref = tvist.TvShaper(tvist.ModalDynamics(robot, tvist.ModalMap.load(map_path)), DT, 6)
    padded = np.vstack([q, np.repeat(q[-1:], shaped.shape[0] - q.shape[0], axis=0)])
    expected = ref.shape(padded)
    # The move must be shaped for the comparison to mean anything.
    assert np.max(np.abs(expected - padded)) > 1e-3
    np.testing.assert_allclose(shaped, expected, atol=ATOL_FILE)


def waypoint_file(tmp_path, name="plan.csv"):
    """10 Hz waypoints Q1 -> Q3 over 2.4 s (25 rows) with a `time` column in the middle and
    the UR joints in a shuffled order."""
    t = 0.1 * np.arange(25)
    s = t / t[-1]
    q1, q3 = np.asarray(PAPER_POSES["Q1"]), np.asarray(PAPER_POSES["Q3"])
    q = q1 + np.outer(s**3 * (10 - 15 * s + 6 * s**2), q3 - q1)
    shuffle = [3, 0, 5, 1, 4, 2]
    cols = [UR_JOINT_NAMES[j] for j in shuffle]
    names = cols[:2] + ["time"] + cols[2:]
    data = np.column_stack([q[:, shuffle[:2]], t, q[:, shuffle[2:]]])
    path = tmp_path / name
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.12f")
    return path, t, q, names


def test_time_column_is_resampled_never_shaped_and_joints_matched_by_name(tmp_path, capsys):
    path, t_wp, q, names = waypoint_file(tmp_path)
    out = tmp_path / "shaped.csv"
    args = ["shape", str(path), "--out", str(out), "--paper-map", "--payload-kg", "5"]
    assert main([*args, "--dt-s", str(DT)]) == 0
    said = capsys.readouterr().out
    assert "time column 'time': 25 waypoints" in said and "resampled" in said
    assert "matched by UR joint name" in said and "path deviation" in said
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    header = out.read_text().splitlines()[0].split(",")
    assert header == ["time_s"] + [n for n in names if n != "time"]
    t_out = data[:, 0]
    # Time: strictly increasing, step dt_s, starting at the first waypoint: never shaped.
    assert np.all(np.diff(t_out) > 0)
    np.testing.assert_allclose(t_out, DT * np.arange(t_out.size), rtol=0, atol=5e-10)
    assert t_out.size > 2.4 / DT  # 25 rows became ~1200 samples plus the shaper delay
    # The unshaped input resampled independently (scipy's clamped B-spline): it passes through
    # every waypoint at the waypoints' times ...
    zero = np.zeros(6)
    spline = make_interp_spline(t_wp, q, k=3, bc_type=([(1, zero)], [(1, zero)]), axis=0)
    n_plan = int(round(t_wp[-1] / DT)) + 1
    planned = spline(DT * np.arange(n_plan))
    k_wp = np.rint(t_wp / DT).astype(int)
    np.testing.assert_allclose(planned[k_wp], q, rtol=0, atol=1e-12)
    # ... and the file is that resampled input shaped by the map-driven FD-TVIST shaper.
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    ref = tvist.TvShaper(tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e()), DT, 6)
    held = np.vstack([planned, np.repeat(planned[-1:], t_out.size - n_plan, axis=0)])
    order = [names.index(n) for n in UR_JOINT_NAMES]  # file column of each robot joint
    joints = data[:, 1:]
    file_cols = [n for n in names if n != "time"]
    by_robot = joints[:, [file_cols.index(names[i]) for i in order]]
    np.testing.assert_allclose(by_robot, ref.shape(held), atol=ATOL_FILE)


def test_padded_move_file_uses_the_motion_only_rule(tmp_path, capsys):
    # The modified-ZTDIS benchmark (T = 0.734 s, 2.55 Hz, zeta 0.04, ZVD) with 0.2 s of rest
    # before and 1.5 s after, as a planner would pad it.
    s = np.arange(368) / 367
    move = 0.3 * s**3 * (10 - 15 * s + 6 * s**2)
    q = np.concatenate([np.zeros(100), move, np.full(750, 0.3)])
    path = tmp_path / "padded.csv"
    np.savetxt(path, q[:, None], fmt="%.12f")
    out = tmp_path / "zd.csv"
    args = ["shape", str(path), "--out", str(out), "--modes", "2.55:0.04", "--shaper", "zvd"]
    assert main([*args, "--method", "modified"]) == 0
    assert "alpha 0.6516" in capsys.readouterr().out
    stored = np.loadtxt(path)
    mode = [(2 * np.pi * 2.55, 0.04)]
    ref = tvist.zero_delay(stored, DT, mode, method="modified", interp="linear")
    np.testing.assert_allclose(np.loadtxt(out), ref.Q, atol=ATOL_FILE)
    assert main([*args, "--method", "ztdis"]) == 0
    assert "alpha 0.4653" in capsys.readouterr().out


def test_rtde_logs_are_read_through_target_q(tmp_path):
    path = tmp_path / "log.csv"
    cols = ["timestamp"] + [f"target_q_{j}" for j in range(6)] + ["actual_q_0"]
    rows = np.column_stack([np.arange(4) * DT, np.ones((4, 6)) * 0.5, np.zeros(4)])
    np.savetxt(path, rows, delimiter=",", header=",".join(cols), comments="")
    q, header = read_joint_csv(path)
    assert header == cols[1:7] and q.shape == (4, 6) and np.all(q == 0.5)


def test_bad_files_and_arguments_are_refused(tmp_path, capsys):
    nan = tmp_path / "nan.csv"
    nan.write_text("0,0\n0,nan\n")
    with pytest.raises(ValueError, match="row 2"):
        read_joint_csv(nan)
    short = tmp_path / "short.csv"
    short.write_text("0,0\n")
    with pytest.raises(ValueError, match="at least 2"):
        read_joint_csv(short)
    ragged = tmp_path / "ragged.csv"
    ragged.write_text("a,b\n0,0\n0,0,1\n")
    with pytest.raises(ValueError, match="row 3 has 3 fields"):
        read_trajectory_csv(ragged)
    back = tmp_path / "back.csv"
    back.write_text("time,q0\n0,0\n0.2,0.1\n0.1,0.1\n")
    ok = tmp_path / "ok.csv"
    ok.write_text("0,0\n0.1,0.1\n0.1,0.1\n")
    o = str(tmp_path / "o.csv")
    refused(["shape", str(back), "--out", o, "--modes", "2:0.1"], "strictly increasing", capsys)
    refused(["shape", str(ok), "--out", o], "--modes, --map", capsys)
    refused(["shape", str(ok), "--out", o, "--paper-map", "--payload-kg", "5"], "--robot", capsys)
    refused(["shape", "--out", o, "--modes", "2:0.1"], "--bag", capsys)
    refused(["shape", str(ok), "--out", o, "--modes", "2:0.1", "--dt-s", "0"], "--dt-s", capsys)
    with pytest.raises(SystemExit):  # argparse: three numbers X Y Z
        main(["shape", str(ok), "--out", o, "--paper-map", "--payload-com", "0", "0"])
