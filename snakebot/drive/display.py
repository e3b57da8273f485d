"""The drive's terminal display: a few lines redrawn in place a few times a second.

The control loop only hands each cycle to ``DriveDisplay`` (a few additions); when a frame is
due it takes a small immutable ``Frame`` and a writer thread renders it and writes it in one
``write``, so neither string building nor a slow terminal touches the loop's timing. Plain ANSI
(cursor up, clear line); the cursor is shown again on close.
"""

from __future__ import annotations

import io
import math
import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TextIO

import numpy as np

from snakebot.drive.keymap import HELP
from snakebot.drive.run import DriveCycle
from snakebot.gaits.live import LiveStatus

WIDTH = 78
"""Longest line drawn: wider lines wrap and would break redrawing in place."""
FRAME_PERIOD_S = 0.25
"""Four frames a second: readable numbers, negligible cost."""
_HIDE_CURSOR, _SHOW_CURSOR, _CLEAR_LINE = "\x1b[?25l", "\x1b[?25h", "\x1b[2K"


@dataclass(frozen=True)
class Frame:
    """What one frame shows; every number already averaged over the frame's cycles."""

    title: str
    status: LiveStatus
    gaits: tuple[str, ...]
    gait_index: int
    rate_hz: float
    achieved_rate_hz: float
    overruns: int
    tracking_rms_rad: float
    worst_error_rad: float
    worst_joint: int
    hottest_c: float | None
    hottest_id: int | None
    alerts: tuple[str, ...]
    drive_time_s: float
    notice: str


def render(frame: Frame) -> list[str]:
    """The lines of one frame, without escapes (the writer adds them)."""
    status = frame.status
    controls = status.controls
    mode = {"driving": "driving", "paused": "PAUSED (space resumes)", "stopping": "STOPPING"}[
        status.mode
    ]
    blend = f"  blending {status.blend:.0%}" if status.blend is not None else ""
    lines = [frame.title, f"  gait      {status.gait:<20} {mode}{blend}"]
    if controls is not None:
        turn = "left" if controls.turn > 0 else "right" if controls.turn < 0 else "straight"
        setpoint = status.setpoint
        lines.append(
            f"  speed     {controls.speed:+5.2f} (set {setpoint.speed:+5.2f}, max "
            f"{status.speed_limit:.2f})   turn {controls.turn:+5.2f} {turn}"
        )
        lines.append(
            f"  amplitude {controls.amplitude:5.2f}   wavelength {controls.wavelength:5.2f}   "
            f"phase {_phase(status.phase_rad)}"
        )
    else:
        held = "the rest pose" if status.mode != "driving" else "the start pose"
        lines += [f"  speed     -    (holding {held})", "  amplitude -"]
    lines.append(
        f"  rate      {frame.achieved_rate_hz:5.1f} Hz of {frame.rate_hz:g}   overruns "
        f"{frame.overruns}   time {frame.drive_time_s:7.1f} s"
    )
    lines.append(
        f"  tracking  {frame.tracking_rms_rad:.3f} rad RMS, worst {frame.worst_error_rad:.3f} "
        f"rad (joint {frame.worst_joint})"
    )
    heat = (
        "n/a"
        if frame.hottest_c is None
        else f"{frame.hottest_c:.0f} degC (servo {frame.hottest_id})"
    )
    lines.append(f"  servos    hottest {heat}   errors {', '.join(frame.alerts) or 'none'}")
    if frame.notice:
        lines.append(f"  note      {frame.notice}")
    gaits = [
        f"[{n + 1} {name}]" if n == frame.gait_index else f"{n + 1} {name}"
        for n, name in enumerate(frame.gaits)
    ]
    lines += _wrapped("  gaits     ", gaits)
    lines += _wrapped("  keys      ", [short for _, _, short in HELP if short])
    return lines


def _wrapped(label: str, items: Sequence[str]) -> list[str]:
    """``items`` after ``label``, two spaces apart, in lines of at most WIDTH characters."""
    rows: list[list[str]] = [[]]
    for item in items:
        if rows[-1] and len(label) + len("  ".join([*rows[-1], item])) > WIDTH:
            rows.append([])
        rows[-1].append(item)
    indent = " " * len(label)
    return [(label if n == 0 else indent) + "  ".join(row) for n, row in enumerate(rows)]


def _columns(stream: TextIO) -> int:
    """The terminal's width (lines longer than it would wrap and break redrawing in place)."""
    try:
        return os.get_terminal_size(stream.fileno()).columns or WIDTH + 2
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        return WIDTH + 2


def _phase(phase_rad: Sequence[float]) -> str:
    if not phase_rad:
        return "-"
    return ", ".join(f"{math.degrees(p) % 360:3.0f} deg" for p in phase_rad)


