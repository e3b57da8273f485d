"""`[model] axes`: how many motors share one case and its communication module (2XL430: two)."""

from pathlib import Path

import pytest

from snakebot.errors import ConfigError
from snakebot.servo_tables import add_model_dir, models, table_for_model


@pytest.fixture(autouse=True)
def _no_added_dirs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(models, "_added", [])
    monkeypatch.delenv(models.ENV_VAR, raising=False)


def test_the_2xl430_has_two_axes_and_single_servos_one() -> None:
    assert table_for_model("2XL430-W250").specs.axes == 2
    assert table_for_model("XL430-W250").specs.axes == 1
    assert table_for_model("AX-12A").specs.axes == 1


@pytest.mark.parametrize("bad", ["0", "1.5", '"two"', "true"])
def test_a_bad_axes_count_names_the_file_and_key(tmp_path: Path, bad: str) -> None:
    (tmp_path / "2xc430_w250.toml").write_text(
        '[model]\nbase = "2xl430_w250"\nname = "2XC430-W250"\nmodel_number = 1160\n'
        f"axes = {bad}\n\n[registers]\nmodel_number = {{ default = 1160 }}\n"
    )
    add_model_dir(tmp_path)
    with pytest.raises(ConfigError, match=r"2xc430_w250\.toml.*model\.axes"):
        table_for_model("2XC430-W250")
