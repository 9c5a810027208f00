"""Independent numpy transcription of the dynamic map's equations (paper eqs. 42-51), for tests.

Typed in from the documented equations (tvist-core ``dynmap`` module docs), never from the
core's code, and evaluated without tvist so that test data made with it do not share the
implementation under test. With ``J_f``/``J_d`` the inertias of the frequency/damping joint,
``τ_f`` the frequency joint's gravity torque and ``K = k_0 + k_J J_f + k_g |τ_f|_s``::

    ω_n = √(1 + k_p/J_f) · √(K / J_f)
    ζ   = (1 + k_p/J_d)^e_d (1 + k_p/J_f)^e_f (c_0 + c_1 √J_d + c_2 J_d)(1 + c_τ J_d) / (2 √(K J_f))

``law="gain_outside_root"`` is a deliberately different law for controls: the proportional
gain factor ``(1 + k_p/J_f)`` multiplies ``√(K/J_f)`` without the square root; ``ζ`` is
unchanged.

The library never imports this module.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from map_smoothing_reference import GRAVITY_TORQUE_SMOOTHING_NM

#: Table 1 / Table 2 of the paper (UR5e), typed in from the paper.
PAPER_BASE: dict[str, Any] = {
    "k_0": 10000.0,
    "k_j": 1060.0,
    "k_g": 0.0,
    "k_p": 2.54,
    "c_0": 1.53,
    "c_1": 0.0,
    "c_2": 0.39,
    "c_tau": 3.81,
    # eqs. 47-48: frequency from J_1, damping from J_0, (1 + k_p/J_0) without a root.
    "frequency_joint": 1,
    "damping_joint": 0,
    "damping_gain_exponent": 1.0,
    "frequency_gain_exponent": -0.5,
}
PAPER_SHOULDER: dict[str, Any] = {
    "k_0": 10000.0,
    "k_j": 763.0,
    "k_g": 0.0,
    "k_p": 1.73,
    "c_0": 0.27,
    "c_1": 0.0,
    "c_2": 0.038,
    "c_tau": 47.2,
    # eqs. 50-51: the general map of joint 1.
    "frequency_joint": 1,
    "damping_joint": 1,
    "damping_gain_exponent": 0.5,
    "frequency_gain_exponent": 0.0,
}
PAPER_MODES = (PAPER_BASE, PAPER_SHOULDER)

LAWS = ("paper", "gain_outside_root")


def mode_reference(
    mode: Mapping[str, Any],
    inertia_kg_m2: np.ndarray | Sequence[Sequence[float]],
    gravity_torque_nm: np.ndarray | Sequence[Sequence[float]] | None = None,
    law: str = "paper",
) -> tuple[np.ndarray, np.ndarray]:
    """``(ω_n rad/s, ζ)`` of one unbounded mode at each pose, arrays ``(n_poses,)``.

    ``inertia_kg_m2`` and ``gravity_torque_nm`` are ``(n_poses, n_dof)``; the gravity torque
    may be omitted when ``k_g`` is 0.
    """
    if law not in LAWS:
        raise ValueError(f"law must be one of {LAWS}, got {law!r}")
    j = np.atleast_2d(np.asarray(inertia_kg_m2, dtype=float))
    j_f = j[:, int(mode["frequency_joint"])]
    j_d = j[:, int(mode["damping_joint"])]
    k_g = float(mode.get("k_g", 0.0))
    stiffness = float(mode["k_0"]) + float(mode["k_j"]) * j_f
    if k_g != 0.0:
        if gravity_torque_nm is None:
            raise ValueError("a mode with k_g != 0 needs gravity torques")
        tau = np.atleast_2d(np.asarray(gravity_torque_nm, dtype=float))[
            :, int(mode["frequency_joint"])
        ]
        s = GRAVITY_TORQUE_SMOOTHING_NM
        stiffness = stiffness + k_g * (np.sqrt(tau * tau + s * s) - s)
    k_p = float(mode["k_p"])
    gain_f = 1.0 + k_p / j_f
    gain_d = 1.0 + k_p / j_d
    # "paper": the gain enters ω_n² linearly; the control law puts it into ω_n itself.
    wn = (np.sqrt(gain_f) if law == "paper" else gain_f) * np.sqrt(stiffness / j_f)
    damping = (
        float(mode["c_0"]) + float(mode.get("c_1", 0.0)) * np.sqrt(j_d) + float(mode["c_2"]) * j_d
    ) * (1.0 + float(mode["c_tau"]) * j_d)
    zeta = (
        gain_d ** float(mode["damping_gain_exponent"])
        * gain_f ** float(mode["frequency_gain_exponent"])
        * damping
        / (2.0 * np.sqrt(stiffness * j_f))
    )
    return wn, zeta


def modes_reference(
    modes: Sequence[Mapping[str, Any]],
    inertia_kg_m2: np.ndarray | Sequence[Sequence[float]],
    gravity_torque_nm: np.ndarray | Sequence[Sequence[float]] | None = None,
    law: str = "paper",
) -> np.ndarray:
    """All modes at every pose: array ``(n_poses, n_modes, 2)`` of ``(ω_n, ζ)``."""
    out = [mode_reference(m, inertia_kg_m2, gravity_torque_nm, law) for m in modes]
    return np.stack([np.column_stack(pair) for pair in out], axis=1)
