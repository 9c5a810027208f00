"""Maps cross the language boundary: C++ (tvist.hpp over the C API) shapes exactly as Python.

Maps written by ``tvist fit-map`` (paper10 and ``--kind modal``), ``DynamicMap.save`` and
``ModalMap.save`` are loaded in C++ through ``tvist_shaper_new_map``
(``examples/cpp/shape_with_map.cpp``) and in Python through ``tvist.load_map``; both shape
the same samples of a move. The two run the same core code
on the same parsed map, so they must agree to rounding: 1e-12 rad (the C++ program writes 17
significant digits, which reproduce a double exactly; any larger gap is a different map or a
different filter).

The fit-map input is synthetic: the modes of a known map (paper10: at the inertias of random
poses of the robot; modal: from the mass matrices there) written in the campaign-record format;
the UR10e's modal fit-map file is the one test_modal_map checks (the UR10e twin's modes, made
once per test run: ``ur10e_twin_fit`` in conftest.py).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import tvist
from cpp_programs import target_lock
from tvist.cli import main
from tvist.maps.modal import modal_map_from_flex
from tvist.sim.flex import UR5E_FLEX

ROOT = Path(__file__).resolve().parents[2]
PAYLOAD_KG, COM_M, DT_S = 5.0, (0.0, 0.0, 0.05), 0.002
TOLERANCE_RAD = 1e-12
#: Poses of the synthetic campaign a fit-map file is made from. The check is that C++ and
#: Python shape one file alike, sample for sample, whatever the fit made of the poses; 16
#: exact (noise-free) records of 2 modes give the modal fit its 12 gear coefficients with
#: residual degrees of freedom (for the UR5e it recovers the gear laws to 1e-9). The fit's
#: time grows with the poses: with 40 it was most of this test's 74 s per robot.
N_POSES = 16


@pytest.fixture(scope="module")
def program(shape_with_map) -> Path:
    """The C++ example (built once per test process: ``shape_with_map`` in conftest.py)."""
    return shape_with_map


def _campaign_records(
    path: Path, robot_name: str, truth: tvist.DynamicMap | tvist.ModalMap
) -> None:
    """Campaign-style records of ``truth``'s modes at random robot poses."""
    payload = tvist.robots.Payload(_payload_kg(robot_name), COM_M)
    robot = tvist.robots.Robot(tvist.robots.params(robot_name), payload)
    rng = np.random.default_rng(7)
    limits = tvist.robots.params(robot_name).joint_limits_rad
    with path.open("w") as fh:
        for i in range(N_POSES):
            q = rng.uniform(limits[:, 0], limits[:, 1])
            inertia = robot.joint_inertia(q)
            if isinstance(truth, tvist.ModalMap):
                modes = truth.modes(robot, q)
            else:
                modes = truth.modes_from_inertia(inertia)
            record = {
                "key": f"p{i}",
                "q": [float(v) for v in q],
                "payload_kg": payload.mass_kg,
                "payload_com_m": list(COM_M),
                "inertia_kg_m2": [float(v) for v in inertia],
                "modes": [
                    {"joint": j, "wn_rad_s": w, "zeta": z, "low_confidence": False}
                    for j, (w, z) in enumerate(modes)
                ],
            }
            fh.write(json.dumps(record) + "\n")


def _move(robot_name: str) -> np.ndarray:
    """A 0.8 s move of the first three joints from a mid-range pose, then 0.4 s of rest."""
    t = np.arange(0.0, 1.2, DT_S)
    s = np.clip(t / 0.8, 0.0, 1.0)
    blend = s**3 * (10 - 15 * s + 6 * s**2)
    p = tvist.robots.params(robot_name)
    if p.placements is None:
        q0 = np.array([0.0, -1.6, 1.2, -1.2, 0.3, 0.0])
    else:  # mid-range, as a UR's q0 lies well within its limits
        q0 = p.joint_limits_rad.mean(axis=1)
    dq = np.zeros(p.n_dof)
    dq[:3] = [0.9, 0.5, -0.6]
    return q0 + blend[:, None] * dq


def _payload_kg(robot_name: str) -> float:
    return min(PAYLOAD_KG, tvist.robots.params(robot_name).max_payload_kg)


def _python_shaped(robot_name: str, map_path: Path, q: np.ndarray) -> np.ndarray:
    payload = tvist.robots.Payload(_payload_kg(robot_name), COM_M)
    robot = tvist.robots.Robot(tvist.robots.params(robot_name), payload)
    shaper = tvist.TvShaper(
        tvist.maps.dynamics_for(robot, tvist.load_map(map_path)), DT_S, robot.n_dof, shaper="zv"
    )
    shaper.reset(q[0])
    return shaper.shape(q)


