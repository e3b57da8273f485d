"""The output rule, swept over every command that writes a file: an output that exists is
refused (exit 1, naming it and --force) and left byte for byte as it was, with nothing else
written; ``--dry-run`` reports the same refusal; ``--force`` replaces it.

The sweep is generated from the parser: every option of type Path is either an output (and then
has a case here) or a known input, so a new output option cannot escape it.
"""

from __future__ import annotations

import argparse
import importlib.util
from dataclasses import dataclass
from pathlib import Path

import pytest

from snakebot.cli.main import build_parser, leaf_parsers, main
from snakebot.telemetry.sidecar import sidecar_path

OUTPUT_OPTIONS = ("--out", "--log", "--video", "--report", "--record", "--mcap")
INPUT_OPTIONS = ("--gait-file", "--script", "--state-file", "--resume")
MINE = b"the user's own bytes\n"


def path_options(parser: argparse.ArgumentParser) -> list[str]:
    return [a.option_strings[0] for a in parser._actions if a.type is Path and a.option_strings]


WRITERS = sorted(
    (" ".join(path), option)
    for path, parser in leaf_parsers(build_parser())
    for option in path_options(parser)
    if option in OUTPUT_OPTIONS
)


@dataclass(frozen=True)
class Case:
    """``argv`` with ``{out}`` (the output), ``{log}`` (a telemetry CSV), ``{script}`` (drive
    keys) or ``{policy}`` (a policy folder); ``name`` the output's file or folder name;
    ``holds`` what a folder output already holds (empty: the output is a file)."""

    argv: tuple[str, ...]
    name: str
    holds: tuple[str, ...] = ()
    force_is_cheap: bool = False
    needs_learning: bool = False


LEARNING_MISSING = any(
    importlib.util.find_spec(module) is None
    for module in ("gymnasium", "stable_baselines3", "torch")
)
RUN = ("run", "--duration", "0.2")
# Small and quick, should the rule ever not hold (the rl commands would then train and replace).
RL_FAST = (
    "--n-envs",
    "1",
    "--vec",
    "dummy",
    "--set",
    "action_hz=25",
    "--set",
    "control_hz=25",
    "--set",
    "episode_s=2",
)
DRIVE = ("drive", "--script", "{script}")
CASES = {
    ("run", "--log"): Case((*RUN, "--log", "{out}"), "run.csv", force_is_cheap=True),
    ("run", "--video"): Case((*RUN, "--video", "{out}"), "run.mp4"),
    ("run", "--mcap"): Case((*RUN, "--mcap", "{out}"), "run.mcap", force_is_cheap=True),
    ("drive", "--log"): Case((*DRIVE, "--log", "{out}"), "drive.csv", force_is_cheap=True),
    ("drive", "--record"): Case((*DRIVE, "--record", "{out}"), "keys.txt", force_is_cheap=True),
    ("drive", "--mcap"): Case((*DRIVE, "--mcap", "{out}"), "drive.mcap"),
    # Refused before rclpy is needed; --force would serve until stopped (tests/integration/ros2).
    ("ros2", "--mcap"): Case(("ros2", "--mcap", "{out}"), "ros2.mcap"),
    ("model", "--out"): Case(("model", "--out", "{out}"), "snake.xml", force_is_cheap=True),
    ("calibrate", "--out"): Case(
        ("calibrate", "--robot", "snake12", "--out", "{out}"), "snake12.toml"
    ),
    ("tune gait", "--out"): Case(("tune", "gait", "--budget", "2", "--out", "{out}"), "gait.toml"),
    ("tune gait", "--report"): Case(
        ("tune", "gait", "--budget", "2", "--report", "{out}"), "report", holds=("summary.json",)
    ),
    ("tune gains", "--out"): Case(("tune", "gains", "--out", "{out}"), "robot.toml"),
    ("tune gains", "--report"): Case(
        ("tune", "gains", "--report", "{out}"), "report", holds=("summary.json", "steps.png")
    ),
    ("sysid", "--out"): Case(("sysid", "{log}", "--out", "{out}"), "robot.toml"),
    ("sysid", "--report"): Case(
        ("sysid", "{log}", "--report", "{out}"), "report", holds=("summary.json",)
    ),
    ("sysid", "--record"): Case(
        ("sysid", "--record", "{out}", "--duration", "0.3"), "chirp.csv", force_is_cheap=True
    ),
    ("log plot", "--out"): Case(
        ("log", "plot", "{log}", "--out", "{out}"),
        "plots",
        holds=("joints.png",),
        force_is_cheap=True,
    ),
    ("log export", "--out"): Case(
        ("log", "export", "{log}", "--format", "mcap", "--out", "{out}"),
        "export.mcap",
        force_is_cheap=True,
    ),
    ("rl train", "--out"): Case(
        ("rl", "train", "--steps", "64", "--rollout", "64", *RL_FAST, "--out", "{out}"),
        "policy",
        holds=("policy.json", "actor.npz"),
        needs_learning=True,
    ),
    ("rl eval", "--video"): Case(
        ("rl", "eval", "{policy}", "--episodes", "1", "--baselines", "off", "--video", "{out}"),
        "eval.mp4",
        needs_learning=True,
    ),
    ("rl compare", "--out"): Case(
        ("rl", "compare", "--encodings", "simple", "--steps", "64", *RL_FAST, "--out", "{out}"),
        "compare",
        holds=("summary.json", "compare.png"),
        needs_learning=True,
    ),
}


