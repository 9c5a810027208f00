"""What an ordinary move's log says about the modes at its end pose: the free decay after
the stop, fitted with the identification estimator.

After the reference stops, the arm rings freely at its end pose: ``ψ_j(t) = Σ_i A_ij
e^{-ζ_i ω_i t} cos(ω_{d,i} t + φ_ij)`` in the tangential direction of each mode joint ``j``
(eqs. 12-13, :func:`tvist.ident.preprocess.tangential_acceleration`). A one-sample pulse
through eq. 17, ``G(s) = (k_a s + k_b)/(s² + k_c s + k_d)``, has exactly that response after
the pulse (the free numerator sets amplitude and phase), so the decay is fitted by the same
output-error estimator as an excitation (:func:`tvist.ident.local_fit.fit_local`) with a pulse
at the stop as input and the pulse sample left out of the cost; its standard errors,
ringing SNR and low-confidence flags come with it. Where a second mode rings in the same
direction (the shoulder mode leaks into the base direction at most poses), the two-mode fit
of identification (:func:`tvist.ident.two_mode.fit_two_modes`) separates them.

A move that does not ring (every fit :data:`~tvist.ident.local_fit.NO_RINGING`) still says
something: with its acceleration at the stop at the noise level, the map that shaped it is
right at that pose (:mod:`tvist.learn.learner` uses it so).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tvist.ident.local_fit import FitOptions, LocalFit, fit_local
from tvist.ident.logs import Record
from tvist.ident.mode_estimates import TwoModeFit
from tvist.ident.preprocess import KinematicModel, tangential_acceleration
from tvist.ident.two_mode import fit_two_modes

__all__ = ["DECAY_S", "Decay", "ModeObservation", "observe_decay", "stop_index"]

#: A reference has stopped once it stays within this distance of its last sample (rad): far
#: below any move, above the 6-7 significant digits a CSV log keeps of an angle.
STOP_TOL_RAD = 1e-6
#: Length of the decay fitted after the stop, s (the estimator needs 1 s besides the pulse;
#: modes of the arm decay by ``e^{-ζω·1 s} < 1e-2`` within it).
DECAY_S = 1.02
#: Samples from the stop that are left out of the cost (the pulse and the one after it).
PULSE_SAMPLES = 2
#: A free decay never grows: a peak later than :data:`EARLY_S` after the stop larger than
#: :data:`GROWTH_FACTOR` times the early peak (and above :data:`SPIKE_NOISE_FACTOR` times the
#: noise) is an outside force (a contact, a collision).
EARLY_S = 0.1
GROWTH_FACTOR = 1.5
SPIKE_NOISE_FACTOR = 8.0
#: Settings of the decay fit: the identification defaults, no timing offset (the pulse is
#: placed at the stop, the response's phase is free).
DECAY_FIT_OPTIONS = FitOptions(max_delay_s=0.0)


@dataclass(frozen=True)
class ModeObservation:
    """One mode ringing at the end pose of a move.

    Attributes
    ----------
    joint
        The mode joint whose tangential direction the mode was fitted in (0 base, 1 shoulder).
    wn_rad_s, zeta
        Natural frequency (rad/s) and damping ratio.
    wn_se_rad_s, zeta_se
        Standard errors of the fit.
    ringing_snr_db
        Energy the mode explains over the energy left, dB.
    low_confidence, reasons
        The estimator's flags.
    """

    joint: int
    wn_rad_s: float
    zeta: float
    wn_se_rad_s: float
    zeta_se: float
    ringing_snr_db: float
    low_confidence: bool
    reasons: tuple[str, ...] = ()

    def to_json(self) -> dict:
        return {
            "joint": self.joint,
            "wn_rad_s": self.wn_rad_s,
            "zeta": self.zeta,
            "wn_se_rad_s": self.wn_se_rad_s,
            "zeta_se": self.zeta_se,
            "ringing_snr_db": self.ringing_snr_db,
            "low_confidence": self.low_confidence,
            "reasons": list(self.reasons),
        }


@dataclass(frozen=True)
class Decay:
    """The free decay after one move's stop.

    Attributes
    ----------
    t_stop_s
        When the reference stopped, s.
    q_end
        End pose (the reference's last sample), rad.
    modes
        Modes that ring above the noise and passed the estimator's checks.
    flagged
        Fits that rang but were flagged low-confidence (not used to learn).
    amplitude_m_s2
        Largest tangential acceleration of the mode joints in the first :data:`EARLY_S` after
        the stop, m/s² (the residual vibration the map left).
    noise_m_s2
        Robust noise level of the tangential acceleration in the last half of the decay, m/s².
    problem
        Why the decay cannot be used (an outside force), or ``None``.
    fits
        The single-mode fit in each mode joint's direction, by joint (for inspection).
    """

    t_stop_s: float
    q_end: np.ndarray
    modes: tuple[ModeObservation, ...] = ()
    flagged: tuple[ModeObservation, ...] = ()
    amplitude_m_s2: float = 0.0
    noise_m_s2: float = 0.0
    problem: str | None = None
    fits: dict = field(default_factory=dict, repr=False)

    @property
    def rings(self) -> bool:
        """Whether any mode rings above the noise."""
        return bool(self.modes or self.flagged)


def stop_index(target_q: np.ndarray, tol_rad: float = STOP_TOL_RAD) -> int:
    """Index of the first sample from which the reference stays within ``tol_rad`` of its last
    sample.

    Raises
    ------
    ValueError
        If the reference never moves, or is still moving at the last sample.
    """
    q = np.asarray(target_q, dtype=float)
    away = np.flatnonzero(np.max(np.abs(q - q[-1]), axis=1) > tol_rad)
    if away.size == 0:
        raise ValueError("the reference never moves: no stop to learn from")
    last = int(away[-1])
    if last >= q.shape[0] - 2:
        raise ValueError("the reference is still moving at the end of the log")
    return last + 1


#: The estimator's flag for an input with few acceleration changes: a free decay is the
#: response to one pulse by construction, so the flag says nothing about it.
_PULSE_FLAG = "weak excitation"
#: The estimator's energy flags, judged over its whole window (:func:`_ringing_window_flags`
#: judges them again over the part of a decay where the mode rings).
_ENERGY_FLAGS = ("weak ringing", "poor fit")
#: Shortest ringing window, s (five periods of a 50 Hz mode).
MIN_RINGING_WINDOW_S = 0.1


def _ringing_window_flags(
    fit: LocalFit, psi: np.ndarray, dt: float, noise: float, options: FitOptions
) -> tuple[str, ...]:
    """The estimator's energy flags (ringing SNR, fit percentage) judged over the ringing
    window: from the pulse until the fitted mode's envelope falls to the noise level
    (at least :data:`MIN_RINGING_WINDOW_S`).

    The estimator judges them over its whole 1 s window; a free decay with ``ζ ω_n`` of
    10-30 /s is below the noise after 0.1-0.3 s, and the noise of the rest of the window
    dilutes the ratio though it carries no information about the mode either way (its
    frequency standard error, which the learner weights by, is the estimator's over the whole
    window). The mode's response is the least-squares damped cosine of the fitted ``ω_n, ζ``
    (free amplitude and phase, an offset) on the samples after the pulse.
    """
    t = np.arange(psi.size) * dt
    sigma = fit.zeta * fit.wn_rad_s
    wd = fit.wn_rad_s * np.sqrt(max(1.0 - fit.zeta**2, 1e-12))
    env = np.exp(-sigma * t)
    basis = np.column_stack([env * np.cos(wd * t), env * np.sin(wd * t), np.ones_like(t)])
    used = slice(PULSE_SAMPLES, None)
    coef, *_ = np.linalg.lstsq(basis[used], psi[used], rcond=None)
    amplitude = float(np.hypot(coef[0], coef[1]))
    t_ring = math.log(max(amplitude / max(noise, 1e-300), 1.0)) / max(sigma, 1e-9)
    n = min(max(int(round(max(t_ring, MIN_RINGING_WINDOW_S) / dt)), PULSE_SAMPLES + 3), psi.size)
    y = psi[PULSE_SAMPLES:n] - coef[2]
    residual = y - basis[PULSE_SAMPLES:n, :2] @ coef[:2]
    noise_energy = max(float(residual @ residual), 1e-300)
    ringing_energy = max(float(y @ y) - noise_energy, 0.0)
    snr_db = 10.0 * math.log10(max(ringing_energy / noise_energy, 1e-10))
    fit_percent = 100.0 * (1.0 - math.sqrt(noise_energy / max(float(y @ y), 1e-300)))
    reasons = []
    if snr_db < options.min_confident_snr_db:
        reasons.append(
            f"weak ringing: the mode's ringing is {snr_db:+.1f} dB against the residual noise "
            f"over its {n * dt:.2f} s ringing window (needs at least "
            f"{options.min_confident_snr_db:+.0f} dB)"
        )
    if fit_percent < options.min_fit_percent:
        reasons.append(
            f"poor fit: {fit_percent:.1f} % < {options.min_fit_percent:.0f} % over the "
            f"{n * dt:.2f} s ringing window"
        )
    return tuple(reasons)


def _observation(
    fit: LocalFit, joint: int, window_flags: tuple[str, ...] | None = None
) -> ModeObservation:
    """``fit`` as an observation; its energy flags replaced by ``window_flags`` if given."""
    reasons = tuple(
        r
        for r in fit.reasons
        if not r.startswith(_PULSE_FLAG)
        and (window_flags is None or not r.startswith(_ENERGY_FLAGS))
    )
    reasons += window_flags or ()
    return ModeObservation(
        joint=joint,
        wn_rad_s=float(fit.wn_rad_s),
        zeta=float(fit.zeta),
        wn_se_rad_s=float(fit.wn_se_rad_s),
        zeta_se=float(fit.zeta_se),
        ringing_snr_db=float(fit.ringing_snr_db),
        low_confidence=bool(reasons),
        reasons=reasons,
    )


def _split_observations(
    split: TwoModeFit, joint: int, options: FitOptions
) -> list[ModeObservation]:
    """Both modes of a significant two-mode fit, flagged where the frequency is uncertain
    beyond the estimator's limit."""
    out = []
    for m in split.modes:
        rel_se = m.wn_se_rad_s / m.wn_rad_s
        reasons = (
            (f"uncertain frequency: standard error {100 * rel_se:.2f} % of ω_n (two-mode fit)",)
            if rel_se > options.max_wn_rel_se
            else ()
        )
        out.append(
            ModeObservation(
                joint=joint,
                wn_rad_s=float(m.wn_rad_s),
                zeta=float(m.zeta),
                wn_se_rad_s=float(m.wn_se_rad_s),
                zeta_se=float(m.zeta_se),
                ringing_snr_db=float(10 * np.log10(1.0 / split.rss_ratio)),
                low_confidence=bool(reasons),
                reasons=reasons,
            )
        )
    return out


def _robust_std(x: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


def observe_decay(
    record: Record,
    robot: KinematicModel,
    mode_joints: tuple[int, ...] = (0, 1),
    *,
    decay_s: float = DECAY_S,
    options: FitOptions = DECAY_FIT_OPTIONS,
) -> Decay:
    """Fit the free decay after the stop of ``record`` in the direction of every mode joint.

    Parameters
    ----------
    record
        Log of one move (SI units, rest before the move, at least ``decay_s`` after the stop).
    robot
        Kinematic model with the declared payload.
    mode_joints
        The map's mode joints; one fit per tangential direction.

    Raises
    ------
    ValueError
        No stop, too short a decay, too little standstill for the gravity estimate, a flange on
        a joint axis.
    """
    k0 = stop_index(record.target_q)
    dt = record.dt_s
    n = int(round(decay_s / dt))
    if k0 + n > record.n_samples:
        raise ValueError(
            f"the log ends {(record.n_samples - k0) * dt:.2f} s after the stop; learning needs "
            f"{decay_s:.2f} s of free decay"
        )
    u = np.zeros(n)
    u[0] = 1.0
    mask = np.ones(n, dtype=bool)
    mask[:PULSE_SAMPLES] = False
    n_early = max(int(round(EARLY_S / dt)), 1)
    modes: list[ModeObservation] = []
    flagged: list[ModeObservation] = []
    fits: dict[int, LocalFit] = {}
    amplitude, noise = 0.0, 0.0
    for j in mode_joints:
        psi = tangential_acceleration(record, j, robot).psi[k0 : k0 + n]
        psi = psi - np.median(psi[n // 2 :])
        early = float(np.max(np.abs(psi[:n_early])))
        late = float(np.max(np.abs(psi[n_early:])))
        sigma = _robust_std(psi[n // 2 :])
        amplitude, noise = max(amplitude, early), max(noise, sigma)
        if late > GROWTH_FACTOR * early and late > SPIKE_NOISE_FACTOR * sigma:
            t_peak = (n_early + int(np.argmax(np.abs(psi[n_early:])))) * dt
            return Decay(
                float(record.t_s[k0]),
                np.array(record.target_q[-1]),
                amplitude_m_s2=amplitude,
                noise_m_s2=noise,
                problem=(
                    f"the vibration grows {t_peak:.2f} s after the stop ({late:.3g} m/s² after "
                    f"{early:.3g} m/s²): an outside force (contact?), not a free decay"
                ),
            )
        fit = fit_local(u, psi, dt, mask=mask, options=options, joint=j)
        fits[j] = fit
        if fit.no_ringing:
            continue
        split = fit_two_modes(
            u, psi, dt, fit, mask=mask, f_min_hz=options.f_min_hz, f_max_hz=options.f_max_hz
        )
        found = _split_observations(split, j, options) if split.significant else []
        if not found:
            found = [_observation(fit, j, _ringing_window_flags(fit, psi, dt, sigma, options))]
        for obs in found:
            (flagged if obs.low_confidence else modes).append(obs)
    return Decay(
        float(record.t_s[k0]),
        np.array(record.target_q[-1]),
        tuple(modes),
        tuple(flagged),
        amplitude,
        noise,
        None,
        fits,
    )
