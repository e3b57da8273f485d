"""`snakebot drive` in a real terminal (a pty), as a person runs it: keys, the display, a
restored terminal, and every way the drive can be cut short stops the snake safely."""

from __future__ import annotations

import contextlib
import json
import os
import select
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

if os.name == "posix":
    import pty
    import termios

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


class Terminal:
    """`snakebot drive` with a pty as its terminal (stdin and stderr); stdout is a pipe."""

    def __init__(self, *argv: str, stdin_tty: bool = True) -> None:
        self.master, self.slave = pty.openpty()
        self.before = termios.tcgetattr(self.slave)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "snakebot", "drive", *argv, "--json"],
            stdin=self.slave if stdin_tty else subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=self.slave,
            start_new_session=True,
        )
        self.screen = b""

    def read_until(self, text: bytes, timeout_s: float = 30.0) -> None:
        deadline = time.monotonic() + timeout_s
        while text not in self.screen:
            remaining = deadline - time.monotonic()
            assert remaining > 0, self.screen[-2000:].decode(errors="replace")
            ready, _, _ = select.select([self.master], [], [], min(remaining, 0.5))
            if not ready:
                exited = self.proc.poll()
                assert exited is None, f"drive exited {exited}: " + self.screen[-2000:].decode(
                    errors="replace"
                )
                continue
            try:
                self.screen += os.read(self.master, 65536)
            except OSError:
                break

    def type(self, keys: bytes) -> None:
        os.write(self.master, keys)

    def finish(self) -> tuple[int, dict[str, object]]:
        out, _ = self.proc.communicate(timeout=60)
        return self.proc.returncode, json.loads(out)

    def close(self) -> None:
        for fd in (self.master, self.slave):
            with contextlib.suppress(OSError):
                os.close(fd)
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


@contextmanager
def terminal(*argv: str) -> Iterator[Terminal]:
    term = Terminal(*argv)
    try:
        yield term
    finally:
        term.close()


def test_keys_drive_the_display_shows_it_and_ctrl_c_stops_with_the_terminal_restored() -> None:
    with terminal("--robot", "snake12", "--gaits", "sidewinding,rolling") as term:
        term.read_until(b"gait      sidewinding")
        term.type(b"ww\x1b[Aw")  # three letters and an arrow: speed 1
        term.read_until(b"speed     +1.00 (set +1.00")
        term.type(b"2")
        term.read_until(b"gait      rolling")
        term.type(b"\x03")  # raw mode: ctrl-c is a key, the stop key
        code, summary = term.finish()
        term.read_until(b"\x1b[?25h", timeout_s=5.0)  # the cursor is shown again
        assert termios.tcgetattr(term.slave) == term.before  # echo, line editing, signals back
    assert code == 0
    assert summary["stopped_by"] == "quit" and summary["keys"] == 6


def test_a_paste_is_dropped_with_a_note_and_the_drive_still_answers() -> None:
    with terminal("--robot", "snake12", "--gaits", "sidewinding,rolling") as term:
        term.read_until(b"gait      sidewinding")
        term.type(b"w1a2" * 700)  # 2,800 keys pasted by mistake
        term.read_until(b"keys that came at once (a paste?)")
        time.sleep(0.5)  # the paste over, the terminal quiet again
        term.type(b"q")
        code, summary = term.finish()
    assert code == 0 and summary["stopped_by"] == "quit"
    assert summary["dropped_keys"] >= 2800 - 32 and summary["keys"] <= 33


def test_a_hang_up_stops_the_snake_and_exits_1() -> None:
    with terminal("--robot", "snake8") as term:
        term.read_until(b"gait      serpenoid")
        term.type(b"wwww")
        term.read_until(b"speed     +1.00")
        time.sleep(1.0)
        term.proc.send_signal(signal.SIGHUP)  # what closing the window sends
        code, summary = term.finish()
    assert code == 1
    assert summary["stopped_by"] == "input lost: the terminal hung up (SIGHUP)"
    assert summary["max_abs_command_rad"] > 0.3  # it was moving, then ramped to rest


