"""Every eigenmode of a modal map's model at many poses, with its shape at the flange.

The Rust core (:class:`tvist.ModalMap`) evaluates only the modes a map shapes; the fit needs
all of them, each with what an identification can compare it with: its natural frequency and
damping ratio, where its strain energy sits (joint shares) and the direction the flange moves
in it. The model is the core's (``tvist-core/src/modes/modal/modal_map.rs``): the
deflections ``δ`` of the flexible joints obey ``M_ff δ'' + C δ' + K δ = 0`` with
``K = diag(k_j(L))``, ``C = diag(c_j(L))`` and the load laws ``v_0 + v_1 |L|_s + v_2 L²``;
the modes are the exact damped roots (``ω_n = |λ|``, ``ζ = −Re λ/|λ|``).
``tests/integration/test_all_modes_fit.py`` checks this against the core's shaped modes.

Arrays are over poses first, modes in increasing ``ω_n`` (the frequency rank: continuous in
the parameters and along a motion, also where two modes veer).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["ModelModes", "joint_laws", "model_modes", "undamped_frequencies"]

#: Width ``τ_s`` of the smoothed ``|L|_s = √(L² + τ_s²) − τ_s`` (N m): the core's
#: ``GRAVITY_TORQUE_SMOOTHING_NM``.
SMOOTHING_NM = 1.0


@dataclass(frozen=True)
class ModelModes:
    """The model's modes at ``n`` poses (``m`` = number of flexible joints).

    Attributes
    ----------
    wn_rad_s, zeta
        ``(n, m)``, increasing ``wn_rad_s`` per pose.
    joint_shares
        ``(n, m, m)``: share of mode ``i``'s strain energy in flexible joint ``k`` (order of
        ``flex_joints``); sums to 1 over ``k``.
    flange_direction
        ``(n, m, 3)`` unit vectors, base frame: the major axis of the flange's path in the mode,
        sign such that the largest component is positive.
    flange_participation
        ``(n, m)``: share of the flange's residual vibration (displacement) carried by each
        mode when the motors of one of the arm's joints stop after an acceleration, the
        largest over the joints (see :func:`model_modes`).
    flex_joints
        The flexible joints.
    """

    wn_rad_s: np.ndarray
    zeta: np.ndarray
    joint_shares: np.ndarray
    flange_direction: np.ndarray
    flange_participation: np.ndarray
    flex_joints: tuple[int, ...]

    def dominant_joint(self) -> np.ndarray:
        """``(n, m)``: the flexible joint storing the largest share of each mode's energy."""
        return np.asarray(self.flex_joints)[np.argmax(self.joint_shares, axis=2)]


def _smooth_abs(load_nm: np.ndarray) -> np.ndarray:
    return np.hypot(load_nm, SMOOTHING_NM) - SMOOTHING_NM