def _cpp_shaped(
    program: Path, robot_name: str, map_path: Path, q: np.ndarray, tmp: Path, robot: str = ""
):
    """The C++ program's shaped samples; ``robot`` a robot file (default: the name)."""
    samples, shaped = tmp / f"{robot_name}_in.txt", tmp / f"{robot_name}_out.txt"
    np.savetxt(samples, q, fmt="%.17g")
    payload = str(_payload_kg(robot_name))
    args = [robot or robot_name, payload, *map(str, COM_M), str(map_path), str(DT_S), "zv"]
    subprocess.run([str(program), *args, str(samples), str(shaped)], check=True)
    return np.loadtxt(shaped)


def _maps(robot_name: str, tmp: Path) -> dict[str, Path]:
    """A fit-map output and a DynamicMap.save output, both for ``robot_name``."""
    truth = tvist.DynamicMap(tvist.DynamicMap.paper_ur5e().mode_maps, {"robot": robot_name})
    results = tmp / f"{robot_name}.jsonl"
    _campaign_records(results, robot_name, truth)
    fitted = tmp / f"{robot_name}_fit.json"
    assert main(["fit-map", str(results), "--out", str(fitted), "--robot", robot_name]) == 0
    saved = tmp / f"{robot_name}_saved.json"
    truth.save(saved)
    return {"fit-map": fitted, "save": saved}


#: Gear laws of the modal map the modal files are made from: the twin's base and shoulder
#: (tvist.sim.UR5E_FLEX), the base damper loaded by the shoulder's gravity torque.
MODAL_ENTRIES = modal_map_from_flex(UR5E_FLEX, joints=(0, 1)).flex_joints


#: Robots whose ``fit-map --kind modal`` file is a fixture made once per test run and shared
#: with the module that checks what the fit found (here only the file matters); the others
#: are fitted here to the synthetic records. (The UR5e's shared fit, of a soft-elbow variant,
#: shapes a third mode that the 5 kg payload overdamps at some poses: refused by the provider.)
SHARED_MODAL_FIT = {"ur10e": "ur10e_twin_fit"}


def _modal_maps(robot_name: str, tmp: Path, request: pytest.FixtureRequest) -> dict[str, Path]:
    """A ``fit-map --kind modal`` output and a ModalMap.save output, both for ``robot_name``."""
    truth = tvist.ModalMap(MODAL_ENTRIES, (0, 1), {"robot": robot_name})
    if robot_name in SHARED_MODAL_FIT:
        folder = request.getfixturevalue(SHARED_MODAL_FIT[robot_name])
        assert json.loads((folder / "fit_map.json").read_text())["code"] == 0
        fitted = folder / "map.json"
    else:
        results = tmp / f"{robot_name}_modal.jsonl"
        _campaign_records(results, robot_name, truth)
        fitted = tmp / f"{robot_name}_modal_fit.json"
        args = ["fit-map", str(results), "--kind", "modal", "--out", str(fitted)]
        assert main([*args, "--robot", robot_name]) == 0
    saved = tmp / f"{robot_name}_modal_saved.json"
    truth.save(saved)
    return {"fit-map --kind modal": fitted, "ModalMap.save": saved}


@pytest.mark.slow
@pytest.mark.parametrize("robot_name", ["ur5e", "ur10e"])
def test_cpp_shapes_a_map_file_exactly_as_python(program, tmp_path, robot_name, request):
    q = _move(robot_name)
    maps = {**_maps(robot_name, tmp_path), **_modal_maps(robot_name, tmp_path, request)}
    for source, path in maps.items():
        kind = tvist.ModalMap if "modal" in source.lower() else tvist.DynamicMap
        loaded = tvist.load_map(path)
        assert isinstance(loaded, kind) and loaded.robot == robot_name, source
        expected = _python_shaped(robot_name, path, q)
        got = _cpp_shaped(program, robot_name, path, q, tmp_path)
        assert got.shape == expected.shape
        # The test would pass trivially on an identity filter: the move must be shaped.
        assert np.max(np.abs(expected - q)) > 1e-3, source
        np.testing.assert_allclose(got, expected, rtol=0, atol=TOLERANCE_RAD, err_msg=source)


