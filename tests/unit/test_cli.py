"""The command line: every subcommand is registered and ``--method`` selects demo rows."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tvist
from tvist.cli import build_parser
from tvist.cli.demo import demo_row_method
from tvist.experiments import default_methods
from tvist.sim.flex import UR5E_FLEX


def test_every_command_parses_its_help():
    parser = build_parser()
    for name in ("demo", "zero-delay", "campaign", "identify", "fit-map", "sensitivity", "shape"):
        with pytest.raises(SystemExit) as exit_:
            parser.parse_args([name, "--help"])
        assert exit_.value.code == 0


def test_demo_rows_belong_to_the_methods_a_user_can_choose():
    kinds = {m.key: demo_row_method(m.key) for m in default_methods()}
    assert kinds["unshaped"] == "unshaped"
    assert {kinds[k] for k in kinds if k != "unshaped"} == {"tvist", "ztdis", "modified"}
    assert demo_row_method("fd-tvist-identified-map") == "tvist"
    with pytest.raises(SystemExit):
        build_parser().parse_args(["demo", "--method", "bogus"])


def test_subpackages_load_on_first_access_without_heavy_imports():
    import subprocess
    import sys

    code = (
        "import sys, tvist\n"
        "assert 'mujoco' not in sys.modules and 'matplotlib' not in sys.modules\n"
        "assert callable(tvist.trajectory.double_s) and callable(tvist.ident.read_rtde_csv)\n"
        "assert tvist.sim.Twin and callable(tvist.analysis.residual_vibration)\n"
        "assert 'mujoco' not in sys.modules  # the simulator loads only with a Twin\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
    with pytest.raises(AttributeError, match="no attribute"):
        import tvist

        _ = tvist.not_a_subpackage


# ---- the commands' outputs are those of the library calls they wrap ----

#: The default --dt-s of the commands below: the --robot's (ur5e) control period.
DT_S = tvist.robots.params("ur5e").control_period_s


def test_zero_delay_command_prints_the_benchmark_of_the_library(tmp_path, capsys):
    """``tvist zero-delay``: the printed table is ``format_table(run_benchmark(...))`` and the
    plot is written; the benchmark's own numbers are checked against closed forms."""
    from tvist.cli import main
    from tvist.experiments.ztdis_benchmark import format_table, run_benchmark

    out = tmp_path / "zero_delay.png"
    assert main(["zero-delay", "--reference", "min_jerk", "--plot", str(out)]) == 0
    printed = capsys.readouterr().out
    bench = run_benchmark("min_jerk", dt_s=DT_S)
    assert format_table(bench) in printed
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # ZVD of the 2.55 Hz, ζ 0.04 payload: one damped period, 1 / (2.55 √(1 − 0.04²)) s.
    assert bench.delay_s == pytest.approx(1.0 / (2.55 * math.sqrt(1.0 - 0.04**2)), rel=1e-12)


@pytest.mark.parametrize("method", ["modified", "ztdis"])
def test_shape_with_the_paper_map_and_zero_delay_equals_zero_delay(
    paper_move_csv, tmp_path, method
):
    """``tvist shape --paper-map --method (m)ztdis`` = ``zero_delay()`` with the modes of the
    end pose, and those modes are the paper map's equations (independent transcription) at
    the end pose's inertias."""
    from map_reference import PAPER_MODES, modes_reference
    from tvist.cli import main
    from tvist.cli.shape import read_joint_csv

    path, q = paper_move_csv
    out = tmp_path / "zd.csv"
    args = ["shape", str(path), "--out", str(out), "--paper-map", "--payload-kg", "5"]
    assert main([*args, "--payload-com", "0", "0", "0.05", "--method", method]) == 0
    shaped, header = read_joint_csv(out)
    assert header == [f"q{j}" for j in range(6)]
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    end_modes = modes_reference(PAPER_MODES, [robot.joint_inertia(q[-1])])[0]
    # The command's fractional delays are linear, as for FD-TVIST (tvist.trajectory.shape_samples).
    expected = tvist.zero_delay(
        q,
        DT_S,
        end_modes,
        shaper="zv",
        method=method,
        interp="linear",
    )
    # 9 decimals in the file; the map evaluations agree to ~1e-15.
    np.testing.assert_allclose(shaped, expected.Q, rtol=0, atol=5e-10)
    assert shaped.shape == q.shape
    np.testing.assert_allclose(shaped[-1], q[-1], atol=1e-6)


