"""The same flags mean the same thing on every command: one walk over the parser's subcommands, so
a subcommand added later is checked without touching this file.

Checked per (sub)command: no abbreviated long options; a misspelled flag is exit 2 with that
subcommand's usage and the nearest flag; ``--debug`` before or after the subcommand; ``--json``
accepted, and errors then printed as ``{"error": ..., "code": ...}``; ``--port``/``--baud`` of
one type and default; ``--robot`` required before real servos are touched; every command that
writes (servos or files) says so and has ``--dry-run``, which writes nothing.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
from pathlib import Path

import pytest

from snakebot.cli.common import baud_arg, port_arg
from snakebot.cli.main import build_parser, leaf_parsers, main
from snakebot.emulation.bench import robot_servos
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.registry import registered

PARSER = build_parser()
LEAVES = list(leaf_parsers(PARSER))
IDS = [" ".join(path) for path, _ in LEAVES]
OUTPUT_OPTIONS = ("--out", "--log", "--video", "--report", "--record", "--mcap")
# Reads servos but writes and moves nothing: lists what answers before any robot file exists.
NO_ROBOT_NEEDED = {("scan",)}
VALUES = {"to": "3", "id": "1", "torque": "off", "angle": "10"}


def options(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {s: a for a in parser._actions for s in a.option_strings}


def required_argv(parser: argparse.ArgumentParser, tmp_path: Path) -> list[str]:
    """The fewest arguments the parser accepts: its required options with plausible values."""
    argv = [
        VALUES.get(a.dest, str(tmp_path / f"{a.dest}.csv"))
        for a in parser._actions
        if not a.option_strings and a.required and a.nargs in (None, "+")  # a positional file
    ]
    wanted = [a for a in parser._actions if a.required and a.option_strings]
    wanted += [g._group_actions[0] for g in parser._mutually_exclusive_groups if g.required]
    for action in wanted:
        option = action.option_strings[0]
        if action.nargs == 0:
            argv.append(option)
        else:
            value = action.choices[0] if action.choices else str(tmp_path / f"{action.dest}.out")
            argv += [option, VALUES.get(action.dest, value)]
    return argv


def run(capsys: pytest.CaptureFixture[str], argv: list[str]) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_the_walk_finds_every_subcommand() -> None:
    assert {
        "run",
        "drive",
        "robots",
        "ports",
        "tune gait",
        "tune gains",
        "config apply",
        "servo reset",
        "sysid",
        "emulate",
    } <= set(IDS)
    assert len(IDS) == len(set(IDS))


def test_no_parser_accepts_abbreviations() -> None:
    def walk(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
        children = [
            child
            for a in parser._actions
            if isinstance(a, argparse._SubParsersAction)
            for child in a.choices.values()
        ]
        return [parser, *(p for child in children for p in walk(child))]

    assert all(not parser.allow_abbrev for parser in walk(PARSER))


@pytest.mark.parametrize(("path", "parser"), LEAVES, ids=IDS)
def test_an_abbreviated_option_is_refused_with_the_subcommands_usage(
    path: tuple[str, ...],
    parser: argparse.ArgumentParser,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = [*path, *required_argv(parser, tmp_path), "--jso"]
    code, out, err = run(capsys, argv)
    assert code == 2 and out == ""
    assert err.startswith(f"usage: snakebot {' '.join(path)} ")
    assert f"snakebot {' '.join(path)}: error: unrecognized arguments: --jso" in err
    assert "did you mean --json?" in err


@pytest.mark.parametrize(("path", "parser"), LEAVES, ids=IDS)
def test_a_misspelled_flag_is_named_with_its_nearest_match(
    path: tuple[str, ...],
    parser: argparse.ArgumentParser,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, _, err = run(capsys, [*path, *required_argv(parser, tmp_path), "--degub"])
    assert code == 2
    assert f"usage: snakebot {' '.join(path)} " in err and "did you mean --debug?" in err


@pytest.mark.parametrize(("path", "parser"), LEAVES, ids=IDS)
def test_debug_is_accepted_before_and_after_the_subcommand(
    path: tuple[str, ...], parser: argparse.ArgumentParser, tmp_path: Path
) -> None:
    rest = required_argv(parser, tmp_path)
    assert PARSER.parse_args([*path, *rest]).debug is False
    assert PARSER.parse_args(["--debug", *path, *rest]).debug is True
    assert PARSER.parse_args([*path, *rest, "--debug"]).debug is True


@pytest.mark.parametrize(("path", "parser"), LEAVES, ids=IDS)
def test_json_is_accepted_and_usage_errors_come_as_json(
    path: tuple[str, ...],
    parser: argparse.ArgumentParser,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    json_action = options(parser).get("--json")
    assert json_action is not None and json_action.nargs == 0
    code, out, err = run(capsys, [*path, *required_argv(parser, tmp_path), "--json", "--bogus"])
    assert code == 2 and out == ""
    error = json.loads(err)
    assert error["code"] == 2 and "--bogus" in error["error"]


@pytest.mark.parametrize(
    ("path", "parser"),
    [(p, parser) for p, parser in LEAVES if "--robot" in options(parser)],
    ids=[i for i, (_, parser) in zip(IDS, LEAVES, strict=True) if "--robot" in options(parser)],
)
def test_a_file_error_with_json_is_a_json_error_of_code_1(
    path: tuple[str, ...],
    parser: argparse.ArgumentParser,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    missing = tmp_path / "nope.toml"
    argv = [*path, *required_argv(parser, tmp_path), "--robot", str(missing), "--json"]
    code, out, err = run(capsys, argv)
    assert code == 1 and out == ""
    error = json.loads(err)
    if path[0] == "rl" and importlib.util.find_spec("gymnasium") is None:
        # A missing extra comes first: nothing of the learning commands runs without it.
        assert error["code"] == 1 and "pip install 'snakebot[rl]'" in error["error"]
        return
    assert error == {"error": f"snakebot: error: {missing}: robot file not found", "code": 1}


@pytest.mark.parametrize(("path", "parser"), LEAVES, ids=IDS)
def test_port_and_baud_mean_the_same_everywhere(
    path: tuple[str, ...], parser: argparse.ArgumentParser
) -> None:
    found = options(parser)
    if "--port" in found:
        assert found["--port"].type is port_arg and found["--port"].default is None
    if "--baud" in found:
        assert found["--baud"].type is baud_arg and found["--baud"].default is None
        assert "--port" in found or path == ("emulate",)  # the emulator's own line rate


HARDWARE = [
    (p, parser) for p, parser in LEAVES if "--port" in options(parser) and p not in NO_ROBOT_NEEDED
]


@pytest.mark.parametrize(("path", "parser"), HARDWARE, ids=[" ".join(p) for p, _ in HARDWARE])
def test_robot_is_required_before_real_servos_are_touched(
    path: tuple[str, ...],
    parser: argparse.ArgumentParser,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    found = options(parser)
    argv = [*path, *required_argv(parser, tmp_path), "--port", "dxlemu://nobody-here"]
    if "--backend" in found:
        argv += ["--backend", "dynamixel"]
    if "--record" in found:
        argv += ["--record", str(tmp_path / "record.csv")]
    code, out, err = run(capsys, argv)
    assert code == 2 and out == ""
    assert "--robot" in err and "no default robot on hardware" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("path", "parser"), LEAVES, ids=IDS)
def test_every_command_that_writes_has_dry_run(
    path: tuple[str, ...], parser: argparse.ArgumentParser
) -> None:
    writes = parser.get_default("writes")
    assert isinstance(writes, bool), f"snakebot {' '.join(path)} declares no writes=True/False"
    found = options(parser)
    if any(option in found for option in OUTPUT_OPTIONS):
        assert writes, f"snakebot {' '.join(path)} has an output option but says writes=False"
    if writes:
        assert found["--dry-run"].nargs == 0


DRY_RUNS = [
    ["run", "--duration", "0.5", "--log", "{tmp}/run.csv", "--video", "{tmp}/run.mp4"],
    ["drive", "--script", "{script}", "--log", "{tmp}/drive.csv", "--record", "{tmp}/keys.txt"],
    ["model", "--out", "{tmp}/snake.xml"],
    ["sysid", "--record", "{tmp}/chirp.csv"],
]


@pytest.mark.parametrize("argv", DRY_RUNS, ids=[a[0] for a in DRY_RUNS])
def test_dry_run_writes_no_file(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = tmp_path.parent / f"{tmp_path.name}-keys.txt"
    script.write_text("0.5 w\n1.0 q\n")
    words = [a.format(tmp=tmp_path, script=script) for a in argv]
    code, out, _ = run(capsys, [*words, "--dry-run", "--json"])
    assert code == 0
    assert json.loads(out)["dry_run"] is True
    assert list(tmp_path.iterdir()) == []


def snake12_bus() -> EmulatedChain:
    return EmulatedChain(robot_servos("XL430-W250", range(1, 13), 1_000_000), baud=1_000_000)


@pytest.mark.parametrize(
    "argv",
    [
        ["servo", "reboot", "--all"],
        ["servo", "reset", "--id", "4"],
        ["config", "assign-id", "--from", "4", "--to", "20"],
        ["servo", "torque", "off"],
        ["servo", "jog", "4", "15"],
    ],
    ids=["servo reboot", "servo reset", "config assign-id", "servo torque", "servo jog"],
)
def test_dry_run_on_servos_writes_no_register(
    argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    chain = snake12_bus()
    chain.servo(4).poke("torque_enable", 1)
    before = [bytes(s.memory.data) for s in chain.servos]
    with registered(chain) as url:
        code, out, err = run(
            capsys, [*argv, "--robot", "snake12", "--port", url, "--dry-run", "--json"]
        )
    assert code == 0, err
    assert json.loads(out)["dry_run"] is True
    after = [bytes(s.memory.data) for s in chain.servos]
    changed = [i for i, (b, a) in enumerate(zip(before, after, strict=True)) if b != a]
    assert [s.servo_id for s in chain.servos] == list(range(1, 13))
    assert (
        not changed
        or all(  # reads may refresh live state (present position...), not EEPROM
            before[i][:64] == after[i][:64] for i in changed
        )
    )
    assert chain.servo(4).torque_enabled
