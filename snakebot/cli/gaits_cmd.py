"""``snakebot gaits``: the gaits, their parameters, units and defaults."""

from __future__ import annotations

import argparse
from typing import Any

from snakebot.cli.common import print_json
from snakebot.gaits import gait_names, get_spec


def add_parser(subparsers: Any) -> None:
    """Register the ``gaits`` command."""
    parser = subparsers.add_parser("gaits", help="list gaits with their parameters and defaults")
    parser.add_argument("name", nargs="?", help="show only this gait")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Print every gait (or one) with parameter name, unit, default and meaning."""
    names = [args.name] if args.name else gait_names()
    specs = [get_spec(name) for name in names]
    if args.json:
        print_json(
            [
                {
                    "name": s.name,
                    "summary": s.summary,
                    "params": [
                        {"name": p.name, "unit": p.unit, "default": p.default, "doc": p.doc}
                        for p in s.params
                    ],
                }
                for s in specs
            ]
        )
        return 0
    for spec in specs:
        print(f"{spec.name}: {spec.summary}")
        for p in spec.params:
            default = (
                ",".join(f"{v:g}" for v in p.default)
                if isinstance(p.default, tuple)
                else (f"{p.default:g}" if isinstance(p.default, float) else str(p.default))
            )
            unit = f" [{p.unit}]" if p.unit else ""
            print(f"    {p.name}{unit} = {default}    {p.doc}")
        print()
    return 0
