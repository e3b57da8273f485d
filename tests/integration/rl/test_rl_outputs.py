"""The one rule for outputs in the learning commands: `rl compare --out` and `rl eval --video`
replace nothing that exists unless --force (`rl train`'s own: test_rl_train.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.rl.settings import GOAL_ENV_ID
from tests.integration.rl.policies import constant_policy


def test_compare_refuses_to_replace_a_comparison_or_a_policy_in_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "compare"
    argv = ["rl", "compare", "--encodings", "sinusoid,dft", "--out", str(out), "--dry-run"]
    out.mkdir()
    (out / "compare.json").write_text("{}")
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert f"{out}: holds the comparison files compare.json, which would be replaced" in err
    assert "--force" in err
    (out / "compare.json").unlink()
    constant_policy(out / "dft", GOAL_ENV_ID, [0, 0, 0, 0, 0], 20)
    assert main(argv) == 1
    assert (
        f"{out / 'dft'}: holds the trained policy files actor.npz, policy.json, which"
        in capsys.readouterr().err
    )
    assert main([*argv, "--force"]) == 0
    assert sorted(p.name for p in (out / "dft").iterdir()) == ["actor.npz", "policy.json"]


def test_eval_refuses_to_replace_a_video(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = constant_policy(tmp_path / "policy", GOAL_ENV_ID, [0, 0, 0, 0, 0], 20)
    video = tmp_path / "first.mp4"
    video.write_bytes(b"a video the user made")
    for extra in (["--dry-run"], []):
        code = main(["rl", "eval", str(folder), "--episodes", "1", "--video", str(video), *extra])
        assert code == 1
        assert (
            f"{video}: the video exists and would be replaced: pass --force"
            in capsys.readouterr().err
        )
        assert video.read_bytes() == b"a video the user made"
    assert main(["rl", "eval", str(folder), "--video", str(video), "--dry-run", "--force"]) == 0
