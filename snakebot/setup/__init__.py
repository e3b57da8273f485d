"""Servo setup driven by the robot config: settings as data, diff/apply, IDs, calibration, recovery.

``load_settings`` reads what a robot wants on each servo; ``survey`` finds the servos (at any baud
rate) and lists the differences; ``plan_apply``/``apply`` write them safely; ``assign_id`` brings
up a factory-fresh servo; ``calibrate`` measures zero offsets; ``maintenance`` reboots, resets and
reads servos. Everything talks to the bus through ``Link`` (the Dynamixel backend's bus).
"""

from snakebot.setup.apply import ApplyPlan, Step, apply, plan_apply
from snakebot.setup.assign import Assignment, Found, assign_id, find_servos
from snakebot.setup.diff import ChainDiff, Difference, survey
from snakebot.setup.errors import DuplicateIdError, SetupError, VerifyError
from snakebot.setup.link import SEARCH_BAUDS, Link
from snakebot.setup.settings import ChainSettings, Setting, load_settings

__all__ = [
    "SEARCH_BAUDS",
    "ApplyPlan",
    "Assignment",
    "ChainDiff",
    "ChainSettings",
    "Difference",
    "DuplicateIdError",
    "Found",
    "Link",
    "Setting",
    "SetupError",
    "Step",
    "VerifyError",
    "apply",
    "assign_id",
    "find_servos",
    "load_settings",
    "plan_apply",
    "survey",
]
