"""The robots of other servo families run every gait their axes allow on the twin.

snake12-ax12a (12 x AX-12A, compliance loop, Protocol 1.0), snake8-2xl430 (four 2XL430 cases)
and snake12-sts3215 (12 x Feetech STS3215 in printed modules) go through ``snakebot run`` for
every gait ``snakebot gaits`` lists: exit 0, every command inside the joint limits, the joints
following them. Miller's mass-spring gaits read the joints as yaw/pitch/axial segments, which 8
joints are not: they are refused with the fix, and run with it,
except rectilinear, which needs an axial channel no servo snake has.
"""

from __future__ import annotations

import json
import warnings

import pytest

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.gaits import gait_names

ROBOTS = ("snake12-ax12a", "snake8-2xl430", "snake12-sts3215")
CHANNEL_GAITS = ("miller_sidewinding", "rectilinear", "undulation")


def run(capsys: pytest.CaptureFixture[str], robot: str, gait: str, *extra: str) -> tuple[int, str]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # e.g. serpenoid, a planar wave, on yaw/pitch joints
        code = main(["run", "--robot", robot, "--gait", gait, "--duration", "3", "--json", *extra])
    out, err = capsys.readouterr()
    return code, out if code == 0 else err + out


@pytest.mark.parametrize("gait", gait_names())
@pytest.mark.parametrize("name", ROBOTS)
def test_every_gait_runs_inside_the_limits(
    capsys: pytest.CaptureFixture[str], name: str, gait: str
) -> None:
    robot = load_robot(name)
    extra: tuple[str, ...] = ()
    if gait in CHANNEL_GAITS and robot.joint_count % 3:
        code, text = run(capsys, name, gait)
        assert code == 1 and "set channels=" in text, text
        extra = ("--set", "channels=yaw,pitch")
    code, text = run(capsys, name, gait, *extra)
    if gait == "rectilinear" and extra:
        assert code == 1 and "drives the axial channel" in text, text
        return
    assert code == 0, text
    summary = json.loads(text)
    assert summary["robot"] == name and summary["joints"] == robot.joint_count
    assert summary["max_abs_command_rad"] <= min(robot.upper_rad.min(), -robot.lower_rad.max())
    assert summary["tracking_rms_rad"] < 0.25  # the servos follow (snake12's XL430s: 0.18)


def test_snakebot_robots_lists_them(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["robots"]) == 0
    names = {line.split()[0] for line in capsys.readouterr().out.splitlines() if line.strip()}
    assert set(ROBOTS) <= names
