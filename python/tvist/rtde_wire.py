"""UR's RTDE protocol (version 2) as the controller speaks it: framing, types, variables.

A package is ``uint16 size, uint8 type, payload`` (big-endian, ``size`` counts the 3-byte
header). The variable names and types are those of Universal Robots' RTDE guide; the twin
provides the subset in :data:`OUTPUTS` and :data:`INPUTS` and answers ``NOT_FOUND`` for any
other name, as a controller does for a name it does not know.
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

#: The only protocol version the twin speaks (ur_rtde and UR's own client ask for it).
PROTOCOL_VERSION = 2
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

#: Number of general-purpose int and double registers of each direction (e-Series: 48).
N_REGISTERS = 48

#: Output variables the twin publishes, with their RTDE types. Values of measurements the twin
#: does not model (motor currents, voltages, temperatures, forces) are NaN, never invented.
OUTPUTS: dict[str, str] = {
    "timestamp": "DOUBLE",
    "target_q": "VECTOR6D",
    "target_qd": "VECTOR6D",
    "target_qdd": "VECTOR6D",
    "target_current": "VECTOR6D",
    "target_moment": "VECTOR6D",
    "actual_q": "VECTOR6D",
    "actual_qd": "VECTOR6D",
    "actual_current": "VECTOR6D",
    "joint_control_output": "VECTOR6D",
    "actual_TCP_pose": "VECTOR6D",
    "actual_TCP_speed": "VECTOR6D",
    "actual_TCP_force": "VECTOR6D",
    "target_TCP_pose": "VECTOR6D",
    "target_TCP_speed": "VECTOR6D",
    "actual_digital_input_bits": "UINT64",
    "joint_temperatures": "VECTOR6D",
    "actual_execution_time": "DOUBLE",
    "robot_mode": "INT32",
    "joint_mode": "VECTOR6INT32",
    "safety_mode": "INT32",
    "safety_status": "INT32",
    "actual_tool_accelerometer": "VECTOR3D",
    "speed_scaling": "DOUBLE",
    "target_speed_fraction": "DOUBLE",
    "actual_momentum": "DOUBLE",
    "actual_main_voltage": "DOUBLE",
    "actual_robot_voltage": "DOUBLE",
    "actual_robot_current": "DOUBLE",
    "actual_joint_voltage": "VECTOR6D",
    "actual_digital_output_bits": "UINT64",
    "runtime_state": "UINT32",
    "robot_status_bits": "UINT32",
    "safety_status_bits": "UINT32",
    "standard_analog_input0": "DOUBLE",
    "standard_analog_input1": "DOUBLE",
    "standard_analog_output0": "DOUBLE",
    "standard_analog_output1": "DOUBLE",
    "ft_raw_wrench": "VECTOR6D",
    "payload": "DOUBLE",
    "payload_cog": "VECTOR3D",
    "payload_inertia": "VECTOR6D",
    "output_bit_registers0_to_31": "UINT32",
    "output_bit_registers32_to_63": "UINT32",
    "input_bit_registers0_to_31": "UINT32",
    "input_bit_registers32_to_63": "UINT32",
}
for _i in range(N_REGISTERS):
    OUTPUTS[f"output_int_register_{_i}"] = "INT32"
    OUTPUTS[f"output_double_register_{_i}"] = "DOUBLE"
    OUTPUTS[f"input_int_register_{_i}"] = "INT32"
    OUTPUTS[f"input_double_register_{_i}"] = "DOUBLE"

#: Input variables a client may write: the general-purpose registers (the twin has no I/O).
INPUTS: dict[str, str] = {
    "external_force_torque": "VECTOR6D",
    # The speed slider (bit 0 of the mask set: the fraction applies).
    "speed_slider_mask": "UINT32",
    "speed_slider_fraction": "DOUBLE",
}
for _i in range(N_REGISTERS):
    INPUTS[f"input_int_register_{_i}"] = "INT32"
    INPUTS[f"input_double_register_{_i}"] = "DOUBLE"

#: Output fields the twin does not measure: published as NaN.
UNMEASURED_OUTPUTS = frozenset(
    {
        "target_current",
        "target_moment",
        "actual_current",
        "joint_control_output",
        "actual_TCP_force",
        "joint_temperatures",
        "actual_momentum",
        "actual_main_voltage",
        "actual_robot_voltage",
        "actual_robot_current",
        "actual_joint_voltage",
        "standard_analog_input0",
        "standard_analog_input1",
        "ft_raw_wrench",
    }
)


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
