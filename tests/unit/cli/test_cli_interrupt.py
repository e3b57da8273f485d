"""Ctrl-C while the CLI starts up (imports, building the parser) ends like Ctrl-C anywhere else."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from snakebot import _started_as_command as started_as_command

pytestmark = pytest.mark.skipif(os.name != "posix", reason="SIGINT to a child needs POSIX")


def imported(line: str) -> str:
    """The module an ``-X importtime`` line reports (``import time: 12 | 34 |   name``)."""
    return line.rsplit("|", 1)[-1].strip()


@pytest.mark.parametrize(
    "marker",
    [
        # the package is imported: Python's runpy goes on to find snakebot.__main__ (issue 18.8)
        "snakebot",
        "snakebot.cli",  # importing snakebot.cli.main (python -m snakebot's own import)
        "snakebot.cli.main",  # main() about to build the parser: every command module imports
        "snakebot.control.runner",  # half way through those imports (run_cmd's)
        # inside MuJoCo's C extensions, whose init turns the interrupt into an ImportError
        "mujoco._enums",
    ],
)
def test_ctrl_c_during_start_up_prints_interrupted_and_exits_130(marker: str) -> None:
    # -X importtime reports each module as it finishes importing: the signal goes out right after
    # `marker` and lands in the start-up that follows it (building the parser alone takes ~0.5 s).
    proc = subprocess.Popen(
        [sys.executable, "-X", "importtime", "-m", "snakebot", "gaits"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stderr is not None
    seen = []
    for line in proc.stderr:
        seen.append(line)
        if imported(line) == marker:
            proc.send_signal(signal.SIGINT)
            break
    out, err = proc.communicate(timeout=60)
    assert marker in map(imported, seen)
    assert "Traceback" not in err, err[-2000:]
    assert err.rstrip().endswith("snakebot: interrupted")
    assert proc.returncode == 130
    assert out == ""  # interrupted before the gait list


@pytest.mark.parametrize("where", ["command_returned", "exiting", "tearing_down"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_after_the_command_finished_keeps_its_exit_code_and_output(
    signum: int, where: str
) -> None:
    # The third Ctrl-C of an impatient user can land after the stop policy went out, while the
    # process is already on its way out (shutting the interpreter down takes a second on a loaded
    # machine): the exit code and the printed output must be the command's, not a death by
    # signal. The signal is sent from those spots.
    hook = {
        "command_returned": "real = main.main\n"
        "def hit(argv=None):\n    code = real(argv)\n"
        "    kill()\n    return code\n"
        "main.main = hit\n",
        "exiting": "real = sys.exit\ndef hit(code):\n    kill()\n    real(code)\nsys.exit = hit\n",
        # module teardown, after Python has put the default signal handlers back
        "tearing_down": "class Dying:\n    def __del__(self):\n        kill()\ndying = Dying()\n",
    }[where]
    script = (
        "import os, sys\n"
        "from snakebot.cli import main\n"
        f"def kill():\n    os.kill(os.getpid(), {int(signum)})\n"
        + hook
        + "sys.argv = ['snakebot', 'gaits', '--json']\n"
        "main.entry_point()\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert proc.returncode == 0
    assert '"serpenoid"' in proc.stdout  # the gait list was printed, not lost


@pytest.mark.parametrize(
    ("argv", "orig_argv", "expected"),
    [
        (["-m", "run"], ["python3", "-m", "snakebot", "run"], True),
        (["-m", "run"], ["python3", "-X", "importtime", "-msnakebot", "run"], True),
        (["-m", "x"], ["python3", "-m", "snakebot.tools", "x"], False),  # another module
        (["-m"], ["python3", "-m", "pytest"], False),  # a program that imports snakebot
        (["/usr/local/bin/snakebot", "run"], ["python3", "/usr/local/bin/snakebot", "run"], True),
        (["train.py"], ["python3", "train.py"], False),
        ([], [], False),
    ],
)
def test_the_start_up_guard_is_for_the_snakebot_command_only(
    argv: list[str], orig_argv: list[str], expected: bool
) -> None:
    # A program that only imports snakebot keeps Python's own Ctrl-C.
    assert started_as_command(argv, orig_argv) is expected


def test_ctrl_c_in_generated_code_does_not_end_python_m_by_signal(tmp_path: Path) -> None:
    # CPython records a KeyboardInterrupt that escapes source run from a string (dataclasses and
    # namedtuple exec one for every class they make, so a Ctrl-C while the parser is built often
    # lands there) and under `python -m` ends the process by SIGINT once it exits, caught or not:
    # CI saw `snakebot: interrupted` and then returncode -2. Here the signal lands in such code.
    (tmp_path / "ctrl_c_in_exec.py").write_text(
        "import sys\n"
        "from snakebot.cli import main\n"
        "def build_parser():\n"
        "    exec('import os, signal; os.kill(os.getpid(), signal.SIGINT); "
        "signal.sigtimedwait([], 0)')\n"
        "    raise AssertionError('the signal handler did not run')\n"
        "main.build_parser = build_parser\n"
        "sys.argv = ['snakebot', 'gaits']\n"
        "main.entry_point()\n"
    )
    proc = subprocess.run(
        [sys.executable, "-m", "ctrl_c_in_exec"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert proc.stderr.rstrip().endswith("snakebot: interrupted")
    assert proc.returncode == 130


def test_ctrl_c_that_foreign_code_turns_into_another_error_is_still_an_interrupt() -> None:
    # ctypes wraps a KeyboardInterrupt raised while it converts an argument in its own error
    # (seen from PyOpenGL, which MuJoCo imports while the parser is built): `ctypes.ArgumentError:
    # argument 1: KeyboardInterrupt`, a traceback and exit 1 before this was handled.
    script = (
        "import ctypes, os, signal\n"
        "from snakebot.cli import main\n"
        "def build_parser():\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        signal.sigtimedwait([], 0)\n"  # let the handler run here
        "    except KeyboardInterrupt as exc:\n"
        "        raise ctypes.ArgumentError(f'argument 1: {type(exc).__name__}: ') from None\n"
        "    raise AssertionError('the signal handler did not run')\n"
        "main.build_parser = build_parser\n"
        "import sys\n"
        "sys.argv = ['snakebot', 'gaits']\n"
        "main.entry_point()\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    assert "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert proc.stderr.rstrip().endswith("snakebot: interrupted")
    assert proc.returncode == 130


@pytest.mark.parametrize("delay_s", [0.0, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8])
def test_ctrl_c_anywhere_in_start_up_is_exit_130_or_the_finished_command(delay_s: float) -> None:
    # Wherever the signal lands after the CLI's module is in (dataclasses, ctypes, C extensions):
    # interrupted with 130 and nothing printed, or, if the command was already over, its output
    # and 0; never a traceback or a death by signal.
    proc = subprocess.Popen(
        [sys.executable, "-X", "importtime", "-m", "snakebot", "gaits"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stderr is not None
    for line in proc.stderr:
        if imported(line) == "snakebot.cli.main":
            time.sleep(delay_s)
            proc.send_signal(signal.SIGINT)
            break
    out, err = proc.communicate(timeout=60)
    assert "Traceback" not in err, err[-2000:]
    if proc.returncode == 0:
        assert "serpenoid" in out
    else:
        assert proc.returncode == 130
        assert err.rstrip().endswith("snakebot: interrupted")
        assert out == ""
