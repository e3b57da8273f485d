"""Build hook: ship the top-level ``firmware_configs/`` and ``sim/`` inside the wheel.

They stay at the top of the repository (the layout users know) and are copied into
``snakebot/_data/`` of the built package, where ``snakebot.config.paths`` finds them with
``importlib.resources``. An editable install needs no copy: it reads them from the checkout.
Everything else about the build is in pyproject.toml.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
DATA_FOLDERS = ("firmware_configs", "sim")
DATA_SUFFIXES = (".toml", ".xml")


class BuildPyWithData(build_py):
    """``build_py`` that also copies the data folders into ``snakebot/_data``."""

    def run(self) -> None:
        """Build the package as usual, then copy the data folders (not for editable installs)."""
        super().run()
        if getattr(self, "editable_mode", False):
            return  # the editable package finds the checkout's own folders
        target = Path(self.build_lib) / "snakebot" / "_data"
        shutil.rmtree(target, ignore_errors=True)
        for name in DATA_FOLDERS:
            source = ROOT / name
            if not source.is_dir():
                raise FileNotFoundError(f"{source}: missing; the wheel would ship without it")
            for path in sorted(source.rglob("*")):
                if path.is_file() and path.suffix in DATA_SUFFIXES:
                    dest = target / name / path.relative_to(source)
                    dest.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy2(path, dest)


setup(cmdclass={"build_py": BuildPyWithData})
