"""`tune gains` and `sysid` never write a robot named by name (it may be a shipped file): results
go into --robot FILE or a copy (--out), and the command says where, or why nowhere."""

from __future__ import annotations

import hashlib
import json
import tomllib
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.config.paths import shipped_configs

GAINS = [
    "tune",
    "gains",
    "--joints",
    "0",
    "--gait-duration",
    "1.5",
    "--budget",
    "4",
    "--no-chirp",
    "--json",
]


def shipped_digest() -> dict[str, str]:
    return {
        str(p): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(shipped_configs().rglob("*.toml"))
    }


def test_tune_gains_by_name_leaves_the_shipped_file_and_says_so(
    capsys: pytest.CaptureFixture[str],
) -> None:
    before = shipped_digest()
    assert main(GAINS) == 0  # --robot omitted: the twin's default robot, snake8, by name
    summary = json.loads(capsys.readouterr().out)
    assert summary["improved"]
    assert "written_to" not in summary
    assert "--robot FILE.toml" in summary["not_written"] and "--out" in summary["not_written"]
    assert shipped_digest() == before


def test_tune_gains_out_writes_a_copy_and_text_says_where(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = shipped_digest()
    out = tmp_path / "mine" / "snake8.toml"
    out.parent.mkdir()  # a file's folder must exist (cli.md: outputs)
    assert main([*GAINS[:-1], "--robot", "snake8", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"written to {out}" in text
    assert shipped_digest() == before
    written = tomllib.loads(out.read_text())["gains"]
    assert load_robot(out).gain_registers.position_p == written["position_p"]
    assert (
        written
        != tomllib.loads((shipped_configs() / "robots" / "snake8.toml").read_text())["gains"]
    )


def test_tune_gains_dry_run_on_a_robot_file_writes_nothing(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = config_dir / "robots" / "snake8.toml"
    original = path.read_bytes()
    assert main([*GAINS, "--robot", str(path), "--dry-run"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["not_written"] == "dry run: the gains not written"
    assert path.read_bytes() == original


def test_sysid_by_name_leaves_the_shipped_file_and_writes_only_to_out(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = shipped_digest()
    log = tmp_path / "chirp.csv"
    assert main(["sysid", "--record", str(log), "--duration", "1.0"]) == 0
    capsys.readouterr()
    fit = ["sysid", str(log), "--params", "damping", "--max-evaluations", "6", "--json"]
    assert main(fit) == 0
    summary = json.loads(capsys.readouterr().out)
    assert "written_to" not in summary
    assert shipped_digest() == before
    out = tmp_path / "fitted.toml"
    assert main([*fit, "--robot", "snake8", "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    if summary["tracking_rms_after_rad"] < summary["tracking_rms_before_rad"]:
        assert summary["written_to"] == f"{out} [twin.servo]"
        assert "damping_nms" in tomllib.loads(out.read_text())["twin"]["servo"]
    assert shipped_digest() == before