def test_cpp_shapes_a_urdf_arm_from_its_robot_file_exactly_as_python(program, tmp_path):
    """The 7-joint iiwa14: its robot file as ``tvist robot-file`` writes it and a modal map
    of the form ``tvist fit-map --kind modal`` gives these arms (four flexible proximal
    joints, the three lowest modes shaped as a set), shaped in C++ from the two files and in
    Python from the shipped arm. (The FR3 with two flexible joints named by joint is
    tests/reference/test_urdf.py's case.)"""
    from tvist.robots import shipped_urdf

    path, base, tip = shipped_urdf("iiwa14")
    robot_file = tmp_path / "iiwa14_robot.json"
    args = ["robot-file", str(path), "--base-link", base, "--tip-link", tip, "--name", "iiwa14"]
    assert main([*args, "--out", str(robot_file)]) == 0
    # The twin's design laws (tvist.sim.flex.IIWA14_FLEX) as a map.
    from tvist.maps.modal import modal_map_from_flex
    from tvist.sim import default_flex

    laws = modal_map_from_flex(default_flex("iiwa14"), joints=(0, 1, 2, 3)).flex_joints
    map_path = tmp_path / "iiwa14_modal.json"
    tvist.ModalMap(laws, metadata={"robot": "iiwa14"}, shaped_modes=3).save(map_path)
    q = _move("iiwa14")
    expected = _python_shaped("iiwa14", map_path, q)
    got = _cpp_shaped(program, "iiwa14", map_path, q, tmp_path, robot=str(robot_file))
    assert np.max(np.abs(expected - q)) > 1e-3  # the move is shaped
    np.testing.assert_allclose(got, expected, rtol=0, atol=TOLERANCE_RAD)


@pytest.mark.parametrize("kind", ["paper10", "modal"])
def test_cpp_refuses_a_map_of_another_robot(program, tmp_path, kind):
    path = tmp_path / "ur5e.json"
    if kind == "modal":
        tvist.ModalMap(MODAL_ENTRIES, (0, 1), {"robot": "ur5e"}).save(path)
    else:
        tvist.DynamicMap.paper_ur5e().save(path)
    args = ["ur10e", "5", "0", "0", "0.05", str(path), "0.002", "zv"]
    q = tmp_path / "q.txt"
    np.savetxt(q, _move("ur10e")[:5])
    run = subprocess.run(
        [str(program), *args, str(q), str(tmp_path / "out.txt")], capture_output=True, text=True
    )
    assert run.returncode == 1
    assert "identified on ur5e, not on ur10e" in run.stderr, run.stderr


def test_the_readme_dynamic_link_line_works_as_printed(program, tmp_path):
    # The line is run verbatim from the repository root (what `make ffi-test` does too).
    lines = [
        line
        for line in (ROOT / "README.md").read_text().splitlines()
        if "-ltvist -lm -Wl,-rpath" in line
    ]
    assert len(lines) == 1, lines
    (ROOT / "target" / "c").mkdir(parents=True, exist_ok=True)
    binary = tmp_path / "shape_move_shared"
    with target_lock():  # the line links into target/c: one test process at a time
        subprocess.run(["bash", "-ec", lines[0]], cwd=ROOT, check=True)
        shutil.copy2(ROOT / "target" / "c" / "shape_move_shared", binary)
    run = subprocess.run([str(binary)], capture_output=True, text=True, env={"PATH": "/usr/bin"})
    assert run.returncode == 0, run.stderr
    assert "ok: the shaped move ends where the commanded one does" in run.stdout


def test_cpp_unknown_robot_error_quotes_the_name(program, tmp_path):
    # The message shows the name as typed, in quotes (not a Rust Option), and the known names.
    path = tmp_path / "ur5e.json"
    tvist.DynamicMap.paper_ur5e().save(path)
    args = ["ur6e", "5", "0", "0", "0.05", str(path), "0.002", "zv"]
    run = subprocess.run([str(program), *args], capture_output=True, text=True)
    assert run.returncode == 1
    assert 'unknown robot "ur6e"; known: ' in run.stderr, run.stderr
    assert "Some(" not in run.stderr


@pytest.mark.parametrize("standard", ["17", "20"])
def test_cpp_wrapper_takes_arrays_vectors_and_spans(hpp_containers, standard):
    # tests/cpp/hpp_containers.cpp: the container forms of step/reset equal the pointer forms
    # to the last bit and refuse wrong lengths as the C API does (its own checks, exit 0).
    run = subprocess.run(
        [str(hpp_containers[standard])],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.strip() == f"ok (C++{standard})"
