"""Learn the modal map from the ringing after ordinary moves: a bounded, gated recursive
estimate of per-joint stiffness and damping scale factors and load-stiffening gains.

**What is estimated.** An ordinary move shows the modes at its end pose only, and only those
that ring: the base and shoulder modes (:mod:`tvist.learn.decay`). A handful of such moves
cannot determine the 3 load-law coefficients of every flexible joint (30 numbers for the
demo's five joints), but they do determine how much stiffer or softer each joint is than the
map says, and how much more it stiffens with load. The state is therefore ``θ = [ln s_k(j)
for every flexible joint j] + [ln s_c(j) for every mode joint j] + [g(j) for every loaded
flexible joint j]``: joint ``j``'s stiffness law is ``s_k(j) (k_j(L) + max(g(j), 0) k_j(0)
|L| / L_ref)`` (:data:`LOAD_REF_NM`; a gear that stiffens with load more than the prior says,
e.g. a strain-wave gear, whose tangent stiffness can triple at rated torque) and its damping
law ``s_c(j) c_j(L)``. A joint is loaded if its gravity torque varies by more than
:data:`MIN_LOAD_SPAN_NM` over the workspace (not the base, whose axis is vertical). Joints
that no observed mode depends on keep their prior values: the estimator's prior holds them.
A map's bending links (``link_hinges``) are kept as the prior has them, with the hinged arm
in every evaluation: their stiffness is not learned.

**Prior.** A modal map is the prior as it is. A paper10 map (the paper's published map) is
first converted into the modal map whose laws fit its modes along the paper's test motions
(:mod:`tvist.learn.prior`), with a prior uncertainty widened by the conversion's error.

**How.** An extended Kalman filter on ``θ`` with the prior map at ``θ = 0`` and
:data:`PRIOR_LOG_SIGMA`; each observed mode gives ``ω_n`` and ``ζ`` with the estimator's
standard errors widened by the map form's own error (:data:`MODEL_WN_REL_SIGMA`,
:data:`MODEL_ZETA_REL_SIGMA`); the measurement function is the map's modes at the end pose
(the Rust eigenproblem), its Jacobian by finite differences. A move that does not ring says
the map is right at its end pose to within what a ZV shaper tolerates
(:data:`QUIET_WN_REL_SIGMA`). Safety:

- an observation whose innovation is implausible (normalised innovation squared above the
  :data:`GATE_PROBABILITY` quantile) is not used; if a payload other than the declared one
  explains it better than the estimate's own uncertainty at that pose does (the estimate's
  modes, paired one to one, and its covariance, as in the gate; a fit of a mode the decay
  cannot tell from its neighbour weighed with their separation), the payload change is
  reported (:class:`PayloadReport`); fits that ring but are too uncertain to learn from are
  checked the same way (a report, never learned from);
- every step is bounded to :data:`MAX_STEP_SIGMAS` prior standard deviations per parameter
  (a shortened gain, whose covariance keeps the uncertainty of the step not taken);
- the load-stiffening gains stay ``>= 0`` (a step that would make one negative is projected
  back onto ``g = 0``, the parameters it covaries with taking up the difference), so the
  filter never sits where the map does not depend on a gain and keeps seeing its
  uncertainty: a mode observed at a heavier load than any before is learned from, not
  mistaken for a payload change;
- the map (:attr:`MapLearner.map`) takes the estimate only when it is statistically
  significant (a likelihood-ratio test on the modes observed so far,
  :data:`SIGNIFICANCE_PROBABILITY`) and the predicted residual vibration (the
  ZV shaper of the map's modes on the observed modes, :func:`tvist.prv`) over all moves seen
  so far decreases;
- a log with wrong units, a misplaced column, an outside force, or only flagged fits is
  rejected with its reason and never touches the estimate.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy import optimize, stats

import tvist
from tvist.ident.logs import Record, read_rtde_csv
from tvist.learn.decay import Decay, ModeObservation, observe_decay
from tvist.learn.poses import random_poses
from tvist.learn.prior import ConvertedPrior, converted_prior_log_sigma, modal_prior_from_paper10
from tvist.maps.modal import ModalMap
from tvist.maps.paper10 import DynamicMap
from tvist.robots import Payload, Robot
from tvist.units import UnitError, check_log

__all__ = ["MapLearner", "Observation", "PayloadReport"]

#: Prior uncertainty of every log scale factor (0.2: a map may be ~20 % off in stiffness,
#: e.g. identified on another arm of the same type; 7-10 % in frequency).
PRIOR_LOG_SIGMA = 0.2
#: Relative error of the map form itself at a pose, added to the estimator's standard errors:
#: the gear laws' first-order modal map of the twin is 2 % off in the base frequency at the
#: folded pose Q3 with exact stiffness; ζ is 20 % off there.
MODEL_WN_REL_SIGMA = 0.01
MODEL_ZETA_REL_SIGMA = 0.15
#: A move that does not ring: the map's frequencies at its end pose are right to within this
#: (a ZV shaper leaves ~16 % of the vibration at 10 % frequency error, which at the twin's
#: accelerometer noise can already be below the noise after an ordinary move).
QUIET_WN_REL_SIGMA = 0.10
#: ... and a move counts as not ringing only if its largest acceleration in the first 0.1 s
#: after the stop is within this multiple of the noise (50 samples of white noise peak at
#: about 2.5 standard deviations).
QUIET_NOISE_FACTOR = 3.0
#: Observations with a normalised innovation squared above this chi-square quantile are not
#: used (inconsistent with the map and its uncertainty).
GATE_PROBABILITY = 0.999
#: The estimate replaces the map when it lowers the misfit of the observed modes by more than
#: this chi-square quantile (one degree of freedom).
SIGNIFICANCE_PROBABILITY = 0.95
#: Largest change of any parameter per observation, in prior standard deviations (0.5: 0.1,
#: ~10 % stiffness, at :data:`PRIOR_LOG_SIGMA`).
MAX_STEP_SIGMAS = 0.5
#: Load of the load-stiffening term, N m: ``g = 1`` doubles the stiffness at this load.
LOAD_REF_NM = 100.0
#: Prior uncertainty of the load-stiffening gains ``g`` (prior mean 0: the prior map's law).
PRIOR_LOAD_SIGMA = 0.5
#: A joint whose gravity torque varies by less than this over the workspace has no load
#: stiffening to learn, N m.
MIN_LOAD_SPAN_NM = 5.0
#: Relative finite-difference step of the Jacobian.
_FD_STEP = 1e-4
#: Two predicted modes closer than this frequency ratio are told apart by the direction they
#: ring in, farther ones by frequency.
CLOSE_MODES_RATIO = 1.1
#: Flags of a fit that rings but is too uncertain to learn from (:meth:`MapLearner.observe`
#: still checks it for a payload change).
_UNCERTAINTY_FLAGS = ("uncertain frequency", "uncertain damping")
#: ... if its frequency's standard error is below this fraction of ω_n ...
FLAGGED_MAX_WN_REL_SE = 0.05
#: A payload estimate that differs from the declared one by less than this is no change, kg.
MIN_PAYLOAD_CHANGE_KG = 0.5
#: Step of the payload search, kg.
PAYLOAD_GRID_KG = 0.25


@dataclass(frozen=True)
class PayloadReport:
    """Observed modes that the map explains only with another payload.

    Attributes
    ----------
    declared_kg, estimate_kg
        The declared payload and the one that explains the observed modes best, kg.
    shift_percent
        Mean relative difference of the observed natural frequencies from the map's, %.
    alternatives_kg
        Other payloads that explain them as well within the measurement's uncertainty (one
        mode seen: the shoulder mode at a light payload can be the base mode at a heavy one).
    """

    declared_kg: float
    estimate_kg: float
    shift_percent: float
    alternatives_kg: tuple[float, ...] = ()

    @property
    def message(self) -> str:
        way = "lower" if self.shift_percent < 0 else "higher"
        fits = " or ".join(f"{m:.1f} kg" for m in (self.estimate_kg, *self.alternatives_kg))
        return (
            f"modes {abs(self.shift_percent):.0f} % {way} than the map predicts at "
            f"{self.declared_kg:g} kg: payload changed? (the modes fit {fits})"
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "declared_kg": self.declared_kg,
            "estimate_kg": self.estimate_kg,
            "shift_percent": self.shift_percent,
            "alternatives_kg": list(self.alternatives_kg),
            "message": self.message,
        }


@dataclass(frozen=True)
class Observation:
    """What one log taught.

    Attributes
    ----------
    source
        The log (a file name, or ``"<record>"``).
    accepted
        Whether the log was used by the estimate.
    reason
        Why it was rejected, or what it contributed.
    decay
        The fitted free decay (``None`` if the log could not be read).
    map_updated
        Whether :attr:`MapLearner.map` changed.
    predicted_residual_before, predicted_residual_after
        Mean predicted residual vibration (fraction of unshaped) of the map's ZV shaper on the
        modes of the moves seen so far, before and after this log.
    payload
        A suspected payload change, or ``None``.
    scales
        The learned map's log scale factors after this log (:attr:`MapLearner.names`).
    """

    source: str
    accepted: bool
    reason: str
    decay: Decay | None = None
    map_updated: bool = False
    predicted_residual_before: float = math.nan
    predicted_residual_after: float = math.nan
    payload: PayloadReport | None = None
    scales: np.ndarray | None = field(default=None, repr=False)

    def to_json(self) -> dict[str, Any]:
        d = self.decay
        return {
            "source": self.source,
            "accepted": self.accepted,
            "reason": self.reason,
            "map_updated": self.map_updated,
            "modes": [] if d is None else [m.to_json() for m in d.modes],
            "flagged_modes": [] if d is None else [m.to_json() for m in d.flagged],
            "residual_amplitude_m_s2": None if d is None else d.amplitude_m_s2,
            "predicted_residual_before": _json(self.predicted_residual_before),
            "predicted_residual_after": _json(self.predicted_residual_after),
            "payload": None if self.payload is None else self.payload.to_json(),
        }


def _json(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _log_record(log: Any) -> tuple[Record, str]:
    """A unit-checked SI record from a path, a :class:`Record` or a twin run."""
    if isinstance(log, (str, Path)):
        return read_rtde_csv(log), str(log)
    record = log if isinstance(log, Record) else Record.from_rtde_fields(log)
    columns = {
        "target_q": record.target_q,
        "target_qd": record.target_qd,
        "target_qdd": record.target_qdd,
        "actual_q": record.actual_q,
        "actual_tool_accelerometer": record.tool_accel,
    }
    check_log(record.t_s, columns)
    return record, "<record>"


@dataclass(frozen=True)
class _SeenMode:
    """An observed mode of an accepted move: the mode joint whose direction it was fitted in,
    ``ω_n`` (rad/s), ``ζ`` and their measurement standard deviations (model error
    included)."""

    joint: int
    wn: float
    zeta: float
    s_wn: float
    s_zeta: float


def _seen_mode(m: ModeObservation) -> _SeenMode:
    """``m`` with its measurement standard deviations: the fit's standard errors and the map
    form's error (:data:`MODEL_WN_REL_SIGMA`, :data:`MODEL_ZETA_REL_SIGMA`)."""
    return _SeenMode(
        m.joint,
        m.wn_rad_s,
        m.zeta,
        math.hypot(m.wn_se_rad_s, MODEL_WN_REL_SIGMA * m.wn_rad_s),
        math.hypot(m.zeta_se, MODEL_ZETA_REL_SIGMA * m.zeta),
    )


