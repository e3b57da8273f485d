"""A paste into the drive's terminal (issue 18.5): the real loop on the twin, keys through a real
pseudo-terminal. The cycle keeps its rate whatever arrives, and a mistaken paste moves nothing."""

from __future__ import annotations

import os
import time

import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer
from snakebot.drive import DriveController, DriveCycle, GaitChoice, run_drive
from snakebot.drive.setup import live_gait

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

RATE_HZ = 100.0
PASTE = b"w1a2" * 700  # 2,800 keys that each act: speed up, turn left, switch gaits
GAITS = [GaitChoice("sidewinding"), GaitChoice("rolling")]


class PasteAt:
    """An observer that pastes into the terminal at drive time 1 s, types q at 3 s, and notes
    each cycle's wall-clock time and the speed asked for."""

    def __init__(self, master: int, slave: int) -> None:
        self.master, self.slave = master, slave
        self.wall_s: list[float] = []
        self.setpoint_speed: list[float] = []
        self.notices: set[str] = set()
        self.controller: DriveController | None = None

    def __call__(self, cycle: DriveCycle) -> None:
        self.setpoint_speed.append(cycle.status.setpoint.speed)
        if self.controller is not None and self.controller.notice:
            self.notices.add(self.controller.notice)
        if abs(cycle.drive_time_s - 1.0) < 0.5 / RATE_HZ:
            os.write(self.master, PASTE)
            self.wait_for_the_terminal(len(PASTE))
        if abs(cycle.drive_time_s - 3.0) < 0.5 / RATE_HZ:
            os.write(self.master, b"q")
        self.wall_s.append(time.monotonic())  # after the paste: the test's wait is not a gap

    def wait_for_the_terminal(self, count: int) -> None:
        """Until the pty has handed all ``count`` bytes to the reading side (the kernel moves
        them over in chunks, on its own time), as when a terminal pastes into a busy program."""
        import fcntl
        import struct
        import termios

        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            queued = struct.unpack("i", fcntl.ioctl(self.slave, termios.FIONREAD, b"\0" * 4))[0]
            if queued >= count:
                return
            time.sleep(0.001)


def test_a_paste_of_thousands_of_keys_neither_stalls_the_loop_nor_moves_the_snake() -> None:
    import pty

    from snakebot.drive.terminal import TerminalSource

    robot = load_robot("snake12")
    live = live_gait(robot, rate_hz=RATE_HZ, gaits=GAITS)
    controller = DriveController(live, GAITS)
    master, slave = pty.openpty()
    paste = PasteAt(master, slave)
    paste.controller = controller
    try:
        with TwinBackend(robot) as twin, TerminalSource(slave) as source:
            result = run_drive(
                twin,
                live,
                SafetyLayer.for_robot(robot),
                controller,
                source,
                rate_hz=RATE_HZ,
                metrics=RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
                observers=[paste],
            )
    finally:
        os.close(master)
        os.close(slave)
    gaps = [b - a for a, b in zip(paste.wall_s, paste.wall_s[1:], strict=False)]
    # Unbounded, the 2,800 keys took seconds inside one cycle; a twin cycle costs milliseconds.
    assert max(gaps) < 0.25, f"max gap {max(gaps):.3f} s"
    assert result.stopped_by == "quit"  # the q typed after the paste still stopped the drive
    assert max(paste.setpoint_speed) == 0.0  # the paste was dropped, not played out
    assert result.summary["keys"] == 1 and result.summary["dropped_keys"] == len(PASTE)
    assert any("ignored" in notice and "paste" in notice for notice in paste.notices)


@pytest.mark.parametrize("ending", ["1 q\n", ""], ids=["quit", "end-of-script"])
def test_a_script_with_many_keys_at_one_time_plays_them_all(ending: str) -> None:
    from snakebot.drive import ScriptSource, parse_script

    robot = load_robot("snake8")
    live = live_gait(robot, rate_hz=RATE_HZ)
    controller = DriveController(live, [GaitChoice("serpenoid")])
    script = ScriptSource(parse_script("0 w\n0 s\n" * 40 + "0 w\n" + ending))
    with TwinBackend(robot) as twin:
        result = run_drive(
            twin,
            live,
            SafetyLayer.for_robot(robot),
            controller,
            script,
            rate_hz=RATE_HZ,
            metrics=RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
        )
    assert result.summary["keys"] == 81 + len(ending.split()) // 2
    assert result.summary["dropped_keys"] == 0
    assert live.setpoint.speed == 0.25  # every w and s applied, in order
