"""A modal-map prior from a paper10 map (the paper's published UR5e map, eqs. 42-51).

The learner refines a modal map: physical joint laws whose modes come from the mass matrix
at every pose, so a few end poses' modes say how stiff each joint is everywhere. A paper10
map is a curve fit of the modes against the joint inertias; its ten coefficients have no
joint to scale, and a few end poses cannot pin them. So a paper10 map is converted, not
learned directly: the modal map whose laws fit the paper10 map's predicted modes over the
workspace (:func:`tvist.ident.modal_fit.fit_modal_map` on those predictions, as if they were
a campaign), with the conversion's own error kept: :func:`converted_prior_log_sigma` widens
the learner's prior so that it covers both the paper10 map's error on the arm and what the
conversion lost.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from tvist.maps.modal import ModalMap
from tvist.maps.paper10 import DynamicMap
from tvist.robots import Robot
from tvist.trajectory import PAPER_POSES

__all__ = ["ConvertedPrior", "converted_prior_log_sigma", "modal_prior_from_paper10"]

#: Poses the paper10 map's modes are fitted at (:func:`conversion_poses`). The published map
#: is a curve fit of one arm's modes along the paper's test motions: off them it extrapolates
#: (on the default twin its base frequency is 28 % off at the median random pose of the
#: ordinary moves, 73 % at worst, against 9 % at Q1), and a modal map fitted to it over the
#: whole workspace is off the map by 25 % at the median pose. So the conversion fits the
#: published map where it holds: along the lines between the test poses.
CONVERSION_POSES = 90
#: Flexible joints of the converted map: base, shoulder, elbow and wrists 1-2 (as the demo's
#: identified modal map).
CONVERSION_FLEX_JOINTS = (0, 1, 2, 3, 4)
#: The elbow and wrists start this many times stiffer than the stiffer of base and shoulder.
STIFF_JOINT_FACTOR = 5.0
#: Weight of the log-damping errors against the log-frequency errors (a ZV shaper is ~10
#: times less sensitive to its damping ratio than to its frequency).
ZETA_WEIGHT = 0.1
#: Log errors beyond this count linearly, not squared (a robust fit: the published map is
#: a curve fit of one arm's modes along its test motions, far from physical at some poses).
ROBUST_SCALE = 0.05


@dataclass(frozen=True)
class ConvertedPrior:
    """A paper10 map as a modal map, with what the conversion lost.

    Attributes
    ----------
    map
        The modal map.
    wn_rel_rms, wn_rel_max, wn_rel_median
        RMS, largest and median absolute relative difference of its natural frequencies from
        the paper10 map's over the conversion poses (both modes, in order of frequency).
    zeta_rel_rms
        RMS relative difference of its damping ratios.
    """

    map: ModalMap
    wn_rel_rms: float
    wn_rel_max: float
    zeta_rel_rms: float
    wn_rel_median: float


def _by_frequency(modes: np.ndarray) -> np.ndarray:
    """Modes ``(n_poses, 2, 2)`` with each pose's two modes in order of frequency."""
    order = np.argsort(modes[:, :, 0], axis=1)
    return np.take_along_axis(modes, order[:, :, None], axis=1)


def conversion_poses() -> np.ndarray:
    """Where the published map holds: :data:`CONVERSION_POSES` poses evenly along the
    joint-space lines between the paper's test poses (Q1-Q2, Q1-Q3, Q2-Q3), ``(n, 6)``."""
    names = sorted(PAPER_POSES)
    ends = [
        (np.asarray(PAPER_POSES[a], dtype=float), np.asarray(PAPER_POSES[b], dtype=float))
        for i, a in enumerate(names)
        for b in names[i + 1 :]
    ]
    per_line = CONVERSION_POSES // len(ends)
    s = np.linspace(0.0, 1.0, per_line)[:, None]
    return np.concatenate([a + s * (b - a) for a, b in ends])


