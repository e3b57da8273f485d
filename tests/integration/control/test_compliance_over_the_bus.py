"""`run --comply` and `--torque-limit` over the emulated bus on the peg field: the same
commands as on the twin, with only what the servos report (Present Current, Present Position)
to go by. `snakebot emulate --physics --terrain` puts the twin under the bus on the pegs; its
own summary on exit is the ground truth the bus never shows."""

from __future__ import annotations

import json
import os
from typing import Any

import pytest

from snakebot.backends.chain import ServoSettingsWarning
from snakebot.cli.main import main
from snakebot.config import load_robot
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

ROBOT = "snake8-xm430"  # XM430-W350: Present Current, current-based position control
PEGS = "pegs:density=100,seed=1"  # the field that jams the stiff gait (docs/compliance.md)


def _over_the_bus(
    capsys: pytest.CaptureFixture[str], *flags: str, seconds: float = 20.0, apply: bool = False
) -> tuple[dict[str, Any], dict[str, Any]]:
    """(the run's summary over the bus, the twin's summary) for ``seconds`` of serpenoid on
    PEGS; ``apply`` first writes the robot file's settings (Operating Mode 5)."""
    run = ["run", "--robot", ROBOT, "--backend", "dynamixel", "--json"]
    run += ["--duration", str(seconds)]
    with emulator("--robot", ROBOT, "--physics", "--terrain", PEGS) as emu:
        if apply:  # Operating Mode 5 and the rest of the robot file's settings
            assert main(["config", "apply", "--robot", ROBOT, "--port", emu.port, "--yes"]) == 0
            capsys.readouterr()
        with pytest.warns(ServoSettingsWarning):  # factory Return Delay / mode 5's limits note
            assert main([*run, "--port", emu.port, *flags]) == 0
        over_bus = json.loads(capsys.readouterr().out)
        twin = emu.stop()[-1]
    return over_bus, twin


def test_compliance_over_the_bus_yields_to_the_pegs_on_present_current(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The compliant gait gives way where Present Current says the servos push hard, and the
    snake swims on. (How much stall it saves is a twin figure: over a real-time
    bus the peg field is chaotic run to run, docs/compliance.md.)"""
    yielding, twin = _over_the_bus(capsys, "--comply")
    compliance = yielding["compliance"]
    assert yielding["distance_m"] is None  # the bus cannot measure it; the twin can
    dead_band_nm = compliance["dead_band"] * load_robot(ROBOT).servo.physics.stall_torque_nm
    assert yielding["peak_servo_torque_nm"] > dead_band_nm, yielding  # the pegs pushed back
    assert min(compliance["lowest_amplitude_scale"]) < 0.95, compliance  # and the gait gave
    assert "servo_stall_s" in yielding  # measured from Present Current and Velocity
    assert twin["distance_m"] > 0.1, twin  # it swims on, measured by the twin


def test_a_torque_limit_over_the_bus_caps_what_the_servos_report(
    capsys: pytest.CaptureFixture[str],
) -> None:
    capped, _ = _over_the_bus(capsys, "--torque-limit", "1.0", seconds=5, apply=True)
    assert capped["torque_limit_nm"] == 1.0
    # Present Current, read back over the bus, never says more than the cap (a tick over).
    assert 0.5 < capped["peak_servo_torque_nm"] <= 1.0 + 0.01, capped
