"""Modal map files written by ``tvist fit-map --kind modal`` that several test modules check,
each a fit of minutes, made once per test run (the session fixtures ``soft_elbow_fit`` and
``ur10e_twin_fit`` in tests/conftest.py).

Under pytest-xdist each worker has its own session: :func:`shared_folder` is then the run's
folder common to the workers, and :func:`shared_files` makes the files there under an
exclusive lock (``fcntl``, as :func:`cpp_programs.target_lock`), so the first worker that
needs them makes them and the others wait and read them."""

from __future__ import annotations

import contextlib
import fcntl
import io
import json
import os
import shutil
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tvist
from tvist.experiments.identified import DEMO_PLAN
from tvist.ident.campaign import campaign_poses
from tvist.sim import Twin

#: Campaign records kept in the repository (``tests/data``): pose records as ``tvist identify``
#: wrote them from MuJoCo logs in ur_rtde CSV form. ``DEMO_CAMPAIGN`` is ``make demo``'s
#: ``out/demo/campaign.jsonl`` (36 poses of the default twin); ``FAMILY_9_CAMPAIGN`` the
#: generalization harness's ``ur5e-9/poses.jsonl`` (``family:ur5e:9``, 30 poses).
DATA = Path(__file__).resolve().parents[1] / "data"
DEMO_CAMPAIGN = DATA / "demo_campaign.jsonl"
FAMILY_9_CAMPAIGN = DATA / "family_ur5e_9_campaign.jsonl"
#: The variant those records come from.
FAMILY_9_SEED = 9

#: A development variant of the UR5e family with a soft elbow (0.10 x its nominal gear: an
#: elbow-dominated mode of 20-30 Hz at folded poses) and soft wrists' neighbours, rigid links.
SOFT_ELBOW_SEED = 14


def demo_plan_poses() -> list[tuple]:
    """The demo's reduced campaign plan (36 poses, no payload and 5 kg)."""
    return [
        (p.key, p.q, p.payload_kg, p.payload_com_m) for p in DEMO_PLAN.poses() if p.q is not None
    ]


def twin_records(robot_name: str, payloads, every: int, seed: int, noise: float = 0.004):
    """Campaign-format records whose modes come from the full twin's eigen-analysis (six
    flexible joints, nonlinear gears linearized at the gravity deflection, gravity stiffness,
    exact damped modes): a more complete model than the modal map's, with noise of the size
    of the local identification's errors (0.4 % on ω, 3 % on ζ)."""
    rng = np.random.default_rng(seed)
    records = []
    for payload in payloads:
        twin = Twin(robot_name, payload_kg=payload)
        poses = campaign_poses(robot_name, payloads_kg=(payload,), seed=seed)[::every]
        for p in poses:
            if p.q is None:
                continue
            truth = twin.modes(p.q)
            modes = [
                {
                    "joint": j,
                    "wn_rad_s": wn * (1 + noise * rng.standard_normal()),
                    "zeta": z * (1 + 0.03 * rng.standard_normal()),
                }
                for j, (wn, z) in enumerate(truth)
            ]
            records.append(
                {
                    "key": p.key,
                    "payload_kg": payload,
                    "payload_com_m": list(p.payload_com_m),
                    "q": p.q.tolist(),
                    "inertia_kg_m2": [0.0] * 6,
                    "modes": modes,
                    "true_modes": [
                        {"joint": j, "wn_rad_s": wn, "zeta": z} for j, (wn, z) in enumerate(truth)
                    ],
                }
            )
    for r in records:  # the published form reads the model's inertias
        payload = tvist.robots.Payload(r["payload_kg"], tuple(r["payload_com_m"]))
        model = tvist.robots.Robot(tvist.robots.params(robot_name), payload)
        r["inertia_kg_m2"] = model.joint_inertia(np.array(r["q"])).tolist()
        r["gravity_torque_nm"] = model.gravity_torque(np.array(r["q"])).tolist()
    return records


def shared_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """This run's folder for shared files: the workers' common one under pytest-xdist, the
    session's own otherwise (never one a later run would find)."""
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "shared_fits"
    folder.mkdir(exist_ok=True)
    return folder


def shared_files(
    tmp_path_factory: pytest.TempPathFactory,
    name: str,
    make: Callable[[Path], None],
) -> Path:
    """The folder ``name`` in :func:`shared_folder`, filled by ``make(folder)`` once per run:
    the first caller makes it under the lock (and marks it complete), later ones (other
    workers: after waiting for the lock) find it."""
    root = shared_folder(tmp_path_factory)
    folder = root / name
    complete = folder / ".complete"
    with (root / f"{name}.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            if not complete.exists():
                shutil.rmtree(folder, ignore_errors=True)  # left by a make that failed
                folder.mkdir()
                make(folder)
                complete.touch()
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    return folder


def write_fit(folder: Path, records: Sequence[dict[str, Any]], args: Sequence[str] = ()) -> None:
    """``records`` as ``folder/records.jsonl``, ``tvist fit-map RECORDS --kind modal ARGS`` of
    them as ``folder/map.json``, and its exit code and printout as ``folder/fit_map.json``."""
    from tvist.cli import main

    path = folder / "records.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in records))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(
            ["fit-map", str(path), "--kind", "modal", *args, "--out", str(folder / "map.json")]
        )
    (folder / "fit_map.json").write_text(json.dumps({"code": code, "printed": out.getvalue()}))
