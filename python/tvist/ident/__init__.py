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

import importlib
from typing import TYPE_CHECKING

#: Public name -> the module that defines it. Each module loads on first access, so
#: ``import tvist.cli.ident`` (every ``tvist`` command) does not pay for scipy.stats etc.
_EXPORTS: dict[str, str] = {
    "BangCoastBangMove": "tvist.ident.excitation",
    "CampaignPose": "tvist.ident.campaign",
    "Excitation": "tvist.ident.excitation",
    "FitOptions": "tvist.ident.local_fit",
    "LocalFit": "tvist.ident.local_fit",
    "LogWarning": "tvist.ident.logs",
    "ModeSpec": "tvist.ident.map_fit",
    "PoseRecord": "tvist.ident.pose",
    "Record": "tvist.ident.logs",
    "TangentialAcceleration": "tvist.ident.preprocess",
    "TwinRobot": "tvist.ident.campaign",
    "TwoModeFit": "tvist.ident.mode_estimates",
    "URRobot": "tvist.ident.campaign",
    "campaign_poses": "tvist.ident.campaign",
    "evaluate_map": "tvist.ident.robustness",
    "find_gaps": "tvist.ident.logs",
    "fit_local": "tvist.ident.local_fit",
    "fit_map": "tvist.ident.map_fit",
    "fit_two_modes": "tvist.ident.two_mode",
    "identify_local": "tvist.ident.local_identification",
    "identify_pose": "tvist.ident.pose",
    "load_results": "tvist.ident.campaign",
    "prv_band": "tvist.ident.robustness",
    "random_excitation": "tvist.ident.excitation",
    "read_rtde_csv": "tvist.ident.logs",
    "run_campaign": "tvist.ident.campaign",
    "summarize": "tvist.ident.robustness",
    "tangential_acceleration": "tvist.ident.preprocess",
    "to_urscript": "tvist.ident.excitation",
    "two_mode_shaper": "tvist.ident.robustness",
}

if TYPE_CHECKING:
    from tvist.ident.campaign import (
        CampaignPose,
        TwinRobot,
        URRobot,
        campaign_poses,
        load_results,
        run_campaign,
    )
    from tvist.ident.excitation import BangCoastBangMove, Excitation, random_excitation, to_urscript
    from tvist.ident.local_fit import FitOptions, LocalFit, fit_local
    from tvist.ident.local_identification import identify_local
    from tvist.ident.logs import LogWarning, Record, find_gaps, read_rtde_csv
    from tvist.ident.map_fit import ModeSpec, fit_map
    from tvist.ident.mode_estimates import TwoModeFit
    from tvist.ident.pose import PoseRecord, identify_pose
    from tvist.ident.preprocess import TangentialAcceleration, tangential_acceleration
    from tvist.ident.robustness import evaluate_map, prv_band, summarize, two_mode_shaper
    from tvist.ident.two_mode import fit_two_modes


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'tvist.ident' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))


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
