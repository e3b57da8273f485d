"""``snakebot gaits``: the gaits, where each comes from, their parameters and tuning bounds."""

from __future__ import annotations

import argparse
import math
from typing import Any

from snakebot.cli.common import gait_arg, print_json
from snakebot.gaits import GAITS, GaitSpec, ParamSpec, get_spec
from snakebot.plugins import Origin


def add_parser(subparsers: Any) -> None:
    """Register the ``gaits`` command."""
    parser = subparsers.add_parser(
        "gaits",
        help="list gaits (built-in, plugins, ...) with their parameters, defaults and bounds",
    )
    parser.add_argument("name", nargs="?", type=gait_arg, help="show only this gait")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(handler=run, writes=False)


def run(args: argparse.Namespace) -> int:
    """Print every gait that loads (or one) with its origin and, per parameter, unit, default,
    tuning bounds, whether ``tune gait`` searches it by default, and meaning."""
    specs = [get_spec(args.name)] if args.name else list(GAITS.load_all().values())
    if args.json:
        print_json([_as_json(spec, GAITS.origin(spec.name)) for spec in specs])
        return 0
    for spec in specs:
        print(_as_text(spec, GAITS.origin(spec.name)))
    return 0


def _as_json(spec: GaitSpec, origin: Origin) -> dict[str, object]:
    plugin = origin.kind == "plugin"
    return {
        "name": spec.name,
        "summary": spec.summary,
        "origin": str(origin),
        "distribution": origin.distribution if plugin else None,
        "version": origin.version if plugin else None,
        "entry_point": origin.entry_point if plugin else None,
        "default_search": list(spec.default_search),
        "rolls_over": spec.rolls_over,
        "axes": {"even": spec.axes.even, "odd": spec.axes.odd, "required": spec.axes.required},
        "params": [
            {
                "name": p.name,
                "unit": p.unit,
                "default": p.default,
                "doc": p.doc,
                "bounds": list(p.bounds) if p.bounds is not None else None,
                "tunable": p.tunable,
                "joint_poses": p.joint_poses,
                "choices": list(p.choices),
            }
            for p in spec.params
        ],
    }


def _as_text(spec: GaitSpec, origin: Origin) -> str:
    rows = [("parameter", "unit", "default", "bounds", "tuned", "meaning")]
    rows += [
        (p.name, p.unit or "-", _default(p), _bounds(p), "yes" if p.tunable else "-", p.doc)
        for p in spec.params
    ]
    widths = [max(len(row[i]) for row in rows) for i in range(5)]
    lines = [f"{spec.name} [{origin}]: {spec.summary}"]
    lines += [
        "    " + "  ".join([*(c.ljust(w) for c, w in zip(row, widths, strict=False)), row[5]])
        for row in rows
    ]
    search = ", ".join(spec.default_search) or "none (name --params)"
    lines.append(f"    tune gait searches by default: {search}")
    if spec.axes.even is not None or spec.axes.odd is not None:
        strict = "refused" if spec.axes.required else "warned about"
        lines.append(f"    joint axes: needs {spec.axes.describe()} (other axes are {strict})")
    return "\n".join(lines) + "\n"


def _default(param: ParamSpec) -> str:
    default = param.default
    if isinstance(default, tuple):
        return ",".join(_number(v) for v in default) or "(empty)"
    return _number(default) if isinstance(default, float) else str(default)


def _bounds(param: ParamSpec) -> str:
    if param.bounds is None:
        return "-"
    low, high = param.bounds
    text = f"{_number(low)}:{_number(high)}"
    return f"{text} (within joint limits)" if param.joint_poses else text


def _number(value: float) -> str:
    """Simple multiples of pi as --set and --bounds accept them ("pi/2", "-6*pi"), else %g."""
    for divisor in (1, 2, 3, 4, 6, 8):
        multiple = value * divisor / math.pi
        whole = round(multiple)
        if whole and abs(multiple - whole) < 1e-9:
            factor = {1: "pi", -1: "-pi"}.get(whole, f"{whole}*pi")
            return factor if divisor == 1 else f"{factor}/{divisor}"
    return f"{value:g}"
