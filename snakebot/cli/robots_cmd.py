"""``snakebot robots``: the robots and bodies ``--robot NAME`` can name, and where each is from."""

from __future__ import annotations

import argparse
from typing import Any

from snakebot.cli.common import print_json
from snakebot.config.paths import config_search_path


def add_parser(subparsers: Any) -> None:
    """Register the ``robots`` command."""
    parser = subparsers.add_parser(
        "robots",
        help="list the robots and bodies --robot can name, and where each comes from",
        description="Robot names are looked up, first match wins, in: $SNAKEBOT_CONFIG_PATH, "
        "./firmware_configs, the user's config directory (~/.config/snakebot on Linux), then "
        "the robots shipped with snakebot. A file further down with the same name is shadowed.",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(handler=run, writes=False)


def find_all() -> list[dict[str, Any]]:
    """Every robot and body file on the search path, in lookup order; ``shadowed`` is True for
    a file hidden by an earlier one of the same kind and name."""
    seen: set[tuple[str, str]] = set()
    found: list[dict[str, Any]] = []
    for folder in config_search_path():
        for kind, sub in (("robot", "robots"), ("body", "bodies")):
            for path in sorted((folder.path / sub).glob("*.toml")):
                key = (kind, path.stem)
                found.append(
                    {
                        "name": path.stem,
                        "kind": kind,
                        "origin": folder.origin,
                        "path": str(path),
                        "shadowed": key in seen,
                    }
                )
                seen.add(key)
    return found


def run(args: argparse.Namespace) -> int:
    """Print the robots and bodies with their origin and file, then the search path."""
    found = find_all()
    search = [
        {"path": str(f.path), "origin": f.origin, "exists": f.path.is_dir()}
        for f in config_search_path()
    ]
    if args.json:
        print_json({"robots": found, "search_path": search})
        return 0
    rows = [("name", "kind", "from", "file")]
    rows += [
        (r["name"] + (" (shadowed)" if r["shadowed"] else ""), r["kind"], r["origin"], r["path"])
        for r in found
    ]
    widths = [max(len(row[i]) for row in rows) for i in range(3)]
    for row in rows:
        print("  ".join([*(c.ljust(w) for c, w in zip(row, widths, strict=False)), row[3]]))
    print("\nsearch path (first match wins; --robot FILE.toml bypasses it):")
    for entry in search:
        missing = "" if entry["exists"] else "  (absent)"
        print(f"  {entry['origin']:<22} {entry['path']}{missing}")
    return 0
