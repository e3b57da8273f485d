"""Tab completion through argcomplete's protocol (the optional `completion` extra): the shell
sets _ARGCOMPLETE and COMP_LINE, snakebot answers with the matching commands or options."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("argcomplete")


def complete(line: str, tmp_path: Path) -> list[str]:
    answer = tmp_path / "candidates"
    env = {
        **os.environ,
        "_ARGCOMPLETE": "1",
        "COMP_LINE": line,
        "COMP_POINT": str(len(line)),
        "_ARGCOMPLETE_STDOUT_FILENAME": str(answer),
    }
    done = subprocess.run(
        [sys.executable, "-m", "snakebot"], env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    return sorted(word.strip() for word in answer.read_text().split("\013"))


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("snakebot tu", ["tune"]),
        ("snakebot ro", ["robots", "ros2"]),
        ("snakebot run --dur", ["--duration"]),
        ("snakebot tune gains --dr", ["--dry-run"]),
        ("snakebot config a", ["apply", "assign-id"]),
    ],
)
def test_completion(line: str, expected: list[str], tmp_path: Path) -> None:
    assert complete(line, tmp_path) == expected
