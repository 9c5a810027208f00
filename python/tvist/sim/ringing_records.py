"""Pose records with a ``ringing`` list made from a twin's true modes (eigen-analysis), for
developing and testing the modal fit without running the excitation campaign.

At each pose the twin's modes below ``max_freq_hz`` (:func:`tvist.sim.family.modes_of`) are
what an identification of the base (shoulder) excitation log would report, with these
imperfections (all seeded):

- a mode rings in a log only if the excited joint holds at least ``min_share`` of its strain
  energy (a mode the excitation hardly moves is below noise), at most three per log, the
  most excited first;
- noise on ``ω_n`` (``noise_wn``, relative, normal), ``ζ`` (``noise_zeta``) and the flange
  direction (``noise_direction_rad`` about a random axis), each stated as the entry's
  standard error;
- a share ``low_confidence_share`` of the entries flagged low-confidence, their frequency
  off by ``outlier_error``;
- a share ``outlier_share`` of confident entries off by ``outlier_error`` (a fit that merged
  two neighbours without noticing).

The records also hold ``true_modes`` (every mode, as the campaign writes them) and the
``modes`` list of the label-based fit (the most excited mode of each log).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from tvist.sim.family import TrueMode, Variant, modes_of

__all__ = ["ringing_records", "true_mode_dicts"]


def true_mode_dicts(modes: Iterable[TrueMode]) -> list[dict[str, Any]]:
    """``true_modes`` entries of a record (INTERFACES: ``freq_hz``, ``zeta``,
    ``joint_shares``, ``flange_direction``, ``link_share``)."""
    return [
        {
            "freq_hz": float(m.freq_hz),
            "zeta": float(m.zeta),
            "joint_shares": [float(v) for v in m.joint_shares],
            "flange_direction": [float(v) for v in m.flange_direction],
            "link_share": float(m.link_share),
        }
        for m in modes
    ]


def _rotate(d: np.ndarray, angle: float, rng: np.random.Generator) -> np.ndarray:
    axis = np.cross(d, rng.normal(size=3))
    axis /= np.linalg.norm(axis)
    out = d * np.cos(angle) + np.cross(axis, d) * np.sin(angle)
    return out * np.sign(out[np.argmax(np.abs(out))])


def ringing_records(
    variant: Variant,
    poses: Sequence[tuple[str, np.ndarray, float, Sequence[float]]],
    *,
    seed: int = 0,
    max_freq_hz: float = 60.0,
    min_share: float = 0.05,
    noise_wn: float = 0.005,
    noise_zeta: float = 0.05,
    noise_direction_rad: float = 0.08,
    low_confidence_share: float = 0.05,
    outlier_share: float = 0.02,
    outlier_error: float = 0.08,
) -> list[dict[str, Any]]:
    """Records at ``poses`` ``[(key, q, payload_kg, payload_com_m), ...]`` (see module)."""
    rng = np.random.default_rng(seed)
    twins: dict[tuple, Any] = {}
    out = []
    for key, q, payload_kg, com in poses:
        tk = (float(payload_kg), tuple(float(v) for v in com))
        if tk not in twins:
            twins[tk] = variant.twin(payload_kg, com)
        truth = modes_of(twins[tk], q, max_freq_hz=max_freq_hz)
        ringing, labelled = [], []
        for log in (0, 1):
            excited = sorted(
                (m for m in truth if m.joint_shares[log] >= min_share),
                key=lambda m: -m.joint_shares[log],
            )[:3]
            for rank, m in enumerate(excited):
                wn = 2 * np.pi * m.freq_hz * (1 + noise_wn * rng.normal())
                zeta = m.zeta * (1 + noise_zeta * rng.normal())
                low = bool(rng.uniform() < low_confidence_share)
                wrong = low or bool(rng.uniform() < outlier_share)
                if wrong:
                    wn *= 1 + outlier_error * rng.choice((-1.0, 1.0))
                entry = {
                    "log_joint": log,
                    "wn_rad_s": float(wn),
                    "zeta": float(abs(zeta)),
                    "wn_se_rad_s": float(noise_wn * wn),
                    "zeta_se": float(noise_zeta * zeta),
                    "amplitude_m_s2": float(m.joint_shares[log]),
                    "flange_direction": _rotate(
                        np.asarray(m.flange_direction), noise_direction_rad * rng.normal(), rng
                    ).tolist(),
                    "low_confidence": low,
                    "reasons": ["below noise"] if low else [],
                }
                ringing.append(entry)
                if rank == 0:
                    labelled.append(
                        {
                            "joint": log,
                            **{k: entry[k] for k in ("wn_rad_s", "zeta", "wn_se_rad_s")},
                            "zeta_se": entry["zeta_se"],
                            "low_confidence": low,
                        }
                    )
        out.append(
            {
                "key": key,
                "q": [float(v) for v in q],
                "payload_kg": float(payload_kg),
                "payload_com_m": [float(v) for v in com],
                "modes": labelled,
                "ringing": ringing,
                "true_modes": true_mode_dicts(truth),
            }
        )
    return out
