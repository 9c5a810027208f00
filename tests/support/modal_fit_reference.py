"""Campaign records of a known modal map with its *exact* damped modes, for the modal fit's
tests (the library never imports this).

Mass matrix and gravity torques come from pinocchio (:mod:`pinocchio_reference`), the laws are
written out here from their documentation (``v_0 + v_1 |L|_s + v_2 L²``, ``|L|_s =
√(L² + 1) − 1`` with a 1 N m width), and the modes are the complex eigenvalues of the first-order
form of ``M_ff δ'' + C δ' + K δ = 0`` (``scipy.linalg.eig`` of the 2n × 2n state matrix):
``ω_n = |λ|``, ``ζ = −Re λ / |λ|``. Each identified mode is the eigenmode with the largest share
of gear strain energy ``k_j |φ_j|²`` in the joint that names it (base first, then the shoulder
among the others), as a local identification at that joint sees it. No tvist map code is used.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import scipy.linalg

import tvist
from pinocchio_reference import pinocchio_model

#: A UR5e modal map: base, shoulder and elbow gears of the twin's size, the base damper loaded
#: by the shoulder's gravity torque. Over test_modal_fit's poses the base mode has ζ 0.05-0.13,
#: the shoulder's 0.12-0.28 (moderate, very different damping), and at Q3 with 5 kg the two
#: modes lie 9 % apart (21.3 and 19.4 Hz), 1.2 % at the closest pose.
LAWS_UR5E = (
    {
        "joint": 0,
        "stiffness_nm_per_rad": [22000.0, 0.0, 0.0],
        "damping_nms_per_rad": [5.0, 0.56, 0.0],
        "damping_load_joint": 1,
    },
    {
        "joint": 1,
        "stiffness_nm_per_rad": [18000.0, 0.0, 0.234],
        "damping_nms_per_rad": [60.0, 0.6, 0.0],
        "damping_load_joint": 1,
    },
    {
        "joint": 2,
        "stiffness_nm_per_rad": [120000.0, 0.0, 0.0],
        "damping_nms_per_rad": [40.0, 0.0, 0.0],
        "damping_load_joint": 2,
    },
)


def smooth_abs(load_nm: float) -> float:
    """The laws' smoothed ``|L|`` (width 1 N m)."""
    return float(np.hypot(load_nm, 1.0) - 1.0)


def law(v: Sequence[float], load_nm: float) -> float:
    return v[0] + v[1] * smooth_abs(load_nm) + v[2] * load_nm * load_nm


def exact_damped_modes(
    m: np.ndarray,
    k: np.ndarray,
    c: np.ndarray,
    mode_joints: Sequence[int] = (0, 1),
    *,
    blend: bool = False,
) -> list[tuple[float, float]]:
    """``[(ω_n, ζ), ...]`` of the mode dominating each of ``mode_joints`` (indices into the
    flexible joints; each mode other than those of earlier joints), for ``M`` ``(n, n)`` and
    diagonal ``K``, ``C`` ``(n,)``. With ``blend``, each is instead blended with the modes that
    veer with it as the core assigns modes (``modal_map.rs``): weights ``(s_i/s_d)^4 h(g)``
    against 1, ``s`` the strain-energy shares in the joint, ``g = |ln(ω_i/ω_d)|``, ``h`` 1 up
    to 3 % and a smoothstep to 0 at 6 %."""
    n = m.shape[0]
    minv = np.linalg.inv(m)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ np.diag(k), -minv @ np.diag(c)]])
    lam, vec = scipy.linalg.eig(a)
    upper = lam.imag > 0  # one of each conjugate pair (underdamped modes)
    lam, phi = lam[upper], vec[:n, upper]
    share = k[:, None] * np.abs(phi) ** 2
    share /= share.sum(axis=0)
    wn, zeta = np.abs(lam), -lam.real / np.abs(lam)
    out, taken = [], []
    for j in mode_joints:
        s = share[j].copy()
        s[taken] = -np.inf
        i = int(np.argmax(s))
        taken.append(i)
        if blend:
            t = np.clip((0.06 - np.abs(np.log(wn / wn[i]))) / 0.03, 0.0, 1.0)
            w = (share[j] / share[j, i]) ** 4 * t * t * (3.0 - 2.0 * t)
            out.append((float(w @ wn / w.sum()), float(w @ zeta / w.sum())))
            continue
        out.append((float(wn[i]), float(zeta[i])))
    return out


class Arm:
    """pinocchio's mass matrix and gravity torques of a tvist robot with a payload."""

    def __init__(self, robot_name: str, payload_kg: float, payload_com_m: Sequence[float]):
        import pinocchio

        self._pin = pinocchio
        p = tvist.robots.params(robot_name)
        self.model, _ = pinocchio_model(p, tvist.robots.Payload(payload_kg, tuple(payload_com_m)))
        self.data = self.model.createData()

    def mass_and_gravity(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m = self._pin.crba(self.model, self.data, q)
        m = np.triu(m) + np.triu(m, 1).T
        tau = self._pin.computeGeneralizedGravity(self.model, self.data, q)
        return m, np.array(tau)


def exact_records(
    laws: Sequence[Mapping],
    poses: Sequence[tuple[str, np.ndarray, float, Sequence[float]]],
    *,
    noise_wn: float,
    noise_zeta: float,
    seed: int,
    robot_name: str = "ur5e",
    blend: bool = False,
) -> list[dict]:
    """Campaign pose records (``key``, ``q``, payload, ``modes`` with stated standard errors,
    ``true_modes``) at ``poses`` ``(key, q, payload_kg, payload_com_m)``: the exact damped modes
    of the flexible joints ``laws`` (modal map file entries) with relative Gaussian noise
    ``noise_wn`` on ω and ``noise_zeta`` on ζ, stated as each mode's standard error (``blend``:
    see :func:`exact_damped_modes`)."""
    rng = np.random.default_rng(seed)
    arms: dict[tuple, Arm] = {}
    joints = [int(e["joint"]) for e in laws]
    records = []
    for key, q, payload_kg, com in poses:
        arm_key = (payload_kg, tuple(com))
        if arm_key not in arms:
            arms[arm_key] = Arm(robot_name, payload_kg, com)
        m, tau = arms[arm_key].mass_and_gravity(np.asarray(q, dtype=float))
        k = np.array([law(e["stiffness_nm_per_rad"], tau[e["joint"]]) for e in laws])
        c = np.array([law(e["damping_nms_per_rad"], tau[e["damping_load_joint"]]) for e in laws])
        truth = exact_damped_modes(m[np.ix_(joints, joints)], k, c, blend=blend)
        modes = []
        for j, (wn, z) in enumerate(truth):
            modes.append(
                {
                    "joint": j,
                    "wn_rad_s": wn * (1 + noise_wn * rng.standard_normal()),
                    "zeta": z * (1 + noise_zeta * rng.standard_normal()),
                    "wn_se_rad_s": noise_wn * wn,
                    "zeta_se": noise_zeta * z,
                    "low_confidence": False,
                }
            )
        records.append(
            {
                "key": key,
                "q": [float(v) for v in q],
                "payload_kg": payload_kg,
                "payload_com_m": list(com),
                "modes": modes,
                "true_modes": [
                    {"joint": j, "wn_rad_s": wn, "zeta": z} for j, (wn, z) in enumerate(truth)
                ],
                "error": None,
            }
        )
    return records


def write_jsonl(records: Sequence[Mapping], path: Path) -> Path:
    """``records`` as a campaign results file (one JSON object a line)."""
    path.write_text("".join(json.dumps(r, allow_nan=False) + "\n" for r in records))
    return path
