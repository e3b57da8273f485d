"""Every command, fed bad files, unwritable outputs and bad values: exit 1 (a problem the user can
fix) or 2 (bad usage), never 3 (a bug in snakebot), and the message names the file, key or option.

Nothing here reaches a servo: each input is refused before a port opens (or the port itself is
the bad input).
"""

from __future__ import annotations

import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from snakebot.cli import gaits_cmd
from snakebot.cli.main import COMMANDS, main
from tests.conftest import edit_robot


@dataclass(frozen=True)
class Bad:
    """One bad command line: the exit code it must end with and what its message must name."""

    argv: tuple[str, ...]
    code: int
    names: tuple[str, ...]

    @property
    def id(self) -> str:
        return " ".join(self.argv)[:80]


def bad(*argv: str, code: int = 1, names: tuple[str, ...] = ()) -> Bad:
    return Bad(argv, code, names)


SNAKE12 = ("--robot", "snake12")
CASES = [
    # drive
    bad("drive", "--robot", "{binary}", "--script", "{script}", names=("{binary}", "not UTF-8")),
    bad("drive", "--script", "{binary}", names=("{binary}", "not UTF-8")),
    bad("drive", "--script", "{badscript}", names=("{badscript}:2",)),
    bad("drive", "--script", "{script}", "--log", "/dev/full", names=("/dev/full",)),
    bad("drive", "--backend", "dynamixel", "--script", "{script}", code=2, names=("--robot",)),
    bad("drive", "--script", "{script}", "--rate", "nan", code=2, names=("--rate",)),
    # ros2 (refused before rclpy is imported: these hold without the ros2 extra)
    bad("ros2", "--robot", "{binary}", names=("{binary}", "not UTF-8")),
    bad("ros2", "--backend", "dynamixel", code=2, names=("--robot",)),
    bad("ros2", "--rate", "nan", code=2, names=("--rate",)),
    bad("ros2", "--command-timeout", "-1", code=2, names=("--command-timeout",)),
    bad("ros2", "--gaits", "moonwalk", code=2, names=("moonwalk",)),
    # run
    bad("run", "--robot", "{binary}", names=("{binary}", "not UTF-8")),
    bad("run", "--robot", "{heavy}", names=("{heavy}", "link.mass_kg")),
    bad("run", "--robot", "{settings}", names=("{settings}", "settings.bogus")),
    bad("run", "--robot", "{tmp}/nope.toml", names=("{tmp}/nope.toml", "not found")),
    bad("run", "--gait-file", "{binary}", names=("{binary}", "not UTF-8")),
    bad("run", "--gait-file", "{gait}", names=("{gait}", "speed", "unknown key")),
    bad("run", "--log", "/dev/full", names=("/dev/full", "No space left")),
    bad("run", "--log", "{blocker}/run.csv", names=("{blocker}/run.csv", "Not a directory")),
    bad("run", "--video", "{tmp}/run.txt", code=2, names=("--video", "{tmp}/run.txt")),
    bad("run", "--video", "{blocker}/run.mp4", names=("{blocker}/run.mp4", "Not a directory")),
    bad("run", "--duration", "abc", code=2, names=("--duration",)),
    bad("run", "--rate", "1e-300", code=2, names=("--rate",)),
    bad("run", "--command", "1,0", code=2, names=("--command",)),
    # rl (cases that need no learning package: the rest are in tests/integration/rl)
    bad("rl", "train", "--steps", "0", code=2, names=("--steps",)),
    bad("rl", "compare", "--encodings", "dft,nope", code=2, names=("--encodings", "dft_shift")),
    bad("run", "--rate", "nan", code=2, names=("--rate",)),
    bad("run", "--set", "omega=abc", code=2, names=("omega",)),
    bad("run", "--gait", "moonwalk", code=2, names=("moonwalk", "usage: snakebot run")),
    bad("run", "--durration", "1", code=2, names=("usage: snakebot run", "--duration?")),
    bad("run", "--friction", "x", code=2, names=("--friction",)),
    bad("run", "--backend", "dynamixel", code=2, names=("--robot",)),
    bad(
        "run",
        "--backend",
        "dynamixel",
        *SNAKE12,
        "--port",
        "socket://127.0.0.1:9",
        code=2,
        names=("--port", "socket://"),
    ),
    bad(
        "run",
        "--backend",
        "dynamixel",
        *SNAKE12,
        "--video",
        "{tmp}/a.mp4",
        code=2,
        names=("--video",),
    ),
    bad("run", "--backend", "dynamixel", *SNAKE12, "--port", "{blocker}", names=("{blocker}",)),
    bad("run", "--mcap", "/dev/full", names=("/dev/full", "MCAP", "I/O error")),
    bad("run", "--mcap", "{blocker}/run.mcap", names=("{blocker}/run.mcap", "Not a directory")),
    bad("run", "--foxglove", "70000", code=2, names=("--foxglove",)),
    bad("drive", "--script", "{script}", "--mcap", "/dev/full", names=("/dev/full", "MCAP")),
    # log
    bad("log", "info", "{csv}", names=("{csv}", "line 2, column command_rad_0", "'abc'")),
    bad("log", "plot", "{binary}", names=("{binary}", "not UTF-8")),
    bad(
        "log",
        "export",
        "{tmp}/nope.csv",
        "--format",
        "mcap",
        names=("{tmp}/nope.csv", "No such file"),
    ),
    bad("log", "export", "{csv}", "--format", "xml", code=2, names=("--format",)),
    bad("log", code=2, names=("ACTION",)),
    # model
    bad("model", "--out", "{blocker}/m.xml", names=("{blocker}/m.xml", "Not a directory")),
    bad("model", "--out", "/dev/full", names=("/dev/full", "No space left")),
    bad("model", "--robot", "{heavy}", "--out", "{tmp}/m.xml", names=("{heavy}", "link.mass_kg")),
    bad("model", "--friction", "1", "--out", "{tmp}/m.xml", code=2, names=("--friction",)),
    bad(
        "model",
        "--robot",
        "{settings}",
        "--out",
        "{tmp}/m.xml",
        names=("{settings}", "settings.bogus"),
    ),
    # gaits
    bad("gaits", "moonwalk", code=2, names=("moonwalk",)),
    # emulate (refused before it serves)
    bad("emulate", "--pty", "--robot", "{heavy}", names=("{heavy}", "link.mass_kg")),
    bad("emulate", "--pty", "--robot", "{binary}", names=("{binary}", "not UTF-8")),
    bad("emulate", "--pty", "--terrain", "pegs", code=2, names=("--terrain", "--physics")),
    bad("emulate", "--pty", "--physics", "--terrain", "pegs:bogus=1", code=2, names=("bogus",)),
    bad("run", "--torque-limit", "9", code=2, names=("--torque-limit", "stall torque")),
    bad(
        "emulate",
        "--pty",
        "--physics",
        "--wrap-on-pole",
        "rolling_helix",
        code=2,
        names=("--wrap-on-pole", "pole terrain"),
    ),
    # scan
    bad("scan", "--port", "socket://127.0.0.1:9", code=2, names=("socket://127.0.0.1:9",)),
    bad("scan", "--port", "{blocker}", names=("{blocker}",)),
    bad("scan", code=2, names=("--port",)),
    # config
    bad("config", "diff", code=2, names=("--robot",)),
    bad("config", "diff", "--robot", "{url}", names=("{url}", "bus.port", "socket://")),
    bad(
        "config", "apply", "--robot", "{settings}", "--yes", names=("{settings}", "settings.bogus")
    ),
    bad(
        "config",
        "apply",
        *SNAKE12,
        "--port",
        "spy:///dev/null?file=x",
        code=2,
        names=("--port", "spy://"),
    ),
    bad("config", "assign-id", *SNAKE12, "--to", "300", code=2, names=("--to",)),
    bad("config", "assign-id", "--robot", "{binary}", "--to", "3", names=("{binary}",)),
    # servo
    bad("servo", "reboot", "--id", "3", code=2, names=("--robot",)),
    bad("servo", "info", *SNAKE12, "--id", "999", code=2, names=("--id",)),
    bad("servo", "reset", "--robot", "{heavy}", "--id", "3", "--yes", names=("{heavy}",)),
    bad("servo", "info", *SNAKE12, "--port", "{blocker}", "--id", "1", names=("{blocker}",)),
    # calibrate
    bad("calibrate", code=2, names=("--robot",)),
    bad("calibrate", "--robot", "{heavy}", names=("{heavy}", "link.mass_kg")),
    bad("calibrate", *SNAKE12, "--max-offset-deg", "-1", code=2, names=("--max-offset-deg",)),
    # tune gait (refused before any simulation)
    bad("tune", "gait", "--robot", "{heavy}", names=("{heavy}", "link.mass_kg")),
    bad("tune", "gait", "--bounds", "omega=x", code=2, names=("--bounds",)),
    bad("tune", "gait", "--budget", "0", code=2, names=("--budget",)),
    # the library names its keyword ("params: ..."); the command line names the flag, exit 2
    bad("tune", "gait", "--gait", "dft", code=2, names=("--params: ",)),
    bad(
        "tune",
        "gait",
        "--method",
        "grid",
        "--params",
        "omega,amplitude,phase_lag,offset",
        "--budget",
        "3",
        code=2,
        names=("--budget: 3",),
    ),
    bad("sysid", "--record", "{tmp}/chirp.csv", "--joint", "99", code=2, names=("--joint: 99",)),
    bad("sysid", "--record", "{tmp}/chirp.csv", "--hold", "3", code=2, names=("--hold: 3",)),
    bad("tune", "gait", "--rate", "0", code=2, names=("--rate",)),
    bad("tune", "gait", "--out", "{blocker}/g.toml", names=("{blocker}/g.toml",)),
    bad("tune", "gait", "--report", "{blocker}/report", names=("{blocker}",)),
    # tune gains
    bad("tune", "gains", "--joints", "99", code=2, names=("--joints",)),
    bad("tune", "gains", "--i-values", "abc", code=2, names=("--i-values",)),
    bad("tune", "gains", "--backend", "dynamixel", code=2, names=("--robot",)),
    bad("tune", "gains", "--max-overshoot", "nan", code=2, names=("--max-overshoot",)),
    bad("tune", "gains", "--report", "{blocker}/report", names=("{blocker}",)),
    # sysid
    bad("sysid", "{csv}", names=("{csv}", "line 2, column command_rad_0", "'abc'")),
    bad("sysid", "{binary}", names=("{binary}", "not UTF-8")),
    bad("sysid", "{tmp}/nope.csv", names=("{tmp}/nope.csv", "No such file")),
    bad("sysid", code=2, names=("LOG",)),
    bad("sysid", "--record", "{blocker}/x.csv", names=("{blocker}/x.csv", "Not a directory")),
    bad("sysid", "--record", "{tmp}/x.csv", "--backend", "dynamixel", code=2, names=("--robot",)),
    bad("sysid", "--report", "{blocker}/report", "{csv}", names=("{blocker}",)),
    bad("sysid", "--workers", "0", "{csv}", code=2, names=("--workers",)),
    # robots, ports
    bad("robots", "--robot", "x", code=2, names=("usage: snakebot robots",)),
    bad("ports", "--port", "x", code=2, names=("usage: snakebot ports",)),
]


