"""``--gaits``, ``--set``, ``--rate``, ``--smoothing`` and ``--transition`` for ``drive`` and
``ros2``: the live gaits a person (or cmd_vel) steers, the options and the gait list they give."""

from __future__ import annotations

import argparse

from snakebot.cli.common import gait_list_arg, positive_float
from snakebot.config import RobotConfig
from snakebot.drive.controller import GaitChoice
from snakebot.drive.setup import (
    DEFAULT_SMOOTHING_S,
    DEFAULT_TRANSITION_S,
    MAX_GAITS,
    default_gaits,
)
from snakebot.errors import ConfigError
from snakebot.gaits import check_joint_axes, parse_set_options
from snakebot.session import DEFAULT_RATE_HZ


def add_gait_options(parser: argparse.ArgumentParser, *, gaits_help: str) -> None:
    """Add the live-gait options to ``parser``; ``gaits_help`` says what the list is for."""
    parser.add_argument("--gaits", type=gait_list_arg, help=gaits_help)
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="GAIT.KEY=VALUE",
        help="a gait parameter (repeatable), e.g. --set sidewinding.amplitude_even=0.5; "
        "KEY=VALUE alone when one gait is listed",
    )
    parser.add_argument(
        "--rate",
        type=positive_float,
        default=DEFAULT_RATE_HZ,
        help=f"control rate in Hz (default {DEFAULT_RATE_HZ:g})",
    )
    parser.add_argument(
        "--smoothing",
        type=float,
        default=DEFAULT_SMOOTHING_S,
        metavar="S",
        help="seconds for a control (speed, turn; on drive's keys amplitude too) to move one "
        f"unit (default {DEFAULT_SMOOTHING_S:g})",
    )
    parser.add_argument(
        "--transition",
        type=float,
        default=DEFAULT_TRANSITION_S,
        metavar="S",
        help=f"shortest blend between gaits in s (default {DEFAULT_TRANSITION_S:g}; longer when "
        "the servos need it)",
    )


def gait_choices(robot: RobotConfig, args: argparse.Namespace) -> list[GaitChoice]:
    """The gait list from --gaits (or the robot's default) with the --set overrides.

    ConfigError naming --gaits (none, or more than MAX_GAITS) or --set (a GAIT not listed, or a
    bare KEY=VALUE with several gaits), or a gait's own error for its parameters or the robot's
    joint axes.
    """
    names = (
        [n.strip() for n in args.gaits.split(",") if n.strip()]
        if args.gaits
        else list(default_gaits(robot))
    )
    if not names or len(names) > MAX_GAITS:
        raise ConfigError(
            "--gaits", "", f"expected 1 to {MAX_GAITS} gait names, got {args.gaits!r}"
        )
    overrides: dict[str, list[str]] = {name: [] for name in names}
    for item in args.set:
        key = item.partition("=")[0]
        gait, dot, _ = key.partition(".")
        if dot and gait in overrides:
            overrides[gait].append(item[len(gait) + 1 :])
        elif not dot and len(names) == 1:
            overrides[names[0]].append(item)
        else:
            raise ConfigError(
                "--set",
                "",
                f"{item}: expected GAIT.KEY=VALUE with GAIT one of {', '.join(names)} "
                "(KEY=VALUE alone only when one gait is listed)",
            )
    for name in names:
        check_joint_axes(name, [joint.axis for joint in robot.joints], robot.name)
    return [GaitChoice(name, parse_set_options(name, overrides[name])) for name in names]
