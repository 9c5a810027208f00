"""``tvist shape``: shape a recorded or planned joint trajectory file offline.

The input is a CSV of joint positions, one row per control cycle (``(n_samples, n_dof)``,
rad), with or without a header row; an RTDE log (``target_q_0 …``) is read through its
``target_q`` columns. The output CSV has the same columns. Three methods:

- ``tvist``: multi-mode FD-TVIST (``TvShaper``); the output is longer than the input by the
  shaper delay at the end pose (the last sample is repeated while the filter settles).
- ``ztdis`` / ``mztdis``: zero-time-delay shaping of a rest-to-rest move (same length), with
  the modes at the end pose.

Modes come from ``--modes`` (fixed, ``FREQ_HZ:ZETA,...``) or from a dynamic map (``--map
FILE`` or ``--paper-map``) with the robot model (``--robot``, ``--payload-kg``,
``--payload-com``).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: The shaping methods offered on the command line (``--method``): FD-TVIST, ZTDIS and
#: modified ZTDIS.
METHODS = ("tvist", "ztdis", "mztdis")


@dataclass(frozen=True)
class ShapedFile:
    """What :func:`shape_file` did: output array, the delay added and the provider's modes."""

    Q: np.ndarray
    added_delay_s: float
    end_modes: list[tuple[float, float]]
    status_counts: dict[str, int]


def read_joint_csv(path: str | Path) -> tuple[np.ndarray, list[str] | None]:
    """Joint positions ``(n_samples, n_dof)`` and the header (``None`` if the file has none).

    An RTDE log is recognized by its ``target_q_0`` column; only ``target_q_*`` is read.
    """
    text = Path(path).read_text().splitlines()
    if not text:
        raise ValueError(f"{path}: empty file")
    first = [c.strip() for c in text[0].replace(" ", ",").split(",") if c.strip()]
    try:
        [float(c) for c in first]
        header = None
    except ValueError:
        header = first
    delimiter = "," if "," in text[0] else None
    data = np.loadtxt(path, delimiter=delimiter, skiprows=0 if header is None else 1, ndmin=2)
    if header is not None and "target_q_0" in header:
        columns = [header.index(f"target_q_{j}") for j in range(6) if f"target_q_{j}" in header]
        header = [header[c] for c in columns]
        data = data[:, columns]
    if header is not None and len(header) != data.shape[1]:
        raise ValueError(f"{path}: {len(header)} header names but {data.shape[1]} columns")
    bad = np.flatnonzero(~np.all(np.isfinite(data), axis=1))
    if bad.size:
        raise ValueError(f"{path}: non-finite value in data row {int(bad[0]) + 1}")
    if data.shape[0] < 2:
        raise ValueError(f"{path}: needs at least 2 samples, got {data.shape[0]}")
    return data, header


def parse_modes(text: str) -> list[tuple[float, float]]:
    """``"8.0:0.26,6.9:0.37"`` (Hz:zeta) -> ``[(wn_rad_s, zeta), ...]``."""
    modes = []
    for item in text.split(","):
        try:
            freq_hz, zeta = (float(v) for v in item.split(":"))
        except ValueError:
            raise ValueError(f"--modes: {item!r} is not FREQ_HZ:ZETA") from None
        modes.append((2.0 * np.pi * freq_hz, zeta))
    return modes


