"""Twin variants whose flexibility the modal map does not model exactly.

The default twin (:data:`tvist.sim.flex.UR5E_FLEX`) is itself a flexible-joint model with a
stiff elbow and stiff wrists, so a modal map of base, shoulder and elbow agrees with it partly
by construction. A variant changes the plant, not the map:

``"ur5e-soft-gears"``
    Strain-wave gears with the stiffness curve of a real harmonic drive: soft at low torque
    and stiffening strongly with load (the tangent stiffness ``k1 + 3 k3 δ²`` triples at rated
    torque instead of growing by 25 %), so the static stiffness grows as about ``τ^(2/3)``
    at large loads, which the map's ``k_0 + k_1|L| + k_2 L²`` only approximates, and the
    vibration itself (a few mrad) sweeps a stiffness that varies along the cycle. The elbow
    is soft (40 000 N m/rad instead of 120 000: at folded poses the base mode then depends on
    the elbow's flexibility), and wrists 1-2 are soft (5 000 N m/rad instead of 15 000) and
    not modelled by a three-joint modal map at all: their compliance lowers the base and
    shoulder modes by a pose-dependent amount the map has to absorb in its base, shoulder
    and elbow laws.

``"ur5e-flex-links"``
    The default gears, and an upper arm and forearm that bend (:mod:`tvist.sim.beams`): each
    is an aluminium tube (E = 69 GPa) of 80 mm outer diameter and 3 mm wall
    (``I = 5.39e-7 m⁴``, ``E I = 37 200 N m²``) along the link's length (0.425 m and
    0.392 m), cut into three rigid segments joined by two bending hinges, each about both axes
    perpendicular to the link, ``k = 2 E I / L`` (174 900 and 189 500 N m/rad), with
    structural damping of loss factor 0.02 (viscous equivalent at 35 Hz). The section is a
    design choice, not a measured UR5e link: it puts link bending among the modes that
    matter. With every joint held and the 5 kg payload, the upper arm, carrying the forearm,
    wrists and payload, bends at 21.4 Hz stretched out (Q1) and 45.7 Hz folded (Q3), the
    forearm at 46.2 Hz (a continuous Euler-Bernoulli beam with the carried links as a rigid
    tip body: 21.3, 45.5 and 45.9 Hz, ``tests/reference/test_flex_links.py``). No joint-spring
    model contains these degrees of freedom: at stretched poses the links' bending adds compliance
    in series with the gears (base and shoulder modes at Q1 7.45 and 7.21 Hz instead of 7.90
    and 7.67), at folded poses it couples with them (Q3 18.21 and 18.15 Hz instead of 20.16
    and 19.22), by amounts that depend on the pose.

``"family:<robot>:<seed>"``
    Variant ``seed`` of the seeded family of :mod:`tvist.sim.family` (UR5e and UR10e): gear
    and servo stiffness, stiffening, damping and link bending drawn from plausible ranges.

Run a campaign on a variant with :func:`tvist.ident.campaign.run_variant_campaign` (the
twin campaign's records, with ``true_modes`` from the variant's own eigen-analysis), or build
the twin directly:
``Twin("ur5e", flex=variant_flex(name), beams=variant_beams(name))``.

Not a variant yet: gear hysteresis (a stiffness that depends on the loading history), which
needs the twin's time-stepping loop to carry extra state.
"""

from __future__ import annotations

from dataclasses import replace

from tvist.sim.beams import LinkBeams
from tvist.sim.flex import UR5E_FLEX, FlexParams, stiffening_k3

__all__ = [
    "VARIANTS",
    "variant_beams",
    "variant_flex",
    "variant_robot",
    "variant_twin_kwargs",
]


_SOFT_K1 = (16000.0, 13000.0, 40000.0, 5000.0, 5000.0, 2000.0)
_RATED_NM = (150.0, 150.0, 150.0, 28.0, 28.0, 28.0)

#: Named variants: ``{name: (robot_name, FlexParams)}``.
VARIANTS: dict[str, tuple[str, FlexParams]] = {
    "ur5e-soft-gears": (
        "ur5e",
        replace(
            UR5E_FLEX,
            k1_nm_per_rad=_SOFT_K1,
            k3_nm_per_rad3=tuple(
                stiffening_k3(k, t, 3.0) for k, t in zip(_SOFT_K1, _RATED_NM, strict=True)
            ),
        ),
    ),
    "ur5e-flex-links": ("ur5e", UR5E_FLEX),
}

#: The bending links of the variants that have them (see :data:`VARIANTS`).
_BEAMS: dict[str, LinkBeams] = {
    "ur5e-flex-links": LinkBeams(links=(1, 2), outer_diameter_m=0.080, wall_m=0.003),
}


def _family(name: str):
    """The family variant named ``name``, or ``None`` for any other name."""
    from tvist.sim.family import parse_family_name

    return parse_family_name(name)


def _unknown(name: str) -> ValueError:
    return ValueError(
        f"unknown, known: {', '.join(VARIANTS)}, family:<robot>:<seed> (twin variant {name!r})"
    )


def variant_robot(name: str) -> str:
    """The robot (parameter-file name) of variant ``name``.

    Raises
    ------
    ValueError
        Unknown variant.
    """
    family = _family(name)
    if family is not None:
        return family.robot
    if name not in VARIANTS:
        raise _unknown(name)
    return VARIANTS[name][0]


def variant_twin_kwargs(name: str) -> dict:
    """The :class:`~tvist.sim.Twin` keywords (``flex``, ``beams`` and, for a family variant,
    ``physics_dt_s``) that make variant ``name``.

    Raises
    ------
    ValueError
        Unknown variant.
    """
    family = _family(name)
    if family is not None:
        return family.twin_kwargs()
    return {"flex": variant_flex(name), "beams": variant_beams(name)}


def variant_beams(name: str) -> LinkBeams | None:
    """The bending links of variant ``name``, ``None`` if its links are rigid.

    Raises
    ------
    ValueError
        Unknown variant.
    """
    family = _family(name)
    if family is not None:
        return family.beams
    variant_flex(name)
    return _BEAMS.get(name)


def variant_flex(name: str) -> FlexParams:
    """The :class:`~tvist.sim.FlexParams` of variant ``name`` (see :data:`VARIANTS`).

    Raises
    ------
    ValueError
        Unknown variant.
    """
    family = _family(name)
    if family is not None:
        return family.flex
    try:
        return VARIANTS[name][1]
    except KeyError:
        raise _unknown(name) from None
