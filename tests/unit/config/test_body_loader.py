from __future__ import annotations

import math
from pathlib import Path

import pytest

from snakebot.config import RobotConfig
from snakebot.config.body import MILLER_TABLE, BodyConfig
from snakebot.config.body_loader import body_names, load_body, load_robot_or_body
from snakebot.config.bounds import BODY, ROBOT
from snakebot.errors import ConfigError

RANGE = "expected a number in"


def _edit(config_dir: Path, name: str, old: str, new: str) -> Path:
    path = config_dir / "bodies" / f"{name}.toml"
    text = path.read_text()
    assert old in text, f"{old!r} not in {path}"
    path.write_text(text.replace(old, new, 1))
    return path


def test_shipped_bodies_are_millers_three_animals() -> None:
    assert {"worm", "snake", "caterpillar"} <= set(body_names())
    for name in ("worm", "snake", "caterpillar"):
        body = load_body(name)
        k, damping = MILLER_TABLE[name]
        assert (body.springs.k, body.springs.damping, body.springs.preset) == (k, damping, name)


def test_unit_scaling_keeps_the_papers_damping_ratios() -> None:
    ratios = {"worm": 0.37, "snake": 2.47, "caterpillar": 0.55}
    for name, ratio in ratios.items():
        body = load_body(name)
        m = body.lattice.point_mass_kg
        k_si, d_si = body.stiffness_n_per_m, body.damping_ns_per_m
        assert d_si / (2 * math.sqrt(k_si * m)) == pytest.approx(ratio, abs=0.005)
        assert body.springs.damping_ratio == pytest.approx(ratio, abs=0.005)
    worm = load_body("worm")
    t = worm.springs.time_unit_s
    assert worm.stiffness_n_per_m == pytest.approx(1.5 * 0.01 / t**2)
    assert worm.damping_ns_per_m == pytest.approx(0.9 * 0.01 / t)


def test_channels_become_joints_segment_by_segment() -> None:
    worm = load_body("worm")
    assert worm.joint_count == 3 * worm.lattice.segments
    assert [j.axis for j in worm.joints[:4]] == ["yaw", "pitch", "axial", "yaw"]
    assert [j.segment for j in worm.joints[:4]] == [0, 0, 0, 1]
    assert worm.upper_rad[2] == worm.muscles.max_contraction
    assert worm.upper_rad[0] == worm.muscles.max_bend_rad
    assert worm.max_speed_rad_s == worm.muscles.max_rate_per_s
    assert worm.body_length_m == pytest.approx(6 * 0.02)
    assert worm.total_mass_kg == pytest.approx(28 * 0.01)


@pytest.mark.parametrize(
    ("old", "new", "key", "expected"),
    [
        ("segments = 6", "segments = 0", "lattice.segments", "expected an integer in [1, 64]"),
        ("segments = 6", "segments = 65", "lattice.segments", "expected an integer in [1, 64]"),
        ("width_m = 0.02", "width_m = -0.02", "lattice.width_m", RANGE),
        ("point_radius_m = 0.003", "point_radius_m = 0.01", "lattice.point_radius_m", "overlap"),
        ('preset = "worm"', 'preset = "eel"', "springs.preset", "expected one of"),
        ('preset = "worm"', 'preset = "worm"\nk = 2.0', "springs.k", "not both"),
        ('preset = "worm"', "damping = 1.0", "springs.preset", "give preset"),
        (
            'channels = ["yaw", "pitch", "axial"]',
            'channels = ["yaw", "roll"]',
            "muscles.channels",
            "unknown channel 'roll'",
        ),
        (
            'channels = ["yaw", "pitch", "axial"]',
            'channels = ["yaw", "yaw"]',
            "muscles.channels",
            "repeat",
        ),
        ('channels = ["yaw", "pitch", "axial"]', "channels = []", "muscles.channels", "expected"),
        (
            "volume_preservation = true",
            "volume_preservation = 1",
            "muscles.volume_preservation",
            "true or false",
        ),
        ("max_contraction = 0.4", "max_contraction = 0.95", "muscles.max_contraction", "(0, 0.8]"),
        ("friction = 0.1", "friction = -1", "ground.friction", RANGE),
        ("directional = true", "directinal = true", "ground.directinal", "unknown key"),
        ('stop_policy = "hold"', 'stop_policy = "float"', "safety.stop_policy", "expected one of"),
        ("timestep_s = 0.001", "timestep_s = 0.004", "twin.timestep_s", "too long for springs"),
        ('kind = "mass-spring"', 'kind = "rigid"', "kind", "expected one of"),
        ("[twin]", "colour = 3\n[twin]", "safety.colour", "unknown key"),
    ],
)
def test_bad_values_name_file_and_key(
    config_dir: Path, old: str, new: str, key: str, expected: str
) -> None:
    path = _edit(config_dir, "worm", old, new)
    with pytest.raises(ConfigError) as info:
        load_body(path)
    assert info.value.source == str(path)
    assert info.value.key == key
    assert expected in info.value.reason


