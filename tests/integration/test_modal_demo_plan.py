"""The demo's reduced campaign plan and the modal fit it feeds: what two payloads determine that
one does not, and a mistaken identification that must not blur the fit's standard errors.

The modes are the full twin's eigen-analysis at the plan's poses (six flexible joints, gears
linearized at the gravity deflection, gravity stiffness, exact damped modes: a more complete
model than the modal map's), with noise of the size of the local identification's errors."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from tvist.experiments.identified import DEMO_PLAN, CampaignPlan
from tvist.experiments.motions import PAYLOAD_COM_M, PAYLOAD_KG
from tvist.ident.modal_fit import DEFAULT_FLEX_JOINTS, fit_modal_map
from tvist.sim import Twin, default_flex

#: Identification-size noise: 0.5 % on ω, 5 % on ζ (the demo campaign's local fits are within
#: 0.5 % of the true frequency at most poses, a few per cent on ζ).
NOISE_WN, NOISE_ZETA = 0.005, 0.05


@functools.cache
def _twin(payload_kg: float) -> Twin:
    return Twin("ur5e", payload_kg=payload_kg, payload_com_m=PAYLOAD_COM_M)


def _plan_records(plan: CampaignPlan, seed: int = 4) -> list[dict]:
    """Campaign-format records at ``plan``'s poses with the twin's true modes plus noise."""
    rng = np.random.default_rng(seed)
    poses = plan.poses()
    records = []
    for p in poses:
        if p.q is None:
            continue
        truth = _twin(p.payload_kg).modes(p.q)
        modes = [
            {
                "joint": j,
                "wn_rad_s": wn * (1 + NOISE_WN * rng.standard_normal()),
                "zeta": z * (1 + NOISE_ZETA * rng.standard_normal()),
            }
            for j, (wn, z) in enumerate(truth)
            # With the arm pointing up the base mode is a torsion of the wrists that the
            # campaign's base excitation does not identify (flagged low-confidence, unused).
            if not (j == 0 and math.isclose(p.angle_rad, math.pi / 2))
        ]
        records.append(
            {
                "key": p.key,
                "payload_kg": p.payload_kg,
                "payload_com_m": list(p.payload_com_m),
                "q": p.q.tolist(),
                "modes": modes,
            }
        )
    return records


def _joints(modal) -> list[int]:
    return [e["joint"] for e in modal.flex_joints]


def _stiffness(modal, joint: int) -> dict:
    stats = modal.metadata["fit_statistics"]["stiffness_nm_per_rad"]
    return next(t for t in stats if t["joint"] == joint and t["term"] == "at_zero")


def test_the_demo_plan_recovers_the_twins_gear_stiffnesses():
    twin_k = default_flex("ur5e").k1_nm_per_rad
    modal = fit_modal_map(_plan_records(DEMO_PLAN), "ur5e", flex_joints=DEFAULT_FLEX_JOINTS)
    # Base, shoulder, elbow and wrist 2 are kept; wrist 1 is not determined by these modes
    # with 0.5 % noise and is made rigid. (While the core blended every mode by share⁴, the
    # data's dominant modes did not fit it at poses where two far-apart modes share a joint,
    # and wrist 2 was made rigid too.)
    assert _joints(modal) == [0, 1, 2, 4]
    # Base and shoulder within 3 % of the twin's gears (measured: 0.8 % and 0.3 %; the fit
    # absorbs wrist 1's flexibility and the gravity stiffness in these two), the elbow, ten
    # times stiffer and seen only through its share of the modes, and wrist 2 within 30 %
    # (measured: 10 % low and 0.1 %, standard errors 4 % and 13 %).
    for joint, tolerance in ((0, 0.03), (1, 0.03), (2, 0.30), (4, 0.30)):
        k = _stiffness(modal, joint)
        assert k["value"] == pytest.approx(twin_k[joint], rel=tolerance), (joint, k)
        assert 0 < k["se"] < 0.25 * k["value"], (joint, k)


def test_one_payload_cannot_determine_the_elbow():
    # The same plan at the experiment's payload only: load and inertia of the shoulder grow
    # together with the reach, and the elbow's stiffness is not determined (made rigid).
    one_payload = CampaignPlan(payloads_kg=(PAYLOAD_KG,), angles_rad=DEMO_PLAN.angles_rad)
    modal = fit_modal_map(_plan_records(one_payload), "ur5e", flex_joints=DEFAULT_FLEX_JOINTS)
    assert 2 not in _joints(modal)
    assert "joint 2 made rigid" in modal.metadata["fit_statistics"]["dropped"]


def test_a_mistaken_identification_does_not_inflate_the_stiffness_standard_errors():
    records = _plan_records(DEMO_PLAN)
    # Base, shoulder and elbow flexible: the joints both fits keep (wrist 2, kept with a 13 %
    # standard error from the clean data, is made rigid with the outlier among them).
    flex = (0, 1, 2)
    clean = fit_modal_map(records, "ur5e", flex_joints=flex)
    # One pose whose local fit took another mode for the shoulder's, 20 % off (as the demo
    # campaign's folded 5 kg pose at V = 3π/4 does).
    wrong = [dict(r, modes=[dict(m) for m in r["modes"]]) for r in records]
    wrong[5]["modes"][1]["wn_rad_s"] *= 0.8
    fitted = fit_modal_map(wrong, "ur5e", flex_joints=flex)
    assert _joints(fitted) == _joints(clean) == list(flex)
    for joint in (0, 1, 2):
        a, b = _stiffness(clean, joint), _stiffness(fitted, joint)
        # The robust loss keeps the estimate (within 2 standard errors) and the standard error
        # leaves the outlier out: within a factor 1.5 of the clean fit's. Without that, the
        # 20 % residual among 0.5 % ones inflates every standard error about threefold.
        assert b["value"] == pytest.approx(a["value"], abs=2 * a["se"]), joint
        assert b["se"] < 1.5 * a["se"], (joint, a, b)
