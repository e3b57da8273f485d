"""`rl train` as a user reruns it: a trained policy is never replaced unless --force, --resume
goes on from the saved weights with the recorded PPO settings, and what it prints and records
(CPU time, returns before any episode ended) is true. Runs of a few hundred steps."""

from __future__ import annotations

import io
import json
import pickle
import resource
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from snakebot.rl.policy_file import TRAIN_FILES
from snakebot.rl.settings import GOAL_ENV_ID
from snakebot.rl.train import TrainSettings, train

pytestmark = pytest.mark.slow
# 25 Hz actions, one control cycle each, 4 s episodes (100 steps): cheap steps, episodes end.
FAST = ["--set", "action_hz=25", "--set", "control_hz=25", "--set", "episode_s=4"]
TINY = ["--rollout", "128", "--n-envs", "1", "--vec", "dummy", "--ppo", "batch_size=64"]


def cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *args],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=cwd,
        check=False,
    )


def trained(folder: Path, steps: int = 256) -> Path:
    done = cli("rl", "train", "--out", str(folder), "--steps", str(steps), *TINY, *FAST)
    assert done.returncode == 0, done.stderr
    return folder


def weights(folder: Path) -> dict[str, np.ndarray]:
    with np.load(folder / "actor.npz") as data:
        return {key: data[key] for key in data.files}


def curve_steps(folder: Path) -> list[int]:
    lines = (folder / "learning_curve.csv").read_text().splitlines()
    return [int(line.split(",")[0]) for line in lines[1:]]


def test_a_trained_policy_is_replaced_only_with_force(tmp_path: Path) -> None:
    out = trained(tmp_path / "policy")
    before = contents(out)
    assert set(before) == {*TRAIN_FILES[:-1], "checkpoints/actor-0000000128.npz",
                           "checkpoints/actor-0000000256.npz"}  # fmt: skip
    for extra in ([], ["--dry-run"]):
        again = cli("rl", "train", "--out", str(out), "--steps", "128", *TINY, *FAST, *extra)
        assert again.returncode == 1, again.stderr
        assert (
            f"{out}: holds the trained policy files actor.npz, checkpoints, learning_curve.csv, "
            "learning_curve.png, policy.json, policy.zip, which would be replaced: pass "
            "--force" in again.stderr
        )
        assert contents(out) == before
    forced = cli("rl", "train", "--out", str(out), "--steps", "128", *TINY, *FAST, "--force")
    assert forced.returncode == 0, forced.stderr
    assert json.loads((out / "policy.json").read_text())["steps"] == 128
    assert curve_steps(out) == [128]  # a new policy, not a continued one
    # its snapshots only: the replaced run's 256-step one would read as this run's
    assert sorted(p.name for p in (out / "checkpoints").iterdir()) == ["actor-0000000128.npz"]


