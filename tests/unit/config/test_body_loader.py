from __future__ import annotations

import math
from pathlib import Path

import pytest

from snakebot.config import RobotConfig
from snakebot.config.body import MILLER_TABLE, BodyConfig
from snakebot.config.body_loader import body_names, load_body, load_robot_or_body
from snakebot.errors import ConfigError


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
        ("segments = 6", "segments = 0", "lattice.segments", ">= 1"),
        ("segments = 6", "segments = 65", "lattice.segments", "<= 64"),
        ("width_m = 0.02", "width_m = -0.02", "lattice.width_m", "positive"),
        ("point_radius_m = 0.003", "point_radius_m = 0.01", "lattice.point_radius_m", "overlap"),
        ('preset = "worm"', 'preset = "eel"', "springs.preset", "expected one of"),
        ('preset = "worm"', 'preset = "worm"\nk = 2.0', "springs.k", "not both"),
        ('preset = "worm"', "damping = 1.0", "springs.preset", "give preset"),
        ('channels = ["yaw", "pitch", "axial"]', 'channels = ["yaw", "roll"]', "muscles.channels",
         "unknown channel 'roll'"),
        ('channels = ["yaw", "pitch", "axial"]', 'channels = ["yaw", "yaw"]', "muscles.channels",
         "repeat"),
        ('channels = ["yaw", "pitch", "axial"]', "channels = []", "muscles.channels", "expected"),
        ("volume_preservation = true", "volume_preservation = 1", "muscles.volume_preservation",
         "true or false"),
        ("max_contraction = 0.4", "max_contraction = 0.95", "muscles.max_contraction", "<= 0.8"),
        ("friction = 0.1", "friction = -1", "ground.friction", ">= 0.0"),
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
