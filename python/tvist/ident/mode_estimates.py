"""What a fit of several modes to one log returns: each mode (:class:`ModeEstimate`) and the
two-mode fit (:class:`TwoModeFit`, made by :func:`tvist.ident.two_mode.fit_two_modes` and
kept in :class:`tvist.ident.local_fit.LocalFit`)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

__all__ = ["ModeEstimate", "TwoModeFit"]


@dataclass(frozen=True)
class ModeEstimate:
    """One mode of a multi-mode fit, with standard errors (white-residual assumption), the
    fraction of the fitted response energy it carries and its numerator ``k_a s + k_b``."""

    wn_rad_s: float
    zeta: float
    wn_se_rad_s: float
    zeta_se: float
    energy_share: float = float("nan")
    k_a: float = float("nan")
    k_b: float = float("nan")

    @property
    def fn_hz(self) -> float:
        return self.wn_rad_s / (2.0 * math.pi)


@dataclass(frozen=True)
class TwoModeFit:
    """Result of :func:`~tvist.ident.two_mode.fit_two_modes`.

    Attributes
    ----------
    modes
        The two modes, lowest frequency first.
    rss_ratio
        Residual sum of squares of the two-mode fit over that of the single-mode fit.
    significant
        Whether the data support two modes (see :mod:`tvist.ident.two_mode`).
    """

    modes: tuple[ModeEstimate, ModeEstimate]
    rss_ratio: float
    significant: bool

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python form (JSON types only); :meth:`from_dict` reads it back."""
        return {
            "modes": [asdict(m) for m in self.modes],
            "rss_ratio": self.rss_ratio,
            "significant": self.significant,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TwoModeFit:
        modes = tuple(ModeEstimate(**m) for m in data["modes"])
        if len(modes) != 2:
            raise ValueError(f"a two-mode fit has 2 modes, got {len(modes)}")
        return cls(
            modes=(modes[0], modes[1]),
            rss_ratio=float(data["rss_ratio"]),
            significant=bool(data["significant"]),
        )

    def away_from(self, wn_rad_s: float) -> ModeEstimate:
        """The mode farther (in log-frequency) from ``wn_rad_s``, e.g. the shoulder mode."""
        return max(self.modes, key=lambda m: abs(math.log(m.wn_rad_s / wn_rad_s)))
