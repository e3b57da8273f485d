"""Dynamixel control tables as data, shared by the real bus layer and the emulator.

Addresses and sizes come from the ROBOTIS SDK's `.model` files; access, range, default, SI unit and
sign come from `data/<model>.toml` (e-Manual facts).
"""

from snakebot.servo_tables.loader import model_file_dir, supported_models, table_for_model
from snakebot.servo_tables.table import (
    Register,
    RegisterValueError,
    ServoSpecs,
    ServoTable,
    UnknownModelError,
    UnknownRegisterError,
    decode_signed,
    encode_value,
    register_key,
)

__all__ = [
    "Register",
    "RegisterValueError",
    "ServoSpecs",
    "ServoTable",
    "UnknownModelError",
    "UnknownRegisterError",
    "decode_signed",
    "encode_value",
    "model_file_dir",
    "register_key",
    "supported_models",
    "table_for_model",
]
