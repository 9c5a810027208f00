"""Flexible links: a link of the twin as a bending beam of rigid segments and hinges.

A link chosen in :class:`LinkBeams` (the upper arm and forearm of a UR arm) is cut into
``n + 1`` rigid segments joined by ``n`` bending hinges, each hinge two hinge joints about the
two axes perpendicular to the link, with a rotational spring and a damper. The link is a tube
of Young's modulus ``E`` and second moment of area ``I`` along the line between its two joint
axes, shifted sideways through its centre of mass (where the link's tube is).

Hinge stiffness (midpoint rule for the beam's curvature): a length ``ℓ`` of beam carrying a
bending moment ``M`` turns one end against the other by ``M ℓ / (E I)``. The link's length
``L`` is cut into ``n`` equal parts of ``ℓ = L / n``, and each part's bending compliance is
lumped into a hinge at its middle:

``k = E I / ℓ = n E I / L``  (N m/rad, the same about both bending axes of a round tube),

with ``I = π (D⁴ − d⁴) / 64`` for outer and inner diameters ``D`` and ``d = D − 2 t``. For a
constant moment this is exact. For a cantilever with a tip force ``F`` (moment falling linearly
to zero) two hinges, at ``L/4`` and ``3L/4``, carry ``3FL/4`` and ``FL/4`` and move the tip by
``(F L / k)(9 L/16 + L/16) = 5 F L³ / (16 E I)``, 6 % less than the beam's ``F L³ / (3 E I)``:
the lumped link is 6 % stiffer, its first bending frequency about 3 % above the continuous
beam's.

Structural damping: the hinge damper is the viscous equivalent of a hysteretic loss factor
``η`` at the reference frequency ``f_ref`` (equal energy lost per cycle there),
``c = η k / (2 π f_ref)``: a damping ratio of ``η / 2`` for a mode at ``f_ref``, rising in
proportion to frequency above it (stiffness-proportional damping).

Mass (the core's ``split_link``, tvist-core ``link_hinges``, which the modal map's link hinges
use too): the link's mass, centre of mass and inertia are distributed over the segments so that
with straight hinges the segments together are exactly the rigid link: segment ``s`` gets
the mass fraction ``f_s`` of its length, a centre of mass ``c + (x_s − x̄) e`` (``x_s`` the
segment's middle along the link's unit axis ``e``, ``x̄ = Σ f_s x_s``), and the inertia about
its centre of mass ``f_s (I_c − I_spread)`` with ``I_spread`` the parallel-axis inertia of
the segment masses about ``c``. The rigid arm's mass matrix is therefore unchanged. If a
link's inertia is too small for that spread (``I_c − I_spread`` not a physical inertia), the
spread is shrunk until it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tvist import _core

__all__ = ["BeamSegment", "LinkBeams", "split_link"]

#: Shortest link (joint-to-joint distance, m) that can be cut into segments (the core's).
MIN_LINK_LENGTH_M = 0.05


@dataclass(frozen=True)
class LinkBeams:
    """Which links of the twin bend, and their tube section (SI units).

    Attributes
    ----------
    links
        Link indices (0-based, link ``i`` turns with joint ``i``; the UR upper arm is 1, the
        forearm 2). Each must have a joint-to-joint length of at least 5 cm.
    outer_diameter_m, wall_m
        Tube section, ``D`` and ``t`` (m).
    youngs_modulus_pa
        ``E`` (Pa); aluminium alloy 69 GPa.
    hinges_per_link
        ``n`` bending hinges per link (``n + 1`` rigid segments).
    loss_factor
        Structural loss factor ``η`` of the link (dimensionless).
    damping_reference_hz
        Frequency at which the viscous hinge damper dissipates as the loss factor says (Hz).
    physics_dt_s
        The twin's time step with these links (s). The hinge springs are integrated
        explicitly (semi-implicit Euler), stable for ``ω dt < 2``; the fastest mode of the
        segmented UR5e links is a short end segment turning between its hinge and the next
        joint, about 1.4 kHz with the default section, so 0.125 ms (``ω dt`` ≈ 1.1).
    """

    links: tuple[int, ...]
    outer_diameter_m: float
    wall_m: float
    youngs_modulus_pa: float = 69e9
    hinges_per_link: int = 2
    loss_factor: float = 0.02
    damping_reference_hz: float = 35.0
    physics_dt_s: float = 0.000125

    def validate(self, n_dof: int) -> None:
        """Raise ValueError naming the field that is impossible for an arm of ``n_dof``."""
        if not self.links or any(not 0 <= i < n_dof for i in self.links):
            raise ValueError(
                f"LinkBeams.links must be link indices in [0, {n_dof}), got {self.links}"
            )
        if len(set(self.links)) != len(self.links):
            raise ValueError(f"LinkBeams.links has duplicates: {self.links}")
        if not (0.0 < self.wall_m < self.outer_diameter_m / 2.0):
            raise ValueError(
                f"LinkBeams.wall_m must be in (0, outer_diameter_m / 2), got {self.wall_m!r}"
            )
        for name in ("youngs_modulus_pa", "loss_factor", "damping_reference_hz", "physics_dt_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"LinkBeams.{name} must be finite and > 0, got {value!r}")
        if self.hinges_per_link < 1:
            raise ValueError(f"LinkBeams.hinges_per_link must be >= 1, got {self.hinges_per_link}")

    @property
    def second_moment_m4(self) -> float:
        """``I = π (D⁴ − d⁴) / 64`` of the tube (m⁴)."""
        outer = self.outer_diameter_m
        inner = outer - 2.0 * self.wall_m
        return math.pi * (outer**4 - inner**4) / 64.0

    @property
    def bending_stiffness_nm2(self) -> float:
        """``E I`` (N m²)."""
        return self.youngs_modulus_pa * self.second_moment_m4

    def hinge_stiffness_nm_per_rad(self, length_m: float) -> float:
        """``k = n E I / L`` of each hinge of a link of length ``length_m`` (N m/rad)."""
        return self.hinges_per_link * self.bending_stiffness_nm2 / float(length_m)

    def hinge_damping_nms_per_rad(self, length_m: float) -> float:
        """``c = η k / (2 π f_ref)`` (N m s/rad)."""
        return (
            self.loss_factor
            * self.hinge_stiffness_nm_per_rad(length_m)
            / (2.0 * math.pi * self.damping_reference_hz)
        )


@dataclass(frozen=True)
class BeamSegment:
    """One rigid segment of a split link, in the link body's frame (m, kg, kg m²).

    ``hinge_m`` is the point where the segment is hinged to the previous one (``None`` for
    the first segment, which is the link body itself); the segment's inertial data is
    ``mass_kg`` at ``com_m`` with ``inertia_kg_m2`` about it.
    """

    hinge_m: np.ndarray | None
    mass_kg: float
    com_m: np.ndarray
    inertia_kg_m2: np.ndarray


def split_link(
    offset_m: np.ndarray,
    mass_kg: float,
    com_m: np.ndarray,
    inertia_kg_m2: np.ndarray,
    n_hinges: int,
) -> tuple[list[BeamSegment], np.ndarray]:
    """The ``n_hinges + 1`` segments of a link from its joint (origin) to the next joint at
    ``offset_m``, with the link's inertial data in the same frame.

    Returns ``(segments, bending_axes)``: ``bending_axes`` (2, 3) are the unit axes of each
    hinge, the first parallel to the link's own joint axis (z, made perpendicular to the link),
    the second perpendicular to both.

    The composite of the segments (parallel-axis theorem) equals ``(mass_kg, com_m,
    inertia_kg_m2)`` to rounding.
    """
    hinge_frac = (np.arange(n_hinges) + 0.5) / n_hinges
    try:
        parts, axes = _core.split_link(
            np.asarray(offset_m, dtype=float).tolist(),
            float(mass_kg),
            np.asarray(com_m, dtype=float).tolist(),
            np.asarray(inertia_kg_m2, dtype=float).tolist(),
            hinge_frac.tolist(),
        )
    except ValueError as exc:
        raise ValueError(str(exc).removeprefix("invalid parameter: ")) from None
    segments = [
        BeamSegment(
            hinge_m=None if hinge is None else np.array(hinge),
            mass_kg=float(mass),
            com_m=np.array(com),
            inertia_kg_m2=np.array(inertia),
        )
        for hinge, mass, com, inertia in parts
    ]
    return segments, np.array(axes)
