"""The terminal display: what a frame shows, its width, and frames only when due."""

from __future__ import annotations

import io
import os
import re

import numpy as np

from snakebot.drive.display import WIDTH, DriveDisplay, Frame, render
from snakebot.drive.run import DriveCycle
from snakebot.gaits.live import LiveGait
from snakebot.types import JointState

GAITS = ("sidewinding", "rolling", "lateral_undulation", "turn_in_place", "linear_progression")


def status(speed: float = 1.0) -> object:
    live = LiveGait(12, lower_rad=-1.5, upper_rad=1.5, max_speed_rad_s=5.0, period_s=0.01)
    live.start(np.zeros(12))
    live.select("sidewinding")
    live.set_controls(live.setpoint.__class__(speed=speed, turn=0.5))
    for k in range(200):
        live.command(k * 0.01)
    return live.status()


def frame(**changes: object) -> Frame:
    base = dict(
        title="snakebot drive: snake12 on dynamixel (/dev/ttyUSB0), 12 joints, stop policy hold",
        status=status(),
        gaits=GAITS,
        gait_index=0,
        rate_hz=100.0,
        achieved_rate_hz=99.7,
        overruns=2,
        tracking_rms_rad=0.0123,
        worst_error_rad=0.0456,
        worst_joint=7,
        hottest_c=47.0,
        hottest_id=5,
        alerts=("watchdog rearms 1",),
        drive_time_s=12.34,
        notice="",
    )
    base.update(changes)
    return Frame(**base)  # type: ignore[arg-type]


def test_a_frame_shows_gait_controls_rate_tracking_and_the_hottest_servo() -> None:
    text = "\n".join(render(frame()))
    assert "sidewinding" in text and "driving" in text
    assert re.search(r"speed\s+\+1\.00 \(set \+1\.00, max \d\.\d\d\)\s+turn \+0\.50 left", text)
    assert "99.7 Hz of 100" in text and "overruns 2" in text
    assert "0.012 rad RMS, worst 0.046 rad (joint 7)" in text
    assert "hottest 47 degC (servo 5)" in text and "errors watchdog rearms 1" in text
    assert "[1 sidewinding]" in text and "q stop" in text


def test_every_line_fits_the_width_so_redrawing_in_place_works() -> None:
    lines = render(frame(notice="", title="t"))
    assert max(len(line) for line in lines) <= WIDTH
    assert any(line.strip().startswith("5 linear_progression") for line in lines)  # wrapped


def test_hardware_readings_missing_on_the_twin_read_n_a() -> None:
    text = "\n".join(render(frame(hottest_c=None, hottest_id=None, alerts=())))
    assert "hottest n/a   errors none" in text


def cycle(k: int, error: float) -> DriveCycle:
    state = JointState(k * 0.01, np.full(12, -error), np.zeros(12), np.zeros(12))
    return DriveCycle(
        cycle=k,
        gait_time_s=k * 0.01,
        target_rad=np.zeros(12),
        command_rad=np.zeros(12),
        state=state,
        body=None,
        amplitude=1.0,
        scored=True,
        period_s=0.01,
        overrun=False,
        achieved_rate_hz=100.0,
        status=status(),
        keys=(),
    )


def test_frames_are_drawn_only_when_due_and_the_cursor_comes_back() -> None:
    stream = io.StringIO()
    now = [0.0]
    display = DriveDisplay(
        stream,
        title="t",
        gaits=GAITS,
        gait_index=lambda: 1,
        notice=lambda: "",
        rate_hz=100.0,
        servo_ids=range(1, 13),
        health=lambda: {"temperature_c": np.array([30.0] * 5 + [52.0] + [30.0] * 6)},
        alerts=lambda: (),
        overruns=lambda: 0,
        clock=lambda: now[0],
    )
    for k in range(100):  # one second of cycles: four frames
        now[0] = k * 0.01
        display(cycle(k, 0.02))
    display.close("stopped by quit")
    text = stream.getvalue()
    assert text.startswith("\x1b[?25l") and text.endswith("\x1b[?25h")
    assert text.count("snakebot") == 0 and text.count("[2 rolling]") in (4, 5)
    assert "hottest 52 degC (servo 6)" in text
    assert "0.020 rad RMS" in text and "stopped by quit" in text
    assert "\x1b[" in text.split("\n", 1)[1]  # later frames move up and redraw in place


def test_a_narrow_terminal_gets_lines_cut_to_its_width_not_wrapped() -> None:
    import pty

    master, slave = pty.openpty()
    try:
        import fcntl
        import struct
        import termios

        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 40, 0, 0))
        with open(slave, "w", closefd=False) as stream:
            display = DriveDisplay(
                stream,
                title="t" * 60,
                gaits=GAITS,
                gait_index=lambda: 0,
                notice=lambda: "",
                rate_hz=100.0,
                servo_ids=range(1, 13),
                health=dict,
                alerts=tuple,
                overruns=lambda: 0,
            )
            display(cycle(0, 0.0))
            display.close()
        text = os.read(master, 65536).decode()
    finally:
        os.close(master)
        os.close(slave)
    for line in text.replace("\r", "").split("\n"):
        visible = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", line)
        assert len(visible) <= 39
