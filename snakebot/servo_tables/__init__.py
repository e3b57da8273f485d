"""Dynamixel control tables as data, shared by the real bus layer and the emulator.

One data file per model, `data/<model>.toml` (e-Manual facts: access, range, default, SI unit and
sign). Protocol 2.0 models take addresses and sizes from the ROBOTIS SDK's `.model` files; Protocol
1.0 models (AX, MX with P1 firmware), which have none, give them in the TOML. More models come from
user folders (`SNAKEBOT_SERVO_DATA`, :func:`add_model_dir`).
"""

from snakebot.servo_tables.loader import build_table, model_file_dir
from snakebot.servo_tables.models import (
    ModelEntry,
    add_model_dir,
    model_dirs,
    model_entries,
    supported_models,
    table_for_model,
)
from snakebot.servo_tables.table import (
    Register,
    RegisterValueError,
    ServoSpecs,
    ServoTable,
    UnknownModelError,
    UnknownRegisterError,
    decode_magnitude,
    decode_signed,
    encode_magnitude,
    encode_value,
    register_key,
)

__all__ = [
    "ModelEntry",
    "Register",
    "RegisterValueError",
    "ServoSpecs",
    "ServoTable",
    "UnknownModelError",
    "UnknownRegisterError",
    "add_model_dir",
    "build_table",
    "decode_magnitude",
    "decode_signed",
    "encode_magnitude",
    "encode_value",
    "model_dirs",
    "model_entries",
    "model_file_dir",
    "register_key",
    "supported_models",
    "table_for_model",
]
