"""The malformed-file sweep (issue 18): every kind of file a user hands snakebot, broken every way
the campaign broke them, through ``snakebot.cli.main.main`` in-process and every command that
reads that kind. Each must end in exit 1 with a message naming the broken file (and the key,
line or column where there is one), never exit 3 or a traceback, and never hang.

Kinds and the commands that read them: robot files (``model``, ``run``, ``config diff`` on an
emulated bus), servo files (through the robot naming them: ``model``, ``run``), mass-spring body
files (``model``, ``run``), gait files (``run --gait-file``), telemetry CSVs and their JSON
sidecars (``log info``, ``log plot``, ``log export``). No command reads an MCAP file (``--mcap``
and ``log export --format mcap`` only write one), so MCAP has no input case here; policy folders
have their own suite.
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.emulation.bench import robot_servos
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.registry import registered

GARBAGE = bytes(range(256)) * 8
NESTED_TOML = "x = " + "[" * 5000 + "]" * 5000 + "\n"
NESTED_JSON = '{"format": "snakebot-telemetry-csv", "x": ' + "[" * 100_000 + "]" * 100_000 + "}"
GAIT_FILE = 'gait = "serpenoid"\n\n[params]\namplitude = 0.4\nomega = 3.0\n'

Make = Callable[[Path, str], None]
"""Writes the malformed file at ``path`` from the good file's text."""


@dataclass(frozen=True)
class Variant:
    """One malformed file: how it is made, and the key (line, column) the message must name."""

    name: str
    make: Make
    key: str = ""


def text(new: str | bytes) -> Make:
    def make(path: Path, good: str) -> None:
        path.unlink(missing_ok=True)
        if isinstance(new, bytes):
            path.write_bytes(new)
        else:
            path.write_text(new, encoding="utf-8")

    return make


def edit(old: str, new: str) -> Make:
    def make(path: Path, good: str) -> None:
        assert old in good, f"{old!r} not in {path.name}"
        path.write_text(good.replace(old, new, 1), encoding="utf-8")

    return make


