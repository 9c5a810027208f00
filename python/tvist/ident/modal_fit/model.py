"""The model the modal fit adjusts: the default structure (flexible joints, dampers, the
damping's load joint), the law terms and their parameters, and the modes the core map
predicts for given laws (the physics stays in one place, the Rust core)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tvist import ModalMap
from tvist.ident.modal_fit.poses import MODE_JOINTS, ModalPoses

#: Flexible joints of the default fit: base, shoulder, elbow, wrists 1 and 2. The wrists'
#: compliance matters where the base inertia is small (arm pointing up): there a base-shoulder-
#: elbow map puts the base mode up to 6 % high on the UR5e twin, while the wrist stiffnesses
#: are identified from the same campaign to about ±15 %. Wrist 3 (tool axis) hardly moves
#: in the base and shoulder modes.
DEFAULT_FLEX_JOINTS = (0, 1, 2, 3, 4)
#: Joints with a damper in the default fit: those of the identified modes. A campaign gives two
#: damping ratios per pose (base and shoulder mode), which cannot tell a damper at the elbow or
#: a wrist from one at the base or shoulder; left free, such dampers take up the damping
#: model's error and, through the damped eigenproblem (where ω depends on the damping), pull
#: the stiffnesses with them. Measured on the UR5e twin's 208-pose campaign (the twin damps
#: every joint): base frequency error against the true modes 0.17 % RMS, 1.6 % max in sample
#: (0.15 / 0.7 % held out), against 0.52 / 6.5 % (0.31 / 2.8 %) with a damper at every
#: flexible joint, which put wrist 1 at 11 100 N m/rad (twin: 15 000).
DEFAULT_DAMPED_JOINTS = MODE_JOINTS
#: The base carries no gravity torque; its bearing and gear friction grow with the arm's
#: tilting moment, which the shoulder's gravity torque measures (see ``tvist.sim.flex``).
DEFAULT_DAMPING_LOAD = {0: 1}
#: A joint whose gravity torque stays below this over the poses gets no load terms, N m.
MIN_LOAD_SPAN_NM = 1.0


def _entries(
    flex_joints: Sequence[int],
    stiffness: Mapping[int, Sequence[float]],
    damping: Mapping[int, Sequence[float]],
    damping_load: Mapping[int, int],
) -> list[dict[str, Any]]:
    return [
        {
            "joint": j,
            "stiffness_nm_per_rad": [float(v) for v in stiffness[j]],
            "damping_nms_per_rad": [float(v) for v in damping.get(j, (0.0, 0.0, 0.0))],
            "damping_load_joint": int(damping_load.get(j, j)),
        }
        for j in flex_joints
    ]


@dataclass
class _Term:
    joint: int
    name: str  # "k_0", "a_1", "a_2" or "c_0", "c_1", "c_2"


def _stiffness_laws(
    x: np.ndarray, terms: Sequence[_Term], flex_joints: Sequence[int]
) -> dict[int, list[float]]:
    k0 = {j: 0.0 for j in flex_joints}
    a = {j: [0.0, 0.0] for j in flex_joints}
    for value, t in zip(x, terms, strict=True):
        if t.name == "k_0":
            k0[t.joint] = math.exp(value)
        else:
            a[t.joint][int(t.name[-1]) - 1] = value
    return {j: [k0[j], k0[j] * a[j][0], k0[j] * a[j][1]] for j in flex_joints}


def _predict(
    poses: ModalPoses,
    flex_joints: Sequence[int],
    stiffness: Mapping[int, Sequence[float]],
    damping: Mapping[int, Sequence[float]],
    damping_load: Mapping[int, int],
) -> np.ndarray:
    """(n_poses, 2, 2) predicted (wn, zeta) through the core map."""
    m = ModalMap(_entries(flex_joints, stiffness, damping, damping_load), MODE_JOINTS)
    tau = poses.gravity_torque_nm if m.uses_gravity else None
    return m.modes_from_mass_matrix_many(poses.mass_kg_m2, tau)


def _term_names(flex_joints: Sequence[int]) -> list[str]:
    """Names of the terms :func:`select_terms` may leave out, for ``flex_joints``."""
    names = [f"joint {j}" for j in flex_joints if j not in MODE_JOINTS]
    return names + [f"stiffness {a} of joint {j}" for j in flex_joints for a in ("a_1", "a_2")]
