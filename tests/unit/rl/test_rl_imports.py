"""`import snakebot` (and the CLI's parser) stay light; a missing extra is named when needed."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

HEAVY = ("gymnasium", "torch", "stable_baselines3")


def python(code: str) -> subprocess.CompletedProcess[str]:
    # torch alone takes seconds to import on a busy machine
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)


def test_import_snakebot_and_building_the_cli_import_no_learning_package() -> None:
    done = python(
        "import sys, snakebot, snakebot.cli.main as m\n"
        "m.build_parser()\n"
        f"print([name for name in {HEAVY!r} if name in sys.modules])\n"
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def blocked(modules: tuple[str, ...], then: str) -> subprocess.CompletedProcess[str]:
    """Run ``then`` with ``modules`` uninstallable (None in sys.modules makes import fail)."""
    block = "".join(f"sys.modules[{m!r}] = None\n" for m in modules)
    return python(f"import sys\n{block}{then}")


def test_without_gymnasium_the_rl_extra_is_named(tmp_path: Path) -> None:
    done = blocked(("gymnasium",), "import snakebot.rl\n")
    assert done.returncode != 0
    assert "MissingDependencyError" in done.stderr and "snakebot[rl]" in done.stderr
    assert "snakebot.rl (the learning environments) needs gymnasium" in done.stderr
    run = blocked(
        ("gymnasium",),
        "from snakebot.cli.main import main\n"
        f"sys.exit(main(['run', '--policy', {str(tmp_path)!r}, '--command', '0,0']))",
    )
    assert run.returncode == 1
    assert "pip install 'snakebot[rl]'" in run.stderr


def test_without_gymnasium_every_rl_command_names_the_rl_extra_first(tmp_path: Path) -> None:
    # gymnasium comes before stable-baselines3 and torch: the 'rl' extra is the one to name
    # whether or not the others are installed (a fresh '.[test]' venv has none of them).
    for argv in (
        ["rl", "train", "--steps", "10", "--out", str(tmp_path / "t")],
        ["rl", "compare", "--steps", "10", "--out", str(tmp_path / "c")],
        ["rl", "eval", str(tmp_path)],
    ):
        done = blocked(
            ("gymnasium",), f"from snakebot.cli.main import main\nsys.exit(main({argv!r}))"
        )
        assert done.returncode == 1, (argv, done.stderr)
        assert "needs gymnasium" in done.stderr and "pip install 'snakebot[rl]'" in done.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(
    importlib.util.find_spec("gymnasium") is None,
    reason="without gymnasium the 'rl' extra is named first (test above)",
)
def test_without_stable_baselines3_or_torch_the_rl_train_extra_is_named(tmp_path: Path) -> None:
    order = ("torch", "stable_baselines3")  # what rl train imports first is named first
    for module in order:
        missing = [m for m in order if m == module or importlib.util.find_spec(m) is None]
        done = blocked(
            (module,),
            "from snakebot.cli.main import main\n"
            f"sys.exit(main(['rl', 'train', '--steps', '10', '--out', "
            f"{str(tmp_path / module)!r}]))",
        )
        assert done.returncode == 1, done.stderr
        assert f"needs {missing[0]}" in done.stderr
        assert "pip install 'snakebot[rl-train]'" in done.stderr
