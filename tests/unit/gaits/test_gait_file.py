import datetime as dt
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snakebot.errors import ConfigError
from snakebot.gaits import load_gait_file, make_gait, save_gait_file


@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("serpenoid", {"amplitude": 0.45, "omega": 2 * math.pi / 3, "phase_lag": 1e-5}),
        ("keyframes", {"poses": (0.1, -0.2, 0.3, 0.0, 0.5, -0.5), "interpolation": "linear"}),
        ("dft_shift", {"coefficients": (0.0, 0.0, 0.1, -0.25), "shift_rate": -2.5}),
        ("simple", {"pose": ()}),
    ],
)
def test_round_trip_gives_identical_targets(
    tmp_path: Path, name: str, params: dict[str, object]
) -> None:
    meta = {
        "objective": "speed",
        "score": 0.4512,
        "robot": "snake12",
        "date": dt.date(2026, 11, 23),
        "generations": 40,
        "tags": ["ga", "tuned"],
        "best": {"seed": 3, "note": 'quote " and \\ and\nnewline'},
    }
    path = tmp_path / "gait.toml"
    save_gait_file(path, name, params, meta)
    loaded_name, loaded_params, loaded_meta = load_gait_file(path)
    assert (loaded_name, loaded_meta) == (name, meta)
    assert loaded_params == {k: tuple(v) if isinstance(v, tuple) else v for k, v in params.items()}
    n = 3 if name == "keyframes" else 12
    times = np.linspace(0.0, 5.0, 11)
    np.testing.assert_array_equal(
        make_gait(loaded_name, n, loaded_params).targets(times),
        make_gait(name, n, params).targets(times),
    )


@settings(
    deadline=None, max_examples=40, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    text=st.text(st.characters(exclude_categories=["Cs"]), max_size=30),
    number=st.floats(allow_nan=False),
)
def test_meta_strings_and_floats_survive_the_round_trip(
    tmp_path: Path, text: str, number: float
) -> None:
    path = tmp_path / "meta.toml"
    save_gait_file(path, "serpenoid", {}, {text or "k": text, "x": number})
    assert load_gait_file(path)[2] == {text or "k": text, "x": number}


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("text", "key", "reason"),
    [
        ("[params]\namplitude = 0.4\n", "gait", "missing"),
        ('gait = "serpentine"\n', "gait", "unknown gait"),
        ("gait = 3\n", "gait", "unknown gait"),
        ('gait = "serpenoid"\n[params]\nnope = 1.0\n', "params.nope", "valid parameters"),
        (
            'gait = "serpenoid"\n[params]\namplitude = "big"\n',
            "params.amplitude",
            "serpenoid.amplitude",
        ),
        ('gait = "serpenoid"\nparams = 3\n', "params", "[params] table"),
        ('gait = "serpenoid"\nmeta = 3\n', "meta", "[meta] table"),
        ('gait = "serpenoid"\nparms = {}\n', "parms", "unknown key"),
        ('gait = "serpenoid\n', "", "not valid TOML"),
    ],
)
def test_bad_file_raises_config_error_naming_the_key(
    tmp_path: Path, text: str, key: str, reason: str
) -> None:
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_gait_file(path)
    assert info.value.key == key and info.value.source == str(path)
    assert reason in str(info.value)


def test_missing_file_raises_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read"):
        load_gait_file(tmp_path / "absent.toml")


def test_expressions_in_files_are_evaluated(tmp_path: Path) -> None:
    path = _write(tmp_path, 'gait = "sidewinding"\n[params]\nphase_shift = "-pi/4"\n')
    assert load_gait_file(path) == ("sidewinding", {"phase_shift": -math.pi / 4}, {})


def test_saving_unwritable_meta_raises(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"meta\.obj"):
        save_gait_file(tmp_path / "x.toml", "serpenoid", {}, {"obj": object()})