def truncated(path: Path, good: str) -> None:
    path.write_text(good[: len(good) // 3], encoding="utf-8")


def directory(path: Path, good: str) -> None:
    path.unlink()
    path.mkdir()


def fifo(path: Path, good: str) -> None:
    path.unlink()
    os.mkfifo(path)  # nobody writes: a reader that opened it would wait for ever


def dev_zero(path: Path, good: str) -> None:
    path.unlink()
    path.symlink_to("/dev/zero")  # endless bytes: a reader without a bound would fill memory


FILE_LEVEL = [
    Variant("binary garbage", text(GARBAGE)),
    Variant("directory", directory),
    Variant("FIFO", fifo),
    Variant("/dev/zero", dev_zero),
]
TOML_LEVEL = [
    *FILE_LEVEL,
    Variant("empty", text("")),
    Variant("truncated", truncated),
    Variant("NUL byte", edit("\n", "\n\x00\n")),
    Variant("not TOML", edit("\n", "\n[[[ oops\n")),
    Variant("deeply nested", lambda p, g: p.write_text(g + NESTED_TOML)),
    Variant("5 MB file", lambda p, g: p.write_text(g + "#" * 5_000_000 + "\n")),
    Variant("integer of 5000 digits", lambda p, g: p.write_text(g + "\nbig = " + "9" * 5000)),
]


def number_variants(old: str, key: str, *, zero_ok: bool = False) -> list[Variant]:
    """``old`` (``name = value``) given every bad number the campaign tried (``1e-300`` too
    unless 0 is in the key's range: a 1e-300 s ramp is no ramp, a valid choice)."""
    name = old.split("=")[0].strip()
    values = [
        "nan",
        "inf",
        "-inf",
        "1e308",
        "-1e308",
        "99999999999999999999",
        '"0.5"',
        "[0.5]",
        "{ v = 0.5 }",
        "true",
        *([] if zero_ok else ["1e-300"]),
    ]
    return [Variant(f"{key} = {value}", edit(old, f"{name} = {value}"), key) for value in values]


ROBOT = [
    *TOML_LEVEL,
    *number_variants("mass_kg = 0.085", "link.mass_kg"),
    *number_variants("ramp_s = 1.0", "safety.ramp_s", zero_ok=True),
    *number_variants("timestep_s = 0.002", "twin.timestep_s"),
    Variant("-0 mass", edit("mass_kg = 0.085", "mass_kg = -0.0"), "link.mass_kg"),
    Variant("length in mm", edit("length_m = 0.065", "length_m = 65"), "link.length_m"),
    Variant("timestep in ms", edit("timestep_s = 0.002", "timestep_s = 2"), "twin.timestep_s"),
    Variant("ramp with a unit", edit("ramp_s = 1.0", 'ramp_s = "1 s"'), "safety.ramp_s"),
    Variant(
        "huge servo ID",
        edit("[[joints]]\nservo_id = 1", "[[joints]]\nservo_id = " + "9" * 30),
        "joints[0].servo_id",
    ),
    Variant("unknown key", edit("[safety]", "[safety]\nramp_time = 2"), "safety.ramp_time"),
    Variant("unknown table", edit("[safety]", "[wheels]\nn = 4\n[safety]"), "wheels"),
    Variant("missing [link]", edit("[link]", "[linkage]"), "link"),
    Variant("missing servo", edit('servo = "XL430-W250"', ""), "servo"),
    Variant(
        "right-to-left override name", edit('name = "snake12"', 'name = "snake\u202e21"'), "name"
    ),
    Variant("bell in the name", edit('name = "snake12"', 'name = "snake\\u0007"'), "name"),
    Variant("500 kB name", edit('name = "snake12"', 'name = "' + "a" * 500_000 + '"'), "name"),
    Variant("bidirectional key", edit("[safety]", '[safety]\n"r\u202eamp" = 1'), "safety."),
]

SERVO = [
    *TOML_LEVEL,
    *number_variants("supply_voltage_v = 11.1", "physics.supply_voltage_v"),
    Variant(
        "voltage with a unit",
        edit("supply_voltage_v = 11.1", 'supply_voltage_v = "12 V"'),
        "physics.supply_voltage_v",
    ),
    Variant(
        "voltage in mV",
        edit("supply_voltage_v = 11.1", "supply_voltage_v = 11100"),
        "physics.supply_voltage_v",
    ),
    Variant("unknown key", edit("[physics]", "[physics]\ngear_ratio = 258"), "physics.gear_ratio"),
    Variant("missing model", edit('model = "XL430-W250"', ""), "model"),
    Variant(
        "model with an override",
        edit('model = "XL430-W250"', 'model = "XL430\u202e-W250"'),
        "model",
    ),
]

BODY = [
    *TOML_LEVEL,
    *number_variants("ramp_s = 1.0", "safety.ramp_s", zero_ok=True),
    *number_variants("timestep_s = 0.001", "twin.timestep_s"),
    *number_variants("point_mass_kg = 0.01", "lattice.point_mass_kg"),
    Variant(
        "huge segment count", edit("segments = 6", "segments = " + "9" * 30), "lattice.segments"
    ),
    Variant("unknown key", edit("[ground]", "[ground]\nslope = 3"), "ground.slope"),
    Variant("missing [lattice]", edit("[lattice]", "[lattic]"), "lattice"),
    Variant("right-to-left override name", edit('name = "worm"', 'name = "w\u202eorm"'), "name"),
    Variant("500 kB name", edit('name = "worm"', 'name = "' + "w" * 500_000 + '"'), "name"),
]

GAIT = [
    # A gait file cut at a line end is a shorter valid file (defaults); cut inside a string it
    # is not TOML. "0.5" is a valid value: gait parameters may be expressions ("pi/4").
    *[v for v in TOML_LEVEL if v.name != "truncated"],
    Variant("truncated", lambda p, g: p.write_text(g[:12])),
    *[
        v
        for v in number_variants("amplitude = 0.4", "params.amplitude", zero_ok=True)
        if v.name != 'params.amplitude = "0.5"'
    ],
    Variant(
        "amplitude a bad expression",
        edit("amplitude = 0.4", 'amplitude = "0.4 rad"'),
        "params.amplitude",
    ),
    Variant("unknown key", edit("[params]", "colour = 1\n[params]"), "colour"),
    Variant("unknown parameter", edit("[params]", "[params]\nwobble = 1"), "params.wobble"),
    Variant("right-to-left override gait", edit('"serpenoid"', '"serpe\u202enoid"'), "gait"),
    Variant("5 MB gait name", edit('"serpenoid"', '"' + "s" * 500_000 + '"'), "gait"),
    Variant("missing gait", edit('gait = "serpenoid"', ""), "gait"),
]


def cell(line: int, column: str, value: str) -> Make:
    def make(path: Path, good: str) -> None:
        lines = good.split("\n")
        index = lines[0].split(",").index(column)
        cells = lines[line - 1].split(",")
        cells[index] = value
        lines[line - 1] = ",".join(cells)
        path.write_text("\n".join(lines))

    return make


CSV = [
    *FILE_LEVEL,
    Variant("empty", text("")),
    Variant("truncated in the header", lambda p, g: p.write_text(g[:40])),
    Variant("header only", lambda p, g: p.write_text(g.split("\n")[0] + "\n")),
    Variant("NaN time", cell(5, "time_s", "nan"), "line 5, column time_s"),
    Variant("empty time", cell(5, "time_s", ""), "line 5, column time_s"),
    Variant("time backwards", cell(5, "time_s", "0.0"), "line 5, column time_s"),
    Variant("NaN cycle", cell(6, "cycle", "nan"), "line 6, column cycle"),
    Variant("1e308 position", cell(5, "position_rad_0", "1e308"), "line 5, column position_rad_0"),
    Variant("-1e308 effort", cell(7, "effort_nm_3", "-1e308"), "line 7, column effort_nm_3"),
    Variant("inf velocity", cell(5, "velocity_rad_s_1", "inf"), "line 5, column velocity_rad_s_1"),
    Variant("1e308 time", cell(5, "time_s", "1e308"), "line 5, column time_s"),
    Variant("text cell", cell(5, "command_rad_0", "abc"), "line 5, column command_rad_0"),
    Variant(
        "control character cell",
        cell(5, "command_rad_0", "0.1\x07"),
        "line 5, column command_rad_0",
    ),
    Variant(
        "duplicated column",
        lambda p, g: p.write_text(g.replace("cycle", "time_s", 1)),
        "line 1, column time_s",
    ),
    Variant(
        "bidirectional column",
        lambda p, g: p.write_text(g.replace("cycle", "cy\u202ecle", 1)),
        "line 1, column 2",
    ),
    Variant("binary rows", lambda p, g: p.write_bytes(g.split("\n")[0].encode() + b"\n" + GARBAGE)),
]


def sidecar_field(change: Callable[[dict[str, object]], None]) -> Make:
    def make(path: Path, good: str) -> None:
        payload = json.loads(good)
        change(payload)
        path.write_text(json.dumps(payload))

    return make


def _set(key: str, value: object) -> Callable[[dict[str, object]], None]:
    def change(payload: dict[str, object]) -> None:
        target: dict[str, object] = payload
        *parents, last = key.split(".")
        for parent in parents:
            target = target[parent]  # type: ignore[assignment]
        target[last] = value

    return change


SIDECAR = [
    *FILE_LEVEL,
    Variant("empty", text("")),
    Variant("truncated", truncated),
    Variant("not an object", text("[1, 2, 3]"), "format"),
    Variant("no format", sidecar_field(lambda d: d.pop("format")), "format"),
    Variant("deeply nested", text(NESTED_JSON)),
    Variant("NaN rate", lambda p, g: p.write_text(g.replace('"rate_hz": 100.0', '"rate_hz": NaN'))),
    Variant("1e308 rate", sidecar_field(_set("rate_hz", 1e308)), "rate_hz"),
    Variant("rate as text", sidecar_field(_set("rate_hz", "fast")), "rate_hz"),
    Variant("negative rate", sidecar_field(_set("rate_hz", -100)), "rate_hz"),
    Variant("robot not an object", sidecar_field(_set("robot", "snake8")), "robot"),
    Variant("robot name an object", sidecar_field(_set("robot.name", {"a": 1})), "robot.name"),
    Variant(
        "right-to-left robot name", sidecar_field(_set("robot.name", "snake\u202e8")), "robot.name"
    ),
    Variant("5 MB robot name", sidecar_field(_set("robot.name", "s" * 5_000_000)), "robot.name"),
    Variant(
        "servo IDs as text", sidecar_field(_set("robot.servo_ids", ["a", "b"])), "robot.servo_ids"
    ),
    Variant("huge servo ID", sidecar_field(_set("robot.servo_ids", [10**30])), "robot.servo_ids"),
    Variant("link not an object", sidecar_field(_set("robot.link", 3)), "robot.link"),
    Variant("1e308 mass", sidecar_field(_set("robot.link.mass_kg", 1e308)), "robot.link.mass_kg"),
    Variant(
        "joint count as text", sidecar_field(_set("robot.joint_count", "8")), "robot.joint_count"
    ),
    Variant("gait a number", sidecar_field(_set("gait", 3)), "gait"),
    Variant("gait name a list", sidecar_field(_set("gait", {"name": [1]})), "gait.name"),
    Variant("created a number", sidecar_field(_set("created_utc", 5)), "created_utc"),
    Variant("command with a bell", sidecar_field(_set("command", "run\x07")), "command"),
]


@pytest.fixture(scope="module")
def good_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real log (snake8 serpenoid on the twin, 0.3 s) and its sidecar."""
    folder = tmp_path_factory.mktemp("good")
    log = folder / "run.csv"
    code = main(
        ["run", "--robot", "snake8", "--gait", "serpenoid", "--duration", "0.3", "--log", str(log)]
    )
    assert code == 0 and log.exists()
    assert '"rate_hz": 100.0' in (folder / "run.csv.json").read_text()
    return log


@pytest.fixture
def bus() -> Iterator[str]:
    chain = EmulatedChain(robot_servos("XL430-W250", range(1, 13), 1_000_000), baud=1_000_000)
    with registered(chain) as url:
        yield url


def check(capsys: pytest.CaptureFixture[str], argv: list[str], path: Path, key: str) -> None:
    capsys.readouterr()
    code = main(argv)
    err = capsys.readouterr().err
    assert "internal error" not in err and "Traceback" not in err, err
    assert code == 1, f"exit {code}: {err[-500:]}"
    assert str(path) in err, err[-500:]
    assert key in err, err[-500:]
    assert len(err) < 5_000, "the message prints the bad value whole"


def _ids(variants: list[Variant]) -> list[str]:
    return [v.name for v in variants]


@pytest.mark.parametrize("variant", ROBOT, ids=_ids(ROBOT))
def test_robot_files(
    variant: Variant,
    config_dir: Path,
    tmp_path: Path,
    bus: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = config_dir / "robots" / "snake12.toml"
    variant.make(path, path.read_text(encoding="utf-8"))
    for argv in (
        ["model", "--robot", str(path), "--out", str(tmp_path / "m.xml")],
        ["run", "--robot", str(path), "--duration", "0.1"],
        ["config", "diff", "--robot", str(path), "--port", bus],
    ):
        check(capsys, argv, path, variant.key)


@pytest.mark.parametrize("variant", SERVO, ids=_ids(SERVO))
def test_servo_files(
    variant: Variant, config_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = config_dir / "servos" / "xl430-w250.toml"
    variant.make(path, path.read_text(encoding="utf-8"))
    robot = config_dir / "robots" / "snake12.toml"
    for argv in (
        ["model", "--robot", str(robot), "--out", str(tmp_path / "m.xml")],
        ["run", "--robot", str(robot), "--duration", "0.1"],
    ):
        check(capsys, argv, path, variant.key)


@pytest.mark.parametrize("variant", BODY, ids=_ids(BODY))
def test_body_files(
    variant: Variant, config_dir: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = config_dir / "bodies" / "worm.toml"
    variant.make(path, path.read_text(encoding="utf-8"))
    for argv in (
        ["model", "--robot", str(path), "--out", str(tmp_path / "m.xml")],
        ["run", "--robot", str(path), "--duration", "0.1"],
    ):
        check(capsys, argv, path, variant.key)


@pytest.mark.parametrize("variant", GAIT, ids=_ids(GAIT))
def test_gait_files(variant: Variant, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "wave.toml"
    path.write_text(GAIT_FILE)
    variant.make(path, GAIT_FILE)
    check(
        capsys,
        ["run", "--robot", "snake8", "--gait-file", str(path), "--duration", "0.1"],
        path,
        variant.key,
    )


def _log_commands(log: Path, tmp_path: Path) -> list[list[str]]:
    return [
        ["log", "info", str(log)],
        ["log", "plot", str(log), "--out", str(tmp_path / "plots")],
        ["log", "export", str(log), "--format", "mcap", "--out", str(tmp_path / "x.mcap")],
    ]


@pytest.mark.parametrize("variant", CSV, ids=_ids(CSV))
def test_telemetry_csvs(
    variant: Variant, good_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "run.csv"
    shutil.copy(good_log, log)
    shutil.copy(good_log.with_name("run.csv.json"), tmp_path / "run.csv.json")
    variant.make(log, good_log.read_text())
    for argv in _log_commands(log, tmp_path):
        check(capsys, argv, log, variant.key)


@pytest.mark.parametrize("variant", SIDECAR, ids=_ids(SIDECAR))
def test_sidecars(
    variant: Variant, good_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "run.csv"
    sidecar = tmp_path / "run.csv.json"
    shutil.copy(good_log, log)
    shutil.copy(good_log.with_name("run.csv.json"), sidecar)
    variant.make(sidecar, sidecar.read_text())
    for argv in _log_commands(log, tmp_path):
        check(capsys, argv, sidecar, variant.key)


@pytest.mark.parametrize(
    "value", ["snake\u202e8", "snake8\x07", "a\u2066b", "s" * 5000, "snake\u200b8"]
)
def test_a_robot_option_that_is_no_identifier_is_bad_usage(
    value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["model", "--robot", value, "--out", "unused.xml"])
    err = capsys.readouterr().err
    assert code == 2 and "argument --robot" in err and len(err) < 2_000, err