@pytest.fixture
def files(config_dir: Path, tmp_path: Path) -> dict[str, Path]:
    """Bad inputs: a binary file, robot files with a bad value, a telemetry log with text in it,
    a gait file with an unknown key, and a regular file where a folder should be."""
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe")
    blocker = tmp_path / "blocker"
    blocker.write_text("")
    csv = tmp_path / "run.csv"
    csv.write_text("time_s,cycle,command_rad_0\n0.0,0,abc\n")
    script = tmp_path / "drive.txt"
    script.write_text("0.5 w\n2.0 q\n")
    badscript = tmp_path / "bad_drive.txt"
    badscript.write_text("0.5 w\nsoon q\n")
    gait = tmp_path / "gait.toml"
    gait.write_text('gait = "serpenoid"\nspeed = 3\n')
    robots = config_dir / "robots"
    heavy = edit_robot(config_dir, "snake8", "mass_kg = 0.085", "mass_kg = 1e308")
    settings = robots / "settings.toml"
    settings.write_text(
        (robots / "snake12.toml").read_text().replace("[settings]", "[settings]\nbogus = 1", 1)
    )
    url = robots / "url.toml"
    url.write_text(
        (robots / "snake12.toml")
        .read_text()
        .replace('port = "/dev/ttyUSB0"', 'port = "socket://127.0.0.1:9"', 1)
    )
    return {
        "binary": binary,
        "blocker": blocker,
        "csv": csv,
        "gait": gait,
        "heavy": heavy,
        "script": script,
        "badscript": badscript,
        "settings": settings,
        "url": url,
        "tmp": tmp_path,
    }


