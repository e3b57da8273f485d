"""Model data from the user's folders: a new model is one TOML file, and its mistakes are named."""

from pathlib import Path

import pytest

from snakebot.errors import ConfigError
from snakebot.servo_tables import (
    add_model_dir,
    model_dirs,
    model_entries,
    models,
    supported_models,
    table_for_model,
)

# XM430-W210: the SDK ships its .model file; the X-series base supplies everything but current.
XM430_W210 = """\
# XM430-W210 (model 1030), e-Manual docs/en/dxl/x/xm430-w210.md
[model]
base = "_x_series"
name = "XM430-W210"
model_number = 1030
model_file = "xm430_w210.model"
stall_torque_nm = 3.0
no_load_speed_rad_s = 8.063

[registers]
model_number = { default = 1030 }
current_limit = { minimum = 0, maximum = 1193, default = 1193, unit = "A", scale = 0.00269 }
goal_current = { minimum = -1193, maximum = 1193, unit = "A", scale = 0.00269, signed = true }
present_current = { access = "R", unit = "A", scale = 0.00269, signed = true }
"""
# AX-12W: a Protocol 1.0 model, the AX-12A's table (no .model file) with its own number.
AX_12W = """\
[model]
base = "ax_12a"
name = "AX-12W"
model_number = 300
no_load_speed_rad_s = 49.5

[registers]
model_number = { default = 300 }
"""


@pytest.fixture(autouse=True)
def _no_added_dirs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(models, "_added", [])
    monkeypatch.delenv(models.ENV_VAR, raising=False)


def _folder(tmp_path: Path, **files: str) -> Path:
    for stem, text in files.items():
        (tmp_path / f"{stem}.toml").write_text(text)
    return tmp_path


def test_a_new_x_model_is_one_file_in_a_folder_named_by_the_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert "XM430-W210" not in supported_models()
    monkeypatch.setenv(models.ENV_VAR, str(_folder(tmp_path, xm430_w210=XM430_W210)))
    table = table_for_model("XM430-W210")
    assert table is table_for_model(1030) is table_for_model("xm430-w210-t")
    assert (table["goal_position"].address, table["present_current"].address) == (116, 126)
    assert table["current_limit"].default == 1193 and table.protocols == (2.0, 1.0)
    assert table.specs.stall_torque_nm == 3.0
    entry = next(e for e in model_entries() if e.name == "XM430-W210")
    assert entry.path == tmp_path / "xm430_w210.toml" and not entry.shipped
    assert "XL430-W250" in supported_models()  # the shipped models stay


def test_add_model_dir_adds_a_protocol_1_model_based_on_a_shipped_one(tmp_path: Path) -> None:
    add_model_dir(_folder(tmp_path, ax_12w=AX_12W))
    table = table_for_model("AX-12W")
    assert table.model_number == 300 and table.protocols == (1.0,)
    assert table["present_load"].sign == "magnitude"
    assert table["cw_compliance_slope"].address == 28
    assert tmp_path.resolve() in model_dirs()


def test_a_user_file_with_a_shipped_name_replaces_it(tmp_path: Path) -> None:
    text = (Path(models.DATA_DIR) / "ax_12a.toml").read_text()
    add_model_dir(_folder(tmp_path, ax_12a=text.replace("default = 24", "default = 25")))
    assert table_for_model("AX-12A")["firmware_version"].default == 25


def test_a_missing_folder_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(ConfigError, match="no such folder"):
        add_model_dir(tmp_path / "nowhere")
    monkeypatch.setenv(models.ENV_VAR, str(tmp_path / "nowhere"))
    with pytest.raises(ConfigError) as info:
        supported_models()
    assert info.value.source == models.ENV_VAR


def _error(tmp_path: Path, text: str) -> ConfigError:
    add_model_dir(_folder(tmp_path, ax_12w=text))
    with pytest.raises(ConfigError) as info:
        table_for_model("AX-12W")
    assert info.value.source == str(tmp_path / "ax_12w.toml")
    return info.value


def test_a_register_without_an_address_names_the_file_and_key(tmp_path: Path) -> None:
    error = _error(tmp_path, AX_12W + 'punch2 = { name = "Punch 2", size = 2 }\n')
    assert error.key == "registers.punch2.address"
    assert "missing" in str(error)


def test_overlapping_registers_are_refused(tmp_path: Path) -> None:
    error = _error(tmp_path, AX_12W + 'extra = { name = "Extra", address = 31, size = 1 }\n')
    assert error.key == "registers.extra"
    assert "overlaps goal_position (30..31)" in str(error)


def test_a_default_outside_its_range_is_refused(tmp_path: Path) -> None:
    error = _error(
        tmp_path, AX_12W.replace("{ default = 300 }", "{ default = 300 }\nid = { default = 254 }")
    )
    assert error.key == "registers.id.default"
    assert "254 lies outside 0..253" in str(error)


def test_a_bad_sign_is_refused(tmp_path: Path) -> None:
    error = _error(tmp_path, AX_12W + 'present_load = { sign = "magnitude", sign_bit = 16 }\n')
    assert error.key == "registers.present_load.sign_bit"
    error = _error(tmp_path, AX_12W + 'present_load = { sign = "ones" }\n')
    assert error.key == "registers.present_load.sign"


def test_a_model_number_taken_by_another_model_is_refused(tmp_path: Path) -> None:
    add_model_dir(_folder(tmp_path, ax_12w=AX_12W.replace("300", "12")))
    with pytest.raises(ConfigError) as info:
        table_for_model("AX-12W")
    assert (info.value.source, info.value.key) == (
        str(tmp_path / "ax_12w.toml"),
        "model.model_number",
    )
    assert "AX-12A" in str(info.value)


def test_a_missing_base_and_bad_toml_are_named(tmp_path: Path) -> None:
    error = _error(tmp_path, AX_12W.replace('"ax_12a"', '"ax_99"'))
    assert error.key == "model.base" and "ax_99.toml" in str(error)
    (tmp_path / "ax_12w.toml").write_text("[model\n")
    models._catalogue.cache_clear()
    with pytest.raises(ConfigError, match=r"ax_12w\.toml"):
        supported_models()


def test_a_default_protocol_the_model_cannot_speak_is_refused(tmp_path: Path) -> None:
    error = _error(tmp_path, AX_12W.replace("[registers]", "protocol = 2.0\n\n[registers]"))
    assert error.key == "model.protocol"
