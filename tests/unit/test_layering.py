"""The package's layering, read from the source: nothing imports upward or across a boundary.

Every ``import`` statement counts, including those inside functions (a lazy import is still a
dependency), so these scans see what ``import snakebot.x`` alone would not.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import snakebot

PACKAGE = Path(snakebot.__file__).resolve().parent

# Production modules allowed to import snakebot.emulation: the `emulate` command, and the
# hardware-in-the-loop bridge (emulated servos whose shafts are the twin's joints) inside it.
EMULATION_USERS = {"snakebot/cli/emulate_cmd.py", "snakebot/emulation/physics.py"}


def _modules(folder: Path) -> list[Path]:
    return sorted(folder.rglob("*.py"))


def _name(path: Path) -> str:
    return path.relative_to(PACKAGE.parent).as_posix()


def _module_of(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(path: Path) -> set[str]:
    """Every module ``path`` imports, relative imports resolved, ``from a import b`` as a.b too."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = _module_of(path) if path.name == "__init__.py" else _module_of(path).rsplit(".", 1)[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            out.add(base)
            out.update(f"{base}.{alias.name}" for alias in node.names)
    return out


def _hits(modules: list[Path], prefix: str) -> dict[str, list[str]]:
    found = {}
    for path in modules:
        names = sorted(n for n in imported(path) if n == prefix or n.startswith(prefix + "."))
        if names:
            found[_name(path)] = names
    return found


def test_the_scan_sees_lazy_and_relative_imports() -> None:
    # A scan that missed function-level or relative imports would pass vacuously.
    module = PACKAGE / "config" / "loader.py"
    assert "snakebot.config.fields" in imported(module)
    assert any(n.startswith("snakebot.emulation") for n in imported(PACKAGE / "cli/emulate_cmd.py"))


def test_config_never_imports_backends() -> None:
    assert _hits(_modules(PACKAGE / "config"), "snakebot.backends") == {}


@pytest.mark.parametrize("layer", ["types.py", "servo", "config", "control"])
def test_lower_layers_never_import_the_backends_or_the_emulator(layer: str) -> None:
    target = PACKAGE / layer
    modules = [target] if target.is_file() else _modules(target)
    for boundary in ("snakebot.backends", "snakebot.emulation", "snakebot.cli"):
        if layer == "control" and boundary == "snakebot.backends":
            continue  # the runner drives a Backend: control sits on the contract
        assert _hits(modules, boundary) == {}, f"{layer} imports {boundary}"


def test_only_the_emulate_command_and_the_hil_bridge_import_the_emulator() -> None:
    production = [p for p in _modules(PACKAGE) if "emulation" not in p.relative_to(PACKAGE).parts]
    production += [PACKAGE / "emulation" / "physics.py"]
    users = set(_hits(production, "snakebot.emulation"))
    assert users <= EMULATION_USERS, f"unexpected importers of snakebot.emulation: {users}"


def test_types_import_neither_mujoco_nor_the_sdk() -> None:
    names = imported(PACKAGE / "types.py")
    assert not {n for n in names if n.split(".")[0] in ("mujoco", "dynamixel_sdk")}
    code = (
        "import sys, snakebot.types, snakebot.servo, snakebot.config; "
        "heavy = [m for m in ('mujoco', 'dynamixel_sdk') if m in sys.modules]; "
        "assert not heavy, heavy"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
