"""Every script in examples/ runs to completion (exit code 0) within a time limit, and what it
prints is checked against closed forms, the library and the twin's pinned calibration.

Scripts run in a fresh temporary working directory (so any files they write stay out of the
source tree) with a non-interactive matplotlib backend.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import tvist

EXAMPLES_DIR = Path(__file__).resolve().parents[2] / "examples"
EXAMPLES = sorted(EXAMPLES_DIR.glob("*.py"))
TIMEOUT_S = 120
#: examples/08 runs the twin server (conftest: realtime tests run alone).
REALTIME = True
#: Every test here reads the module fixture that runs all the examples (18 s): slow
#: (docs/test-quality.md), ``make test`` runs them.
pytestmark = pytest.mark.slow


def zv_delay_s(modes) -> float:
    """Two-mode ZV delay: half a damped period per mode, ``Σ π / (ω_n √(1 − ζ²))``."""
    return sum(math.pi / (wn * math.sqrt(1.0 - zeta**2)) for wn, zeta in modes)


def numbers_after(text: str, label: str) -> list[float]:
    """The numbers on the first line that contains ``label``, after it."""
    line = next(line for line in text.splitlines() if label in line)
    return [float(v) for v in re.findall(r"[-+]?\d+\.?\d*(?:e[-+]?\d+)?", line.split(label, 1)[1])]


@pytest.fixture(scope="module")
def outputs(tmp_path_factory) -> dict[str, subprocess.CompletedProcess]:
    """Each example run once; its ``CompletedProcess`` by file name."""
    runs = {}
    for script in EXAMPLES:
        cwd = tmp_path_factory.mktemp(script.stem)
        runs[script.name] = subprocess.run(
            [sys.executable, str(script)],
            cwd=cwd,
            env={**os.environ, "MPLBACKEND": "Agg"},
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
        )
        runs[script.name].cwd = cwd
    return runs


def test_examples_exist() -> None:
    assert any(p.name.startswith("01_") for p in EXAMPLES)


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs(script: Path, outputs) -> None:
    result = outputs[script.name]
    assert result.returncode == 0, (
        f"{script.name} failed:\n--- stdout\n{result.stdout[-3000:]}\n--- stderr\n"
        f"{result.stderr[-3000:]}"
    )


def test_shape_a_move_prints_the_two_mode_zv_delay_and_ends_on_target(outputs) -> None:
    out = outputs["01_shape_a_move.py"].stdout
    modes = [(2 * math.pi * 8.31, 0.26), (2 * math.pi * 7.45, 0.37)]  # those of the script
    # Printed to 0.1 ms.
    for line in out.splitlines():
        if "shaper delay" in line:
            (delay_ms,) = numbers_after(line, "shaper delay")
            assert delay_ms == pytest.approx(1e3 * zv_delay_s(modes), abs=0.05)
    # The lag is target − shaped, both printed to 4 decimals (rounding ≤ 1e-4 rad).
    for line in out.splitlines():
        if line.startswith("t = "):
            target, shaped = numbers_after(line, "target")[0], numbers_after(line, "shaped")[0]
            (lag,) = numbers_after(line, "lag")[:1]
            assert lag == pytest.approx(1e3 * (target - shaped), abs=0.11)
    assert "final shaped pose: [ 0.   0.5 -0.5  0.   0.   0. ]" in out


def test_zero_delay_example_prints_the_library_results(outputs) -> None:
    result = outputs["02_zero_delay.py"]
    out = result.stdout
    from tvist.trajectory import min_jerk

    wn, zeta, dt_s = 2.0 * np.pi * 2.55, 0.04, 0.002
    move = min_jerk([0.0], [0.3], duration_s=0.734, dt_s=dt_s).q
    for method in ("ztdis", "modified"):
        lib = tvist.zero_delay(move, dt_s, [(wn, zeta)], shaper="zvd", method=method)
        alpha, delay, ends, error = numbers_after(out, f"{method:>8}:")
        assert alpha == pytest.approx(lib.alpha, abs=5e-5)
        # ZVD: one damped period; the move keeps its 0.734 s.
        assert delay == pytest.approx(2 * math.pi / (wn * math.sqrt(1 - zeta**2)), abs=5e-5)
        assert ends == pytest.approx(0.734, abs=5e-4)
        assert error < 1e-6
    png = result.cwd / "out" / "zero_delay.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_twin_example_prints_its_shaper_delay_and_the_pinned_twin_modes(outputs) -> None:
    """The shaper delay at Q3 is the two-mode ZV delay of the paper map's modes there (the
    map's equations, independent transcription), the twin's modes are its pinned calibration
    (tests/twin_calibration.py), and the reduction follows from the two printed amplitudes."""
    from map_reference import PAPER_MODES, modes_reference
    from tvist.trajectory import PAPER_POSES
    from twin_calibration import TWIN_CALIBRATION

    out = outputs["03_twin_q1_to_q3.py"].stdout
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    modes = modes_reference(PAPER_MODES, [robot.joint_inertia(PAPER_POSES["Q3"])])[0]
    # Printed to 0.1 ms.
    assert numbers_after(out, "shaper delay at Q3:")[0] == pytest.approx(
        1e3 * zv_delay_s(modes), abs=0.05
    )
    for label, (f_hz, zeta) in zip(("base", "shoulder"), TWIN_CALIBRATION["Q3"], strict=True):
        printed_f, printed_zeta = numbers_after(out, f"twin's true {label} mode at Q3:")
        assert printed_f == pytest.approx(f_hz, abs=0.006)  # printed to 0.01 Hz
        assert printed_zeta == pytest.approx(zeta, abs=6e-4)  # printed to 0.001
    unshaped = numbers_after(out, "unshaped: residual vibration")[0]
    shaped = numbers_after(out, "FD-TVIST: residual vibration")[0]
    reduction = numbers_after(out, "reduction:")[0]
    assert reduction == pytest.approx(100 * (1 - shaped / unshaped), abs=0.06)
    assert shaped < 0.2 * unshaped


def test_identify_example_finds_the_twins_base_mode_from_its_log(outputs) -> None:
    """The twin's base mode at Q1 printed is its pinned calibration; the mode identified from
    the written log is within the accuracy the identification reaches on twin logs (base
    modes within 3 % in frequency in the full campaign), and confident."""
    from twin_calibration import TWIN_CALIBRATION

    out = outputs["05_identify_from_log.py"].stdout
    (f_hz, zeta) = TWIN_CALIBRATION["Q1"][0]
    twin_f, twin_zeta = numbers_after(out, "twin:")
    assert twin_f == pytest.approx(f_hz, abs=6e-4)  # printed to 0.001 Hz
    assert twin_zeta == pytest.approx(zeta, abs=6e-5)  # printed to 1e-4
    found_f, found_zeta = numbers_after(out, "identified:")
    assert found_f == pytest.approx(f_hz, rel=0.03)
    assert found_zeta == pytest.approx(zeta, rel=0.10)  # damping: the map fit's 10 % band
    assert "confident:  True" in out
    assert (outputs["05_identify_from_log.py"].cwd / "base_excitation.csv").is_file()


def test_map_loop_example_ends_on_target_with_the_maps_delay(outputs) -> None:
    """The delay printed at the end pose Q3 is the two-mode ZV delay of the paper map's modes
    there (independent transcription of the map), and the loop ends on the planned pose."""
    from map_reference import PAPER_MODES, modes_reference
    from tvist.trajectory import PAPER_POSES

    out = outputs["06_map_loop_500hz.py"].stdout
    robot = tvist.robots.ur5e(5.0, (0.0, 0.0, 0.05))
    modes = modes_reference(PAPER_MODES, [robot.joint_inertia(PAPER_POSES["Q3"])])[0]
    delay_ms = numbers_after(out, "delay at the end pose")[0]
    assert delay_ms == pytest.approx(1e3 * zv_delay_s(modes), abs=0.05)  # printed to 0.1 ms
    assert numbers_after(out, "final error")[0] < 1e-9  # at rest on the input: rounding only
    assert "status:" not in out  # no held input or mode, no clamped delay on this move
    assert (outputs["06_map_loop_500hz.py"].cwd / "ur5e_map.json").is_file()


def test_cartesian_example_keeps_the_line_straight_and_joint_shaping_does_not(outputs) -> None:
    out = outputs["07_cartesian_line.py"].stdout
    in_tcp = numbers_after(out, "Cartesian shaping: flange leaves the line by")[0]
    in_joints = numbers_after(out, "joint shaping: flange leaves the line by")[0]
    # Cartesian: only the inverse kinematics' residual (solved to 1e-10) leaves the line.
    assert in_tcp < 1e-8
    # Joint space: the ZVD blend of a curved joint path cuts it by millimetres on this move.
    assert in_joints > 1e-3


def test_twin_server_example_moves_the_base_through_ur_rtde(outputs) -> None:
    out = outputs["08_twin_server_rtde.py"].stdout
    assert "twin server ready on" in out
    # moveJ reaches its target; 0.5 s after the stop the link still rings by far less than
    # 1 mrad (printed to 0.1 mrad).
    assert numbers_after(out, "base moved")[0] == pytest.approx(0.5, abs=1e-3)
    # At rest the accelerometer reads gravity; the ringing shows as a non-zero spread.
    mean, ringing = numbers_after(out, "accelerometer after the stop: mean")[:2]
    assert mean == pytest.approx(9.81, abs=0.05)
    assert ringing > 0.0