class DriveDisplay:
    """A drive observer that shows the drive on ``stream`` (a terminal) every FRAME_PERIOD_S.

    ``health()`` gives the backend's slow readings (``temperature_c`` (N,)), ``alerts()`` the
    counters worth showing (clipped commands, watchdog re-arms), ``servo_ids`` names joints.
    ``failed`` is set when the terminal could not be written any more (it was closed).
    """

    def __init__(
        self,
        stream: TextIO,
        *,
        title: str,
        gaits: Sequence[str],
        gait_index: Callable[[], int],
        notice: Callable[[], str],
        rate_hz: float,
        servo_ids: Sequence[int],
        health: Callable[[], Mapping[str, np.ndarray]],
        alerts: Callable[[], tuple[str, ...]],
        overruns: Callable[[], int],
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.stream = stream
        self.title, self.gaits, self.rate_hz = title, tuple(gaits), rate_hz
        self._gait_index, self._notice = gait_index, notice
        self._servo_ids = tuple(servo_ids)
        self._health, self._alerts, self._overruns = health, alerts, overruns
        self._clock = clock
        self._due = 0.0
        self._cycles = 0
        self._first_time_s: float | None = None
        self._squared = 0.0
        self._samples = 0
        self._worst = (0.0, 0)
        self._slot: Frame | None = None
        self._wake = threading.Event()
        self._closing = False
        self._lines = 0
        self.failed = False
        self._thread = threading.Thread(
            target=self._write_frames, name="drive-display", daemon=True
        )
        self._thread.start()

    def __call__(self, cycle: DriveCycle) -> None:
        """Account one cycle; hand a frame to the writer when one is due."""
        error = cycle.command_rad - cycle.state.position_rad
        self._squared += float(error @ error)
        self._samples += error.size
        joint = int(np.argmax(np.abs(error)))
        if abs(error[joint]) > self._worst[0]:
            self._worst = (float(abs(error[joint])), joint)
        self._cycles += 1
        if self._first_time_s is None:
            self._first_time_s = cycle.state.time_s
        now = self._clock()
        if now < self._due:
            return
        self._due = now + FRAME_PERIOD_S
        self._publish(self._frame(cycle))

    def close(self, final_notice: str = "") -> None:
        """Draw a last frame (with ``final_notice``), show the cursor, stop the writer."""
        if self._slot is not None and final_notice:
            self._slot = replace(self._slot, notice=final_notice)
        self._closing = True
        self._wake.set()
        self._thread.join(timeout=2.0)

    def _frame(self, cycle: DriveCycle) -> Frame:
        elapsed = cycle.state.time_s - (self._first_time_s or cycle.state.time_s)
        rate = (self._cycles - 1) / elapsed if elapsed > 0 else self.rate_hz
        temps = self._health().get("temperature_c")
        hottest = hottest_id = None
        if temps is not None and len(temps) == len(self._servo_ids):
            index = int(np.argmax(temps))
            hottest, hottest_id = float(temps[index]), self._servo_ids[index]
        frame = Frame(
            title=self.title,
            status=cycle.status,
            gaits=self.gaits,
            gait_index=self._gait_index(),
            rate_hz=self.rate_hz,
            achieved_rate_hz=rate,
            overruns=self._overruns(),
            tracking_rms_rad=math.sqrt(self._squared / max(self._samples, 1)),
            worst_error_rad=self._worst[0],
            worst_joint=self._worst[1],
            hottest_c=hottest,
            hottest_id=hottest_id,
            alerts=self._alerts(),
            drive_time_s=cycle.drive_time_s,
            notice=self._notice(),
        )
        self._cycles, self._first_time_s = 1, cycle.state.time_s
        self._squared, self._samples, self._worst = 0.0, 0, (0.0, 0)
        return frame

    def _publish(self, frame: Frame) -> None:
        self._slot = frame
        self._wake.set()

    def _write_frames(self) -> None:
        drawn: Frame | None = None
        try:
            self.stream.write(_HIDE_CURSOR)
            while True:
                self._wake.wait()
                self._wake.clear()
                frame = self._slot
                if frame is not None and frame is not drawn:
                    self._draw(frame)
                    drawn = frame
                if self._closing:
                    break
            self.stream.write(_SHOW_CURSOR)
            self.stream.flush()
        except (OSError, ValueError):  # the terminal went away (hang-up): stop drawing
            self.failed = True

    def _draw(self, frame: Frame) -> None:
        width = _columns(self.stream)
        lines = [line[: width - 1] for line in render(frame)]
        up = f"\x1b[{self._lines}F" if self._lines else "\r"
        body = "".join(f"{_CLEAR_LINE}{line}\n" for line in lines)
        extra = max(self._lines - len(lines), 0)  # a shorter frame: clear what is left below
        tail = "".join(f"{_CLEAR_LINE}\n" for _ in range(extra)) + (
            f"\x1b[{extra}F" if extra else ""
        )
        self.stream.write(up + body + tail)
        self.stream.flush()
        self._lines = len(lines)
