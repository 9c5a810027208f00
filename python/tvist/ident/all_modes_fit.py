"""Fit a modal map to every identified mode of every pose, matched to the model's eigenmodes.

Each identified mode (a pose record's ``ringing`` entry, :mod:`tvist.ident.observed_modes`)
is compared with the model eigenmode it physically is, not with the mode a joint label names:
at a folded pose the base excitation's strongest ringing is often an elbow-dominated mode.

**Matching.** Per pose and excitation log, identified modes and the model's eigenmodes
(:func:`tvist.ident.model_modes.model_modes`) are paired one to one (Hungarian assignment)
at the least cost ``(ln(ω_id/ω_model)/F_TOL)² + (sin θ/D_TOL)²``, ``θ`` the angle between the
identified and the model's flange direction (the eigenvector through the flange Jacobian; the
term is left out for a mode identified without a direction). A pair costing more than
:data:`GATE` is no match: that identification is left out. The model's modes are tracked by
frequency rank, which is continuous in the parameters (also where two modes veer), so the
assignment is fixed during each least-squares fit and redone after it until it settles.

**Fit.** (1) Stiffness on the matched frequencies, from several starts of the joints other
than base and shoulder (the pairing depends on them), robust least squares with the
undamped modes; (2) damping, non-negative least squares on the matched damping ratios with
the damping projected on the undamped modes (linear in the coefficients); (3) both together on
``ω`` and ``ζ`` with the exact damped modes (the core's model), each in units of its scatter.
Load terms below ``drop_t`` standard errors are dropped, the weakest first (standard errors
per parameter: the load terms of a joint no identified mode involves are not determined, and
must not make the others' infinite: :mod:`tvist.ident.standard_errors`).

**Every candidate joint stays flexible** (:func:`flexible_candidates`: base to wrist 2 on a
UR). A joint's gear is a spring whether or not its own mode was identified, and a joint made
rigid forces its compliance into the others' laws: on development variant 1 of
:mod:`tvist.sim.family` (elbow and wrists never identified), a likelihood-ratio test that made
its wrists rigid left the shoulder law 3.1 % RMS / 11.3 % max off the true modes at 20 poses
outside the campaign; with every joint flexible 1.3 / 4.7 % (variants 0, 2 and 4 about
unchanged; variant 3's wrist 1, 3.5 times softer than nominal, is not determined by base and
shoulder excitations either way: its base and shoulder laws stay 2.7 / 8.9 % and 8.7 / 28 %
off). A joint whose mode the campaign never identified keeps a stiffness the data bound only
loosely (within a factor :data:`STIFFNESS_SPAN` of its start); its mode is not shaped unless
identified (:mod:`tvist.ident.shaped_modes`).

**Which joints are damped** is decided by the damping ratios. Base and shoulder and any
joint or hinge that dominates at least :data:`MIN_DOMINATED_FOR_LOAD_LAW` identified modes
carry a damper with its load law (the joint's ``v_0 + v_1|L| + v_2 L²``). Every other
flexible coordinate gets a constant damper if it lowers the damping fit's truncated χ² by
more than the same likelihood-ratio test as a link's (:func:`_select_dampers`): a gear damps
whether or not its own mode rang, and a joint left undamped makes the modes it takes part in
too light, which a ZV shaper turns into residual vibration (on development variant 0 of
:mod:`tvist.sim.family`, dampers at base and shoulder only left the elbow-involved mode at
the demo's Q3, 14.8 Hz with ζ 0.060, at ζ 0.014, and Q1→Q3 kept 87.6 % of its reduction).
Not every joint is damped by default: a damper the data barely determine trades against the
stiffnesses in the joint refinement (on the default twin's demo campaign, dampers at every
joint put wrist 1 at 380 times critical and the shaped modes' errors from 0.2 / 0.5 % to
1.1 / 1.7 % RMS held out). A constant damper is also bounded at :data:`MAX_OWN_ZETA` of
critical for its coordinate alone (:func:`_damping_caps`).

**Which links bend** is decided by the data: a candidate link's hinge is made stiff (removed)
when the evidence for its bending is weak: the truncated χ² of the frequency fit (each
residual in units of the full model's robust scatter, capped at :data:`GATE` like an
unmatched mode) must fall by more than the ``1 − JOINT_P`` quantile of χ² with one degree of
freedom when the link bends (a likelihood-ratio test at level :data:`JOINT_P`); the weakest
link is removed first and the test repeated. A model fits at least as well as one nested
in it (a stiff hinge is a rigid link), so where a nested fit is better by more than
:data:`NESTED_TOLERANCE`, the larger model's fit is a local optimum: it is refitted from the
nested fit's solution (the hinge left out there started stiff) before any test is judged,
and the joint tests record it (``refit_chi2``).

**Bending links.** A link that bends (a bending mode of the upper arm or forearm, which a
model of joints alone can only absorb into wrong joint stiffnesses) is a hinge pair at its
middle about the two axes perpendicular to it (:class:`tvist.ModalMap` ``link_hinges``), one
stiffness and one damping for both axes (a round tube) and no load law. Each candidate link
of ``candidate_links`` (upper arm and forearm) enters the fit like a candidate joint: its
stiffness is one parameter (start: its own mode at :data:`HINGE_START_HZ`, bounds a factor
:data:`STIFFNESS_SPAN` either way) and it is kept only if the same likelihood-ratio test
keeps it (one degree of freedom); a rigid link's hinge is stiff, explains nothing and is
removed, which leaves the model of joints alone exactly (at straight hinges the hinged arm's
mass matrix on the joints is the rigid arm's). Internally the fit works in the columns of
the hinged arm's arrays (:meth:`~tvist.ident.observed_modes.ObservedModes.column`); a
hinge's key is its first coordinate's column.

**A servo of finite stiffness** ``k_s`` in series with a gear ``k_g`` is not fitted as a
parameter of its own: with the motor's inertia neglected (as the core's model, and the twin,
take it: the motor is held by the servo) the pair is exactly one spring
``k_g k_s / (k_g + k_s)``, and the gear's stiffening with load, diluted by the linear servo,
is what the law ``k_0 + k_1 |L| + k_2 L²`` of that joint fits. The data cannot separate the two.

**Which modes to shape** (:mod:`tvist.ident.shaped_modes`): each physical mode (the eigenmode
dominated by one flexible joint) is reported with its flange participation over the poses;
the map shapes its ``K`` lowest eigenmodes, ``K`` chosen from how often each mode was
identified and which frequency ranks the shaped ones hold, and the report says at which share
of the poses each mode is among them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import optimize, stats

from tvist.ident.forward_difference import forward_difference_jacobian
from tvist.ident.model_modes import ModelModes, _smooth_abs, model_modes, undamped_frequencies
from tvist.ident.observed_modes import HINGE_AT_FRACTION, ObservedModes, observed_modes
from tvist.ident.standard_errors import standard_errors
from tvist.maps.modal import ModalMap

__all__ = [
    "CANDIDATE_JOINTS",
    "CANDIDATE_LINKS",
    "AllModesFit",
    "bending_candidates",
    "fit_all_modes",
    "flexible_candidates",
    "match_modes",
    "unmatched_warning",
]

#: Joints of a UR (DH) arm that may be flexible: base, shoulder, elbow, wrists 1-2 (wrist 3,
#: the tool axis, hardly moves the flange in the arm's modes). An arm placed by its URDF:
#: its proximal joints (:func:`flexible_candidates`).
CANDIDATE_JOINTS = (0, 1, 2, 3, 4)


def flexible_candidates(robot_name: str) -> tuple[int, ...]:
    """The joints of ``robot_name`` that may be flexible: :data:`CANDIDATE_JOINTS` for a DH
    arm, :data:`tvist.robots.urdf.PROXIMAL_JOINTS` for a URDF-placed arm."""
    from tvist.robots import params
    from tvist.robots.urdf import PROXIMAL_JOINTS

    return CANDIDATE_JOINTS if params(robot_name).placements is None else PROXIMAL_JOINTS


def bending_candidates(robot_name: str) -> tuple[int, ...]:
    """The links of ``robot_name`` that may bend: :data:`CANDIDATE_LINKS` for a DH arm (a
    UR's upper arm and forearm); none for a URDF-placed arm, whose link numbering names no
    long link (give ``candidate_links`` to :func:`fit_all_modes`)."""
    from tvist.robots import params

    return CANDIDATE_LINKS if params(robot_name).placements is None else ()


#: Always flexible: the joints whose excitation logs the campaign records.
ALWAYS_FLEXIBLE = (0, 1)
#: Links of a UR (DH) arm that may bend: the upper arm and the forearm (its long links). An
#: arm placed by its URDF: none unless given (:func:`bending_candidates`).
CANDIDATE_LINKS = (1, 2)
#: Start of a link hinge's stiffness: its own mode (hinge inertia alone) at this frequency.
HINGE_START_HZ = 60.0
#: Matching scales: relative frequency difference and sine of the angle between directions.
F_TOL = 0.05
D_TOL = 0.35
#: Largest matching cost of a pair (3 "standard deviations"), and the cap of one residual's
#: squared size in the joint test.
GATE = 9.0
#: Level of the likelihood-ratio test that keeps a link's bending hinge (the fit statistics'
#: ``joint_test_level``).
JOINT_P = 1e-3
#: Refits of a model from the solution of a model nested in it that fitted better (at most),
#: and the starts of the hinge left out there, as multiples of its start stiffness (stiff:
#: the nested model's solution is where the hinge is rigid).
MAX_NESTED_REPAIRS = 3
NESTED_HINGE_STARTS = (4.0, 25.0)
#: How much better (truncated χ², the joint test's units) a nested fit must be to show a
#: local optimum: separate least-squares runs differ by a fraction of a unit (a stiff hinge
#: is not quite rigid), and the test rejects rigidity only at a gain of 10.8.
NESTED_TOLERANCE = 1.0
#: Starts of the joints other than base and shoulder, as multiples of the shoulder's
#: stiffness (elbow) and as the frequency (Hz) of their own mode (wrists).
ELBOW_STARTS = (0.5, 1.0, 2.0, 5.0)
WRIST_START_HZ = 60.0
#: Quantile over the poses of the base's and the shoulder's start values ``ω² M_jj`` (each a
#: lower bound of the joint's stiffness, :func:`_start`). Not the largest: one log whose
#: lowest modes were all flagged lifts it (a base log's lowest confident mode at 38 Hz,
#: 3.1 times the fit, on development variant 5 of :mod:`tvist.sim.family`). Over variants
#: 0-9 the median was 0.29-0.80 of the fitted base stiffness and this quantile 0.51-1.17.
START_QUANTILE = 0.75
#: Passes of match-then-fit.
MATCH_PASSES = 4
#: Smallest relative standard errors believed of a local fit (ω, ζ), as the label-based fit.
MIN_RELATIVE_SE = (1.0e-3, 1.0e-2)
ROBUST_SCALE = 0.02
STIFFNESS_SPAN = 100.0
MIN_LOAD_SPAN_NM = 1.0
#: Identified modes a joint or hinge must dominate (the largest share of the strain energy
#: of the model's mode each is matched to) for its damper to get load terms: a joint whose
#: mode rang at fewer poses has a constant damper only (its load terms would not be
#: determined).
MIN_DOMINATED_FOR_LOAD_LAW = 5
#: Share of the identified modes a fit matches below which it is reported as doubtful
#: (:func:`unmatched_warning`). Every fit of the development variants 0-9 of
#: :mod:`tvist.sim.family` and of the default twin's demo campaign matched 98-100 %; one that
#: ended in a wrong basin (variant 5 with wrist 1 excited, started from the median of
#: :func:`_start`'s values) matched 70 % at 4.1 % RMS, its base mode 2-3 times off.
MIN_MATCHED_SHARE = 0.9
#: Largest damping ratio a constant-only damper may give its own coordinate at its smallest
#: inertia (:func:`_damping_caps`): the family's joint modes span ζ 0.03-0.64, no real gear
#: is overdamped.
MAX_OWN_ZETA = 0.9
DAMPING_LOAD = {0: 1}
_LSQ = {"x_scale": "jac", "xtol": 1e-10, "ftol": 1e-10, "gtol": 1e-10, "max_nfev": 200}
_INVALID = 10.0


def match_modes(obs: ObservedModes, model: ModelModes, f_tol: float = F_TOL) -> np.ndarray:
    """``(k,)`` index of the model eigenmode (frequency rank) each identified mode is, or -1.

    One to one within each pose's excitation log, least total cost (module docstring)."""
    out = np.full(obs.wn_rad_s.size, -1)
    groups: dict[tuple[int, int], list[int]] = {}
    for i, (p, log) in enumerate(zip(obs.pose, obs.log_joint, strict=True)):
        groups.setdefault((int(p), int(log)), []).append(i)
    for (p, _), rows in groups.items():
        wn = model.wn_rad_s[p]
        cost = (np.log(obs.wn_rad_s[rows][:, None] / wn[None, :]) / f_tol) ** 2
        d = obs.direction[rows]
        cos = np.abs(d @ model.flange_direction[p].T)
        sin2 = np.clip(1.0 - cos**2, 0.0, 1.0)
        cost = cost + np.where(np.isfinite(sin2), sin2 / D_TOL**2, 0.0)
        cost = np.where(np.isfinite(cost), cost, 1e6)
        r, c = optimize.linear_sum_assignment(cost)
        for a, b in zip(r, c, strict=True):
            if cost[a, b] <= GATE:
                out[rows[a]] = b
    return out


@dataclass
class _Model:
    """Parameters of one candidate model: flexible joints and link hinges (by column of the
    model arrays, a hinge by its first coordinate's), and kept terms."""

    flex: tuple[int, ...]
    load_terms: dict[int, list[int]]  # joint -> stiffness load terms kept (1: |L|, 2: L²)
    damped: tuple[int, ...]
    damp_terms: dict[int, list[int]]  # joint -> damping terms kept (0, 1, 2)
    hinges: tuple[int, ...] = ()  # the keys in ``flex`` that are link hinges
    damping_load: dict[int, int] = field(default_factory=dict)  # column -> load column

    def stiffness_names(self) -> list[tuple[int, int]]:
        return [(j, 0) for j in self.flex] + [(j, t) for j in self.flex for t in self.load_terms[j]]

    def damping_names(self) -> list[tuple[int, int]]:
        return [(j, t) for j in self.damped for t in self.damp_terms[j]]


def _entries(
    model: _Model, x_stiff: np.ndarray, x_damp: np.ndarray | None = None
) -> list[dict[str, Any]]:
    """Map entries of parameters ``x_stiff`` (``log k_0`` then ``a_t``, ``k_t = k_0 a_t``) and
    ``x_damp`` (N m s/rad)."""
    k = {j: [0.0, 0.0, 0.0] for j in model.flex}
    c = {j: [0.0, 0.0, 0.0] for j in model.flex}
    names = model.stiffness_names()
    for v, (j, t) in zip(x_stiff, names, strict=True):
        if t == 0:
            k[j][0] = math.exp(v)
    for v, (j, t) in zip(x_stiff, names, strict=True):
        if t:
            k[j][t] = k[j][0] * v
    if x_damp is not None:
        for v, (j, t) in zip(x_damp, model.damping_names(), strict=True):
            c[j][t] = float(v)
    out = []
    for j in model.flex:
        # A hinge: both of its coordinates, with the same laws.
        for column in (j, j + 1) if j in model.hinges else (j,):
            out.append(
                {
                    "joint": column,
                    "stiffness_nm_per_rad": k[j],
                    "damping_nms_per_rad": c[j],
                    "damping_load_joint": model.damping_load.get(j, column),
                }
            )
    return out


def _mass_ff(obs: ObservedModes, model: _Model) -> np.ndarray:
    """The mass-matrix blocks on the model's flexible coordinates (a hinge's two)."""
    idx = np.asarray([e["joint"] for e in _entries(model, np.zeros(len(model.stiffness_names())))])
    return obs.mass_kg_m2[:, idx][:, :, idx]


@dataclass(frozen=True)
class _UndampedFrequencies:
    """The undamped frequencies of a model at the poses of the fit, for many stiffness
    parameter vectors at once: what the frequency fit evaluates, its Jacobian included.

    The stiffness of each entry (column) is :func:`joint_laws`'s, with the same operations in
    the same order, the smoothed loads computed once: the frequencies equal those of
    :func:`undamped_frequencies` of :func:`joint_laws` of :func:`_entries` to the bit."""

    flex: tuple[int, ...]
    names: list[tuple[int, int]]
    keys: list[int]  # (m,) the key of each entry column (a hinge's two columns share it)
    load_nm: np.ndarray  # (n, m) gravity torque on each entry column
    smooth_load_nm: np.ndarray  # (n, m) its smoothed absolute value |L|_s
    mass_ff: np.ndarray  # (n, m, m)

    @classmethod
    def of(cls, obs: ObservedModes, model: _Model) -> _UndampedFrequencies:
        # The columns in the order of _entries: a hinge's two coordinates after its key.
        pairs = [(j, c) for j in model.flex for c in ((j, j + 1) if j in model.hinges else (j,))]
        keys, columns = [j for j, _ in pairs], [c for _, c in pairs]
        load = obs.gravity_torque_nm[:, columns]
        smooth = np.column_stack([_smooth_abs(obs.gravity_torque_nm[:, c]) for c in columns])
        return cls(model.flex, model.stiffness_names(), keys, load, smooth, _mass_ff(obs, model))

    def stiffness_many(self, x_stiff: np.ndarray) -> np.ndarray:
        """``(b, n, m)`` stiffness (N m/rad) of ``b`` parameter vectors ``(b, p)``: the
        arithmetic of :func:`_entries` (``math.exp``, then ``k_t = k_0 a_t``) and
        :func:`joint_laws`, per element."""
        key = {j: i for i, j in enumerate(self.flex)}
        laws = np.zeros((x_stiff.shape[0], 3, len(self.flex)))
        for i, (j, t) in enumerate(self.names):
            if t == 0:
                laws[:, 0, key[j]] = [math.exp(v) for v in x_stiff[:, i]]
        for i, (j, t) in enumerate(self.names):
            if t:
                laws[:, t, key[j]] = laws[:, 0, key[j]] * x_stiff[:, i]
        per_column = laws[:, :, [key[j] for j in self.keys]]
        k0, k1, k2 = (per_column[:, t, None, :] for t in range(3))
        return k0 + k1 * self.smooth_load_nm + k2 * self.load_nm * self.load_nm

    def wn_many(self, x_stiff: np.ndarray) -> np.ndarray:
        """``(b, n, m)`` undamped frequencies (rad/s, increasing) of ``(b, p)`` parameters."""
        return undamped_frequencies(self.mass_ff, self.stiffness_many(x_stiff))


def _sigma(value: np.ndarray, se: np.ndarray, floor: float) -> np.ndarray:
    """Relative measurement error of each identification: its stated standard error, floored."""
    rel = se / value
    return np.where(np.isfinite(rel), np.maximum(rel, floor), floor)


@dataclass
class _FreqFit:
    x: np.ndarray
    assignment: np.ndarray
    residual: np.ndarray  # relative ω error over σ, matched modes (others NaN), (k,)
    jac: np.ndarray
    cost: float


def _fit_frequencies(
    obs: ObservedModes, model: _Model, x0: np.ndarray, bounds: tuple[list, list]
) -> _FreqFit:
    """Match-then-fit passes of the stiffness on the matched frequencies (undamped modes)."""
    frequencies = _UndampedFrequencies.of(obs, model)
    sigma = _sigma(obs.wn_rad_s, obs.wn_se_rad_s, MIN_RELATIVE_SE[0])
    x = np.clip(x0, *bounds)
    assignment = np.full(obs.wn_rad_s.size, -1)
    res = None
    for i in range(MATCH_PASSES):
        entries = _entries(model, x)
        modes = model_modes(entries, obs.mass_kg_m2, obs.gravity_torque_nm, obs.jacobian)
        # A wide first pairing (the start may be 20 % off), the stated one after.
        new = match_modes(obs, modes, f_tol=3 * F_TOL if i == 0 else F_TOL)
        if res is not None and np.array_equal(new, assignment):
            break
        assignment = new
        used = assignment >= 0
        if used.sum() <= x.size:
            break
        rows, cols = obs.pose[used], assignment[used]

        def residual_many(v: np.ndarray, rows=rows, cols=cols, used=used) -> np.ndarray:
            wn = frequencies.wn_many(v)[:, rows, cols]
            r = (wn / obs.wn_rad_s[used] - 1.0) / sigma[used]
            return np.where(np.isfinite(r), r, _INVALID / MIN_RELATIVE_SE[0])

        # The forward-difference Jacobian least_squares would take (jac="2-point"), from one
        # batched evaluation instead of one per parameter.
        res = optimize.least_squares(
            lambda v, f=residual_many: f(v[None, :])[0],
            x,
            jac=lambda v, f=residual_many: forward_difference_jacobian(f, v, bounds),
            bounds=bounds,
            loss="soft_l1",
            f_scale=ROBUST_SCALE / 1e-3,
            **_LSQ,
        )
        x = res.x
    full = np.full(obs.wn_rad_s.size, np.nan)
    if res is None:
        return _FreqFit(x, assignment, full, np.zeros((0, x.size)), math.inf)
    used = assignment >= 0
    full[used] = res.fun if res.fun.size == used.sum() else np.nan
    return _FreqFit(x, assignment, full, res.jac, float(res.cost))


def _truncated_chi2(fit: _FreqFit, scale: float) -> float:
    """Σ min((r/scale)², GATE) over every identified mode (unmatched ones count GATE)."""
    r = fit.residual / scale
    return float(np.sum(np.where(np.isfinite(r), np.minimum(r * r, GATE), GATE)))


def _robust_scale(r: np.ndarray) -> float:
    r = r[np.isfinite(r)]
    return max(1.4826 * float(np.median(np.abs(r))), 1e-6) if r.size else 1.0


def _elbow_column(obs: ObservedModes) -> int | None:
    """Column of the robot's elbow (:attr:`ObservedModes.elbow_joint`), ``None`` if none."""
    return None if obs.elbow_joint is None else obs.column(obs.elbow_joint)


def _start(obs: ObservedModes, model: _Model, elbow_factor: float) -> dict[int, float]:
    """Start stiffnesses (by column): base and shoulder ``ω² M_jj`` of the lowest mode of
    their own log, the :data:`START_QUANTILE` over the poses, the robot's elbow
    ``elbow_factor`` times the shoulder's, the other joints' (wrists, an upper-arm rotation)
    own mode at :data:`WRIST_START_HZ`, a link hinge's at :data:`HINGE_START_HZ`.

    Why a high quantile: with diagonal springs ``K`` the lowest eigenvalue is at most the
    Rayleigh quotient of joint ``j`` alone, ``ω_1² <= K_jj / M_jj``, so every pose's value is
    a lower bound of the joint's stiffness, reached where its mode is the joint's own. The
    median fell 2-3 times short on the base (its log's lowest mode is often the shoulder's
    or the elbow's), a start from which the fit could end in another basin: on development
    variant 5 with wrist 1 excited too, 49 of 70 identified modes matched at 4.1 % RMS, and 69
    at 0.5 % from this start."""
    start: dict[int, float] = {}
    for j in ALWAYS_FLEXIBLE:
        c = obs.column(j)
        vals = []
        for p in range(obs.n_poses):
            sel = (obs.pose == p) & (obs.log_joint == j)
            if sel.any():
                vals.append(obs.wn_rad_s[sel].min() ** 2 * obs.mass_kg_m2[p, c, c])
        start[c] = float(np.quantile(vals, START_QUANTILE)) if vals else 2.0e4
    for j in model.flex:
        if j == _elbow_column(obs) and j not in model.hinges:
            start[j] = elbow_factor * start[obs.column(1)]
        elif j not in start:
            hz = HINGE_START_HZ if j in model.hinges else WRIST_START_HZ
            inertia = float(np.median(obs.mass_kg_m2[:, j, j]))
            start[j] = (2 * math.pi * hz) ** 2 * inertia
    return start


def _stiffness_bounds(model: _Model, start: Mapping[int, float]) -> tuple[list, list]:
    span = math.log(STIFFNESS_SPAN)
    lo, hi = [], []
    for j, t in model.stiffness_names():
        if t == 0:
            lo.append(math.log(start[j]) - span)
            hi.append(math.log(start[j]) + span)
        else:
            lo.append(0.0)
            hi.append(np.inf)
    return lo, hi


def _best_frequency_fit(
    obs: ObservedModes, model: _Model, warm: Mapping[tuple[int, int], float] | None = None
) -> tuple[_FreqFit, dict[int, float]]:
    """The stiffness fit of ``model`` from every start (:data:`ELBOW_STARTS`), least cost;
    with ``warm`` (parameter values by name, e.g. of a larger model's fit) from that alone."""
    best, best_start = None, {}
    elbow = _elbow_column(obs)
    factors = ELBOW_STARTS if elbow is not None and elbow in model.flex and warm is None else (1.0,)
    for factor in factors:
        start = _start(obs, model, factor)
        names = model.stiffness_names()
        x0 = np.array([math.log(start[j]) if t == 0 else 0.0 for j, t in names])
        if warm is not None:
            x0 = np.array([warm.get(n, v) for n, v in zip(names, x0, strict=True)])
        fit = _fit_frequencies(obs, model, x0, _stiffness_bounds(model, start))
        # Ranked by the truncated χ² in common units (matched share and residual size).
        if best is None or _truncated_chi2(fit, 1.0) < _truncated_chi2(best, 1.0):
            best, best_start = fit, start
    assert best is not None
    return best, best_start


def _standard_errors(jac: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Per-parameter standard errors ``√diag(σ² (JᵀJ)⁺)`` over the inliers (within 4 robust
    standard deviations), :func:`tvist.ident.standard_errors.standard_errors`.

    A parameter the data do not determine (the load terms of a joint no identified mode
    involves, a wrist's on a UR) makes ``J`` singular; its standard error is infinite, and
    it must not make the others infinite, which would read as every load term being weak."""
    sigma = _robust_scale(residual)
    keep = np.abs(residual) <= 4 * sigma
    if keep.sum() > jac.shape[1]:
        jac, residual = jac[keep], residual[keep]
    return standard_errors(jac, residual)


def _candidate(obs: ObservedModes, flex: Sequence[int]) -> _Model:
    """The model with flexible columns ``flex`` (joints and hinge keys), every load term
    where the load spans :data:`MIN_LOAD_SPAN_NM` (none for a hinge)."""
    hinges = tuple(j for j in flex if j in _hinge_keys(obs))
    load = {
        j: [1, 2]
        if j not in hinges and np.ptp(np.abs(obs.gravity_torque_nm[:, j])) > MIN_LOAD_SPAN_NM
        else []
        for j in flex
    }
    damping_load = {obs.column(j): obs.column(k) for j, k in DAMPING_LOAD.items()}
    return _Model(tuple(flex), load, (), {}, hinges, damping_load)


def _hinge_keys(obs: ObservedModes) -> dict[int, int]:
    """Key (first coordinate's column) -> link of every hinge the arrays of ``obs`` have."""
    return {obs.hinge_columns(link)[0]: link for link in obs.hinged_links}


def _name(obs: ObservedModes, key: int) -> dict[str, int]:
    """``{"joint": j}`` or ``{"link": l}`` of a column key."""
    link = _hinge_keys(obs).get(key)
    if link is not None:
        return {"link": link}
    return {"joint": int(np.flatnonzero([obs.column(j) == key for j in range(obs.q.shape[1])])[0])}


def _drop_weak_load_terms(
    obs: ObservedModes, model: _Model, drop_t: float, dropped: list[str]
) -> tuple[_FreqFit, dict[int, float]]:
    while True:
        fit, start = _best_frequency_fit(obs, model)
        used = np.isfinite(fit.residual)
        se = _standard_errors(fit.jac, fit.residual[used])
        weak = [
            (abs(fit.x[i]) / se[i] if se[i] > 0 else math.inf, i)
            for i, (_, t) in enumerate(model.stiffness_names())
            if t
        ]
        weak = [w for w in weak if w[0] < drop_t]
        if not weak:
            return fit, start
        j, t = model.stiffness_names()[min(weak)[1]]
        model.load_terms[j].remove(t)
        dropped.append(f"stiffness term {t} of joint {_name(obs, j)['joint']}")


def _select_links(
    obs: ObservedModes, candidates: Sequence[int], drop_t: float
) -> tuple[_Model, _FreqFit, dict[int, float], list[dict[str, Any]], list[str]]:
    """The model of every candidate joint, bending links kept by backward elimination with the
    likelihood-ratio test (module doc)."""
    dropped: list[str] = []
    model = _candidate(obs, candidates)
    fit, start = _drop_weak_load_terms(obs, model, drop_t, dropped)
    tests: list[dict[str, Any]] = []
    repairs = 0
    while True:
        scale = _robust_scale(fit.residual)
        chi2_full = _truncated_chi2(fit, scale)
        trials = []
        nested: dict[int, _FreqFit] = {}
        for j in model.flex:
            if j not in model.hinges:  # joints stay flexible (module doc)
                continue
            rigid = _candidate(obs, [i for i in model.flex if i != j])
            for i in rigid.flex:
                rigid.load_terms[i] = list(model.load_terms[i])
            warm = dict(zip(model.stiffness_names(), fit.x, strict=True))
            trial, _ = _best_frequency_fit(obs, rigid, warm)
            dof = 1 + len(model.load_terms[j])
            gain = _truncated_chi2(trial, scale) - chi2_full
            p_value = float(stats.chi2.sf(max(gain, 0.0), dof))
            trials.append({**_name(obs, j), "chi2_gain": gain, "dof": dof, "p_value": p_value})
            trials[-1]["_key"] = j
            nested[j] = trial
        # A model fits at least as well as any model nested in it (a stiff hinge is a rigid
        # link): a nested fit that is better shows a local optimum of this one, which is
        # then refitted from the nested fit's solution before any test is judged.
        better = min(trials, key=lambda t: t["chi2_gain"], default=None)
        if (
            better is not None
            and better["chi2_gain"] < -NESTED_TOLERANCE
            and repairs < MAX_NESTED_REPAIRS
        ):
            repairs += 1
            key = better["_key"]
            refit = _refit_from_nested(obs, model, start, nested[key], key)
            chi2_refit = _truncated_chi2(refit, scale)
            if chi2_refit < chi2_full:
                fit = refit
                better["refit_chi2"] = [chi2_full, chi2_refit]
                tests.append(better)
                continue
        weakest = max(trials, key=lambda t: t["p_value"], default=None)
        tests += trials
        if weakest is None or weakest["p_value"] < JOINT_P:
            for t in tests:
                t.pop("_key", None)
            return model, fit, start, tests, dropped
        weakest["made_rigid"] = True
        dropped.append(f"{_what(obs, weakest['_key'])} made rigid (p = {weakest['p_value']:.2g})")
        # The remaining columns start again from every load term: a term dropped while the
        # link could bend (its hinge taking up what the term would fit) may matter without it.
        model = _candidate(obs, [i for i in model.flex if i != weakest["_key"]])
        dropped = [d for d in dropped if not d.startswith("stiffness term")]
        fit, start = _drop_weak_load_terms(obs, model, drop_t, dropped)


def _what(obs: ObservedModes, key: int) -> str:
    """``"link l"`` or ``"joint j"`` of a column key."""
    ((kind, index),) = _name(obs, key).items()
    return f"{kind} {index}"


def _refit_from_nested(
    obs: ObservedModes, model: _Model, start: Mapping[int, float], nested: _FreqFit, key: int
) -> _FreqFit:
    """The frequency fit of ``model`` from the solution of ``nested`` (the fit of ``model``
    without the hinge ``key``), the hinge from each of :data:`NESTED_HINGE_STARTS` times its
    start stiffness; the least truncated χ² (in common units) of them."""
    names = model.stiffness_names()
    warm = dict(zip([n for n in names if n[0] != key], nested.x, strict=True))
    best = None
    for factor in NESTED_HINGE_STARTS:
        warm[(key, 0)] = math.log(factor * start[key])
        x0 = np.array([warm[n] for n in names])
        fit = _fit_frequencies(obs, model, x0, _stiffness_bounds(model, start))
        if best is None or _truncated_chi2(fit, 1.0) < _truncated_chi2(best, 1.0):
            best = fit
    assert best is not None
    return best


def _fit_damping(
    obs: ObservedModes, model: _Model, x_stiff: np.ndarray, assignment: np.ndarray
) -> np.ndarray:
    """Damping coefficients of ``model.damped`` (:func:`_damping_fit`)."""
    return _damping_fit(obs, model, x_stiff, assignment)[0]


def _damping_fit(
    obs: ObservedModes, model: _Model, x_stiff: np.ndarray, assignment: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Damping coefficients by bounded linear least squares on the matched ζ (damping
    projected on undamped modes; at least 0, at most :func:`_damping_caps`), and the
    relative ζ residuals of the matched modes: each column is the model's ζ with one unit
    coefficient."""
    used = assignment >= 0
    columns = []
    for name in model.damping_names():
        x_damp = np.array([1.0 if n == name else 0.0 for n in model.damping_names()])
        modes = model_modes(
            _entries(model, x_stiff, x_damp),
            obs.mass_kg_m2,
            obs.gravity_torque_nm,
            obs.jacobian,
        )
        # Unit coefficients are light damping: the projection is linear in them.
        columns.append(modes.zeta[obs.pose[used], assignment[used]])
    a = np.column_stack(columns) / obs.zeta[used][:, None]
    ok = np.all(np.isfinite(a), axis=1)
    scale = np.linalg.norm(a[ok], axis=0)
    scale[scale == 0] = 1.0
    cap = _damping_caps(obs, model, x_stiff) * scale
    fit = optimize.lsq_linear(a[ok] / scale, np.ones(int(ok.sum())), bounds=(0.0, cap))
    return fit.x / scale, fit.fun


def _select_dampers(
    obs: ObservedModes,
    model: _Model,
    x_stiff: np.ndarray,
    assignment: np.ndarray,
    base: Sequence[int],
) -> list[dict[str, Any]]:
    """Sets ``model.damped``: ``base``, then, one at a time and the strongest first, each
    other flexible coordinate whose constant damper lowers the damping fit's truncated χ²
    (relative ζ residuals in units of the ``base`` fit's robust scatter, each term capped at
    :data:`GATE`) by more than the ``1 − JOINT_P`` quantile of χ² with one degree of freedom.
    Returns the tests (``key``: a column, ``chi2_gain``, ``kept``)."""

    def chi2(damped: Sequence[int], scale: float) -> tuple[float, float]:
        model.damped = tuple(j for j in model.flex if j in damped)
        r = _damping_fit(obs, model, x_stiff, assignment)[1]
        return float(np.sum(np.minimum((r / scale) ** 2, GATE))), _robust_scale(r)

    chosen = list(base)
    _, scale = chi2(chosen, 1.0)
    current, _ = chi2(chosen, scale)
    threshold = float(stats.chi2.isf(JOINT_P, 1))
    tests: list[dict[str, Any]] = []
    while True:
        gains = {j: current - chi2([*chosen, j], scale)[0] for j in model.flex if j not in chosen}
        if not gains:
            break
        best = max(gains, key=lambda j: gains[j])
        kept = gains[best] > threshold
        tests.append({"key": best, "chi2_gain": gains[best], "kept": kept})
        if not kept:
            break
        chosen.append(best)
        current -= gains[best]
    model.damped = tuple(j for j in model.flex if j in chosen)
    return tests


def _damping_caps(obs: ObservedModes, model: _Model, x_stiff: np.ndarray) -> np.ndarray:
    """Upper bound of each damping coefficient (``model.damping_names()`` order), N m s/rad:
    for a damper with a constant term only (a joint that dominates few identified modes, or
    a hinge) the value at which its coordinate alone, at the smallest inertia it has over
    the poses, would be damped at :data:`MAX_OWN_ZETA` (``c = 2 ζ √(k J)``); unbounded for
    the others. Such a damper is weakly determined: unbounded, it can take an overdamped
    value that shifts its neighbours' modes (with a damper at every joint, on the default
    twin's demo campaign wrist 1's went to 1.4e5 N m s/rad, 380 times critical)."""
    names = model.stiffness_names()
    k0 = {j: math.exp(v) for (j, t), v in zip(names, x_stiff, strict=True) if t == 0}
    caps = []
    for j, _ in model.damping_names():
        if model.damp_terms[j] != [0]:
            caps.append(np.inf)
            continue
        coords = [j, j + 1] if j in model.hinges else [j]
        inertia = min(float(np.min(obs.mass_kg_m2[:, c, c])) for c in coords)
        caps.append(2.0 * MAX_OWN_ZETA * math.sqrt(k0[j] * inertia))
    return np.array(caps)


def _refine(
    obs: ObservedModes,
    model: _Model,
    x_stiff: np.ndarray,
    x_damp: np.ndarray,
    assignment: np.ndarray,
    start: Mapping[int, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Stiffness and damping together on the matched ω and ζ, exact damped modes, each
    quantity in units of its robust scatter at the start."""
    used = assignment >= 0
    rows, cols = obs.pose[used], assignment[used]
    sw = _sigma(obs.wn_rad_s, obs.wn_se_rad_s, MIN_RELATIVE_SE[0])[used]
    sz = _sigma(obs.zeta, obs.zeta_se, MIN_RELATIVE_SE[1])[used]
    n_s = x_stiff.size

    def relative(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        modes = model_modes(
            _entries(model, v[:n_s], v[n_s:]), obs.mass_kg_m2, obs.gravity_torque_nm, obs.jacobian
        )
        return (
            modes.wn_rad_s[rows, cols] / obs.wn_rad_s[used] - 1.0,
            modes.zeta[rows, cols] / obs.zeta[used] - 1.0,
        )

    lo, hi = _stiffness_bounds(model, start)
    lo, hi = lo + [0.0] * x_damp.size, hi + list(_damping_caps(obs, model, x_stiff))
    x = np.clip(np.concatenate([x_stiff, x_damp]), lo, hi)
    ew, ez = relative(x)
    scale_w, scale_z = _robust_scale(ew / sw), _robust_scale(ez / sz)

    def residual(v: np.ndarray) -> np.ndarray:
        rw, rz = relative(v)
        r = np.concatenate([rw / (sw * scale_w), rz / (sz * scale_z)])
        return np.where(np.isfinite(r), r, _INVALID / MIN_RELATIVE_SE[0])

    res = optimize.least_squares(residual, x, bounds=(lo, hi), loss="soft_l1", f_scale=4.0, **_LSQ)
    return res.x[:n_s], res.x[n_s:], res.jac, res.fun


@dataclass(frozen=True)
class AllModesFit:
    """The fitted map and what the fit found.

    Attributes
    ----------
    entries
        The flexible coordinates' laws in the columns of ``observed``'s arrays (a hinge's two
        coordinates each with the hinge's laws): what :func:`model_modes` evaluates.
    map_fields
        The modal map's ``flex_joints`` (by the robot's joint indices) and, if a link bends,
        ``link_hinges``.
    observed
        The identified modes the fit used.
    assignment
        ``(k,)`` model eigenmode (frequency rank) of each identified mode, -1: no match.
    statistics
        JSON-ready: coefficients with standard errors, the joint tests, dropped terms,
        matched share and residuals.
    """

    entries: list[dict[str, Any]]
    map_fields: dict[str, Any]
    observed: ObservedModes
    assignment: np.ndarray
    statistics: dict[str, Any]

    def coordinate_names(self) -> list[str]:
        """Per entry of :attr:`entries`: ``"joint j"`` or ``"link l bending"`` (axis ``a``:
        0 about the axis parallel to the link's joint, 1 across it)."""
        keys = _hinge_keys(self.observed)
        out = []
        for e in self.entries:
            c = int(e["joint"])
            if c in keys:
                out.append(f"link {keys[c]} bending (axis 0)")
            elif c - 1 in keys:
                out.append(f"link {keys[c - 1]} bending (axis 1)")
            else:
                out.append(f"joint {_name(self.observed, c)['joint']}")
        return out

    def model_modes(self, obs: ObservedModes | None = None) -> ModelModes:
        """The fitted model's every mode at the poses of ``obs`` (default: the fit's)."""
        o = self.observed if obs is None else obs
        return model_modes(self.entries, o.mass_kg_m2, o.gravity_torque_nm, o.jacobian)


def fit_all_modes(
    records: Sequence[Mapping[str, Any]] | ObservedModes,
    robot_name: str = "ur5e",
    *,
    candidate_joints: Sequence[int] | None = None,
    drop_t: float = 3.0,
    include_low_confidence: bool = False,
    candidate_links: Sequence[int] | None = None,
) -> AllModesFit:
    """Fit the flexible joints' laws, and of the bending links among ``candidate_links``
    their hinges', to every identified mode (module docstring); ``candidate_joints``
    ``None``: :func:`flexible_candidates` of the robot, ``candidate_links`` ``None``:
    :func:`bending_candidates`.

    Raises
    ------
    ValueError
        Unusable records, too few identified modes, or candidates without base and shoulder.
    """
    if candidate_joints is None:
        candidate_joints = flexible_candidates(robot_name)
    candidates = tuple(sorted(int(j) for j in candidate_joints))
    if not set(ALWAYS_FLEXIBLE) <= set(candidates):
        raise ValueError(f"candidate joints must include base and shoulder, got {candidates}")
    if candidate_links is None:
        candidate_links = bending_candidates(robot_name)
    links = tuple(sorted(int(link) for link in candidate_links))
    if isinstance(records, ObservedModes):
        obs = records
    else:
        obs = observed_modes(
            records,
            robot_name,
            include_low_confidence=include_low_confidence,
            hinged_links=links,
        )
    if obs.wn_rad_s.size < 2 * len(candidates) + 2:
        raise ValueError(
            f"{obs.wn_rad_s.size} usable identified modes, need at least "
            f"{2 * len(candidates) + 2} to fit {len(candidates)} flexible joints"
        )
    columns = [obs.column(j) for j in candidates] + list(_hinge_keys(obs))
    model, fit, start, joint_tests, dropped = _select_links(obs, sorted(columns), drop_t)

    # Dampers: base and shoulder and any joint or hinge dominating identified modes, then
    # the others the damping ratios show (module docstring, "Which joints are damped").
    modes = model_modes(_entries(model, fit.x), obs.mass_kg_m2, obs.gravity_torque_nm, obs.jacobian)
    used = fit.assignment >= 0
    dominant = modes.dominant_joint()[obs.pose[used], fit.assignment[used]]
    always = {obs.column(j) for j in ALWAYS_FLEXIBLE}

    def dominates(j: int) -> int:
        return int(np.sum(np.isin(dominant, [j, j + 1] if j in model.hinges else [j])))

    base = [j for j in model.flex if j in always or dominates(j) >= MIN_DOMINATED_FOR_LOAD_LAW]
    for j in model.flex:
        spans = np.ptp(np.abs(obs.gravity_torque_nm[:, model.damping_load.get(j, j)]))
        with_load = j in base and j not in model.hinges and spans > MIN_LOAD_SPAN_NM
        model.damp_terms[j] = [0, 1, 2] if with_load else [0]
    damper_tests = _select_dampers(obs, model, fit.x, fit.assignment, base)
    x_damp = _fit_damping(obs, model, fit.x, fit.assignment)
    x_stiff, assignment = fit.x, fit.assignment
    for _ in range(MATCH_PASSES):
        x_stiff, x_damp, jac, fun = _refine(obs, model, x_stiff, x_damp, assignment, start)
        modes = model_modes(
            _entries(model, x_stiff, x_damp), obs.mass_kg_m2, obs.gravity_torque_nm, obs.jacobian
        )
        new = match_modes(obs, modes)
        if np.array_equal(new, assignment):
            break
        assignment = new
    entries = _entries(model, x_stiff, x_damp)
    se = _standard_errors(jac, fun)
    names = [("stiffness", j, t) for j, t in model.stiffness_names()]
    names += [("damping", j, t) for j, t in model.damping_names()]
    coefficients = []
    by_joint = {e["joint"]: e for e in entries}
    for i, (what, j, t) in enumerate(names):
        law = "stiffness_nm_per_rad" if what == "stiffness" else "damping_nms_per_rad"
        value = by_joint[j][law][t]
        # d k_0 = k_0 d(log k_0); k_t = k_0 a_t: d k_t ≈ k_0 d a_t.
        err = by_joint[j][law][0] * se[i] if what == "stiffness" else se[i]
        coefficients.append(
            {
                "what": what,
                **_name(obs, j),
                "term": ("at_zero", "per_nm", "per_nm2")[t],
                "value": float(value),
                "se": float(err) if math.isfinite(err) else None,
            }
        )
    used = assignment >= 0
    rel = modes.wn_rad_s[obs.pose[used], assignment[used]] / obs.wn_rad_s[used] - 1.0
    rel_zeta = modes.zeta[obs.pose[used], assignment[used]] / obs.zeta[used] - 1.0
    rel_zeta = rel_zeta[np.isfinite(rel_zeta)]
    statistics = {
        "robot": robot_name,
        "n_poses": obs.n_poses,
        "identified_modes": int(obs.wn_rad_s.size),
        "matched_modes": int(used.sum()),
        "flexible_joints": [_name(obs, j)["joint"] for j in model.flex if j not in model.hinges],
        "bending_links": [_name(obs, j)["link"] for j in model.hinges],
        "damped_joints": [
            _name(obs, j).get("joint") for j in model.damped if j not in model.hinges
        ],
        "joint_tests": joint_tests,
        "damper_tests": [
            {**_name(obs, t["key"]), "chi2_gain": t["chi2_gain"], "kept": t["kept"]}
            for t in damper_tests
        ],
        "joint_test_level": JOINT_P,
        "dropped": dropped,
        "coefficients": coefficients,
        "frequency_error_matched": {
            "rms": float(np.sqrt(np.mean(rel**2))) if rel.size else None,
            "max": float(np.max(np.abs(rel))) if rel.size else None,
        },
        "damping_error_matched": {
            "rms": float(np.sqrt(np.mean(rel_zeta**2))) if rel_zeta.size else None,
            "max": float(np.max(np.abs(rel_zeta))) if rel_zeta.size else None,
        },
    }
    return AllModesFit(entries, _map_fields(obs, model, entries), obs, assignment, statistics)


def _map_fields(
    obs: ObservedModes, model: _Model, entries: Sequence[Mapping[str, Any]]
) -> dict[str, Any]:
    """The modal map's ``flex_joints`` and ``link_hinges`` of the fitted ``entries``."""
    by_column = {e["joint"]: e for e in entries}
    flex = []
    hinges = []
    for j in model.flex:
        e = by_column[j]
        if j in model.hinges:
            hinges.append(
                {
                    "link": _name(obs, j)["link"],
                    "at_fraction": HINGE_AT_FRACTION,
                    "stiffness_nm_per_rad": float(e["stiffness_nm_per_rad"][0]),
                    "damping_nms_per_rad": float(e["damping_nms_per_rad"][0]),
                }
            )
        else:
            flex.append(
                {
                    **e,
                    "joint": _name(obs, j)["joint"],
                    "damping_load_joint": _name(obs, e["damping_load_joint"])["joint"],
                }
            )
    return {"flex_joints": flex, **({"link_hinges": hinges} if hinges else {})}


def unmatched_warning(statistics: Mapping[str, Any]) -> str | None:
    """What to tell a user of a fit (its ``statistics``) that matched fewer than
    :data:`MIN_MATCHED_SHARE` of the identified modes, ``None`` otherwise."""
    n, matched = statistics["identified_modes"], statistics["matched_modes"]
    if n == 0 or matched >= MIN_MATCHED_SHARE * n:
        return None
    return (
        f"only {matched} of {n} identified modes ({100 * matched / n:.0f} %) match an eigenmode "
        f"of the fitted model, where a fit that found the arm matches "
        f"{100 * MIN_MATCHED_SHARE:.0f} % or more: "
        "it may have settled on a wrong solution, or the records hold modes no model of the arm "
        "has; check the records' ringing modes before shaping with this map"
    )


def fitted_map(fit: AllModesFit, metadata: Mapping[str, Any] | None = None) -> ModalMap:
    """The :class:`~tvist.ModalMap` of ``fit``, shaping the modes
    :func:`tvist.ident.shaped_modes.physical_modes` says matter."""
    from tvist.ident.shaped_modes import physical_modes, shaping_field, with_coverage

    report = physical_modes(fit)
    shaping = shaping_field(report)
    meta = {"robot": fit.statistics["robot"], "source": "tvist.ident.fit_all_modes"}
    meta.update(metadata or {})
    meta["fit_statistics"] = {
        **fit.statistics,
        "physical_modes": with_coverage(report, shaping["shaped_modes"]),
    }
    return ModalMap(
        fit.map_fields["flex_joints"],
        metadata=meta,
        link_hinges=fit.map_fields.get("link_hinges"),
        **shaping,
    )
