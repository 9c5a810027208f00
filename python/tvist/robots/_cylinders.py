"""Solid-cylinder link inertias for robots whose maker publishes no inertia tensors.

A robot entry in the robot data (``crates/tvist-core/data/ur_e_series.json``) may carry an
``inertia_cylinders`` block::

    "inertia_cylinders": {
        "radius_m": [r_1, ..., r_n],
        "length_m": [l_1, ..., l_n],
        "axis": ["y", "x", ...]
    }

Link ``i`` is then modelled as a homogeneous solid cylinder of the link's mass ``m_i``, radius
``r_i`` and length ``l_i``, centred on the link's centre of mass, with its symmetry axis along
the named axis of DH frame ``i``. About the centre of mass, in DH frame ``i``::

    I_axis = m r^2 / 2,    I_perpendicular = m (3 r^2 + l^2) / 12,    products of inertia = 0.

The block is the source; the ``inertia_kg_m2`` rows of such a robot are derived from it by
this module, stored with :data:`SIGNIFICANT_DIGITS` significant digits. Regenerate them after
changing a block or a mass with::

    python -m tvist.robots._cylinders --write

``python -m tvist.robots._cylinders`` alone only reports whether the file is up to date. This
is a maintenance tool for a source checkout: it edits the data file's text (and parses it to
find the blocks); the package itself reads robot data only through the core.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

#: The robot-data file in a source checkout (the core embeds it when it is built).
DATA_PATH = Path(__file__).resolve().parents[3] / "crates/tvist-core/data/ur_e_series.json"
SIGNIFICANT_DIGITS = 10
AXES = ("x", "y", "z")


def cylinder_inertia(mass_kg: float, radius_m: float, length_m: float, axis: str) -> list[float]:
    """``[ixx, iyy, izz, ixy, ixz, iyz]`` of a solid cylinder about its centre of mass.

    Parameters
    ----------
    mass_kg, radius_m, length_m
        Mass (>= 0), radius and length (> 0) of the cylinder.
    axis
        ``"x"``, ``"y"`` or ``"z"``: the frame axis the cylinder's symmetry axis lies along.
    """
    if axis not in AXES:
        raise ValueError(f"cylinder axis must be one of {AXES}, got {axis!r}")
    if not (mass_kg >= 0.0 and radius_m > 0.0 and length_m > 0.0):
        raise ValueError(
            f"cylinder needs mass >= 0 and radius, length > 0; got mass_kg={mass_kg!r}, "
            f"radius_m={radius_m!r}, length_m={length_m!r}"
        )
    # Plain Python floats keep the arithmetic (and so the stored digits) platform-independent.
    along = mass_kg * radius_m * radius_m / 2.0
    across = mass_kg * (3.0 * radius_m * radius_m + length_m * length_m) / 12.0
    diagonal = [along if a == axis else across for a in AXES]
    return [*diagonal, 0.0, 0.0, 0.0]


def link_inertias(entry: Mapping[str, Any]) -> list[list[float]]:
    """``inertia_kg_m2`` rows of a robot entry, computed from its ``inertia_cylinders`` block."""
    block = entry["inertia_cylinders"]
    masses = [float(m) for m in entry["mass_kg"]]
    radii, lengths, axes = block["radius_m"], block["length_m"], block["axis"]
    if not len(radii) == len(lengths) == len(axes) == len(masses):
        raise ValueError(
            "inertia_cylinders: radius_m, length_m and axis need one entry per link "
            f"({len(masses)}), got {len(radii)}, {len(lengths)}, {len(axes)}"
        )
    return [
        _rounded(cylinder_inertia(m, float(r), float(length), str(a)))
        for m, r, length, a in zip(masses, radii, lengths, axes, strict=True)
    ]


def _rounded(row: Sequence[float]) -> list[float]:
    return [float(f"{v:.{SIGNIFICANT_DIGITS}g}") for v in row]


def _format_rows(rows: Sequence[Sequence[float]], indent: str) -> str:
    """Rows in the file's layout: one ``[...]`` per line, numbers as JSON writes them."""
    lines = [indent + "  " + json.dumps(row) for row in rows]
    return "[\n" + ",\n".join(lines) + "\n" + indent + "]"


def regenerate(text: str) -> str:
    """``text`` of the data file with every cylinder robot's ``inertia_kg_m2`` recomputed.

    Only those blocks are rewritten; the rest of the file is left byte for byte.
    """
    robots = json.loads(text)["robots"]
    for name, entry in robots.items():
        if "inertia_cylinders" not in entry:
            continue
        start = text.index(f'"{name}": {{')
        match = re.compile(r'( *)"inertia_kg_m2": (\[.*?\n\1\])', re.DOTALL).search(text, start)
        if match is None:
            raise ValueError(f"{name}: no inertia_kg_m2 block found in the data file")
        rows = link_inertias(entry)
        text = text[: match.start(2)] + _format_rows(rows, match.group(1)) + text[match.end(2) :]
        if json.loads(text)["robots"][name]["inertia_kg_m2"] != rows:
            raise ValueError(f"{name}: its inertia_kg_m2 block could not be located in the file")
    return text


def main(argv: Sequence[str] | None = None) -> int:
    """Check (default) or rewrite (``--write``) the derived rows in the data file."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="rewrite the data file in place")
    args = parser.parse_args(argv)
    if not DATA_PATH.is_file():
        print(f"{DATA_PATH}: not found (this tool needs a source checkout)", file=sys.stderr)
        return 2
    text = DATA_PATH.read_text(encoding="utf-8")
    new = regenerate(text)
    if args.write:
        if new != text:
            DATA_PATH.write_text(new, encoding="utf-8")
        print(f"{DATA_PATH.name}: {'updated' if new != text else 'already up to date'}")
        return 0
    print(f"{DATA_PATH.name}: {'up to date' if new == text else 'OUT OF DATE (run --write)'}")
    return 0 if new == text else 1


if __name__ == "__main__":
    sys.exit(main())
