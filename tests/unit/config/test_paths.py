"""The robot search path: $SNAKEBOT_CONFIG_PATH, ./firmware_configs, the user's config directory,
then the robots shipped with snakebot; `snakebot robots` shows where each one comes from."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.config.paths import config_search_path, scene_path, shipped_configs, user_config_dir


@pytest.fixture
def clean_env(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """An empty working directory and home, no SNAKEBOT_CONFIG_PATH, XDG_CONFIG_HOME in tmp."""
    home = tmp_path / "home"
    work = tmp_path / "work"
    home.mkdir()
    work.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "xdg"))
    monkeypatch.delenv("SNAKEBOT_CONFIG_PATH", raising=False)
    monkeypatch.chdir(work)
    return tmp_path


def robot_file(folder: Path, name: str, link_mass_kg: float) -> Path:
    """A copy of snake8 named ``name`` whose link mass tells the copies apart."""
    text = (shipped_configs() / "robots" / "snake8.toml").read_text()
    path = folder / "robots" / f"{name}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(
        text.replace('name = "snake8"', f'name = "{name}"').replace(
            "mass_kg = ", f"mass_kg = {link_mass_kg}  # was ", 1
        )
    )
    return path


def test_shipped_data_is_found_without_the_working_directory(clean_env: Path) -> None:
    assert (shipped_configs() / "robots" / "snake12.toml").is_file()
    assert scene_path().is_file() and scene_path().name == "scene.xml"
    assert load_robot("snake12").joint_count == 12


def test_order_is_env_then_cwd_then_user_then_shipped(
    clean_env: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    env_a, env_b = clean_env / "a", clean_env / "b"
    monkeypatch.setenv("SNAKEBOT_CONFIG_PATH", f"{env_a}:{env_b}")
    folders = config_search_path()
    assert [f.origin for f in folders] == [
        "SNAKEBOT_CONFIG_PATH",
        "SNAKEBOT_CONFIG_PATH",
        "./firmware_configs",
        "user config",
        "shipped",
    ]
    assert [f.path for f in folders[:4]] == [
        env_a,
        env_b,
        clean_env / "work" / "firmware_configs",
        clean_env / "xdg" / "snakebot",
    ]


def test_user_config_dir_follows_xdg_and_defaults_to_dot_config(
    clean_env: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert user_config_dir() == clean_env / "xdg" / "snakebot"
    monkeypatch.delenv("XDG_CONFIG_HOME")
    assert user_config_dir() == clean_env / "home" / ".config" / "snakebot"
    monkeypatch.setenv("XDG_CONFIG_HOME", "relative/path")  # invalid per the XDG spec: ignored
    assert user_config_dir() == clean_env / "home" / ".config" / "snakebot"


def test_first_match_wins_and_robots_names_the_origin(
    clean_env: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    user = robot_file(clean_env / "xdg" / "snakebot", "mysnake", 0.11)
    assert load_robot("mysnake").link.mass_kg == 0.11  # found in the user's config directory
    local = robot_file(clean_env / "work" / "firmware_configs", "mysnake", 0.12)
    assert load_robot("mysnake").link.mass_kg == 0.12  # ./firmware_configs comes first
    env = robot_file(clean_env / "env", "mysnake", 0.13)
    monkeypatch.setenv("SNAKEBOT_CONFIG_PATH", str(clean_env / "env"))
    assert load_robot("mysnake").link.mass_kg == 0.13

    assert main(["robots", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    mine = [
        (r["origin"], r["path"], r["shadowed"]) for r in listed["robots"] if r["name"] == "mysnake"
    ]
    assert mine == [
        ("SNAKEBOT_CONFIG_PATH", str(env), False),
        ("./firmware_configs", str(local), True),
        ("user config", str(user), True),
    ]
    shipped = {r["name"]: r["origin"] for r in listed["robots"] if r["kind"] == "robot"}
    assert shipped["snake12"] == shipped["snake8"] == "shipped"
    assert {r["name"] for r in listed["robots"] if r["kind"] == "body"} >= {"worm"}

    assert main(["robots"]) == 0
    text = capsys.readouterr().out
    assert "mysnake (shadowed)" in text and "shipped" in text and str(user) in text
