"""``snakebot model``: write the twin's MJCF for MuJoCo's own viewer or other tools."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from snakebot.backends.twin.model_builder import (
    GroundFriction,
    add_actuators,
    build_spec,
    compile_spec,
)
from snakebot.cli.common import (
    add_dry_run,
    add_force_option,
    add_robot_option,
    check_writable,
    os_reason,
    print_json,
    report_dry_run,
    robot_name,
)
from snakebot.cli.terrain_options import (
    add_terrain_options,
    refuse_friction_model,
    terrain_help,
    twin_ground,
)
from snakebot.config.body import BodyConfig
from snakebot.config.body_loader import load_robot_or_body
from snakebot.errors import OutputError


def add_parser(subparsers: Any) -> None:
    """Register the ``model`` command."""
    parser = subparsers.add_parser("model", help="export the twin's MuJoCo model (MJCF)")
    add_robot_option(parser)
    parser.add_argument("--out", required=True, type=Path, help="MJCF file to write")
    parser.add_argument(
        "--friction",
        help="AXIAL,LATERAL ground friction (overrides the robot's); MU for a mass-spring body",
    )
    parser.add_argument("--terrain", metavar="NAME[:KEY=VALUE,...]", help=terrain_help())
    add_terrain_options(parser, terrain=False)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    add_force_option(parser)
    add_dry_run(parser, "no MJCF file")
    parser.set_defaults(handler=run, writes=True)


def run(args: argparse.Namespace) -> int:
    """Build the model exactly as the twin does and write it as XML."""
    robot = load_robot_or_body(robot_name(args, hardware=False, what="model"))
    check_writable(args.out, "model", force=args.force)
    if isinstance(robot, BodyConfig):
        from snakebot.cli.softbody_options import describe_body, softbody_spec

        refuse_friction_model(args, "applies to the rigid twin only")
        spec = softbody_spec(robot, args)
        what = describe_body(robot)
        spec.compile()
    else:
        friction = GroundFriction.parse(args.friction, "--friction") if args.friction else None
        spec = build_spec(robot, friction=friction, **twin_ground(args, robot))
        add_actuators(spec, robot)
        compile_spec(spec, robot)
        what = f"{robot.joint_count} joints"
    xml = spec.to_xml()
    if args.dry_run:
        return report_dry_run(
            args, {"robot": robot.name, "model": what, "out": args.out, "bytes": len(xml.encode())}
        )
    try:
        args.out.write_text(xml)
    except OSError as exc:
        raise OutputError(args.out, f"cannot write the model: {os_reason(exc)}") from exc
    if args.json:
        print_json({"robot": robot.name, "model": what, "out": str(args.out)})
    else:
        print(f"wrote {args.out} ({robot.name}: {what})")
    return 0
