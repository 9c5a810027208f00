"""UR's RTDE protocol (version 2) on the wire: framing, package types, value types, recipes.

What both ends share: the recorder of :mod:`tvist.live` (a client) and the twin server of
:mod:`tvist.urserver` (a controller). A package is ``uint16 size, uint8 type, payload``
(big-endian, ``size`` counts the 3-byte header). The type names are those of Universal Robots'
RTDE guide; which variables a controller provides is the server's
(:mod:`tvist.urserver.variables`).
"""

from __future__ import annotations

import struct

#: Package types (ASCII codes of the protocol's letters).
REQUEST_PROTOCOL_VERSION = ord("V")
GET_URCONTROL_VERSION = ord("v")
TEXT_MESSAGE = ord("M")
DATA_PACKAGE = ord("U")
CONTROL_PACKAGE_SETUP_OUTPUTS = ord("O")
CONTROL_PACKAGE_SETUP_INPUTS = ord("I")
CONTROL_PACKAGE_START = ord("S")
CONTROL_PACKAGE_PAUSE = ord("P")

#: The protocol version both ends speak (ur_rtde and UR's own client ask for it).
PROTOCOL_VERSION = 2
#: Major software version of the CB-series controllers (CB3: 3.x); the e-Series runs 5.x.
CB_SERIES_MAJOR_VERSION = 3


def output_rate_hz(controller_major_version: int) -> float:
    """The highest RTDE output rate of a controller (Hz), from the major version its
    ``GET_URCONTROL_VERSION`` reply names: 125 on the CB-series (3.x), 500 on the e-Series
    (5.x) and later (the rule ur_rtde follows too)."""
    return 125.0 if controller_major_version <= CB_SERIES_MAJOR_VERSION else 500.0


HEADER = struct.Struct(">HB")
#: Largest package a client may send (the size field is 16 bits).
MAX_PACKAGE_BYTES = 65535

#: RTDE type name -> struct format of one value.
TYPE_FORMATS = {
    "BOOL": "?",
    "UINT8": "B",
    "UINT32": "I",
    "UINT64": "Q",
    "INT32": "i",
    "DOUBLE": "d",
    "VECTOR3D": "3d",
    "VECTOR6D": "6d",
    "VECTOR6INT32": "6i",
    "VECTOR6UINT32": "6I",
}
#: Number of values of each type (1 for scalars).
TYPE_WIDTHS = {"VECTOR3D": 3, "VECTOR6D": 6, "VECTOR6INT32": 6, "VECTOR6UINT32": 6}


def package(kind: int, payload: bytes = b"") -> bytes:
    """One package: header and payload."""
    return HEADER.pack(HEADER.size + len(payload), kind) + payload


def text_message(message: str, source: str = "twin", level: int = 1) -> bytes:
    """A text message package (``M``); ``level`` 0 exception, 1 error, 2 warning, 3 info."""
    msg = message.encode()[:255]
    src = source.encode()[:255]
    return package(TEXT_MESSAGE, bytes([len(msg)]) + msg + bytes([len(src)]) + src + bytes([level]))


class Recipe:
    """A set of variables exchanged in one data package, with its packer.

    Parameters
    ----------
    recipe_id
        1..255 (0 marks an invalid recipe).
    names
        Variable names in package order.
    types
        RTDE type of each name.
    """

    def __init__(self, recipe_id: int, names: list[str], types: list[str]) -> None:
        self.recipe_id = recipe_id
        self.names = names
        self.types = types
        self.struct = struct.Struct(">B" + "".join(TYPE_FORMATS[t] for t in types))
        #: Recipes with equal keys pack equal values into equal packages.
        self.key = (recipe_id, *names)

    def pack(self, values: dict) -> bytes:
        """The data package of ``values`` (a name -> value or sequence mapping)."""
        flat: list = [self.recipe_id]
        for name, kind in zip(self.names, self.types, strict=True):
            value = values[name]
            if kind in TYPE_WIDTHS:
                flat.extend(value)
            else:
                flat.append(value)
        return package(DATA_PACKAGE, self.struct.pack(*flat))

    def unpack(self, payload: bytes) -> dict:
        """Values of a client's data package payload (recipe id included).

        Raises
        ------
        ValueError
            If the payload does not have this recipe's size.
        """
        if len(payload) != self.struct.size:
            raise ValueError(
                f"data package for recipe {self.recipe_id} has {len(payload)} bytes, "
                f"expected {self.struct.size}"
            )
        flat = self.struct.unpack(payload)[1:]
        out = {}
        i = 0
        for name, kind in zip(self.names, self.types, strict=True):
            width = TYPE_WIDTHS.get(kind, 0)
            if width:
                out[name] = list(flat[i : i + width])
                i += width
            else:
                out[name] = flat[i]
                i += 1
        return out


def split_names(text: bytes) -> list[str]:
    """Variable names of a setup request (comma-separated; ur_rtde ends them with a comma)."""
    return [n.strip() for n in text.decode("ascii", errors="replace").split(",") if n.strip()]
