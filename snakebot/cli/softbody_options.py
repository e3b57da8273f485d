"""Command-line options of mass-spring bodies, shared by ``run``, ``model`` and ``tune gait``."""

from __future__ import annotations

import argparse

import mujoco

from snakebot.backends.softbody import build_body_spec
from snakebot.backends.softbody.factory import body_terrain_option
from snakebot.backends.softbody.factory import parse_floor_friction as floor_friction
from snakebot.backends.twin.terrain.cliff import Cliff
from snakebot.config.body import BodyConfig


def parse_floor_friction(text: str, option: str = "--friction") -> float:
    """A body's floor friction: ``MU``, or ``MU,MU`` (the twin's AXIAL,LATERAL with both equal)."""
    return floor_friction(text, option)


def softbody_options(
    args: argparse.Namespace,
) -> tuple[float | None, bool | None, Cliff | None]:
    """(friction, directional, terrain) from --friction, --directional and --terrain; None where
    the option was not given (the body file decides)."""
    text = getattr(args, "friction", None)
    friction = parse_floor_friction(text) if text else None
    directional = getattr(args, "directional", None)
    terrain_text = getattr(args, "terrain", None)
    return (
        friction,
        None if directional is None else directional == "on",
        body_terrain_option(terrain_text, "--terrain") if terrain_text else None,
    )


def softbody_spec(body: BodyConfig, args: argparse.Namespace) -> mujoco.MjSpec:
    """The MjSpec ``snakebot model`` writes: the body with --friction and --terrain applied."""
    friction, _directional, terrain = softbody_options(args)
    return build_body_spec(body, friction=friction, terrain=terrain)


def describe_body(body: BodyConfig) -> str:
    """One line: segments, points, springs and their SI constants."""
    segments = body.lattice.segments
    springs = 6 * (segments + 1) + 12 * segments
    return (
        f"{segments} segments, {body.point_count} points, {springs} springs of "
        f"{body.stiffness_n_per_m:.4g} N/m and {body.damping_ns_per_m:.4g} N·s/m "
        f"(damping ratio {body.springs.damping_ratio:.2f}), {body.joint_count} channels"
    )
