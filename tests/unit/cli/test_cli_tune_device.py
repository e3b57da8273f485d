"""`tune gait --device` belongs to `--engine warp`, and `--engine warp` needs the gpu extra."""

from __future__ import annotations

import sys

import pytest

from snakebot.cli.main import main


@pytest.mark.parametrize("engine", ["batch", "processes"])
def test_a_device_without_the_warp_engine_is_a_usage_error(
    engine: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["tune", "gait", "--method", "grid", "--engine", engine, "--device", "cuda"]
    assert main([*argv, "--budget", "2", "--quiet"]) == 2
    assert "only --engine warp runs on a Warp device" in capsys.readouterr().err


def test_the_warp_engine_without_the_gpu_extra_names_the_install_command(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "mujoco_warp", None)  # import fails as when not installed
    argv = ["tune", "gait", "--method", "grid", "--engine", "warp", "--budget", "2", "--quiet"]
    assert main(argv) != 0
    assert "pip install 'snakebot[gpu]'" in capsys.readouterr().err


def test_the_warp_engine_refuses_the_ray_executor(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("mujoco_warp")
    argv = ["tune", "gait", "--method", "grid", "--engine", "warp", "--executor", "ray"]
    assert main([*argv, "--budget", "2", "--quiet"]) == 2
    assert "the warp engine batches a generation on this machine" in capsys.readouterr().err
