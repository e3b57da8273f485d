"""Install plugin projects for tests as pip lays them out: the package beside a ``*.dist-info``
(METADATA, entry_points.txt) in a folder put on sys.path or PYTHONPATH.

importlib.metadata finds such a folder like any site-packages, so the registries see the entry
points exactly as for a real install, in this process or in a `snakebot` subprocess.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import re
import shutil
import sys
import tomllib
from collections.abc import Iterator, Mapping
from pathlib import Path

from snakebot.backends.registry import BACKENDS
from snakebot.backends.terrains import TERRAINS
from snakebot.gaits import GAITS

EXAMPLE = Path(__file__).resolve().parent / "example"
EntryPoints = Mapping[str, Mapping[str, str]]


def install_project(site: Path, project: Path = EXAMPLE) -> str:
    """Copy ``project``'s packages into ``site`` and write its dist-info from pyproject.toml (the
    [project] name, version and entry-points tables); returns the distribution name."""
    data = tomllib.loads((project / "pyproject.toml").read_text(encoding="utf-8"))
    meta = data["project"]
    for package in data["tool"]["setuptools"]["packages"]:
        shutil.copytree(project / package, site / package)
    write_dist_info(site, meta["name"], meta["version"], meta.get("entry-points", {}))
    return str(meta["name"])


def write_dist_info(site: Path, name: str, version: str, entry_points: EntryPoints) -> Path:
    """A dist-info folder for distribution ``name`` declaring ``entry_points`` {group: {name:
    "module:attr"}}."""
    info = site / f"{re.sub(r'[-_.]+', '_', name)}-{version}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(
        f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n", encoding="utf-8"
    )
    lines: list[str] = []
    for group, points in entry_points.items():
        lines += [f"[{group}]", *(f"{key} = {value}" for key, value in points.items()), ""]
    (info / "entry_points.txt").write_text("\n".join(lines), encoding="utf-8")
    return info


def write_module(site: Path, name: str, source: str) -> Path:
    """A top-level module ``name`` in ``site`` holding ``source``."""
    path = site / f"{name}.py"
    path.write_text(source, encoding="utf-8")
    return path


def environment(site: Path) -> dict[str, str]:
    """The environment of a `snakebot` subprocess that sees the plugins in ``site``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(site), env.get("PYTHONPATH", "")]))
    return env


@contextlib.contextmanager
def on_path(site: Path) -> Iterator[None]:
    """Make the plugins in ``site`` visible to this process (the gait, backend and terrain
    registries re-read their entry points), then remove them and every module imported from
    ``site``."""
    sys.path.insert(0, str(site))
    importlib.invalidate_caches()
    for registry in (GAITS, BACKENDS, TERRAINS):
        registry.refresh()
    try:
        yield
    finally:
        sys.path.remove(str(site))
        for name, module in list(sys.modules.items()):
            origin = getattr(module, "__file__", None) or ""
            if origin.startswith(str(site)):
                del sys.modules[name]
        importlib.invalidate_caches()
        for registry in (GAITS, BACKENDS, TERRAINS):
            registry.refresh()