def test_sigterm_stops_a_scripted_drive_through_the_rest_pose(tmp_path: Path) -> None:
    script = tmp_path / "long.txt"
    script.write_text("0 w\n0 w\n0 w\n0 w\n600 q\n")
    log = tmp_path / "drive.csv"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakebot",
            "drive",
            "--robot",
            "snake8",
            "--realtime",
            "--script",
            str(script),
            "--log",
            str(log),
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    deadline = time.monotonic() + 30
    while not (log.exists() and log.read_text().count("\n") > 200):
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err.decode()
    summary = json.loads(out)
    assert summary["stopped_by"] == "interrupted (SIGTERM)"
    last = log.read_text().splitlines()[-1].split(",")
    assert all(float(v) == 0.0 for v in last[2:10])  # last command: the rest pose


def test_without_a_terminal_it_asks_for_a_script() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "snakebot", "drive"],
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        start_new_session=True,
        timeout=60,
    )
    assert proc.returncode == 2  # usage: without a terminal, drive needs --script
    assert "no terminal to read keys from" in proc.stderr and "--script" in proc.stderr


@pytest.mark.parametrize(
    ("controlling", "to_file"),
    [(False, True), (True, True), (True, False)],
    ids=["eio", "sighup", "sighup-stderr-on-the-terminal-too"],
)
def test_a_terminal_closed_mid_drive_stops_the_snake_and_exits_1_not_3(
    tmp_path: Path, controlling: bool, to_file: bool
) -> None:
    """`snakebot drive ... 2> err.txt` in a terminal window that is then closed: the summary
    cannot be printed any more, and that must not turn a safe stop into an internal error
    (nor, with stderr on the dead terminal too, the error message)."""
    master, slave = pty.openpty()
    log, err = tmp_path / "drive.csv", tmp_path / "err.txt"

    def own_the_terminal() -> None:  # as a shell makes the window the session's terminal
        os.setsid()
        import fcntl

        fcntl.ioctl(0, termios.TIOCSCTTY, 0)

    with err.open("wb") as stderr:
        proc = subprocess.Popen(
            [sys.executable, "-m", "snakebot", "drive", "--robot", "snake8", "--log", str(log)],
            stdin=slave,
            stdout=slave,
            stderr=stderr if to_file else slave,
            preexec_fn=own_the_terminal if controlling else None,
            start_new_session=not controlling,
        )
    try:
        deadline = time.monotonic() + 60
        while not (log.exists() and log.read_text().count("\n") > 50):
            assert time.monotonic() < deadline and proc.poll() is None, err.read_text()
            time.sleep(0.05)
        os.write(master, b"wwww")
        rows = log.read_text().count("\n")
        while log.read_text().count("\n") < rows + 150:  # 1.5 s of driving at full speed
            assert time.monotonic() < deadline and proc.poll() is None, err.read_text()
            time.sleep(0.05)
        os.close(master)  # the window closes
        os.close(slave)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    message = err.read_text()
    assert proc.returncode == 1, message
    if to_file:
        assert "Traceback" not in message and "internal error" not in message
        assert "snake was stopped" in message
        assert "terminal closed" in message or "hung up" in message
    rows = [line.split(",") for line in log.read_text().splitlines()[1:]]
    assert max(abs(float(v)) for row in rows for v in row[2:10]) > 0.3  # it was moving
    assert all(float(v) == 0.0 for v in rows[-1][2:10])  # then went to the rest pose


def test_a_summary_reader_that_quit_is_exit_1_saying_so(tmp_path: Path) -> None:
    """`snakebot drive --json ... | reader` and the reader quits mid-drive: a stop, then exit 1
    saying the summary could not be printed (not a traceback, nor Python's exit 120)."""
    script, log = tmp_path / "short.txt", tmp_path / "drive.csv"
    script.write_text("0 w\n0 w\n3 q\n")
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "snakebot",
            "drive",
            "--robot",
            "snake8",
            "--realtime",
            "--script",
            str(script),
            "--log",
            str(log),
            "--json",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert proc.stdout is not None and proc.stderr is not None
    deadline = time.monotonic() + 60
    while not (log.exists() and log.read_text().count("\n") > 50):
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.05)
    proc.stdout.close()  # the reader quits
    err = proc.stderr.read().decode()
    proc.wait(timeout=60)
    assert proc.returncode == 1, err
    assert "Traceback" not in err and "Exception ignored" not in err
    assert "the summary could not be printed (Broken pipe)" in err and "snake was stopped" in err