def shape_file(
    Q: np.ndarray,
    dt_s: float,
    method: str,
    *,
    shaper: str = "zv",
    modes: list[tuple[float, float]] | None = None,
    robot=None,
    dynmap=None,
) -> ShapedFile:
    """Shape ``Q`` with ``method``: fixed ``modes``, or a ``robot`` with a ``dynmap``."""
    import tvist

    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    if (modes is None) == (dynmap is None or robot is None):
        raise ValueError("give either fixed modes or a robot with a dynamic map")
    if modes is not None:
        provider, end_modes = tvist.ConstantModes(modes), modes
    else:
        provider, end_modes = tvist.MapDynamics(robot, dynmap), dynmap.modes(robot, Q[-1])
    if method == "tvist":
        shaper_ = tvist.TvShaper(provider, dt_s=dt_s, n_dof=Q.shape[1], shaper=shaper)
        end_delay = tvist.convolve(*(tvist.shaper(shaper, w, z) for w, z in end_modes))
        # Hold the last sample until the filter has settled at the end pose (plus one sample).
        n_tail = int(np.ceil(end_delay.duration_s / dt_s)) + 1
        padded = np.vstack([Q, np.repeat(Q[-1:], n_tail, axis=0)])
        out = shaper_.shape(padded)
        return ShapedFile(out, n_tail * dt_s, list(end_modes), dict(shaper_.status_counts))
    result = tvist.zero_delay(
        Q, dt_s, end_modes, shaper=shaper, method="ztdis" if method == "ztdis" else "modified"
    )
    return ShapedFile(result.Q, 0.0, list(end_modes), {})


def _mode_source(args: argparse.Namespace, n_dof: int) -> dict:
    """Keyword arguments of :func:`shape_file` that say where the modes come from."""
    import tvist

    if args.modes:
        return {"modes": parse_modes(args.modes)}
    if not (args.map or args.paper_map):
        raise ValueError("give --modes, --map FILE or --paper-map")
    dynmap = tvist.DynamicMap.paper_ur5e() if args.paper_map else tvist.DynamicMap.load(args.map)
    com = tuple(float(v) for v in args.payload_com.split(","))
    robot = tvist.robots.Robot(
        tvist.robots.params(args.robot), tvist.robots.Payload(args.payload_kg, com)
    )
    if robot.n_dof != n_dof:
        raise ValueError(f"the file has {n_dof} joints, the {args.robot} has {robot.n_dof}")
    return {"robot": robot, "dynmap": dynmap}


def _cmd_shape(args: argparse.Namespace) -> int:
    Q, header = read_joint_csv(args.input)
    shaped = shape_file(
        Q, args.dt, args.method, shaper=args.shaper, **_mode_source(args, Q.shape[1])
    )
    np.savetxt(
        args.out,
        shaped.Q,
        delimiter=",",
        fmt="%.9f",
        header=",".join(header) if header else "",
        comments="",
    )
    freq = ", ".join(
        f"{w * np.sqrt(1 - z * z) / (2 * np.pi):.2f} Hz / ζ {z:.3f}" for w, z in shaped.end_modes
    )
    print(f"{args.method}: modes at the end pose {freq}")
    print(f"wrote {shaped.Q.shape[0]} samples to {args.out} (+{shaped.added_delay_s * 1e3:.0f} ms)")
    if any(shaped.status_counts.values()):
        print(f"status counts: {shaped.status_counts}")
    return 0


def add_shape_command(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("shape", help="shape a joint trajectory CSV file offline")
    p.add_argument("input", help="CSV of joint positions (rad), one row per cycle")
    p.add_argument("--out", required=True, help="output CSV")
    p.add_argument("--dt", type=float, default=0.002, help="sample period, s (default 0.002)")
    p.add_argument("--method", choices=METHODS, default="tvist", help="default tvist")
    p.add_argument("--shaper", default="zv", help="registry shaper name (default zv)")
    source = p.add_mutually_exclusive_group()
    source.add_argument("--modes", help="fixed modes FREQ_HZ:ZETA,... (undamped frequency)")
    source.add_argument("--map", help="dynamic map file (tvist fit-map)")
    source.add_argument("--paper-map", action="store_true", help="the paper's UR5e map")
    p.add_argument("--robot", default="ur5e", help="robot model for a map (default ur5e)")
    p.add_argument("--payload-kg", type=float, default=0.0)
    p.add_argument("--payload-com", default="0,0,0", help="payload CoM in the flange frame, m")
    p.set_defaults(func=_cmd_shape)