@dataclass
class _Seen:
    """An accepted move: its end pose and its observed modes. Which map mode each one is, is
    decided again at every parameter vector it is compared with (:meth:`MapLearner._pair`):
    a joint's mode is the one that strains it most, and near a veering of two modes a step
    of the estimate can hand that name from one branch to the other."""

    q_end: np.ndarray
    modes: list[_SeenMode] = field(default_factory=list)


class MapLearner:
    """Refine a modal map from the logs of ordinary moves (see the module docstring).

    Parameters
    ----------
    robot
        The rigid-body model with the declared payload.
    modal_map
        The prior map.
    prior_log_sigma
        Prior uncertainty of the log scale factors.
    """

    def __init__(
        self,
        robot: Robot,
        modal_map: ModalMap | DynamicMap,
        *,
        prior_log_sigma: float = PRIOR_LOG_SIGMA,
    ) -> None:
        self.converted: ConvertedPrior | None = None
        if isinstance(modal_map, DynamicMap):
            self.converted = modal_prior_from_paper10(robot, modal_map)
            prior_log_sigma = converted_prior_log_sigma(self.converted, prior_log_sigma)
            modal_map = self.converted.map
        if not isinstance(modal_map, ModalMap):
            raise ValueError("modal_map: the learner refines a modal map or a paper10 map")
        self.robot = robot
        self.prior = modal_map
        self.prior_log_sigma = prior_log_sigma
        self.flex_joints = [int(f["joint"]) for f in modal_map.flex_joints]
        #: The modes the learner observes and refines, named by the joint each strains most.
        self.mode_joints = _observed_mode_joints(modal_map)
        #: The learned map shapes what the prior shaped (its mode_joints or shaped_modes).
        self._shaping = (
            {"mode_joints": self.mode_joints}
            if modal_map.mode_joints is not None
            else {"shaped_modes": modal_map.shaped_modes}
        )
        span = np.ptp(
            robot.gravity_torque_many(random_poses(robot, 50, np.random.default_rng(0))), axis=0
        )
        self.load_joints = [j for j in self.flex_joints if span[j] > MIN_LOAD_SPAN_NM]
        self.names = (
            [f"stiffness scale, joint {j}" for j in self.flex_joints]
            + [f"damping scale, joint {j}" for j in self.mode_joints]
            + [f"load stiffening, joint {j}" for j in self.load_joints]
        )
        sigma = np.array(
            [prior_log_sigma] * (len(self.flex_joints) + len(self.mode_joints))
            + [PRIOR_LOAD_SIGMA] * len(self.load_joints)
        )
        self._max_step = MAX_STEP_SIGMAS * sigma
        self.theta = np.zeros(sigma.size)
        self.cov = np.diag(sigma**2)
        self._published = np.zeros(sigma.size)
        self._map = modal_map
        self._seen: list[_Seen] = []
        self.history: list[Observation] = []

    # -- the map at a parameter vector -------------------------------------------------------
    def map_at(self, theta: np.ndarray) -> ModalMap:
        """The prior map with its laws scaled by ``exp(theta)`` and stiffened with load by the
        gains ``theta`` holds for the loaded joints."""
        n_flex = len(self.flex_joints)
        n_log = n_flex + len(self.mode_joints)
        entries = copy.deepcopy(self.prior.flex_joints)
        for i, entry in enumerate(entries):
            j = entry["joint"]
            law = list(entry["stiffness_nm_per_rad"])
            if j in self.load_joints:
                gain = max(float(theta[n_log + self.load_joints.index(j)]), 0.0)
                law[1] += gain * law[0] / LOAD_REF_NM
            scale_k = math.exp(theta[i])
            entry["stiffness_nm_per_rad"] = [v * scale_k for v in law]
            if j in self.mode_joints:
                scale_c = math.exp(theta[n_flex + self.mode_joints.index(j)])
                entry["damping_nms_per_rad"] = [v * scale_c for v in entry["damping_nms_per_rad"]]
        return self._with_prior_hinges(entries, self.mode_joints, self.prior.metadata)

    def _with_prior_hinges(self, flex_joints: list, *args: Any, **kwargs: Any) -> ModalMap:
        """A :class:`ModalMap` of ``flex_joints`` (other arguments as its own) with the prior's
        bending links, which the learner keeps as they are."""
        return ModalMap(flex_joints, *args, link_hinges=self.prior.link_hinges, **kwargs)

    def _modes(self, theta: np.ndarray, q: np.ndarray, robot: Robot | None = None) -> np.ndarray:
        return self.map_at(theta).modes_many(robot or self.robot, q[None, :])[0]

    def _all_modes(
        self, theta: np.ndarray, q: np.ndarray, robot: Robot | None = None
    ) -> np.ndarray:
        """Natural frequencies (rad/s) of the map's eigenmodes at ``theta``, pose ``q``: as many
        of the lowest as it has flexible joints (with bending links, of the hinged arm)."""
        every = self._with_prior_hinges(
            self.map_at(theta).flex_joints, shaped_modes=len(self.flex_joints)
        )
        return every.modes_many(robot or self.robot, q[None, :])[0, :, 0]

    @property
    def map(self) -> ModalMap:
        """The learned map (the prior until a significant, non-worsening update)."""
        return self._map

    @property
    def _n_log(self) -> int:
        return len(self.flex_joints) + len(self.mode_joints)

    @property
    def scales(self) -> dict[str, float]:
        """The learned map's scale factors and load-stiffening gains, by name."""
        n = self._n_log
        return {
            name: float(math.exp(v) if k < n else max(v, 0.0))
            for k, (name, v) in enumerate(zip(self.names, self._published, strict=True))
        }

    # -- predicted residual vibration -------------------------------------------------------
    def predicted_residual(self, theta: np.ndarray | None = None) -> float:
        """Mean residual vibration (fraction of unshaped) that the ZV shapers of the map at
        ``theta`` (default: the learned map) leave on the modes observed so far."""
        theta = self._published if theta is None else theta
        values = []
        for seen in self._seen:
            if not seen.modes:
                continue
            modes = self._modes(theta, seen.q_end)
            for i, m in zip(self._pairs(modes[:, 0], seen.modes), seen.modes, strict=True):
                design = tvist.shaper("zv", float(modes[i, 0]), float(min(modes[i, 1], 0.99)))
                values.append(tvist.prv(design, m.wn, m.zeta))
        return float(np.mean(values)) if values else math.nan

    # -- one log -----------------------------------------------------------------------------
    def observe(self, log: Any) -> Observation:
        """Learn from one move's log: a path to an RTDE CSV, a :class:`Record` or a twin run
        (:class:`tvist.sim.SimRecord`). Never raises for a bad log: it is rejected."""
        source = str(log) if isinstance(log, (str, Path)) else "<record>"
        before = self.predicted_residual()
        try:
            record, source = _log_record(log)
            decay = observe_decay(record, self.robot, tuple(self.mode_joints))
        except (UnitError, ValueError) as exc:
            return self._note(Observation(source, False, str(exc), None, False, before, before))
        if decay.problem is not None:
            return self._note(
                Observation(source, False, decay.problem, decay, False, before, before)
            )
        modes = self._assign(decay)
        if not modes:
            if decay.flagged:
                reasons = "; ".join(r for m in decay.flagged for r in m.reasons)
                payload = self._flagged_payload_check(decay)
                reason = f"low-confidence fit: {reasons}"
                if payload is not None:
                    reason = f"{payload.message}; not learned from ({reason})"
                return self._note(
                    Observation(source, False, reason, decay, False, before, before, payload)
                )
            if decay.amplitude_m_s2 > QUIET_NOISE_FACTOR * decay.noise_m_s2:
                return self._note(
                    Observation(
                        source,
                        False,
                        f"rings ({decay.amplitude_m_s2:.3g} m/s² at the stop, "
                        f"{decay.amplitude_m_s2 / decay.noise_m_s2:.1f} times the noise) but no "
                        "mode was fitted",
                        decay,
                        False,
                        before,
                        before,
                    )
                )
            z, h, r_diag, h_of = self._quiet_measurement(decay.q_end)
            what = (
                f"no ringing above noise ({decay.amplitude_m_s2:.3g} m/s² at the stop, noise "
                f"{decay.noise_m_s2:.3g}): the map is right here"
            )
            seen = _Seen(np.asarray(decay.q_end, dtype=float))
        else:
            seen = _Seen(np.asarray(decay.q_end, dtype=float), [_seen_mode(m) for _, m in modes])
            z, h, r_diag, h_of = self._mode_measurement(
                seen.q_end, [i for i, _ in modes], seen.modes
            )
            what = "modes " + ", ".join(
                f"joint {self.mode_joints[i]}: {m.wn_rad_s / (2 * math.pi):.2f} Hz, ζ {m.zeta:.3f}"
                for i, m in modes
            )
        jac = self._jacobian(h_of, h)
        s = jac @ self.cov @ jac.T + np.diag(r_diag)
        nu = z - h
        nis = float(nu @ np.linalg.solve(s, nu))
        if nis > stats.chi2.ppf(GATE_PROBABILITY, len(z)):
            payload = self._payload_check(seen.q_end, seen.modes) if modes else None
            reason = (
                payload.message
                if payload is not None
                else f"inconsistent with the map and its uncertainty (NIS {nis:.1f}): {what}"
            )
            return self._note(
                Observation(source, False, reason, decay, False, before, before, payload)
            )
        gain = self.cov @ jac.T @ np.linalg.inv(s)
        # A bounded step: the gain shortened so that no parameter moves by more than
        # MAX_STEP_SIGMAS prior standard deviations; the Joseph form below is the exact
        # covariance for any gain, so the estimate keeps the uncertainty of the step it did
        # not take.
        largest = float(np.max(np.abs(gain @ nu) / self._max_step))
        if largest > 1.0:
            gain = gain / largest
        ikh = np.eye(len(self.theta)) - gain @ jac
        self.cov = ikh @ self.cov @ ikh.T + gain @ np.diag(r_diag) @ gain.T
        self.theta = self._feasible(self.theta + gain @ nu)
        self._seen.append(seen)
        updated = self._maybe_publish()
        after = self.predicted_residual()
        return self._note(Observation(source, True, what, decay, updated, before, after))

    def _feasible(self, theta: np.ndarray) -> np.ndarray:
        """``theta`` with every negative load-stiffening gain set to zero and the other
        parameters moved by what they covary with it (the projection onto the constraint
        ``g >= 0`` in the metric of the inverse covariance).

        The map reads ``max(g, 0)``: a negative gain would leave the estimate where the map
        does not depend on it, so the Jacobian, the gate and the update would no longer see
        that joint's stiffening or its uncertainty (a mode observed at a load the map
        extrapolates to would then fail the gate instead of being learned from).
        """
        active = self._n_log + np.flatnonzero(theta[self._n_log :] < 0.0)
        if active.size == 0:
            return theta
        cross = self.cov[:, active]
        theta = theta - cross @ np.linalg.solve(self.cov[np.ix_(active, active)], theta[active])
        theta[active] = 0.0
        return theta

    def _note(self, obs: Observation) -> Observation:
        obs = replace(obs, scales=self._published.copy())
        self.history.append(obs)
        return obs

    def _pair(self, predicted_wn: np.ndarray, joint: int, wn: float) -> int:
        """Index of the map mode (of ``predicted_wn``, rad/s: the modes by mode joint, then
        optionally the map's other eigenmodes) that a mode of ``wn`` rad/s fitted in
        ``joint``'s direction is.

        A fit in the tangential direction of one mode joint may show another joint's mode (a
        shoulder mode leaks into the base direction at most poses), so a fit is the map mode
        nearest in frequency; where the modes of the mode joints are closer than
        :data:`CLOSE_MODES_RATIO`, frequency cannot tell and the direction decides.
        """
        named = predicted_wn[: len(self.mode_joints)]
        if float(np.max(named) / np.min(named)) < CLOSE_MODES_RATIO:
            return self.mode_joints.index(joint)
        return int(np.argmin(np.abs(np.log(wn / predicted_wn))))

    def _pairs(self, predicted_wn: np.ndarray, modes: Sequence[_SeenMode]) -> list[int]:
        """The map mode each of ``modes`` is (:meth:`_pair`), one to one: where two name the
        same map mode, the one nearer in frequency keeps it and the other is the nearest map
        mode left. ``modes`` are one fit per map mode at the parameter vector they were
        assigned at (:meth:`_assign`), but another parameter vector or payload can move two
        map modes across one fit's frequency."""
        wanted = [self._pair(predicted_wn, m.joint, m.wn) for m in modes]
        distance = [
            abs(math.log(m.wn / predicted_wn[i])) for m, i in zip(modes, wanted, strict=True)
        ]
        out = list(wanted)
        taken: set[int] = set()
        for k in sorted(range(len(modes)), key=distance.__getitem__):
            if out[k] in taken:
                free = [i for i in range(predicted_wn.size) if i not in taken]
                out[k] = min(
                    free, key=lambda i, wn=modes[k].wn: abs(math.log(wn / predicted_wn[i]))
                )
            taken.add(out[k])
        return out

    def _unresolved(self, q: np.ndarray) -> np.ndarray:
        """By map mode (mode joint): the largest relative separation of a neighbour that a
        free decay cannot tell it from, else 0.

        Two modes are resolved when their separation exceeds the sum of their half-power
        half-widths (``|ln(ω_i/ω_j)| > ζ_i + ζ_j``, the estimate's modes at ``q``). Closer,
        each direction rings with both and a fit in it is a blend of the two, its frequency
        off from either by up to their separation whatever its standard error says (on the
        twin, fits 3-10 standard errors off where the base and shoulder modes lie 6-13 %
        apart with ζ 0.14-0.24)."""
        wn, zeta = self._modes(self.theta, q).T
        out = np.zeros(wn.size)
        for i in range(wn.size):
            for j in range(wn.size):
                sep = abs(math.log(wn[i] / wn[j]))
                if j != i and sep < zeta[i] + zeta[j]:
                    out[i] = max(out[i], sep)
        return out

    def _assign(self, decay: Decay) -> list[tuple[int, ModeObservation]]:
        """The observed modes with the index of the map mode each one is (:meth:`_pair`), one
        per map mode (two fits of one mode: the one with the higher ringing SNR).

        Paired with the modes of the estimate, the map the gate and the update compare them
        with: the published map can name the modes the other way round at this pose (base
        and shoulder modes veer, and the estimate may have moved across), and a mode paired
        with the wrong one fails the gate or, once learned, is a misfit no update removes.
        """
        if not decay.modes:
            return []
        predicted = self._modes(self.theta, np.asarray(decay.q_end, dtype=float))[:, 0]
        chosen: dict[int, ModeObservation] = {}
        for m in decay.modes:
            i = self._pair(predicted, m.joint, m.wn_rad_s)
            if i not in chosen or m.ringing_snr_db > chosen[i].ringing_snr_db:
                chosen[i] = m
        return sorted(chosen.items())

    def _mode_measurement(self, q_end: np.ndarray, idx: Sequence[int], modes: Sequence[_SeenMode]):
        """The observed ``modes`` (``ω_n``, ``ζ`` of each) as a measurement of the map modes
        ``idx``, their variances the modes' measurement standard deviations squared."""
        z = np.array([v for m in modes for v in (m.wn, m.zeta)])
        r = np.array([v for m in modes for v in (m.s_wn**2, m.s_zeta**2)])
        q = np.asarray(q_end, dtype=float)

        def h_of(theta: np.ndarray) -> np.ndarray:
            modes_at = self._modes(theta, q)
            return np.array([v for i in idx for v in (modes_at[i, 0], modes_at[i, 1])])

        return z, h_of(self.theta), r, h_of

    def _quiet_measurement(self, q_end: np.ndarray):
        # The published map's shapers left no ringing: its frequencies are right here, in
        # order of frequency (the shaper cascade does not depend on which joint names which
        # mode, and near a veering the estimate may name them the other way round).
        q = np.asarray(q_end, dtype=float)
        published = np.sort(self._modes(self._published, q)[:, 0])

        def h_of(theta: np.ndarray) -> np.ndarray:
            return np.sort(self._modes(theta, q)[:, 0])

        r = (QUIET_WN_REL_SIGMA * published) ** 2
        return published, h_of(self.theta), r, h_of

    def _jacobian(self, h_of, h0: np.ndarray) -> np.ndarray:
        jac = np.empty((h0.size, self.theta.size))
        for k in range(self.theta.size):
            theta = self.theta.copy()
            theta[k] += _FD_STEP
            jac[:, k] = (h_of(theta) - h0) / _FD_STEP
        return jac

    def misfit(self, theta: np.ndarray) -> float:
        """Chi-square of the modes observed so far against the map at ``theta`` (each paired
        with the map mode it is at ``theta``, :meth:`_pair`)."""
        total = 0.0
        for seen in self._seen:
            if seen.modes:
                modes = self._modes(theta, seen.q_end)
                for i, m in zip(self._pairs(modes[:, 0], seen.modes), seen.modes, strict=True):
                    total += ((m.wn - modes[i, 0]) / m.s_wn) ** 2
                    total += ((m.zeta - modes[i, 1]) / m.s_zeta) ** 2
        return total

    def _maybe_publish(self) -> bool:
        # Likelihood-ratio test on the moves seen so far: the estimate explains them better
        # than the map by more than chance would (one degree of freedom: the observations move
        # the estimate along the few directions the observed modes depend on).
        gain = self.misfit(self._published) - self.misfit(self.theta)
        if gain <= stats.chi2.ppf(SIGNIFICANCE_PROBABILITY, 1):
            return False
        # Never worse: the estimate must lower the predicted residual vibration on the modes
        # of the moves seen so far (the first modes seen have none to compare with).
        new, old = self.predicted_residual(self.theta), self.predicted_residual(self._published)
        if math.isfinite(old) and not new < old:
            return False
        self._published = self.theta.copy()
        self._map = self.map_at(self._published)
        return True

    # -- payload ---------------------------------------------------------------------------
    def _flagged_payload_check(self, decay: Decay) -> PayloadReport | None:
        """A payload change shown by fits too uncertain to learn from: modes that ring
        (flagged only for the standard errors of their frequency or damping, not for weak
        ringing or a poor fit, the frequency's below :data:`FLAGGED_MAX_WN_REL_SE`), whose
        frequencies fail the gate of :meth:`observe` (paired one to one with the estimate's
        modes, :meth:`_pairs`; their standard errors and the map form's error, the
        estimate's uncertainty). A report only: such fits never touch the estimate."""
        ringing = [
            m
            for m in decay.flagged
            if all(r.startswith(_UNCERTAINTY_FLAGS) for r in m.reasons)
            and m.wn_se_rad_s < FLAGGED_MAX_WN_REL_SE * m.wn_rad_s
        ]
        if not ringing:
            return None
        q = np.asarray(decay.q_end, dtype=float)
        predicted = self._modes(self.theta, q)[:, 0]
        # Fits of one mode (within CLOSE_MODES_RATIO): the one with the smaller error; at
        # most one fit per map mode.
        distinct: list[ModeObservation] = []
        for m in sorted(ringing, key=lambda m: m.wn_se_rad_s / m.wn_rad_s):
            if len(distinct) < predicted.size and all(
                abs(math.log(m.wn_rad_s / d.wn_rad_s)) > math.log(CLOSE_MODES_RATIO)
                for d in distinct
            ):
                distinct.append(m)
        modes = [_seen_mode(m) for m in distinct]
        idx = self._pairs(predicted, modes)

        def h_of(theta: np.ndarray) -> np.ndarray:
            return self._modes(theta, q)[idx, 0]

        jac = self._jacobian(h_of, predicted[idx])
        nu = np.array([m.wn for m in modes]) - predicted[idx]
        r = np.array([m.s_wn**2 for m in modes])
        nis = float(nu @ np.linalg.solve(jac @ self.cov @ jac.T + np.diag(r), nu))
        if nis <= stats.chi2.ppf(GATE_PROBABILITY, len(idx)):
            return None
        return self._payload_check(q, modes)

    def _eigenmodes(self, theta: np.ndarray, q: np.ndarray, robot: Robot) -> np.ndarray:
        """Natural frequencies (rad/s) of the map at ``theta``: its modes by mode joint
        (:meth:`_modes`), then its other eigenmodes in order of frequency."""
        named = self._modes(theta, q, robot)[:, 0]
        others = list(self._all_modes(theta, q, robot))
        for wn in named:
            others.pop(int(np.argmin(np.abs(np.log(np.asarray(others) / wn)))))
        return np.concatenate([named, np.sort(others)])

    def _payload_check(self, q_end: np.ndarray, modes: Sequence[_SeenMode]) -> PayloadReport | None:
        """The payload that makes the estimate predict the observed ``modes`` (as the gate of
        :meth:`observe` weighed them: one fit per map mode, its standard error and the map
        form's error), if it differs from the declared one by more than
        :data:`MIN_PAYLOAD_CHANGE_KG` and the declared one explains them worse by more than
        the :data:`SIGNIFICANCE_PROBABILITY` chi-square quantile (one degree of freedom).

        The estimate, what the gate compared the modes with, predicts them at every candidate
        payload, weighted by the estimate's own uncertainty at this pose (its covariance
        through the modes' Jacobian; the published map is the estimate of fewer logs, and its
        modes with the estimate's covariance would be a map that nobody estimated). Which map
        mode an observed mode is depends on the payload (all of them move), so at every
        candidate the modes are paired again, one to one (:meth:`_pairs`), with the map's
        modes by mode joint and its other eigenmodes (a mode of a joint the map does not
        shape, a soft elbow at a folded pose, is no payload change). A grid over the payload
        (:data:`PAYLOAD_GRID_KG` steps up to twice the rated payload), refined around its
        local minima.
        """
        declared = self.robot.payload
        q = np.asarray(q_end, dtype=float)
        wn = np.array([m.wn for m in modes])
        # The fits' relative standard deviations, widened where the estimate's modes at the
        # declared payload lie too close to be told apart (:meth:`_unresolved`): such a fit
        # is a blend of the two, and a blend off the map by its separation is no payload.
        unresolved = self._unresolved(q)[self._pairs(self._modes(self.theta, q)[:, 0], modes)]
        measured = np.diag([(m.s_wn / m.wn) ** 2 for m in modes] + unresolved**2)
        # The estimate's own uncertainty at this pose, what it has not learned yet: the
        # covariance of its modes' log frequencies. Without it, a map a few per cent off an
        # arm it was not identified on is explained better by another payload than by its
        # own error.
        log_wn = np.log(self._eigenmodes(self.theta, q, self.robot))
        jac = self._jacobian(lambda t: np.log(self._eigenmodes(t, q, self.robot)), log_wn)
        map_cov = jac @ self.cov @ jac.T

        def assigned(mass: float) -> tuple[np.ndarray, list[int]]:
            payload = Payload(mass, tuple(declared.com_m), declared.inertia_kg_m2)
            pred = self._eigenmodes(self.theta, q, Robot(self.robot.params, payload))
            idx = self._pairs(pred, modes)
            return np.log(wn / pred[idx]), idx

        def misfit(mass: float) -> float:
            errors, idx = assigned(mass)
            return float(errors @ np.linalg.solve(map_cov[np.ix_(idx, idx)] + measured, errors))

        upper = 2.0 * max(float(self.robot.params.max_payload_kg), declared.mass_kg)
        grid = np.arange(0.0, upper + PAYLOAD_GRID_KG / 2, PAYLOAD_GRID_KG)
        values = np.array([misfit(m) for m in grid])
        # Local minima of the grid, refined; those within the chi-square quantile of the best.
        padded = np.concatenate(([np.inf], values, [np.inf]))
        minima = np.flatnonzero((values <= padded[:-2]) & (values <= padded[2:]))
        found = []
        for k in minima:
            lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
            best = optimize.minimize_scalar(misfit, bounds=(lo, hi), method="bounded")
            found.append((float(best.fun), float(best.x)))
        found.sort()
        limit = found[0][0] + stats.chi2.ppf(SIGNIFICANCE_PROBABILITY, 1)
        # The declared payload explains the modes as well (a likelihood-ratio test against
        # the best payload), or a payload that does lies within MIN_PAYLOAD_CHANGE_KG of it.
        if misfit(declared.mass_kg) <= limit:
            return None
        masses = [m for f, m in found if f <= limit]
        if any(abs(m - declared.mass_kg) < MIN_PAYLOAD_CHANGE_KG for m in masses):
            return None
        shift = 100.0 * float(np.mean(np.expm1(assigned(declared.mass_kg)[0])))
        return PayloadReport(float(declared.mass_kg), masses[0], shift, tuple(masses[1:]))

    # -- provenance ------------------------------------------------------------------------
    def provenance(self) -> dict[str, Any]:
        """What the learned map was learned from: logs with their verdicts, the scale factors
        (and their standard errors), the predicted residual."""
        se = np.sqrt(np.diag(self.cov))
        return {
            "prior_source": self.prior.metadata.get("source"),
            "logs": [
                {
                    "source": o.source,
                    "accepted": o.accepted,
                    "reason": o.reason,
                    "map_updated": o.map_updated,
                }
                for o in self.history
            ],
            "scale_factors": {
                name: {
                    "value": float(math.exp(v)),
                    "change_percent": 100.0 * math.expm1(v),
                    "log_se": float(s),
                }
                for name, v, s in zip(self.names[: self._n_log], self._published, se, strict=False)
            },
            # g: the joint's stiffness at LOAD_REF_NM of load is (1 + g) times the prior law's.
            "load_stiffening": {
                name: {"gain": max(float(v), 0.0), "se": float(s), "load_ref_nm": LOAD_REF_NM}
                for name, v, s in zip(
                    self.names[self._n_log :],
                    self._published[self._n_log :],
                    se[self._n_log :],
                    strict=True,
                )
            },
            "prior_conversion": None
            if self.converted is None
            else {
                "from": "paper10",
                "frequency_rms_percent": 100.0 * self.converted.wn_rel_rms,
                "frequency_max_percent": 100.0 * self.converted.wn_rel_max,
                "prior_log_sigma": self.prior_log_sigma,
            },
            "predicted_residual": _json(self.predicted_residual()),
            "predicted_residual_prior": _json(self.predicted_residual(np.zeros_like(self.theta))),
        }

    def learned_map(self) -> ModalMap:
        """The learned map with its provenance in ``metadata["learned"]``."""
        meta = dict(self.prior.metadata)
        meta["learned"] = self.provenance()
        meta["source"] = f"learned from {len(self.history)} logs; prior: {meta.get('source')}"
        return self._with_prior_hinges(self._map.flex_joints, metadata=meta, **self._shaping)


def _observed_mode_joints(modal_map: ModalMap) -> list[int]:
    """The joints whose modes the learner observes and refines: a joint-named map's
    ``mode_joints``; for a frequency-ranked map (``shaped_modes``) the joints of the physical
    modes its fit shaped (``metadata.fit_statistics.physical_modes``), else base and shoulder
    among its flexible joints."""
    if modal_map.mode_joints is not None:
        return [int(j) for j in modal_map.mode_joints]
    report = (modal_map.metadata.get("fit_statistics") or {}).get("physical_modes") or []
    shaped = [int(m["joint"]) for m in report if m.get("shaped") and "joint" in m]
    flex = [int(f["joint"]) for f in modal_map.flex_joints]
    joints = [j for j in shaped if j in flex] or [j for j in (0, 1) if j in flex]
    if not joints:
        raise ValueError("modal_map: the learner needs the base or the shoulder flexible")
    return sorted(joints)
