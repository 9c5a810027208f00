"""One log's mode, end to end: :func:`identify_local` preprocesses the accelerometer
(:mod:`tvist.ident.preprocess`), fits eq. 17 (:func:`tvist.ident.local_fit.fit_local`) and,
where asked or for the base joint, fits two modes (:mod:`tvist.ident.two_mode`) and separates
the base mode (:mod:`tvist.ident.base_mode`)."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from tvist.ident.base_mode import separate_base_mode
from tvist.ident.local_fit import (
    FitOptions,
    LocalFit,
    fit_local,
    interval_mean_acceleration,
    saturated_samples,
)
from tvist.ident.logs import LogWarning, Record, is_uniform, resample_uniform
from tvist.ident.preprocess import (
    MIN_STANDSTILL_SAMPLES,
    KinematicModel,
    TangentialAcceleration,
    tangential_acceleration,
)
from tvist.ident.two_mode import fit_two_modes

__all__ = ["identify_local"]


def identify_local(
    record: Record,
    joint: int,
    robot: KinematicModel,
    *,
    options: FitOptions | None = None,
    accel_frame: str = "flange",
    accel_limit_m_s2: float | None = None,
    min_standstill_samples: int = MIN_STANDSTILL_SAMPLES,
    two_modes: bool = False,
    base_mode: bool = True,
) -> LocalFit:
    """Identify ``(ω_n, ζ)`` of the mode excited through ``joint`` from one log.

    Preprocesses the accelerometer (eqs. 12-13, :func:`tangential_acceleration`), excludes
    saturated samples, and fits eq. 17 (:func:`fit_local`).

    Parameters
    ----------
    record
        Log of one excitation (standstill first), e.g. from :func:`read_rtde_csv`.
    joint
        Excited joint (0 = base, 1 = shoulder, 2 = elbow, ...).
    robot
        Kinematic model, e.g. ``tvist.robots.ur5e(payload_kg, payload_com_m)``.
    options
        Fit settings.
    accel_frame
        ``"flange"`` (raw sensor frame) or ``"base"``.
    accel_limit_m_s2
        Known accelerometer range, for the saturation check (optional).
    min_standstill_samples
        Fewest initial standstill samples accepted for the gravity estimate.
    two_modes
        Also fit two modes (:func:`tvist.ident.two_mode.fit_two_modes`) and attach the result
        as ``two_mode``.
    base_mode
        For the base joint (0): return the base mode, separated from a shoulder mode that
        rings in the same log (:func:`tvist.ident.base_mode.separate_base_mode`), flagged
        where the two cannot be told apart. ``False`` returns the paper's single-mode fit.

    Raises
    ------
    ValueError
        Too little standstill, too short, no excitation or mostly saturated accelerometer.
        (A log with skipped samples is resampled, with a :class:`LogWarning`.)
    """
    opts = options or FitOptions()
    if not is_uniform(record.t_s):
        record, filled = resample_uniform(record)
        warnings.warn(
            f"the log is not uniformly sampled: resampled onto a uniform grid, {filled} of "
            f"{record.n_samples} samples filled by linear interpolation",
            LogWarning,
            stacklevel=2,
        )
    dt = record.dt_s
    tangential: TangentialAcceleration = tangential_acceleration(
        record,
        joint,
        robot,
        accel_frame=accel_frame,  # type: ignore[arg-type]
        min_standstill_samples=min_standstill_samples,
    )
    saturated = saturated_samples(record.tool_accel, limit_m_s2=accel_limit_m_s2)
    reasons: tuple[str, ...] = ()
    n_sat = int(np.count_nonzero(saturated))
    if n_sat:
        fraction = n_sat / record.n_samples
        if fraction > opts.max_saturated_fraction:
            raise ValueError(
                f"accelerometer saturated on {n_sat} of {record.n_samples} samples "
                f"({100 * fraction:.1f} %); lower the excitation's acceleration"
            )
        reasons = (f"accelerometer saturated on {n_sat} samples (excluded from the fit)",)
    u = interval_mean_acceleration(record.target_qd[:, joint], dt)
    fit = fit_local(
        u,
        tangential.psi,
        dt,
        mask=~saturated,
        options=opts,
        joint=joint,
        extra_reasons=reasons,
    )
    separate = base_mode and joint == 0 and not fit.no_ringing
    if two_modes or separate:
        split = fit_two_modes(
            u,
            tangential.psi,
            dt,
            fit,
            mask=~saturated,
            f_min_hz=opts.f_min_hz,
            f_max_hz=opts.f_max_hz,
        )
        fit = replace(fit, two_mode=split)
    if separate:
        jac = robot.jacobian_many(np.ascontiguousarray(record.actual_q))[:, :3, :2]
        assert tangential.accel_base is not None
        fit = separate_base_mode(
            fit,
            u,
            tangential.accel_base,
            jac[:, :, 0],
            jac[:, :, 1],
            dt,
            ~saturated,
            max_wn_rel_se=opts.max_wn_rel_se,
        )
    return fit
