"""Identification of the arm's vibration modes (paper sections 4.4 and 5.2-5.4).

Offline flow: RTDE log (real robot or twin) → :func:`tangential_acceleration` (eqs. 12-13)
→ :func:`identify_local` (eq. 17) → per-pose modes from a campaign (:func:`run_campaign`,
Algorithm 1, with :func:`random_excitation`, Algorithm 2) → :func:`fit_map` → map file →
shaper; :func:`evaluate_map` judges the map against the shaper's 10 % PRV band.

Modules: ``logs``, ``excitation``, ``preprocess``, ``zoh``, ``local_fit``, ``two_mode``,
``base_mode``, ``pose`` (:func:`identify_pose`), ``batch`` (many logs → pose records),
``map_fit``, campaign (``pose_plan``, ``campaign_robots``, ``campaign`` runner,
``results_store``), ``robustness``, ``plots`` (matplotlib, imported lazily) and ``cli``.
"""

from __future__ import annotations

from tvist.ident.campaign import (
    CampaignPose,
    TwinRobot,
    URRobot,
    campaign_poses,
    load_results,
    run_campaign,
)
from tvist.ident.excitation import BangCoastBangMove, Excitation, random_excitation, to_urscript
from tvist.ident.local_fit import FitOptions, LocalFit, fit_local, identify_local
from tvist.ident.logs import LogWarning, Record, find_gaps, read_rtde_csv
from tvist.ident.map_fit import ModeSpec, fit_map
from tvist.ident.pose import PoseRecord, identify_pose
from tvist.ident.preprocess import TangentialAcceleration, tangential_acceleration
from tvist.ident.robustness import evaluate_map, prv_band, summarize, two_mode_shaper
from tvist.ident.two_mode import TwoModeFit, fit_two_modes

__all__ = [
    "BangCoastBangMove",
    "CampaignPose",
    "Excitation",
    "FitOptions",
    "LocalFit",
    "LogWarning",
    "ModeSpec",
    "PoseRecord",
    "Record",
    "TangentialAcceleration",
    "TwinRobot",
    "TwoModeFit",
    "URRobot",
    "campaign_poses",
    "evaluate_map",
    "find_gaps",
    "fit_local",
    "fit_map",
    "fit_two_modes",
    "identify_local",
    "identify_pose",
    "load_results",
    "prv_band",
    "random_excitation",
    "read_rtde_csv",
    "run_campaign",
    "summarize",
    "tangential_acceleration",
    "to_urscript",
    "two_mode_shaper",
]
