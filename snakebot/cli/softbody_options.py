"""Command-line options of mass-spring bodies, shared by ``run``, ``model`` and ``tune gait``."""

from __future__ import annotations

import argparse
import math

import mujoco

from snakebot.backends.softbody import SoftBodyBackend, build_body_spec
from snakebot.backends.twin.cliff import Cliff, parse_terrain
from snakebot.config.body import BodyConfig
from snakebot.errors import ConfigError


def parse_floor_friction(text: str, option: str = "--friction") -> float:
    """A body's floor friction: ``MU``, or ``MU,MU`` (the twin's AXIAL,LATERAL with both equal)."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if not 1 <= len(values) <= 2 or not all(math.isfinite(v) and v >= 0 for v in values):
        raise ConfigError(option, "", f"expected one friction coefficient >= 0, got {text!r}")
    if len(values) == 2 and values[0] != values[1]:
        raise ConfigError(
            option,
            "",
            f"a mass-spring body's floor is isotropic: give one number, got {text!r} "
            "(forward/backward asymmetry is --directional on)",
        )
    return values[0]


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
        parse_terrain(terrain_text) if terrain_text else None,
    )


def make_softbody_backend(body: BodyConfig, args: argparse.Namespace) -> SoftBodyBackend:
    """The soft-body twin of ``body`` as ``snakebot run`` options ask (sim backend only)."""
    if getattr(args, "backend", "sim") != "sim":
        raise ConfigError(
            "--backend",
            "",
            f"{body.name} is a mass-spring body: it runs on the twin only (--backend sim)",
        )
    friction, directional, terrain = softbody_options(args)
    return SoftBodyBackend(
        body,
        friction=friction,
        directional=directional,
        terrain=terrain,
        realtime=bool(getattr(args, "realtime", False) or getattr(args, "viewer", False)),
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