def contents(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` by its relative path."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_training_keeps_evenly_spaced_actor_snapshots_and_the_last(tmp_path: Path) -> None:
    # 640 steps in 128-step rollouts, 2 snapshots: after the rollouts at or past 320 and 640
    # steps; a resumed run counts on and keeps the first run's. The last snapshot is the actor.
    out = tmp_path / "policy"
    done = cli("rl", "train", "--out", str(out), "--steps", "640", "--checkpoints", "2",
               *TINY, *FAST)  # fmt: skip
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in (out / "checkpoints").iterdir())
    assert names == ["actor-0000000384.npz", "actor-0000000640.npz"]
    with np.load(out / "checkpoints" / "actor-0000000640.npz") as last:
        assert {k: last[k].tolist() for k in last.files} == {
            k: v.tolist() for k, v in weights(out).items()
        }
    more = cli("rl", "train", "--resume", str(out), "--steps", "256", "--checkpoints", "1",
               "--n-envs", "1", "--vec", "dummy")  # fmt: skip
    assert more.returncode == 0, more.stderr
    names = sorted(p.name for p in (out / "checkpoints").iterdir())
    assert names == ["actor-0000000384.npz", "actor-0000000640.npz", "actor-0000000896.npz"]
    none = cli("rl", "train", "--out", str(tmp_path / "bare"), "--steps", "128",
               "--checkpoints", "0", *TINY, *FAST)  # fmt: skip
    assert none.returncode == 0, none.stderr
    assert not (tmp_path / "bare" / "checkpoints").exists()
    bad = cli("rl", "train", "--checkpoints", "-1", "--dry-run", "--out", str(tmp_path / "x"))
    assert bad.returncode == 2 and "--checkpoints: expected a whole number" in bad.stderr


def test_resume_goes_on_from_the_saved_weights_and_counts_on(tmp_path: Path) -> None:
    first = trained(tmp_path / "first")
    saved = json.loads((first / "policy.json").read_text())
    assert saved["ppo"]["batch_size"] == 64 and saved["ppo"]["learning_rate"] == 3e-4
    assert set(saved["ppo"]) >= {"n_steps", "gamma", "clip_range", "n_epochs", "ent_coef"}

    # Learning rate 0 leaves the weights as they are: the resumed actor is the saved one, not
    # a fresh network (another seed would start from other weights).
    frozen = tmp_path / "frozen"
    done = cli(
        "rl",
        "train",
        "--resume",
        str(first),
        "--out",
        str(frozen),
        "--steps",
        "128",
        "--ppo",
        "learning_rate=0",
        "--seed",
        "7",
        "--n-envs",
        "1",
        "--vec",
        "dummy",
    )
    assert done.returncode == 0, done.stderr
    assert f"from 256 steps in {first} for 128 more" in done.stdout
    for key, value in weights(first).items():
        np.testing.assert_array_equal(weights(frozen)[key], value)
    record = json.loads((frozen / "policy.json").read_text())
    assert record["steps"] == 384 and record["resumed_from"] == {"folder": str(first), "steps": 256}
    assert record["ppo"] == {**saved["ppo"], "learning_rate": 0}  # recorded, one changed
    assert record["env_kwargs"] == saved["env_kwargs"]
    assert curve_steps(frozen) == [128, 256, 384]

    # In place (no --out): the user asked to go on, so no --force; training really goes on.
    again = cli(
        "rl", "train", "--resume", str(first), "--steps", "128", "--n-envs", "1", "--vec", "dummy"
    )
    assert again.returncode == 0, again.stderr
    assert json.loads((first / "policy.json").read_text())["steps"] == 384
    assert curve_steps(first) == [128, 256, 384]
    moved = weights(first)
    assert any(not np.array_equal(moved[k], v) for k, v in weights(frozen).items())


def test_resume_refuses_what_it_cannot_train_on(tmp_path: Path) -> None:
    first = trained(tmp_path / "first", steps=128)
    model = first / "policy.zip"
    good = model.read_bytes()

    def refused(*extra: str) -> str:
        done = cli(
            "rl",
            "train",
            "--resume",
            str(first),
            "--steps",
            "128",
            "--n-envs",
            "1",
            "--vec",
            "dummy",
            *extra,
        )
        assert done.returncode == 1, done.stderr
        assert "Traceback" not in done.stderr
        return done.stderr

    model.unlink()
    assert f"{model}: missing: the model to train on" in refused("--dry-run")
    model.write_bytes(b"weights")
    assert f"{model}: not a stable-baselines3 model (not a zip file)" in refused("--dry-run")

    # A zip, but a pickle where the weights go: loaded weights-only, nothing in it runs.
    marker = tmp_path / "MARKER"

    class Payload:
        def __reduce__(self) -> tuple[object, tuple[str]]:
            return (exec, (f"open({str(marker)!r}, 'w').write('ran')",))

    with zipfile.ZipFile(model, "w") as archive:
        archive.writestr("data", "{}")
        archive.writestr("policy.pth", pickle.dumps(Payload()))
    assert f"{model}: cannot train on this model" in refused()
    assert not marker.exists()
    with zipfile.ZipFile(model, "w") as archive:
        archive.writestr("data", "{}")
    assert f"{model}: cannot train on this model" in refused()

    model.write_bytes(good)
    record = json.loads((first / "policy.json").read_text())
    record["ppo"]["learning_rate"] = "fast"
    (first / "policy.json").write_text(json.dumps(record))
    assert f"{first / 'policy.json'}: ppo.learning_rate: expected a number" in refused("--dry-run")

    usage = cli("rl", "train", "--resume", str(first), "--encoding", "dft", "--dry-run")
    assert usage.returncode == 2 and "drop --encoding" in usage.stderr


def test_subproc_training_records_the_workers_cpu_and_no_return_before_an_episode(
    tmp_path: Path,
) -> None:
    # 8 s episodes (200 steps) and 64 steps per env: no episode ends in the one rollout.
    kwargs = {
        "robot": "snake8",
        "encoding": "dft_shift",
        "action_hz": 25,
        "control_hz": 25,
        "episode_s": 8,
    }
    settings = TrainSettings(
        GOAL_ENV_ID, kwargs, 128, 2, "subproc", rollout_steps=128, ppo={"batch_size": 64}
    )
    progress = io.StringIO()
    own = resource.getrusage(resource.RUSAGE_SELF)
    result = train(settings, tmp_path / "sub", progress=progress, plot=False)
    after = resource.getrusage(resource.RUSAGE_SELF)
    own_s = after.ru_utime + after.ru_stime - own.ru_utime - own.ru_stime
    record = json.loads((tmp_path / "sub" / "policy.json").read_text())
    assert record["cpu_s"] is not None and record["cpu_s"] == round(result.cpu_s, 2)
    assert result.cpu_s > own_s + 0.5  # the two workers built and stepped the twins
    line = progress.getvalue().strip()
    assert "nan" not in line
    assert line.endswith("return      n/a  success   n/a  (no episode ended yet)")
