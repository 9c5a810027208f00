"""Logs in the wrong unit, or with misplaced columns, are refused with one line naming the
column, the likely unit and the fix; declared units are converted; a fit on broken data is
flagged, never reported confident.

The logs come from :mod:`ident_reference` (an exactly integrated mode, plain-numpy
kinematics, gravity, sensor bias and noise, written in the ur_rtde CSV format), then their
columns are converted to another unit or swapped as a recorder or a hand edit would.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

from ident_reference import generate_log, random_case
from tvist.cli import main
from tvist.ident.local_fit import FitOptions, fit_local
from tvist.ident.local_identification import identify_local
from tvist.ident.logs import read_rtde_csv
from tvist.robots import ur5e
from tvist.units import DEG, STANDARD_GRAVITY, UnitError, parse_units

Q0 = np.array([0.4, -1.6, 1.3, -1.3, 1.57, 0.2])
JOINT_COLUMNS = ("target_q_", "actual_q_", "target_qd_", "target_qdd_")


@pytest.fixture(scope="module")
def radian_log(tmp_path_factory):
    """A base excitation at Q0 (15 Hz, ζ 0.05, 20 dB), in SI units."""
    folder = tmp_path_factory.mktemp("units")
    return generate_log(
        folder / "base.csv", seed=21, joint=0, wn_rad_s=2 * math.pi * 15.0, zeta=0.05, q0=Q0
    ).path


def rewrite(src, dst, edit):
    """``src`` with ``edit(header, table)`` applied to its numbers, written like ur_rtde."""
    lines = src.read_text().splitlines()
    header = lines[0].split(",")
    table = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    edit(header, table)
    with dst.open("w") as fh:
        fh.write(lines[0] + "\n")
        for row in table:
            fh.write(",".join(f"{v:.6f}" for v in row) + "\n")
    return dst


def columns(header, *prefixes):
    return [i for i, name in enumerate(header) if name.startswith(prefixes)]


def in_degrees(header, table):
    table[:, columns(header, *JOINT_COLUMNS)] /= DEG


def in_g(header, table):
    table[:, columns(header, "actual_tool_accelerometer_")] /= STANDARD_GRAVITY


def in_mg(header, table):
    table[:, columns(header, "actual_tool_accelerometer_")] /= STANDARD_GRAVITY / 1000.0


def swap(a, b):
    def edit(header, table):
        i, k = header.index(a), header.index(b)
        table[:, [i, k]] = table[:, [k, i]]

    return edit


def identify(*argv):
    """``tvist identify`` as a user runs it: exit code, stdout, stderr lines."""
    proc = subprocess.run(
        [sys.executable, "-m", "tvist.cli", "identify", "--payload-kg", "0", *map(str, argv)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    return proc.returncode, proc.stdout, proc.stderr.strip().splitlines()


def fit_json(path, *extra):
    code, out, err = identify(path, "--json", *extra)
    assert code == 0, err
    return json.loads(out)


# --------------------------------------------------------------------------- refusals


@pytest.mark.parametrize(
    ("edit", "declare", "names"),
    [
        (in_degrees, "q=deg,qd=deg/s,qdd=deg/s2", ("target_q_0", "look like degrees")),
        pytest.param(
            in_g, "acc=g", ("actual_tool_accelerometer", "looks like g"), marks=pytest.mark.slow
        ),
        pytest.param(
            in_mg, "acc=mg", ("actual_tool_accelerometer", "looks like mg"), marks=pytest.mark.slow
        ),
    ],
    ids=["degrees", "g", "mg"],
)
def test_a_log_in_another_unit_is_refused_then_read_once_declared(
    radian_log, tmp_path, edit, declare, names
):
    """Refused: one line, exit 2, naming the column, the likely unit and the --units that
    declares it. Declared: the same fit as the SI log (to 1e-4 relative: the converted
    columns differ from the SI ones by the 6-decimal rounding only)."""
    log = rewrite(radian_log, tmp_path / "converted.csv", edit)
    code, out, err = identify(log)
    assert code == 2 and out == "" and len(err) == 1, err
    assert err[0].startswith(f"tvist identify: error: {log}: "), err
    for text in (*names, f"--units {declare}"):
        assert text in err[0], err
    assert "Traceback" not in err[0]

    declared, reference = fit_json(log, "--units", declare), fit_json(radian_log)
    assert declared["wn_rad_s"] == pytest.approx(reference["wn_rad_s"], rel=1e-4)
    assert declared["zeta"] == pytest.approx(reference["zeta"], rel=1e-4)
    assert declared["low_confidence"] is False


def test_the_python_reader_converts_declared_units(radian_log, tmp_path):
    log = rewrite(radian_log, tmp_path / "deg_g.csv", lambda h, t: (in_degrees(h, t), in_g(h, t)))
    with pytest.raises(UnitError, match="look like degrees"):
        read_rtde_csv(log)
    back = read_rtde_csv(log, units={"q": "deg", "qd": "deg/s", "qdd": "deg/s2", "acc": "g"})
    si = read_rtde_csv(radian_log)
    # 6 decimals of a degree (1.7e-8 rad) and of a g (1e-5 m/s²) plus the SI file's own
    # rounding (5e-7): the converted columns agree to 2e-5.
    for name in ("target_q", "target_qd", "target_qdd", "actual_q", "tool_accel"):
        np.testing.assert_allclose(getattr(back, name), getattr(si, name), atol=2e-5, rtol=0)


def test_swapped_joint_and_accelerometer_columns_are_refused_naming_both(radian_log, tmp_path):
    log = rewrite(
        radian_log, tmp_path / "swapped.csv", swap("actual_q_5", "actual_tool_accelerometer_2")
    )
    code, _, err = identify(log)
    assert code == 2 and len(err) == 1, err
    assert "actual_q_5 does not follow target_q_5" in err[0], err
    assert "but actual_tool_accelerometer_2 does: the two columns look swapped" in err[0], err


def test_velocities_of_another_joint_are_refused(radian_log, tmp_path):
    log = rewrite(radian_log, tmp_path / "qd.csv", swap("target_qd_0", "target_qd_3"))
    with pytest.raises(UnitError, match=r"target_qd_0 is not the rate of change of target_q_0"):
        read_rtde_csv(log)


def test_velocities_in_deg_s_with_positions_in_rad_are_named(radian_log, tmp_path):
    def qd_in_deg_s(header, table):
        table[:, columns(header, "target_qd_")] /= DEG

    log = rewrite(radian_log, tmp_path / "qd_deg.csv", qd_in_deg_s)
    with pytest.raises(UnitError, match=r"target_qd_0 looks like deg/s.*--units qd=deg/s "):
        read_rtde_csv(log)


def test_a_declared_unit_that_is_wrong_is_refused(radian_log):
    # The log is in m/s²; declared g, its accelerometer would read 96 "m/s²" at rest.
    with pytest.raises(UnitError, match=r"it looks like m/s2, not g"):
        read_rtde_csv(radian_log, units="acc=g")


def test_an_unknown_unit_is_one_line_naming_the_option(radian_log, capsys):
    assert main(["identify", str(radian_log), "--units", "acc=furlong", "--payload-kg", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--units: acc=furlong is not a known unit of acc" in err[0], err
    with pytest.raises(ValueError, match="unknown quantity 'speed'"):
        parse_units("speed=deg/s")


def test_pose_records_in_degrees_are_refused_by_fit_map(tmp_path, capsys):
    """Pose records identified from logs in degrees read as radians: q = (17.2, -91.7, ...),
    inertias and gravity torques of the poses those numbers name in radians, modes of the
    true poses (the paper's map). Enough poses for a map: only the unit stops the fit."""
    import tvist

    rng = np.random.default_rng(4)
    robot = ur5e()
    truth = tvist.DynamicMap.paper_ur5e()
    with (tmp_path / "poses.jsonl").open("w") as fh:
        for i in range(12):
            q = Q0 + rng.uniform(-0.6, 0.6, 6)
            wrong = q / DEG  # degrees, taken for radians
            modes = truth.modes_from_inertia_many(
                robot.joint_inertia_many([q]), robot.gravity_torque_many([q])
            )[0]
            record = {
                "key": f"p{i}",
                "q": wrong.tolist(),
                "payload_kg": 0.0,
                "inertia_kg_m2": robot.joint_inertia(wrong).tolist(),
                "gravity_torque_nm": robot.gravity_torque(wrong).tolist(),
                "modes": [
                    {"joint": j, "wn_rad_s": float(w), "zeta": float(z), "low_confidence": False}
                    for j, (w, z) in enumerate(modes)
                ],
            }
            fh.write(json.dumps(record) + "\n")
    out = tmp_path / "map.json"
    assert main(["fit-map", str(tmp_path / "poses.jsonl"), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "record 1 (p0)" in err[0] and "--units q=deg" in err[0], err
    assert not out.exists()


# --------------------------------------------------------------------------- confidence


def test_a_fit_on_a_misplaced_accelerometer_column_is_flagged(tmp_path):
    """The swapped log read without the unit check: the fit lands near the true mode (22.33
    Hz, ζ 0.039 against 22.30 Hz, ζ 0.045) but its ringing is below the residual noise
    (measured -0.7 dB; 7.6 dB and more on the 40 logs of test_ident_independent), so it must
    not be reported confident."""
    case = random_case(tmp_path, 2)
    log = rewrite(
        case.path, tmp_path / "swapped.csv", swap("actual_q_5", "actual_tool_accelerometer_2")
    )
    fit = identify_local(read_rtde_csv(log, check_units=False), case.joint, ur5e(), base_mode=False)
    assert fit.ringing_snr_db < 3.0
    assert fit.low_confidence, fit
    assert any(r.startswith("weak ringing") for r in fit.reasons), fit.reasons


def test_a_damping_within_two_standard_errors_of_zero_is_flagged():
    """2 s of a 15 Hz mode with ζ = 0.002 under noise twice its size: ζ = 0.0046 ± 0.0026
    (measured), under the 0.005 floor of the damping check. With every other check off, the
    damping alone must flag it: it is not 2 standard errors above zero."""
    from ident_reference import mode_signals

    u, y, dt = mode_signals(1, 2 * math.pi * 15.0, 0.002, snr_db=-6.0, duration_s=2.0)
    lenient = FitOptions(min_fit_percent=0.0, min_confident_snr_db=-math.inf)
    fit = fit_local(u, y, dt, options=lenient)
    assert fit.zeta_se < 0.005 and fit.zeta < 2.0 * fit.zeta_se, fit
    assert fit.reasons == (
        f"uncertain damping: ζ = {fit.zeta:.4f} ± {fit.zeta_se:.4f} is not 2 standard errors "
        "above zero",
    )


@pytest.mark.parametrize("column", ["target_q_3", "target_qd_0"])
def test_a_cell_near_the_float_limit_is_refused_without_numpy_warnings(
    radian_log, tmp_path, column
):
    def edit(header, table):
        table[100, header.index(column)] = 1e300

    log = rewrite(radian_log, tmp_path / "huge.csv", edit)
    text = log.read_text().replace(f"{1e300:.6f}", "1e300")  # a short cell, as a recorder writes
    log.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning would be raised here
        with pytest.raises(UnitError):
            read_rtde_csv(log)


@pytest.mark.slow
def test_identify_many_logs_converts_declared_units(radian_log, tmp_path):
    """Batch identification (worker processes) reads each log with the declared units: the
    pose record of a base and a shoulder log in degrees holds q in rad, equal to Q0."""
    shoulder = generate_log(
        tmp_path / "shoulder.csv", seed=22, joint=1, wn_rad_s=2 * math.pi * 12.0, zeta=0.1, q0=Q0
    ).path
    folder = tmp_path / "deg"
    folder.mkdir()
    for src in (radian_log, shoulder):
        rewrite(src, folder / src.name, in_degrees)
    out = tmp_path / "poses.jsonl"
    declare = ["--units", "q=deg,qd=deg/s,qdd=deg/s2", "--workers", "1", "--payload-kg", "0"]
    assert main(["identify", str(folder), "--out", str(out), *declare]) == 0
    (record,) = [json.loads(line) for line in out.read_text().splitlines()]
    # q is the median of actual_q over the first standstill (at Q0); 6 decimals of a degree
    # are 1.7e-8 rad.
    np.testing.assert_allclose(record["q"], Q0, atol=1e-6)
    assert {m["joint"] for m in record["modes"]} == {0, 1}
