"""``run --to`` over the emulated bus: the odometry sees only what the servos report.

`snakebot emulate --physics --pty` backs each virtual servo with the twin in real time; the
twin's own summary on exit is the ground truth the bus never shows.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from snakebot.backends.chain import ServoSettingsWarning
from snakebot.cli.main import main
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def test_run_to_a_point_over_the_bus_ends_near_it(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["run", "--backend", "dynamixel", "--robot", "snake8", "--to", "1.5,0.5", "--json"]
    with emulator("--robot", "snake8", "--physics") as emu:
        with pytest.warns(ServoSettingsWarning, match="config apply"):  # factory settings
            assert main([*argv, "--port", emu.port, "--duration", "40"]) == 0
        over_bus = json.loads(capsys.readouterr().out)
        twin = emu.stop()[-1]  # the twin's summary, printed on exit
    assert over_bus["distance_m"] is None  # the bus cannot measure it; the twin can
    assert over_bus["reached"] is True and "reached the point" in over_bus["stopped_by"]
    # The twin starts straight at the origin facing +x: the point is 1.5 m ahead, 0.5 m left.
    dx, dy = twin["displacement_m"]
    facts = {k: over_bus.get(k) for k in ("achieved_rate_hz", "overruns", "duration_s")}
    assert math.hypot(dx - 1.5, dy - 0.5) <= 0.3, (twin["displacement_m"], facts)


def test_a_goal_policy_on_the_odometry_over_the_bus(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`run --policy GOAL --odometry` over the bus: the policy's pose is the odometry of the
    joints the servos report (no IMU on the bus), and the twin behind the bus moves."""
    pytest.importorskip("gymnasium")
    from snakebot.rl.settings import GOAL_ENV_ID
    from tests.integration.rl.policies import constant_policy

    folder = constant_policy(
        tmp_path / "goal", GOAL_ENV_ID, [0, 0, 0, 0], 2 * 8 + 2 + 2, encoding="sinusoid"
    )
    argv = ["run", "--backend", "dynamixel", "--robot", "snake8", "--policy", str(folder)]
    argv += ["--odometry", "--command", "1,0", "--duration", "4", "--json"]
    with emulator("--robot", "snake8", "--physics") as emu:
        with pytest.warns(ServoSettingsWarning, match="config apply"):  # factory settings
            code = main([*argv, "--port", emu.port])
        out, err = capsys.readouterr()
        assert code == 0, err + out
        over_bus = json.loads(out)
        twin = emu.stop()[-1]
    assert over_bus["gait"] == "policy:goal:sinusoid"
    assert over_bus["distance_m"] is None  # the bus cannot measure it
    assert twin["distance_m"] > 0.1, twin  # the policy swam the twin behind the bus
