"""JSON Schemas of the telemetry channels: snakebot's own messages and the Foxglove ones we use.

Every channel is JSON-encoded, so any client (a test, ``mcap cat``, jq) reads it without protobuf.
Foxglove recognises its own message types by schema name (``foxglove.FrameTransforms``, ...) in
JSON as in protobuf; the schemas below describe the fields we write, which is what Foxglove's
message-path completion and the Plot panel read.
"""

from __future__ import annotations

import json
from typing import Any

JOINTS_TOPIC = "/joints"
HEALTH_TOPIC = "/servo_health"
ERRORS_TOPIC = "/servo_errors"
METRICS_TOPIC = "/run_metrics"
DRIVE_TOPIC = "/drive"
TF_TOPIC = "/tf"
SCENE_TOPIC = "/scene"

_NUMBERS = {"type": "array", "items": {"type": "number"}}
_TIME = {
    "type": "object",
    "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}},
}
_VECTOR3 = {
    "type": "object",
    "properties": {axis: {"type": "number"} for axis in "xyz"},
}
_QUATERNION = {
    "type": "object",
    "properties": {axis: {"type": "number"} for axis in "xyzw"},
}
_POSE = {"type": "object", "properties": {"position": _VECTOR3, "orientation": _QUATERNION}}
_COLOR = {"type": "object", "properties": {c: {"type": "number"} for c in ("r", "g", "b", "a")}}

JOINTS: dict[str, Any] = {
    "title": "snakebot.Joints",
    "description": "One control cycle, head to tail: what was commanded and what was measured",
    "type": "object",
    "properties": {
        "time_s": {"type": "number", "description": "robot time (s)"},
        "cycle": {"type": "integer"},
        "command_rad": _NUMBERS,
        "position_rad": _NUMBERS,
        "velocity_rad_s": _NUMBERS,
        "effort_nm": _NUMBERS,
        "tracking_error_rad": {**_NUMBERS, "description": "command - position"},
        "com_m": {**_NUMBERS, "description": "centre of mass (x, y, z); absent on hardware"},
    },
}
HEALTH: dict[str, Any] = {
    "title": "snakebot.ServoHealth",
    "description": "Slow servo readings where the backend has them (hardware)",
    "type": "object",
    "properties": {
        "time_s": {"type": "number"},
        "servo_ids": {"type": "array", "items": {"type": "integer"}},
        "temperature_c": _NUMBERS,
        "input_voltage_v": _NUMBERS,
    },
}
ERRORS: dict[str, Any] = {
    "title": "snakebot.ServoErrors",
    "description": "What went wrong so far: clipped commands, watchdog re-arms, retries, alerts",
    "type": "object",
    "properties": {
        "time_s": {"type": "number"},
        "count": {"type": "integer"},
        "errors": {"type": "array", "items": {"type": "string"}},
    },
}
METRICS: dict[str, Any] = {
    "title": "snakebot.RunMetrics",
    "description": "The run so far, refreshed a few times a second",
    "type": "object",
    "properties": {
        "time_s": {"type": "number"},
        "cycles": {"type": "integer"},
        "rate_hz": {"type": "number", "description": "control rate asked for"},
        "achieved_rate_hz": {"type": "number", "description": "over the last interval"},
        "overruns": {"type": "integer"},
        "tracking_rms_rad": {"type": "number", "description": "over the last interval"},
        "distance_m": {"type": ["number", "null"]},
        "speed_mps": {"type": ["number", "null"], "description": "over the last interval"},
    },
}
DRIVE: dict[str, Any] = {
    "title": "snakebot.DriveStatus",
    "description": "The live gait a drive plays: gait, mode, controls and keys applied",
    "type": "object",
    "properties": {
        "time_s": {"type": "number"},
        "gait": {"type": "string"},
        "mode": {"type": "string"},
        "speed": {"type": "number"},
        "turn": {"type": "number"},
        "amplitude": {"type": "number"},
        "wavelength": {"type": "number"},
        "blend": {"type": ["number", "null"]},
        "target_rad": _NUMBERS,
        "keys": {"type": "array", "items": {"type": "string"}},
    },
}
FRAME_TRANSFORMS: dict[str, Any] = {
    "title": "foxglove.FrameTransforms",
    "type": "object",
    "properties": {
        "transforms": {
            "type": "array",
            "items": {
                "type": "object",
                "properties": {
                    "timestamp": _TIME,
                    "parent_frame_id": {"type": "string"},
                    "child_frame_id": {"type": "string"},
                    "translation": _VECTOR3,
                    "rotation": _QUATERNION,
                },
            },
        }
    },
}
_PRIMITIVE = {
    "type": "array",
    "items": {"type": "object", "properties": {"pose": _POSE, "size": _VECTOR3, "color": _COLOR}},
}
SCENE_UPDATE: dict[str, Any] = {
    "title": "foxglove.SceneUpdate",
    "type": "object",
    "properties": {
        "deletions": {"type": "array", "items": {"type": "object"}},
        "entities": {
            "type": "array",
            "items": {
                "type": "object",
                "properties": {
                    "timestamp": _TIME,
                    "frame_id": {"type": "string"},
                    "id": {"type": "string"},
                    "lifetime": _TIME,
                    "frame_locked": {"type": "boolean"},
                    "cylinders": _PRIMITIVE,
                    "spheres": _PRIMITIVE,
                },
            },
        },
    },
}


def schema_bytes(schema: dict[str, Any]) -> bytes:
    """The schema as the UTF-8 JSON an MCAP Schema record or a channel advertisement carries."""
    return json.dumps(schema, separators=(",", ":")).encode()


CHANNELS: dict[str, dict[str, Any]] = {
    JOINTS_TOPIC: JOINTS,
    HEALTH_TOPIC: HEALTH,
    ERRORS_TOPIC: ERRORS,
    METRICS_TOPIC: METRICS,
    DRIVE_TOPIC: DRIVE,
    TF_TOPIC: FRAME_TRANSFORMS,
    SCENE_TOPIC: SCENE_UPDATE,
}
"""Topic -> JSON Schema (its ``title`` is the schema name)."""