def test_every_command_is_covered() -> None:
    covered = {case.argv[0] for case in CASES}
    assert covered == set(COMMANDS)
    assert {case.argv[1] for case in CASES if case.argv[0] == "config"} == {
        "diff",
        "apply",
        "assign-id",
    }
    assert {case.argv[1] for case in CASES if case.argv[0] == "servo"} == {
        "reboot",
        "reset",
        "info",
    }
    assert {case.argv[1] for case in CASES if case.argv[0] == "tune"} == {"gait", "gains"}


@pytest.mark.parametrize("case", CASES, ids=[case.id for case in CASES])
def test_bad_input_is_exit_1_or_2_naming_what_is_wrong(
    case: Bad, files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [arg.format(**files) for arg in case.argv]
    if argv[0] == "emulate":  # one that wrongly starts serves until Ctrl-C: run it on a leash
        done = subprocess.run(
            [sys.executable, "-m", "snakebot", *argv], capture_output=True, text=True, timeout=60
        )
        code, err = done.returncode, done.stderr
    else:
        code = main(argv)
        err = capsys.readouterr().err
    assert code == case.code, err
    assert "Traceback" not in err and "internal error" not in err
    for name in case.names:
        assert name.format(**files) in err, err


def test_a_bug_is_exit_3_with_the_traceback(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # The one deliberate internal error: a command whose code breaks (here gaits' spec lookup).
    def broken(name: str) -> object:
        raise KeyError(name)

    monkeypatch.setattr(gaits_cmd, "get_spec", broken)
    assert main(["gaits", "serpenoid"]) == 3
    err = capsys.readouterr().err
    assert "Traceback" in err and "KeyError: 'serpenoid'" in err
    assert err.rstrip().endswith(
        "internal error (a bug in snakebot); please report it with the traceback"
    )