def test_springs_by_hand_in_millers_units(config_dir: Path) -> None:
    path = _edit(config_dir, "worm", 'preset = "worm"', "k = 1.0\ndamping = 0.5")
    body = load_body(path)
    assert (body.springs.k, body.springs.damping, body.springs.preset) == (1.0, 0.5, "")


def test_robot_option_finds_robots_and_bodies(config_dir: Path) -> None:
    assert isinstance(load_robot_or_body("snake8"), RobotConfig)
    assert isinstance(load_robot_or_body("worm"), BodyConfig)
    assert isinstance(load_robot_or_body(config_dir / "bodies" / "snake.toml"), BodyConfig)
    assert isinstance(load_robot_or_body(config_dir / "robots" / "snake12.toml"), RobotConfig)
    with pytest.raises(ConfigError, match=r"known robots: .*snake12.*known bodies: .*worm"):
        load_robot_or_body("centipede")


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        # The campaign's two: a ramp that never ends, a step that never lets run --duration end.
        ("ramp_s = 1.0", "ramp_s = 1e308", "safety.ramp_s"),
        ("timestep_s = 0.001", "timestep_s = 1e-300", "twin.timestep_s"),
        ("timestep_s = 0.001", "timestep_s = 0", "twin.timestep_s"),
        ("ramp_s = 1.0", "ramp_s = -1", "safety.ramp_s"),
        ("point_mass_kg = 0.01", "point_mass_kg = 1e-300", "lattice.point_mass_kg"),
        ("point_radius_m = 0.003", "point_radius_m = 1e-300", "lattice.point_radius_m"),
        ("segment_length_m = 0.02", "segment_length_m = 1e-300", "lattice.segment_length_m"),
        ("time_unit_s = 0.005", "time_unit_s = 1e-300", "springs.time_unit_s"),
        ("max_rate_per_s = 20.0", "max_rate_per_s = 1e308", "muscles.max_rate_per_s"),
        ("max_bend_rad = 0.6", "max_bend_rad = 0", "muscles.max_bend_rad"),
        ("friction = 0.1", "friction = 1e308", "ground.friction"),
        ('preset = "worm"', "k = 1e-300\ndamping = 0.5", "springs.k"),
        ('preset = "worm"', "k = 1.0\ndamping = 1e308", "springs.damping"),
    ],
)
def test_every_body_number_has_its_documented_range(
    config_dir: Path, old: str, new: str, key: str
) -> None:
    path = _edit(config_dir, "worm", old, new)
    with pytest.raises(ConfigError) as info:
        load_body(path)
    assert (info.value.source, info.value.key) == (str(path), key)
    assert BODY[key].describe() in info.value.reason
    assert "expected a" in info.value.reason


def test_body_ranges_are_documented_as_the_code_has_them() -> None:
    docs = (Path(__file__).resolve().parents[3] / "docs" / "soft-bodies.md").read_text("utf-8")
    for key, limits in BODY.items():
        assert f"| `{key}` | {limits.describe()} | {limits.why} |" in docs, key


def test_body_ranges_reuse_the_robot_ranges_where_the_key_means_the_same() -> None:
    assert BODY["safety.ramp_s"] is ROBOT["safety.ramp_s"]
    assert BODY["ground.friction"] is ROBOT["twin.axial_friction"]


@pytest.mark.parametrize(
    ("name", "reason"),
    [("worm\u202e", "U+202E"), ("a" * 129, "at most 128 characters"), ("w\u0085", "U+0085")],
)
def test_body_names_are_identifiers(config_dir: Path, name: str, reason: str) -> None:
    path = _edit(config_dir, "worm", 'name = "worm"', f'name = "{name}"')
    with pytest.raises(ConfigError) as info:
        load_body(path)
    assert (info.value.key, reason in info.value.reason) == ("name", True)
