"""Gaits: joint-angle targets (rad) over time (s) for head-to-tail indexed snake joints."""

from snakebot.gaits.base import Gait, PhasedGait
from snakebot.gaits.compound import CompoundGait
from snakebot.gaits.dft import DftGait, DftShiftGait, dft_coefficients_from_pose, scale_into_limits
from snakebot.gaits.expr import parse_number
from snakebot.gaits.gait_file import load_gait_file, save_gait_file
from snakebot.gaits.keyframes import KeyframeGait
from snakebot.gaits.live import LiveGait, LiveStatus
from snakebot.gaits.live_track import LiveControls
from snakebot.gaits.registry import (
    GAITS,
    GaitSpec,
    ParamSpec,
    check_joint_axes,
    gait_names,
    gait_origin,
    get_spec,
    make_gait,
    parse_set_options,
    register_gait,
    resolve_params,
)
from snakebot.gaits.serpenoid import SerpenoidGait
from snakebot.gaits.simple import SimpleGait
from snakebot.gaits.spec import JointAxes, LiveRoles, ParamValues

__all__ = [
    "GAITS",
    "CompoundGait",
    "DftGait",
    "DftShiftGait",
    "Gait",
    "GaitSpec",
    "JointAxes",
    "KeyframeGait",
    "LiveControls",
    "LiveGait",
    "LiveRoles",
    "LiveStatus",
    "ParamSpec",
    "ParamValues",
    "PhasedGait",
    "SerpenoidGait",
    "SimpleGait",
    "check_joint_axes",
    "dft_coefficients_from_pose",
    "gait_names",
    "gait_origin",
    "get_spec",
    "load_gait_file",
    "make_gait",
    "parse_number",
    "parse_set_options",
    "register_gait",
    "resolve_params",
    "save_gait_file",
    "scale_into_limits",
]