def modal_prior_from_paper10(
    robot: Robot, paper: DynamicMap, joint_stiffness: Mapping[int, float] | None = None
) -> ConvertedPrior:
    """The modal map whose joint laws best reproduce ``paper``'s modes on ``robot`` (declared
    payload) over :data:`CONVERSION_POSES` workspace poses.

    The paper10 map's modes read joint inertias only, so they say how stiff the base and
    shoulder are but nothing about the elbow and wrists: those get ``joint_stiffness[j]``
    (N m/rad, constant) where given, else the identification's start guess
    (:data:`STIFF_JOINT_FACTOR` times the stiffer of base and shoulder, as
    :func:`tvist.ident.modal_fit.fit_modal_map` starts them), left to the learner; the base
    and shoulder laws are fitted with them in place. Fitted: the
    base and shoulder stiffness (constant laws: the published map has no load term) and their
    dampers (``c_0 + c_2 L²``), on log-frequency and log-damping errors.

    Raises
    ------
    ValueError
        ``paper`` does not have the two modes (base, shoulder) of a modal map, or
        ``joint_stiffness`` names a joint other than the elbow and wrists or a stiffness that
        is not positive.
    """
    given = dict(joint_stiffness or {})
    guessed = [j for j in CONVERSION_FLEX_JOINTS if j not in (0, 1)]
    for j, k in given.items():
        if j not in guessed or not (math.isfinite(k) and k > 0.0):
            raise ValueError(
                f"joint_stiffness: joint {j}: {k!r}; give a positive stiffness (N m/rad) of "
                f"joints {guessed}"
            )
    if len(paper.mode_maps) != 2:
        raise ValueError(
            f"a paper10 map with {len(paper.mode_maps)} modes; the modal prior has two (base, "
            "shoulder)"
        )
    q = conversion_poses()
    inertia = robot.joint_inertia_many(q)
    tau = robot.gravity_torque_many(q)
    # The two maps name their modes differently (the published one by the joint its
    # frequency reads, the modal one by the joint that holds most of the mode's strain
    # energy); a shaper of both modes does not depend on the names, so the conversion
    # compares the modes in order of frequency.
    target = _by_frequency(
        paper.modes_from_inertia_many(inertia, tau if paper.uses_gravity else None)
    )
    mass = robot.mass_matrix_many(q)
    # Single-joint guesses k = ω² J, as the identification's start.
    k_start = [float(np.median(target[:, m, 0] ** 2 * mass[:, j, j])) for m, j in enumerate((0, 1))]
    stiff = STIFF_JOINT_FACTOR * max(k_start)
    load_joint = {0: 1, 1: 1}

    def entries(x: np.ndarray) -> list[dict]:
        out = []
        for j in CONVERSION_FLEX_JOINTS:
            entry = {
                "joint": j,
                "stiffness_nm_per_rad": [float(given.get(j, stiff)), 0.0, 0.0],
                "damping_nms_per_rad": [0.0, 0.0, 0.0],
                "damping_load_joint": load_joint.get(j, j),
            }
            if j in (0, 1):
                k, c0, c2 = np.exp(x[3 * j : 3 * j + 3])
                entry["stiffness_nm_per_rad"] = [float(k), 0.0, 0.0]
                entry["damping_nms_per_rad"] = [float(c0), 0.0, float(c2)]
            out.append(entry)
        return out

    def predict(x: np.ndarray) -> np.ndarray:
        modal = ModalMap(entries(x), (0, 1))
        return _by_frequency(
            modal.modes_from_mass_matrix_many(mass, tau if modal.uses_gravity else None)
        )

    def residual(x: np.ndarray) -> np.ndarray:
        pred = predict(x)
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.log(pred / target)
        r[:, :, 1] *= ZETA_WEIGHT
        return np.nan_to_num(r, nan=10.0).ravel()

    # Dampers started at ζ = 0.1 of the single-joint modes, c = 2 ζ √(k J).
    c_start = [0.2 * math.sqrt(k * float(np.median(mass[:, j, j]))) for j, k in enumerate(k_start)]
    x0 = np.log([k_start[0], c_start[0], 1e-3, k_start[1], c_start[1], 1e-3])
    fit = optimize.least_squares(residual, x0, loss="soft_l1", f_scale=ROBUST_SCALE, max_nfev=400)
    source = paper.metadata.get("source") or "a paper10 map"
    modal = ModalMap(
        entries(fit.x),
        (0, 1),
        {
            "robot": paper.robot or robot.params.name,
            "source": f"modal laws fitted to {source} ({q.shape[0]} poses)",
        },
    )
    fitted = predict(fit.x)
    wn_rel = fitted[:, :, 0] / target[:, :, 0] - 1.0
    zeta_rel = fitted[:, :, 1] / target[:, :, 1] - 1.0
    return ConvertedPrior(
        modal,
        float(np.sqrt(np.nanmean(wn_rel**2))),
        float(np.nanmax(np.abs(wn_rel))),
        float(np.sqrt(np.nanmean(zeta_rel**2))),
        float(np.nanmedian(np.abs(wn_rel))),
    )


def converted_prior_log_sigma(converted: ConvertedPrior, base_log_sigma: float) -> float:
    """Prior uncertainty of the log scale factors learned from a converted map:
    ``base_log_sigma`` (the paper10 map's own error on the arm) and the conversion's typical
    frequency error as a stiffness error (``k ∝ ω²``: twice the relative frequency error; the
    robust standard deviation, 1.4826 times the median absolute error), added in quadrature.
    Not the largest error: where the published map departs from any joint-spring model
    (its second mode in the middle of Q1-Q3, where the arm's base inertia is small but the
    published base frequency reads the shoulder's) the conversion does not follow it by
    design."""
    return math.hypot(base_log_sigma, 2.0 * 1.4826 * converted.wn_rel_median)