def params(cases: list[tuple[str, str]]) -> list[object]:
    return [
        pytest.param(
            key,
            id=" ".join(key),
            marks=[pytest.mark.skipif(LEARNING_MISSING, reason="needs the rl-train extra")]
            if CASES[key].needs_learning
            else [],
        )
        for key in cases
    ]


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A telemetry log of the twin (with its sidecar), a drive script and a policy folder."""
    folder = tmp_path_factory.mktemp("inputs")
    log = folder / "twin.csv"
    assert main(["run", "--duration", "0.5", "--log", str(log), "--json"]) == 0
    script = folder / "keys.txt"
    script.write_text("0.0 w\n0.3 q\n")
    if LEARNING_MISSING:  # the rl cases skip
        return {"log": log, "script": script, "policy": folder / "policy"}
    from snakebot.rl import GOAL_ENV_ID
    from tests.integration.rl.policies import constant_policy

    policy = constant_policy(
        folder / "policy",
        GOAL_ENV_ID,
        [0, 0, 0, 0],
        2 * 8 + 2 + 2,
        encoding="sinusoid",
        action_hz=25,
        control_hz=25,
        episode_s=2,
    )
    return {"log": log, "script": script, "policy": policy}


def prepare(case: Case, tmp_path: Path) -> tuple[Path, Path]:
    """The output, made with known bytes, inside a folder of its own."""
    folder = tmp_path / "outputs"
    folder.mkdir()
    target = folder / case.name
    if case.holds:
        target.mkdir()
        for name in case.holds:
            (target / name).write_bytes(MINE + name.encode())
    else:
        target.write_bytes(MINE)
    return folder, target


def snapshot(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes() if p.is_file() else b"<dir>"
        for p in sorted(folder.rglob("*"))
    }


def argv(case: Case, target: Path, inputs: dict[str, Path]) -> list[str]:
    return [word.format(out=target, **inputs) for word in case.argv]


def test_the_sweep_covers_every_output_option() -> None:
    assert sorted(CASES) == WRITERS
    for path, parser in leaf_parsers(build_parser()):
        for option in path_options(parser):
            assert option in OUTPUT_OPTIONS + INPUT_OPTIONS, (
                f"snakebot {' '.join(path)} {option}: an input or an output? Outputs need a case "
                "here"
            )


@pytest.mark.parametrize("dry_run", [False, True], ids=["run", "dry-run"])
@pytest.mark.parametrize("key", params(WRITERS))
def test_an_existing_output_is_refused_and_left_as_it_was(
    key: tuple[str, str],
    dry_run: bool,
    inputs: dict[str, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    case = CASES[key]
    folder, target = prepare(case, tmp_path)
    before = snapshot(folder)
    capsys.readouterr()
    code = main([*argv(case, target, inputs), *(["--dry-run"] if dry_run else [])])
    err = capsys.readouterr().err
    assert code == 1, err
    assert str(target) in err and "--force" in err, err
    assert snapshot(folder) == before


@pytest.mark.parametrize("key", params([k for k in WRITERS if CASES[k].force_is_cheap]))
def test_force_replaces_the_output(
    key: tuple[str, str],
    inputs: dict[str, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    case = CASES[key]
    _, target = prepare(case, tmp_path)
    code = main([*argv(case, target, inputs), "--force"])
    assert code == 0, capsys.readouterr().err
    if case.holds:
        assert all((target / name).read_bytes() != MINE + name.encode() for name in case.holds)
    else:
        assert target.read_bytes() != MINE


def test_an_existing_sidecar_refuses_the_log_it_belongs_to(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "run.csv"
    sidecar_path(log).write_bytes(MINE)
    assert main([*RUN, "--log", str(log)]) == 1
    assert str(sidecar_path(log)) in capsys.readouterr().err
    assert sidecar_path(log).read_bytes() == MINE and not log.exists()


def test_a_refused_recording_leaves_the_other_outputs_unwritten(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "run.mcap").write_bytes(MINE)
    code = main([*RUN, "--log", str(tmp_path / "run.csv"), "--mcap", str(tmp_path / "run.mcap")])
    assert code == 1, capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]


def test_log_export_by_default_leaves_the_live_recording_beside_the_log(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The README's lines: `drive --mcap drive.mcap --log drive.csv`, then `log export drive.csv
    --format mcap`. The export goes to drive.export.mcap; drive.mcap stays as recorded."""
    recording, log = tmp_path / "drive.mcap", tmp_path / "drive.csv"
    script = tmp_path / "keys.txt"
    script.write_text("0.0 w\n0.3 q\n")
    assert main([*DRIVE[:2], str(script), "--mcap", str(recording), "--log", str(log)]) == 0
    recorded = recording.read_bytes()
    capsys.readouterr()
    assert main(["log", "export", str(log), "--format", "mcap", "--json"]) == 0
    assert recording.read_bytes() == recorded
    exported = tmp_path / "drive.export.mcap"
    assert exported.stat().st_size > 0
    assert '"out": "' + str(exported) in capsys.readouterr().out
    assert main(["log", "export", str(log), "--format", "mcap"]) == 1  # and not again
    assert str(exported) in capsys.readouterr().err


@pytest.mark.parametrize("option", ["--log", "--mcap", "--video"])
def test_a_missing_folder_is_refused_not_made(
    option: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "no" / "such" / f"x.{'mp4' if option == '--video' else 'csv'}"
    assert main([*RUN, option, str(target)]) == 1
    err = capsys.readouterr().err
    assert f"folder {tmp_path / 'no'} does not exist" in err
    assert list(tmp_path.iterdir()) == []
