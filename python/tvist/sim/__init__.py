"""MuJoCo twin of a flexible UR e-Series arm: RTDE-like logs and ground-truth modes.

Examples
--------
>>> import numpy as np
>>> from tvist.sim import Twin
>>> twin = Twin("ur5e", payload_kg=5.0, payload_com_m=(0.0, 0.0, 0.05))
>>> q1 = np.array([0.0, -np.pi, 0.0, -np.pi / 2, 0.0, 0.0])
>>> (wn_base, zeta_base), (wn_shoulder, zeta_shoulder) = twin.modes(q1)
>>> record = twin.run(np.tile(q1, (500, 1)))  # 1 s at rest, 500 Hz
>>> record.to_csv("rest.csv")  # doctest: +SKIP
"""

from __future__ import annotations

from tvist.sim.beams import LinkBeams
from tvist.sim.flex import UR5E_FLEX, FlexParams, default_flex
from tvist.sim.mjcf import GRAVITY_M_S2, build_mjcf
from tvist.sim.modal import ModalAnalysis, modal_analysis
from tvist.sim.record import RTDE_FIELDS, SimRecord, csv_header
from tvist.sim.twin import PAYLOAD_LIMIT_FACTOR, SimulationDiverged, Twin

__all__ = [
    "GRAVITY_M_S2",
    "PAYLOAD_LIMIT_FACTOR",
    "RTDE_FIELDS",
    "UR5E_FLEX",
    "FlexParams",
    "LinkBeams",
    "ModalAnalysis",
    "SimRecord",
    "SimulationDiverged",
    "Twin",
    "build_mjcf",
    "csv_header",
    "default_flex",
    "modal_analysis",
]
