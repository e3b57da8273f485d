"""Plain `pytest` from the repository root collects the suite, not only `python -m pytest`
(which alone puts the working directory on sys.path for the shared tests.* helpers)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PYTEST = Path(sys.executable).with_name("pytest")


@pytest.mark.skipif(not PYTEST.exists(), reason="no pytest console script beside the interpreter")
def test_the_pytest_script_imports_the_shared_helpers() -> None:
    helper_user = "tests/integration/tuning/test_tuning_gains.py"  # imports tests.pty_emulator
    assert "from tests.pty_emulator import" in (REPO / helper_user).read_text()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [str(PYTEST), "--collect-only", "-q", "-p", "no:cacheprovider", helper_user],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "::test_cli_writes_the_new_gains_into_the_robot_file" in done.stdout
