"""`tune gait --device` belongs to `--engine warp`: any other engine refuses it before tuning."""

from __future__ import annotations

import pytest

from snakebot.cli.main import main


@pytest.mark.parametrize("engine", ["batch", "processes"])
def test_a_device_without_the_warp_engine_is_a_usage_error(
    engine: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["tune", "gait", "--method", "grid", "--engine", engine, "--device", "cuda"]
    assert main([*argv, "--budget", "2", "--quiet"]) == 2
    assert "only --engine warp runs on a Warp device" in capsys.readouterr().err
