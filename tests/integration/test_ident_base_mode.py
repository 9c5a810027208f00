"""The base mode by default: ``identify_local`` on base logs of the flexible twin.

At many poses the base excitation rings the shoulder mode too (strongly at V = π/2, where the
arm stands over the base axis). The default result must be the twin's base mode (within 3 %)
or flagged low-confidence - never the shoulder mode reported as the base mode.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor

import pytest

from tvist.ident.campaign import campaign_poses
from tvist.ident.excitation import random_excitation
from tvist.ident.local_identification import identify_local
from tvist.robots import params

#: The UR5e's control period, s (its robot data).
UR5E_DT_S = params("ur5e").control_period_s

#: Every 5th pose of the 0 kg and 5 kg campaigns: 21 poses over all angles and radii (fixed
#: before looking at the results).
POSES = campaign_poses(payloads_kg=(0.0, 5.0))[::5]


def _identify(pose):
    from tvist.ident.campaign_robots import TwinRobot
    from tvist.robots import ur5e

    twin = TwinRobot(seed=0)
    twin.set_payload(pose.payload_kg, pose.payload_com_m)
    log = twin.record_excitation(
        random_excitation(pose.q, 0, seed=pose.seed, duration_s=4.0, dt_s=UR5E_DT_S)
    )
    fit = identify_local(log, 0, ur5e(pose.payload_kg, pose.payload_com_m))
    return pose.key, fit, twin.true_modes(pose.q)


def _single_mode(fit):
    """The paper's single-mode value of the same log and whether it was flagged: kept in
    ``apparent`` when replaced, or the fit itself (less the separation's own reason)."""
    if fit.apparent is not None:
        return fit.apparent["wn_rad_s"], bool(fit.apparent["low_confidence"])
    own = [r for r in fit.reasons if "shoulder" not in r]
    return fit.wn_rad_s, bool(own)


@pytest.fixture(scope="module")
def base_fits():
    assert len(POSES) >= 20 and all(p.q is not None for p in POSES)
    with ProcessPoolExecutor(max_workers=2) as pool:
        return list(pool.map(_identify, POSES))


@pytest.mark.slow
def test_base_mode_is_right_or_flagged_never_silently_wrong(base_fits):
    confident = 0
    for key, fit, truth in base_fits:
        error = abs(fit.wn_rad_s / truth[0][0] - 1)
        if not fit.low_confidence:
            confident += 1
            assert error < 0.03, (key, fit.fn_hz, truth)
        elif "-V2-" not in key:  # flagged elsewhere only for a stated reason
            assert fit.reasons, key
    # Not vacuous: most poses give the base mode (measured: 16 of 21, worst 1.4 %; the 5
    # flagged ones all at V = π/2, where the base log alone cannot tell the modes apart).
    assert confident >= 14, confident


@pytest.mark.slow
def test_the_paper_single_mode_fit_is_what_goes_wrong(base_fits):
    """Control: the single-mode fit of the same logs returns the shoulder mode (or a blend)
    at some poses without a flag - what the default avoids (measured: 7 of 21)."""
    silently_wrong = []
    for key, fit, truth in base_fits:
        wn, flagged = _single_mode(fit)
        if not flagged and abs(wn / truth[0][0] - 1) > 0.03:
            silently_wrong.append(key)
    assert len(silently_wrong) >= 3, silently_wrong
