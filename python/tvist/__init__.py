"""tvist: time-varying multi-mode input shaping that stops robot arms from ringing.

Array layout everywhere: ``(n_samples, n_dof)``, time along rows. SI units, radians; the unit
is in the name (``dt_s``, ``wn_rad_s``, ``zeta``, ``payload_kg``).
"""

from __future__ import annotations

import enum

import numpy as np

from tvist import _core, robots
from tvist._core import ConstantModes, Impulses, TvShaper
from tvist.maps import DynamicMap, MapDynamics, ModalDynamics, ModalMap, dynamics_for, load_map
from tvist.ztdis import ZeroDelayResult, zero_delay

__all__ = [
    "MAX_DELAY_LINE_BYTES",
    "MAX_DOF",
    "MAX_LN_WN_RATE_PER_S",
    "MAX_MAP_FILE_BYTES",
    "MAX_MODES",
    "MAX_ZETA_RATE_PER_S",
    "REST_TOLERANCE",
    "SHAPERS",
    "ConstantModes",
    "DynamicMap",
    "Impulses",
    "MapDynamics",
    "ModalDynamics",
    "ModalMap",
    "Status",
    "TvShaper",
    "ZeroDelayResult",
    "convolve",
    "dynamics_for",
    "load_map",
    "prv",
    "robots",
    "shaper",
    "zero_delay",
]

#: Subpackages imported on first access (``tvist.sim`` etc.), so ``import tvist`` stays light.
_LAZY_SUBPACKAGES = ("analysis", "ident", "sim", "trajectory")


def __getattr__(name: str):
    if name in _LAZY_SUBPACKAGES:
        import importlib

        return importlib.import_module(f"tvist.{name}")
    raise AttributeError(f"module 'tvist' has no attribute {name!r}")


#: Names of the registry shapers, for :func:`shaper` and ``TvShaper(shaper=...)``.
SHAPERS: tuple[str, ...] = tuple(_core.SHAPERS)


class _StatusFlags(enum.IntFlag):
    """Status bits that print as their flag names (``INPUT_HELD|DELAY_CLAMPED``, ``OK``)."""

    def __str__(self) -> str:
        names = [flag.name for flag in type(self) if flag and flag in self]
        unknown = int(self) & ~sum(int(flag) for flag in type(self))
        if unknown:  # bits the core has not named (a newer library): shown as a number
            names.append(hex(unknown))
        return "|".join(names) or "OK"


#: Per-step status flags reported by ``TvShaper.last_status`` (defined once, in the core).
Status = _StatusFlags("Status", {"OK": 0, **_core.STATUS_FLAGS})

#: Largest ``n_dof`` of a shaper, and largest total delay-line memory (bytes) it may request;
#: larger requests raise ``ValueError`` (limits of the core, shared with the C API).
MAX_DOF: int = _core.MAX_DOF
MAX_DELAY_LINE_BYTES: int = _core.MAX_DELAY_LINE_BYTES
#: Most modes of a shaper, a map or a map file (the core's limit, shared by Python, C, Rust).
MAX_MODES: int = _core.MAX_MODES
#: Longest map file read, bytes (1 MiB): a longer file or a device is refused unread.
MAX_MAP_FILE_BYTES: int = _core.MAX_MAP_FILE_BYTES
#: Fastest change of a shaped mode a shaper follows, per second: ``|d ln ω_n/dt|`` and
#: ``|dζ/dt|`` (1 % and 0.01 per 2 ms cycle); a faster one (a provider's mode that jumps) is
#: approached at this rate and reported as ``Status.MODE_SLEW_LIMITED``.
MAX_LN_WN_RATE_PER_S: float = _core.MAX_LN_WN_RATE_PER_S
MAX_ZETA_RATE_PER_S: float = _core.MAX_ZETA_RATE_PER_S
#: Largest distance (rad or m) of a shaper's delay lines and output from its held input at
#: which it counts as at rest (``TvShaper.is_at_rest``): far above rounding, far below any
#: encoder's resolution. A shaper at rest may toggle the last bits of its output; a change of
#: a shaped reference this small is not motion.
REST_TOLERANCE: float = _core.REST_TOLERANCE


def shaper(
    name: str, wn_rad_s: float, zeta: float = 0.0, *, tolerance: float | None = None
) -> Impulses:
    """Design registry shaper ``name`` for the mode ``(wn_rad_s, zeta)``.

    Parameters
    ----------
    name
        One of :data:`SHAPERS`.
    wn_rad_s
        Undamped natural frequency, rad/s (> 0).
    zeta
        Damping ratio, ``0 <= zeta < 1``.
    tolerance
        EI only: vibration tolerance as a fraction in ``[0.005, 0.2]`` (default 0.05). The EI
        shaper is exact (residual vibration ``tolerance`` at the design point) for
        ``zeta <= 0.4``, or less for a tolerance above 0.1 (0.28 at 0.2).

    Returns
    -------
    Impulses
        Amplitudes summing to 1 and non-decreasing times in seconds.
    """
    return _core.design_shaper(name, float(wn_rad_s), float(zeta), tolerance)


def convolve(*impulses: Impulses) -> Impulses:
    """Convolve impulse sequences (the multi-mode shaper of eq. 53)."""
    return _core.convolve(*impulses)


def prv(impulses: Impulses, wn_rad_s, zeta=0.0):
    """Percent residual vibration (as a fraction, eqs. 52-55) of ``impulses`` on a mode.

    ``wn_rad_s`` and ``zeta`` broadcast against each other like numpy arrays. Returns a float
    for scalar inputs, otherwise an array of the broadcast shape. Invalid modes give NaN.
    """
    wn, z = np.broadcast_arrays(np.asarray(wn_rad_s, dtype=float), np.asarray(zeta, dtype=float))
    flat_wn, flat_zeta = np.ascontiguousarray(wn).ravel(), np.ascontiguousarray(z).ravel()
    out = _core.prv_flat(impulses, flat_wn, flat_zeta)
    if wn.ndim == 0:
        return float(out[0])
    return out.reshape(wn.shape)
