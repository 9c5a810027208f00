"""The RTDE variables the twin controller provides: the outputs it publishes and the inputs a
client may write (names and types of Universal Robots' RTDE guide, the wire format in
:mod:`tvist.rtde_wire`). A setup request naming any other variable gets ``NOT_FOUND`` for it,
as from a controller that does not know the name.
"""

from __future__ import annotations

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