def test_run_takes_a_modal_map_file_like_shape_does(paper_move_csv, tmp_path):
    """``tvist run --map FILE`` reads either map kind (as ``tvist shape`` does): its live
    shaper for a modal map file is ``TvShaper(ModalDynamics(robot, ModalMap.load(FILE)))``,
    step for step; a paper10 file gives the paper10 provider."""
    from tvist.cli import build_parser
    from tvist.cli.live import _shaper

    path, q = paper_move_csv
    entries = [  # the twin's base and shoulder gears, without load terms
        {
            "joint": j,
            "stiffness_nm_per_rad": [UR5E_FLEX.k1_nm_per_rad[j], 0.0, 0.0],
            "damping_nms_per_rad": [UR5E_FLEX.c0_nms_per_rad[j], 0.0, 0.0],
            "damping_load_joint": 1,
        }
        for j in (0, 1)
    ]
    modal_path = tmp_path / "modal.json"
    tvist.ModalMap(entries, [0, 1], {"robot": "ur5e"}).save(modal_path)
    paper_path = tmp_path / "paper.json"
    tvist.DynamicMap.paper_ur5e().save(paper_path)
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    for map_path, loaded in (
        (modal_path, tvist.ModalMap.load(modal_path)),
        (paper_path, tvist.DynamicMap.paper_ur5e()),
    ):
        args = build_parser().parse_args(
            ["run", str(path), "--robot-ip", "127.0.0.1", "--map", str(map_path)]
            + ["--payload-kg", "5", "--payload-com", "0", "0", "0.05"]
        )
        live = _shaper(args, q)
        expected = tvist.TvShaper(tvist.maps.dynamics_for(robot, loaded), DT_S, 6, shaper="zv")
        live.reset(q[0])
        expected.reset(q[0])
        got = np.array([live.step(row) for row in q])
        np.testing.assert_array_equal(got, np.array([expected.step(row) for row in q]))
        assert np.max(np.abs(got - q)) > 1e-3  # the map shaped the move (a delayed copy)


def test_shape_with_a_map_file_equals_the_map_driven_shaper(paper_move_csv, tmp_path, capsys):
    """``tvist shape --map FILE`` = ``TvShaper(MapDynamics(robot, map))`` on the input padded
    with its last sample for the end pose's ZV delay."""
    from tvist.cli import main
    from tvist.cli.shape import read_joint_csv

    path, q = paper_move_csv
    map_path = tmp_path / "map.json"
    tvist.DynamicMap.paper_ur5e().save(map_path)
    out = tmp_path / "fd.csv"
    args = ["shape", str(path), "--out", str(out), "--map", str(map_path), "--payload-kg", "5"]
    assert main([*args, "--payload-com", "0", "0", "0.05"]) == 0
    shaped, _ = read_joint_csv(out)
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    shaper = tvist.TvShaper(
        tvist.MapDynamics(robot, tvist.DynamicMap.paper_ur5e()), DT_S, 6, shaper="zv"
    )
    padded = np.vstack([q, np.repeat(q[-1:], shaped.shape[0] - q.shape[0], axis=0)])
    np.testing.assert_allclose(shaped, shaper.shape(padded), rtol=0, atol=5e-10)
    # The padding is the end pose's two-mode ZV delay (π/ω_d per mode) rounded up, plus one.
    end = tvist.DynamicMap.paper_ur5e().modes(robot, q[-1])
    delay_s = sum(math.pi / (w * math.sqrt(1 - z * z)) for w, z in end)
    assert shaped.shape[0] - q.shape[0] == math.ceil(delay_s / DT_S - 1e-9) + 1
    np.testing.assert_allclose(shaped[-1], q[-1], atol=5e-10)
    assert f"(+{(shaped.shape[0] - q.shape[0]) * DT_S * 1e3:.0f} ms)" in capsys.readouterr().out


def test_identify_summary_counts_modes_that_rang_faster_while_moving():
    """``tvist identify``'s ringing line: confident modes, and the ones flagged for ringing
    faster while their joint moved than at rest, with the median excess (here +4 % and +6 %:
    +5 %); without such flags the line says nothing of it."""
    from tvist.cli.ident import _ringing_summary
    from tvist.ident.ringing import AT_REST_REASON

    def entry(wn, at_rest, flagged):
        reasons = [f"{AT_REST_REASON}: …"] if flagged else []
        return {
            "wn_rad_s": wn,
            "wn_at_rest_rad_s": at_rest,
            "low_confidence": flagged,
            "reasons": reasons,
        }

    records = [
        {"ringing": [entry(52.0, 50.0, True), entry(80.0, 80.1, False)]},
        {"ringing": [entry(53.0, 50.0, True)]},
    ]
    line = _ringing_summary(records)
    assert "3 modes in the logs, 1 confident" in line
    assert "2 flagged for ringing faster while the joint moved than at rest" in line
    assert "(median +5.0 %)" in line
    quiet = _ringing_summary([{"ringing": [entry(80.0, 80.1, False)]}])
    assert "faster" not in quiet
