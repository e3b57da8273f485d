"""A policy folder is data people share: whatever is in it, `rl eval`, `run --policy` and their
dry runs refuse it with exit 1 naming the file and the key, import nothing named in it, and
never end in exit 3 (a snakebot bug)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from snakebot.cli.main import main
from snakebot.rl.settings import GOAL_ENV_ID, VELOCITY_ENV_ID
from tests.integration.rl.policies import constant_policy

PAYLOAD = "open({marker!r}, 'w').write('imported')\n"
COMMANDS: dict[str, list[str]] = {
    "rl eval": ["rl", "eval", "{dir}", "--episodes", "1", "--baselines", "off"],
    "rl eval --dry-run": ["rl", "eval", "{dir}", "--dry-run"],
    "run --policy": ["run", "--policy", "{dir}", "--command", "0,0", "--duration", "0.1"],
    "run --policy --dry-run": ["run", "--policy", "{dir}", "--command", "0,0", "--dry-run"],
}


def good_policy(folder: Path, env_id: str = GOAL_ENV_ID) -> Path:
    if env_id == GOAL_ENV_ID:
        return constant_policy(folder, env_id, [0, 0, 0, 0, 0], 2 * 8 + 2 + 2)
    return constant_policy(folder, env_id, [0, 0, 0, 0, 0], 3 * 8 + 2 + 2)


def edit_json(change: Callable[[dict[str, Any]], None]) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        path = folder / "policy.json"
        payload = json.loads(path.read_text())
        change(payload)
        path.write_text(json.dumps(payload))  # NaN and Infinity as Python's json writes them

    return edit


def setting(key: str, value: object) -> Callable[[Path], None]:
    return edit_json(lambda p: p["env_kwargs"].__setitem__(key, value))


def top(key: str, value: object) -> Callable[[Path], None]:
    return edit_json(lambda p: p.__setitem__(key, value))


def write(name: str, data: bytes) -> Callable[[Path], None]:
    return lambda folder: (folder / name).write_bytes(data)


def actor(**arrays: Any) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        np.savez(folder / "actor.npz", **arrays)

    return edit


def nested(depth: int) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        text = (folder / "policy.json").read_text().rstrip().rstrip("}")
        (folder / "policy.json").write_text(f'{text}, "versions": {"[" * depth}{"]" * depth}}}')

    return edit


# (what is wrong, the folder's edit, the file named, the key named)
CASES: list[tuple[str, Callable[[Path], None], str, str]] = [
    ("no policy.json", lambda f: (f / "policy.json").unlink(), "policy.json", "missing"),
    ("garbled JSON", write("policy.json", b'{"format": 1, "env_id": '), "policy.json", "JSON"),
    ("not UTF-8", write("policy.json", b"\xff\xfe{\x00}"), "policy.json", "JSON"),
    ("a JSON list", write("policy.json", b"[1, 2]"), "policy.json", "object"),
    ("wrong format", top("format", 2), "policy.json", "format"),
    ("env id of a module", top("env_id", "payloadpkg.evil:SnakeGoal-v0"), "policy.json", "env_id"),
    (
        "env id of an unknown module",
        top("env_id", "nosuchmodule:SnakeGoal-v0"),
        "policy.json",
        "env_id",
    ),
    ("a gymnasium env, not ours", top("env_id", "CartPole-v1"), "policy.json", "env_id"),
    ("env id a number", top("env_id", 7), "policy.json", "env_id"),
    ("env_kwargs a list", top("env_kwargs", [1]), "policy.json", "env_kwargs"),
    ("episode_s 1e308", setting("episode_s", 1e308), "policy.json", "env_kwargs.episode_s"),
    ("episode_s NaN", setting("episode_s", float("nan")), "policy.json", "episode_s"),
    ("episode_s text", setting("episode_s", "30"), "policy.json", "env_kwargs.episode_s"),
    ("episode_s true", setting("episode_s", True), "policy.json", "env_kwargs.episode_s"),
    ("action_hz negative", setting("action_hz", -10), "policy.json", "env_kwargs.action_hz"),
    ("a render_mode", setting("render_mode", "human"), "policy.json", "env_kwargs.render_mode"),
    ("an unknown setting", setting("speed", 1), "policy.json", "env_kwargs.speed"),
    ("robot a number", setting("robot", 5), "policy.json", "env_kwargs.robot"),
    ("robot unknown", setting("robot", "no-such-robot"), "policy.json", "env_kwargs.robot"),
    ("encoding a list", setting("encoding", ["dft"]), "policy.json", "env_kwargs.encoding"),
    ("dft_bins 2.5", setting("dft_bins", 2.5), "policy.json", "env_kwargs.dft_bins"),
    ("timestep_s 1e-300", setting("timestep_s", 1e-300), "policy.json", "env_kwargs.timestep_s"),
    ("goal_bonus Infinity", setting("goal_bonus", float("inf")), "policy.json", "goal_bonus"),
    (
        "goal_distance_bl text",
        setting("goal_distance_bl", ["a", "b"]),
        "policy.json",
        "env_kwargs.goal_distance_bl",
    ),
    ("an unknown key", top("trainer", "me"), "policy.json", "trainer"),
    ("steps text", top("steps", "many"), "policy.json", "steps"),
    ("steps NaN", top("steps", float("nan")), "policy.json", "steps"),
    ("nested 20 deep", nested(20), "policy.json", "nested"),
    ("nested 100,000 deep", nested(100_000), "policy.json", "nested"),
    ("no actor.npz", lambda f: (f / "actor.npz").unlink(), "actor.npz", "missing"),
    ("actor.npz text", write("actor.npz", b"weights"), "actor.npz", "not a policy actor"),
    ("actor.npz empty", write("actor.npz", b""), "actor.npz", "not a policy actor"),
    (
        "actor.npz a broken zip",
        write("actor.npz", b"PK\x03\x04broken"),
        "actor.npz",
        "not a policy actor",
    ),
    (
        "actor.npz layers that do not chain",
        actor(
            w0=np.zeros((4, 20)),
            b0=np.zeros(4),
            w1=np.zeros((5, 3)),
            b1=np.zeros(5),
            activation=np.array("tanh"),
        ),
        "actor.npz",
        "layer 1",
    ),
    (
        "actor.npz a scalar layer",
        actor(w0=np.array(1.0), b0=np.zeros(1), activation=np.array("tanh")),
        "actor.npz",
        "layer 0",
    ),
    (
        "actor.npz NaN weights",
        actor(
            w0=np.full((4, 20), np.nan),
            b0=np.zeros(4),
            w1=np.zeros((5, 4)),
            b1=np.zeros(5),
            activation=np.array("tanh"),
        ),
        "actor.npz",
        "finite",
    ),
    (
        "actor.npz an unknown activation",
        actor(
            w0=np.zeros((4, 20)),
            b0=np.zeros(4),
            w1=np.zeros((5, 4)),
            b1=np.zeros(5),
            activation=np.array("sigmoid"),
        ),
        "actor.npz",
        "activation",
    ),
    (
        "actor.npz pickled objects",
        actor(w0=np.array([object()], dtype=object), b0=np.zeros(1), activation=np.array("tanh")),
        "actor.npz",
        "not a policy actor",
    ),
]


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize(("what", "edit", "file", "key"), CASES, ids=[c[0] for c in CASES])
def test_a_malformed_policy_folder_is_exit_1_naming_the_file_and_key(
    what: str,
    edit: Callable[[Path], None],
    file: str,
    key: str,
    command: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    folder = good_policy(tmp_path / "policy")
    edit(folder)
    argv = [a.replace("{dir}", str(folder)) for a in COMMANDS[command]]
    capsys.readouterr()
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 1, err
    assert f"{folder / file}" in err and key in err, err
    assert "internal error" not in err and "Traceback" not in err


def test_the_velocity_tasks_settings_are_checked_too(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = good_policy(tmp_path / "vel", VELOCITY_ENV_ID)
    setting("command_period_s", 1e308)(folder)
    assert main(["rl", "eval", str(folder), "--episodes", "1"]) == 1
    assert "policy.json: env_kwargs.command_period_s" in capsys.readouterr().err


def test_a_good_folder_passes_the_same_checks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = good_policy(tmp_path / "policy")
    (folder / "policy.zip").write_bytes(b"not read by eval or run")  # kept only to train on
    top("action", [0, 1, 0, 0, 0])(folder)  # what tools/rl_open_loop.py records
    for argv in COMMANDS.values():
        if "--dry-run" in argv:
            assert main([a.replace("{dir}", str(folder)) for a in argv]) == 0
    assert "policy:goal:dft_shift" in capsys.readouterr().out


def test_nothing_named_in_a_policy_folder_is_imported(tmp_path: Path) -> None:
    # The payload sits where gymnasium's import would find it: the working folder and on
    # PYTHONPATH. Proof that it would run if imported: importing it writes the marker.
    marker = tmp_path / "MARKER"
    package = tmp_path / "payloadpkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "evil.py").write_text(PAYLOAD.format(marker=str(marker)))
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]),
    }
    proof = subprocess.run(
        [sys.executable, "-c", "import payloadpkg.evil"],
        cwd=tmp_path,
        env=env,
        timeout=60,
        check=False,
    )
    assert proof.returncode == 0 and marker.exists()
    marker.unlink()

    folder = good_policy(tmp_path / "shared")
    top("env_id", "payloadpkg.evil:SnakeGoal-v0")(folder)
    for name, argv in COMMANDS.items():
        done = subprocess.run(
            [sys.executable, "-m", "snakebot", *(a.replace("{dir}", "shared") for a in argv)],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        assert done.returncode == 1, (name, done.stderr)
        assert "shared/policy.json: env_id: expected one of snakebot/SnakeGoal-v0" in done.stderr
        assert not marker.exists(), f"{name} imported the payload"


@pytest.mark.parametrize(
    ("item", "key"),
    [
        ("episode_s=1e308", "episode_s"),
        ("timestep_s=1e-300", "timestep_s"),
        ("action_hz=1e9", "action_hz"),
    ],
)
def test_the_same_ranges_hold_for_a_new_training_run(
    item: str, key: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: accepted, and episode_s=1e308 overflowed in the first episode (exit 3)
    assert main(["rl", "train", "--set", item, "--dry-run", "--out", str(tmp_path / "x")]) == 1
    assert f"{key}: expected" in capsys.readouterr().err
