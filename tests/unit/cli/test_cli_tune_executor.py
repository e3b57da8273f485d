"""`tune gait --executor/--address`: refused where they cannot apply, before any simulation."""

from __future__ import annotations

import sys

import pytest

from snakebot.cli.main import main


def test_address_without_the_ray_executor_is_a_usage_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code = main(["tune", "gait", "--robot", "snake8", "--address", "127.0.0.1:1", "--quiet"])
    assert code == 2
    assert "--executor ray" in capsys.readouterr().err


def test_the_ray_executor_without_ray_names_the_extra(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    code = main(["tune", "gait", "--robot", "snake8", "--executor", "ray", "--quiet"])
    assert code != 0
    assert "snakebot[cluster]" in capsys.readouterr().err
