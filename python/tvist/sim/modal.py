"""Eigen-analysis of a linear second-order system ``M x'' + C x' + K x = 0``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg


@dataclass(frozen=True)
class ModalAnalysis:
    """Vibration modes of a linearized flexible-joint arm, sorted by natural frequency.

    Attributes
    ----------
    wn_rad_s
        Undamped natural frequencies ``|lambda|`` (rad/s), ``(n_modes,)``.
    zeta
        Damping ratios ``-Re(lambda) / |lambda|``, ``(n_modes,)``.
    shapes
        Complex mode shapes (joint deflection amplitudes), one per column, each scaled so its
        largest entry is 1, ``(n_dof, n_modes)``.
    strain_energy
        Fraction of each mode's gear strain energy ``k_j |phi_j|² / sum`` stored in joint
        ``j``, ``(n_dof, n_modes)``; each column sums to 1.
    """

    wn_rad_s: np.ndarray
    zeta: np.ndarray
    shapes: np.ndarray
    strain_energy: np.ndarray

    @property
    def freq_hz(self) -> np.ndarray:
        """Undamped natural frequencies (Hz)."""
        return self.wn_rad_s / (2.0 * np.pi)

    def dominant_mode(self, joint: int, exclude: tuple[int, ...] = ()) -> int:
        """Index of the mode that stores the largest share of its strain energy in ``joint``."""
        share = self.strain_energy[joint].copy()
        share[list(exclude)] = -np.inf
        return int(np.argmax(share))


def modal_analysis(
    mass: np.ndarray,
    damping: np.ndarray,
    stiffness: np.ndarray,
    gear_stiffness: np.ndarray,
) -> ModalAnalysis:
    """Modes of ``M x'' + C x' + K x = 0`` from the eigenvalues of its first-order form.

    Parameters
    ----------
    mass, damping, stiffness
        ``M`` (symmetric positive definite), ``C`` and ``K``, each ``(n, n)``.
    gear_stiffness
        Tangent gear stiffness per joint ``(n,)`` (N m/rad), used to weigh the strain energy.

    Returns
    -------
    ModalAnalysis
        The underdamped (oscillating) modes. Overdamped real eigenvalues are not modes of
        vibration and are left out.
    """
    n = mass.shape[0]
    m_inv_k = np.linalg.solve(mass, stiffness)
    m_inv_c = np.linalg.solve(mass, damping)
    system = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv_k, -m_inv_c]])
    eigenvalues, eigenvectors = scipy.linalg.eig(system)
    # One of each complex-conjugate pair: the oscillating modes with positive imaginary part.
    keep = eigenvalues.imag > 1e-9 * np.abs(eigenvalues)
    lam = eigenvalues[keep]
    shapes = eigenvectors[:n, keep]
    order = np.argsort(np.abs(lam))
    lam, shapes = lam[order], shapes[:, order]
    shapes = shapes / shapes[np.argmax(np.abs(shapes), axis=0), np.arange(shapes.shape[1])]
    energy = np.asarray(gear_stiffness, dtype=float)[:, None] * np.abs(shapes) ** 2
    energy = energy / energy.sum(axis=0, keepdims=True)
    wn = np.abs(lam)
    return ModalAnalysis(wn_rad_s=wn, zeta=-lam.real / wn, shapes=shapes, strain_energy=energy)