def joint_laws(
    entries: Sequence[Mapping[str, Any]], gravity_torque_nm: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness ``(n, m)`` (N m/rad) and damping ``(n, m)`` (N m s/rad) of the flexible joints
    ``entries`` (a modal map's ``flex_joints``) at gravity torques ``(n, n_dof)``."""
    tau = np.asarray(gravity_torque_nm, dtype=float)
    k, c = [], []
    for e in entries:
        load = tau[:, int(e["joint"])]
        k0, k1, k2 = e["stiffness_nm_per_rad"]
        k.append(k0 + k1 * _smooth_abs(load) + k2 * load * load)
        load = tau[:, int(e["damping_load_joint"])]
        c0, c1, c2 = e["damping_nms_per_rad"]
        c.append(c0 + c1 * _smooth_abs(load) + c2 * load * load)
    return np.column_stack(k), np.column_stack(c)


def undamped_frequencies(mass_ff: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """``(..., n, m)`` undamped natural frequencies (rad/s, increasing) of ``K φ = ω² M_ff φ``
    (``mass_ff`` ``(n, m, m)``, ``stiffness`` ``(..., n, m)``: leading dimensions for many
    stiffness sets at once): ``B = K^{-1/2} M_ff K^{-1/2}`` has eigenvalues ``1/ω²``; NaN where
    ``K`` is not positive. Each pose's matrix is solved alone, so a set's frequencies are the
    same to the bit whether it comes alone or with others."""
    s = 1.0 / np.sqrt(np.where(stiffness > 0, stiffness, np.nan))
    b = mass_ff * s[..., :, None] * s[..., None, :]
    ok = np.all(np.isfinite(b), axis=(-2, -1))
    mu = np.full(stiffness.shape, np.nan)
    if ok.any():
        mu[ok] = np.linalg.eigvalsh(b[ok])
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sort(1.0 / np.sqrt(np.where(mu > 0, mu, np.nan)), axis=-1)


def model_modes(
    entries: Sequence[Mapping[str, Any]],
    mass_kg_m2: np.ndarray,
    gravity_torque_nm: np.ndarray,
    jacobian: np.ndarray,
) -> ModelModes:
    """Every mode of the map ``entries`` at ``n`` poses.

    Parameters
    ----------
    entries
        The flexible joints' laws (a modal map's ``flex_joints``).
    mass_kg_m2
        Link-side mass matrices ``(n, n_dof, n_dof)``.
    gravity_torque_nm
        ``(n, n_dof)``.
    jacobian
        Flange Jacobians ``(n, 6, n_dof)`` or their translational rows ``(n, 3, n_dof)``.

    The flange participation: when the motors of joint ``j`` decelerate by ``a`` and stop, the
    inertial load ``−M_f,j a`` excites undamped mode ``i`` (mass-normalised ``φ_i``) with the
    modal force ``f_i = φ_iᵀ M_f,j a``; the mode rings on with modal displacement ``f_i/ω_i²``,
    i.e. flange displacement amplitude ``|J_f φ_i| |f_i| / ω_i²``. Its share of the sum over
    the modes, the largest over the joints ``j``, is the participation.
    """
    joints = np.array([int(e["joint"]) for e in entries])
    mass = np.asarray(mass_kg_m2, dtype=float)
    n, m = mass.shape[0], joints.size
    mff = mass[:, joints][:, :, joints]
    k, c = joint_laws(entries, gravity_torque_nm)
    jac_f = np.asarray(jacobian, dtype=float)[:, :3, :][:, :, joints]

    # Undamped modes (shapes for participation and for the fallback of an overdamped mode).
    s = 1.0 / np.sqrt(k)
    b = mff * s[:, :, None] * s[:, None, :]
    mu, v = np.linalg.eigh(b)  # ascending 1/ω²: reverse for ascending ω
    mu, v = mu[:, ::-1], v[:, :, ::-1]
    with np.errstate(invalid="ignore", divide="ignore"):  # NaN where M_ff is not positive
        wn_u = 1.0 / np.sqrt(mu)
    phi_u = v * s[:, :, None]  # K-scaled: φᵀ K φ = 1, so φᵀ M φ = 1/ω²
    phi_mass = phi_u * wn_u[:, None, :]  # mass-normalised: φᵀ M φ = 1
    zeta_p = 0.5 * wn_u * np.einsum("nki,nk,nki->ni", phi_u, c, phi_u)

    # Exact damped roots of the first-order form, one of each conjugate pair.
    minv = np.linalg.inv(mff)
    a = np.zeros((n, 2 * m, 2 * m))
    a[:, :m, m:] = np.eye(m)
    a[:, m:, :m] = -minv * k[:, None, :]
    a[:, m:, m:] = -minv * c[:, None, :]
    lam, vec = np.linalg.eig(a)
    wn, zeta = wn_u.copy(), zeta_p.copy()
    shape = phi_u.astype(complex)
    for p in range(n):
        keep = lam[p].imag > 1e-9 * np.abs(lam[p])
        if keep.sum() != m:  # an overdamped mode: the projection, as the core falls back to
            continue
        order = np.argsort(np.abs(lam[p][keep]))
        root = lam[p][keep][order]
        wn[p], zeta[p] = np.abs(root), -root.real / np.abs(root)
        shape[p] = vec[p][:m][:, keep][:, order]
    energy = k[:, :, None] * np.abs(shape) ** 2
    shares = np.transpose(energy / energy.sum(axis=1, keepdims=True), (0, 2, 1))

    motion = np.einsum("nck,nki->nic", jac_f, shape)  # complex flange translation per mode
    pair = np.stack([motion.real, motion.imag], axis=-1)  # (n, m, 3, 2)
    u, _, _ = np.linalg.svd(pair)
    direction = u[..., 0]
    largest = np.take_along_axis(direction, np.argmax(np.abs(direction), axis=2)[..., None], 2)
    direction = direction * np.where(largest < 0, -1.0, 1.0)

    flange = np.linalg.norm(np.einsum("nck,nki->nic", jac_f, phi_mass), axis=2)  # (n, m)
    force = np.abs(np.einsum("nki,nkj->nij", phi_mass, mass[:, joints, :]))  # (n, m, n_dof)
    amplitude = (flange / wn_u**2)[:, :, None] * force
    total = amplitude.sum(axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(total > 0, amplitude / total, 0.0)
    return ModelModes(
        wn_rad_s=wn,
        zeta=zeta,
        joint_shares=shares,
        flange_direction=direction,
        flange_participation=share.max(axis=2),
        flex_joints=tuple(int(j) for j in joints),
    )
