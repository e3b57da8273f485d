"""``snakebot servo models``: what a user sees after dropping a model file in a folder."""

import json
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.servo_tables import models

AX_12W = """\
[model]
base = "ax_12a"
name = "AX-12W"
model_number = 300

[registers]
model_number = { default = 300 }
"""


@pytest.fixture(autouse=True)
def _no_added_dirs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(models, "_added", [])
    monkeypatch.delenv(models.ENV_VAR, raising=False)


def test_lists_shipped_and_user_models(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "ax_12w.toml").write_text(AX_12W)
    monkeypatch.setenv(models.ENV_VAR, str(tmp_path))
    assert main(["servo", "models", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    rows = {row["model"]: row for row in payload["models"]}
    assert rows["AX-12W"]["file"] == str(tmp_path / "ax_12w.toml")
    assert rows["AX-12A"] == {
        "model": "AX-12A",
        "model_number": 12,
        "family": "dynamixel",
        "protocols": [1.0],
        "ticks": 1024,
        "registers": 32,
        "file": "shipped",
    }
    assert rows["XL430-W250"]["protocols"] == [2.0, 1.0]
    assert payload["folders"][-1] == str(tmp_path.resolve())
    assert main(["servo", "models"]) == 0
    assert "AX-12W            300  1.0" in capsys.readouterr().out


def test_a_broken_user_file_is_exit_1_naming_file_and_key(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "ax_12w.toml").write_text(AX_12W + "id = { default = 300 }\n")
    monkeypatch.setenv(models.ENV_VAR, str(tmp_path))
    assert main(["servo", "models"]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'ax_12w.toml'}: registers.id.default: 300 lies outside 0..253" in err
