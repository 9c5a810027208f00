"""The flexible payload on the twin and the zero-delay paper's experiment with it."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from tvist import cartesian, robots
from tvist.cli import main
from tvist.experiments.flexible_payload import DT_S, START_POSE
from tvist.sim.payload import FlexiblePayload, PayloadTwin

ROW_KEYS = (
    "delay_s",
    "residual_vibration_m_s2",
    "reduction_percent",
    "velocity_peaks",
    "peak_jerk",
)


def test_payload_hangs_at_its_static_sag_and_reads_no_acceleration_at_rest():
    payload = FlexiblePayload()
    twin = PayloadTwin("ur5e", payload)
    q0 = np.array(START_POSE)
    record = twin.run(np.tile(q0, (100, 1)), DT_S)
    # Started in equilibrium: nothing moves, and the gravity-free tip acceleration is zero
    # (1e-9 m/s² is round-off of the rotated accelerometer reading minus g).
    assert np.max(np.abs(record.tip_acceleration_m_s2)) < 1e-9
    # The mount sags by g / ω² along gravity, seen in the flange axes (flange z points about
    # down here; the arm's own gravity deflection tilts it by ~2e-3 rad).
    rot = twin.data.site_xmat[twin.model.site("flange").id].reshape(3, 3)
    sag = rot.T @ np.array([0.0, 0.0, -9.81]) / payload.wn_rad_s**2
    assert sag[2] == pytest.approx(9.81 / payload.wn_rad_s**2, rel=1e-5)
    # Equilibrium solved to 1e-13 in the accelerations: the sag to ~1e-12 m.
    assert record.mount_deflection_m[-1] == pytest.approx(sag, abs=1e-10)


@pytest.mark.parametrize(("freq_hz", "zeta"), [(2.55, 0.04), (4.0, 0.1)])
def test_tip_moves_like_the_base_excited_mode_it_is_tuned_to(freq_hz, zeta):
    # Independent model: the tip as a linear base-excited oscillator
    # x'' = ω²(u − x) + 2ζω(u' − x') driven by the simulated flange position u along X,
    # integrated by scipy's lsim. It leaves out the flange's small rotation from the arm's
    # gear flex (felt at the 0.15 m offset) and interpolates the 2 ms flange samples
    # linearly; both are below 2 % of the peak acceleration.
    payload = FlexiblePayload(freq_hz=freq_hz, zeta=zeta)
    assert payload.stiffness_n_per_m == pytest.approx(
        payload.mass_kg * (2 * math.pi * freq_hz) ** 2
    )
    assert payload.damping_ns_per_m == pytest.approx(
        2 * zeta * payload.mass_kg * 2 * math.pi * freq_hz
    )
    robot = robots.ur5e(payload_kg=0.0)
    q0 = np.array(START_POSE)
    traj, r0 = cartesian.straight_line(
        robot, q0, (0.3, 0.0, 0.0), 0.734, DT_S, t_pre_s=0.1, t_post_s=1.0
    )
    record = PayloadTwin("ur5e", payload).run(
        cartesian.joints_from_tcp(robot, traj.q, r0, q0), DT_S
    )
    t, u = record.t_s, record.flange_position_m[:, 0] - record.flange_position_m[0, 0]
    w = payload.wn_rad_s
    _, x, _ = signal.lsim(([2 * zeta * w, w * w], [1.0, 2 * zeta * w, w * w]), u, t)
    model = w * w * (u - x) + 2 * zeta * w * (np.gradient(u, t) - np.gradient(x, t))
    measured = record.tip_acceleration_m_s2[:, 0]
    assert np.max(np.abs(measured - model)) < 0.02 * np.max(np.abs(measured))


def test_invalid_payload_is_refused():
    with pytest.raises(ValueError, match="freq_hz"):
        FlexiblePayload(freq_hz=0.0)
    with pytest.raises(ValueError, match="zeta"):
        FlexiblePayload(zeta=1.2)


@pytest.fixture(scope="module")
def experiment(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("payload")
    assert main(["demo", "--experiment", "flexible-payload", "--out", str(out)]) == 0
    return out, json.loads((out / "results.json").read_text())


@pytest.mark.slow
def test_experiment_writes_the_four_rows_and_the_figures(experiment):
    out, results = experiment
    assert list(results["methods"]) == ["unshaped", "conventional", "ztdis", "modified"]
    for key, row in results["methods"].items():
        for name in ROW_KEYS:
            assert isinstance(row[name], (int, float)) and math.isfinite(row[name]), (key, name)
    for name in ("tip_acceleration.png", "velocity_references.png", "path_deviation.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    assert "Against the paper" in (out / "report.md").read_text()


@pytest.mark.slow
def test_experiment_reproduces_the_papers_qualitative_result(experiment):
    _, results = experiment
    rows = results["methods"]
    wn, zeta = 2 * math.pi * 2.55, 0.04
    # Conventional ZVD ends one damped period late: Δ_n = 2π / (ω_n √(1 − ζ²)) = 0.3925 s
    # (the spec's verified example); the stop is found on the 2 ms grid.
    zvd_delay = 2 * math.pi / (wn * math.sqrt(1 - zeta**2))
    assert abs(rows["conventional"]["delay_s"] - zvd_delay) <= DT_S
    # ZTDIS and modified ZTDIS end with the planned move (one sample for the nanometre
    # truncation residue of the compressed move's approach).
    for key in ("ztdis", "modified"):
        assert abs(rows[key]["delay_s"]) <= DT_S + 1e-12, key
    # All three suppress the residual vibration (the paper: "effectively suppressed").
    for key in ("conventional", "ztdis", "modified"):
        assert rows[key]["reduction_percent"] >= 90.0, key
    # Fig. 13: one TCP-speed hump for the modified method, several for ZTDIS.
    assert rows["unshaped"]["velocity_peaks"] == 1
    assert rows["modified"]["velocity_peaks"] == 1
    assert rows["ztdis"]["velocity_peaks"] >= 2
    # The unshaped move rings at the tuned mode, shifted only slightly by the arm it sits on.
    fit = rows["unshaped"]["residual_fit"]
    assert fit["damped_freq_hz"] == pytest.approx(2.55 * math.sqrt(1 - zeta**2), rel=0.02)
    # Cartesian shaping keeps the straight line (IK tolerance); joint-space shaping does not.
    deviation = results["path_deviation_m"]
    assert deviation["cartesian_zvd_max"] < 1e-8
    assert deviation["joint_space_zvd_max"] > 1e-5


@pytest.mark.slow
def test_figures_leave_the_global_matplotlib_backend_alone(tmp_path):
    # Plotting must not select a backend or import pyplot (that breaks inline plots in
    # Jupyter): run the figure code in a fresh interpreter and inspect it afterwards.
    import subprocess
    import sys

    code = (
        "import sys, numpy as np, matplotlib\n"
        "matplotlib.use('svg')\n"
        "from tvist import DynamicMap\n"
        "from tvist.experiments import plots\n"
        "from tvist.ident.plots import plot_prv_sensitivity\n"
        "t = np.linspace(0, 1, 50)\n"
        f"plots.plot_velocity_references(t, {{'a': np.sin(t)}}, 0.5, r'{tmp_path}/v.png',\n"
        "    title='t', ylabel='v [m/s]')\n"
        f"plot_prv_sensitivity(DynamicMap.paper_ur5e(), r'{tmp_path}/prv.png',\n"
        "    j1_values_kg_m2=(3.2,))\n"
        "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend()\n"
        "assert 'matplotlib.pyplot' not in sys.modules\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
    assert (tmp_path / "v.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_names_the_flag_of_a_bad_payload(capsys):
    assert main(["demo", "--experiment", "flexible-payload", "--payload-hz", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("tvist demo: error: --payload-hz") and err.count("\n") == 1
    assert main(["demo", "--experiment", "flexible-payload", "--payload-zeta", "1.5"]) == 2
    assert "--payload-zeta" in capsys.readouterr().err
