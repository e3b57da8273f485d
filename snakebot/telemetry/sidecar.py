"""The JSON sidecar of a telemetry CSV: what made the log (robot, servos, gains, gait, backend,
snakebot version) and the unit of every column, written when the log opens.

``run.csv`` gets ``run.csv.json`` beside it. A log without one (older, or renamed) still reads:
:func:`read_sidecar` returns None and the log commands fall back to the columns.
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakebot import __version__
from snakebot.config.input_file import MAX_TEXT_CHARS, read_input, text_problem
from snakebot.errors import ConfigError, OutputError

FORMAT = "snakebot-telemetry-csv"
FORMAT_VERSION = 1

_COLUMN_UNITS = {
    "time_s": ("s", "robot time: simulated on the twin, monotonic wall clock on hardware"),
    "cycle": ("", "control cycle number, from 0"),
    "command_rad": ("rad", "goal position sent after the safety layer, joint {i} (0 = head)"),
    "position_rad": ("rad", "measured position, joint {i}"),
    "velocity_rad_s": ("rad/s", "measured velocity, joint {i}"),
    "effort_nm": ("N m", "joint torque, joint {i} (hardware: from present current)"),
    "com_x_m": ("m", "centre of mass x (world); empty (NaN) on hardware"),
    "com_y_m": ("m", "centre of mass y (world); NaN on hardware"),
    "com_z_m": ("m", "centre of mass z (world); NaN on hardware"),
}


def sidecar_path(log_path: str | Path) -> Path:
    """``run.csv`` -> ``run.csv.json``."""
    path = Path(log_path)
    return path.with_name(path.name + ".json")


def describe_columns(columns: Sequence[str]) -> list[dict[str, str]]:
    """Name, unit and meaning of every CSV column."""
    described = []
    for name in columns:
        key, index = name, ""
        if name not in _COLUMN_UNITS:
            key, _, index = name.rpartition("_")
        unit, text = _COLUMN_UNITS.get(key, ("", ""))
        described.append({"name": name, "unit": unit, "description": text.format(i=index)})
    return described


def robot_facts(robot: Any) -> dict[str, Any]:
    """The robot's facts for a sidecar: name, file, servo IDs, joints, links, servo, gains (SI
    and the register form).

    Takes a RobotConfig (servo chain) or a mass-spring BodyConfig (what it has of these).
    """
    facts: dict[str, Any] = {
        "name": getattr(robot, "name", ""),
        "source": str(getattr(robot, "source", "")),
        "joint_count": int(robot.joint_count),
    }
    if hasattr(robot, "joints") and hasattr(robot, "servo_ids"):
        facts["servo_ids"] = list(robot.servo_ids)
        facts["joints"] = [
            {
                "servo_id": j.servo_id,
                "axis": j.axis,
                "direction": j.direction,
                "zero_offset_rad": j.zero_offset_rad,
                "lower_rad": j.lower_rad,
                "upper_rad": j.upper_rad,
            }
            for j in robot.joints
        ]
    for key in ("link", "gains", "safety"):
        value = getattr(robot, key, None)
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            facts[key] = _jsonable(dataclasses.asdict(value))
    if "gains" in facts:
        facts["gains_units"] = "kp_nm_per_rad: N m/rad, kd_nms_per_rad: N m s/rad"
    writes = getattr(robot, "gain_writes", None)
    if isinstance(writes, dict):  # the position-loop registers, P/I/D or Compliance Slope
        facts["gain_writes"] = _jsonable(writes)
    registers = getattr(robot, "gain_registers", None)
    if dataclasses.is_dataclass(registers) and not isinstance(registers, type):
        facts["gain_registers"] = _jsonable(dataclasses.asdict(registers))
    servo = getattr(robot, "servo", None)
    if servo is not None and hasattr(servo, "name"):
        facts["servo_model"] = servo.name
    bus = getattr(robot, "bus", None)
    if bus is not None and dataclasses.is_dataclass(bus) and not isinstance(bus, type):
        facts["bus"] = _jsonable(dataclasses.asdict(bus))
    return facts


def gait_facts(name: str, gait: object | None, params: Mapping[str, object]) -> dict[str, Any]:
    """A gait for a sidecar: its name and parameters (all of them where the gait is a
    dataclass, else the ones given)."""
    values: Mapping[str, object] = params
    if dataclasses.is_dataclass(gait) and not isinstance(gait, type):
        values = {
            f.name: getattr(gait, f.name)
            for f in dataclasses.fields(gait)
            if f.init and not f.name.startswith("_")
        }
    return {"name": name, "params": _jsonable(dict(values))}


def write_sidecar(
    log_path: str | Path,
    *,
    command: str,
    robot: Any,
    backend: str,
    rate_hz: float,
    columns: Sequence[str],
    extra: Mapping[str, Any] | None = None,
) -> Path:
    """Write the sidecar of ``log_path`` and return its path; OutputError naming it if it
    cannot be written."""
    path = sidecar_path(log_path)
    payload: dict[str, Any] = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "snakebot_version": __version__,
        "created_utc": datetime.datetime.now(datetime.UTC).isoformat(timespec="milliseconds"),
        "command": command,
        "log": Path(log_path).name,
        "robot": robot_facts(robot),
        "backend": backend,
        "rate_hz": rate_hz,
        **_jsonable(dict(extra or {})),
        "columns": describe_columns(columns),
    }
    text = json.dumps(payload, indent=2, allow_nan=False) + "\n"
    try:
        with open(path, "w", encoding="utf-8") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
    except OSError as exc:
        raise OutputError(path, f"cannot write the log's sidecar: {exc.strerror}") from exc
    return path


MAX_SIDECAR_BYTES = 16 << 20
"""Largest sidecar read (16 MiB; snakebot writes a few kB)."""


def read_sidecar(log_path: str | Path) -> dict[str, Any] | None:
    """The sidecar of ``log_path``, or None when there is none.

    ConfigError naming the sidecar and the key when it is not a snakebot sidecar: not a regular
    file of at most MAX_SIDECAR_BYTES, not UTF-8 JSON (or nested too deeply to parse), not an
    object, or a field the log commands read (``rate_hz``, ``robot``, ``gait``, ...) of the
    wrong type or out of range.
    """
    path = sidecar_path(log_path)
    if not os.path.lexists(path):
        return None
    data = read_input(path, what="log sidecar", limit_bytes=MAX_SIDECAR_BYTES)
    try:
        payload = json.loads(data.decode("utf-8"), parse_constant=_no_constant)
    except UnicodeDecodeError as exc:
        raise ConfigError(path, "", f"not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    except json.JSONDecodeError as exc:
        raise ConfigError(path, f"line {exc.lineno}", f"not JSON: {exc.msg}") from None
    except RecursionError:
        raise ConfigError(path, "", "not a sidecar: JSON nested too deeply to read") from None
    except ValueError as exc:  # NaN/Infinity, or an integer of more digits than Python converts
        raise ConfigError(path, "", f"not a sidecar: {exc}") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ConfigError(path, "format", f"expected a {FORMAT!r} sidecar")
    _check_fields(path, payload)
    return payload


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number")


_TEXT_FIELDS = ("command", "backend", "created_utc", "snakebot_version", "log")


def _check_fields(path: Path, payload: dict[str, Any]) -> None:
    """The fields the log commands read have the types snakebot writes them with."""

    def refuse(key: str, expected: str, value: Any) -> None:
        shown = repr(value)
        shown = shown if len(shown) <= 80 else shown[:80] + "..."
        raise ConfigError(path, key, f"expected {expected}, got {shown}")

    def text(key: str, value: Any) -> None:
        if not isinstance(value, str) or text_problem(value, max_chars=MAX_TEXT_CHARS):
            refuse(key, "a string without control or bidirectional characters", value)

    def number(key: str, value: Any, low: float, high: float) -> None:
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not (low <= value <= high)
        ):
            refuse(key, f"a number in [{low:g}, {high:g}]", value)

    for key in _TEXT_FIELDS:
        if key in payload:
            text(key, payload[key])
    if "rate_hz" in payload:
        number("rate_hz", payload["rate_hz"], 1e-3, 1e5)
    if "duration_s" in payload and payload["duration_s"] is not None:
        number("duration_s", payload["duration_s"], 0, 1e9)
    robot = payload.get("robot", {})
    if not isinstance(robot, dict):
        refuse("robot", "an object", robot)
    for key in ("name", "source", "servo_model"):
        if key in robot:
            text(f"robot.{key}", robot[key])
    if "joint_count" in robot and (
        isinstance(robot["joint_count"], bool)
        or not isinstance(robot["joint_count"], int)
        or not 0 <= robot["joint_count"] <= 10_000
    ):
        refuse("robot.joint_count", "an integer in [0, 10000]", robot["joint_count"])
    ids = robot.get("servo_ids", [])
    if not isinstance(ids, list) or not all(
        isinstance(i, int) and not isinstance(i, bool) and 0 <= i <= 252 for i in ids
    ):
        refuse("robot.servo_ids", "a list of servo IDs (0 to 252)", ids)
    link = robot.get("link", {})
    if not isinstance(link, dict):
        refuse("robot.link", "an object", link)
    if "mass_kg" in link:
        number("robot.link.mass_kg", link["mass_kg"], 0, 1e6)
    gaits = [payload["gait"]] if "gait" in payload else []
    if "gaits" in payload:
        if not isinstance(payload["gaits"], list):
            refuse("gaits", "a list of objects", payload["gaits"])
        gaits += payload["gaits"]
    for gait in gaits:
        if not isinstance(gait, dict):
            refuse("gait", "an object with the gait's name and params", gait)
        if "name" in gait:
            text("gait.name", gait["name"])


def _jsonable(value: Any) -> Any:
    """Numbers, strings, lists and dicts as JSON takes them (arrays as lists, NaN as None)."""
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, str | bool) or value is None:
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "tolist"):
        return _jsonable(value.tolist())
    if isinstance(value, Sequence):
        return [_jsonable(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _jsonable(dataclasses.asdict(value))
    return str(value)
