"""Every python block of docs/learning.md runs as a reader would paste it: its own script in a
folder that holds the policy it names (a hand-made goal policy in ``goal/``)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from snakebot.rl.settings import GOAL_ENV_ID
from tests.conftest import REPO
from tests.integration.rl.policies import constant_policy

BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
BLOCKS = BLOCK.findall((REPO / "docs" / "learning.md").read_text(encoding="utf-8"))


def test_the_page_has_its_two_examples() -> None:
    assert len(BLOCKS) == 2
    assert "pose=Mocap(snake)" in BLOCKS[1]


@pytest.mark.parametrize("code", BLOCKS, ids=[f"block{i}" for i in range(len(BLOCKS))])
def test_each_example_runs_as_written(code: str, tmp_path: Path) -> None:
    # swims ahead (dft_shift bin 1): the pose example's snake moves toward its goal
    constant_policy(tmp_path / "goal", GOAL_ENV_ID, [0, 1, 0, 0, 0], 2 * 8 + 2 + 2)
    script = tmp_path / "example.py"
    script.write_text(code, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, str(script)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, f"{code}\n---\n{done.stderr[-3000:]}"
    assert "Traceback" not in done.stderr
    if "Mocap" in code:
        gait, distance = done.stdout.split()
        assert gait == "PolicyGait", done.stdout
        assert float(distance) > 0.1, done.stdout
