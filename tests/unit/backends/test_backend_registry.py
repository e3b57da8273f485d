"""The backend registry: one table behind `--backend` and snakebot.connect, open to plugins and
runtime registrations, and no backend name special-cased anywhere else in snakebot."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import snakebot
from snakebot.backends.registry import (
    BACKENDS,
    BackendOption,
    BackendSpec,
    get_backend_spec,
    make_backend,
    register_backend,
)
from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.errors import BackendError, ConfigError

PACKAGE = Path(snakebot.__file__).parent


def test_sim_is_the_twin_and_each_builtin_declares_its_options() -> None:
    assert get_backend_spec("sim") is get_backend_spec("twin")
    assert set(get_backend_spec("twin").option_names) >= {"friction", "terrain", "realtime"}
    dynamixel = get_backend_spec("dynamixel")
    assert dynamixel.hardware and {"port", "baud", "allow_extra_servos"} <= set(
        dynamixel.option_names
    )
    assert not get_backend_spec("twin").hardware


def test_a_runtime_backend_is_made_by_name_and_cannot_take_a_name_by_accident() -> None:
    made: list[object] = []

    def factory(robot: object, *, speed: str = "1") -> TwinBackend:
        made.append((robot, speed))
        return TwinBackend(load_robot("snake8"))

    spec = BackendSpec("echo", "test", factory, options=(BackendOption("speed"),), aliases=("e",))
    register_backend(spec)
    try:
        assert isinstance(make_backend("robot", "e", speed="2"), TwinBackend)
        assert made == [("robot", "2")]
        assert "echo" in snakebot.backend_names() and "e" not in snakebot.backend_names()
        with pytest.raises(BackendError, match="'echo' is already registered"):
            register_backend(spec)
        with pytest.raises(BackendError, match=r"'twin' is already registered \(built-in"):
            register_backend(BackendSpec("twin", "mine", factory))
    finally:
        BACKENDS.unregister("echo")
        BACKENDS.unregister("e")
    with pytest.raises(BackendError, match="unknown backend 'echo'"):
        get_backend_spec("echo")


def test_a_bad_spec_says_what_is_wrong() -> None:
    with pytest.raises(ValueError, match="'module:attr'"):
        BackendSpec("x", "bad", "no_colon_here")
    with pytest.raises(ValueError, match="declares an option twice"):
        BackendSpec("x", "bad", "m:f", options=(BackendOption("a"), BackendOption("a")))
    with pytest.raises(BackendError, match="expects a BackendSpec"):
        register_backend("twin")  # type: ignore[arg-type]


def test_bad_option_values_name_the_option_not_a_flag() -> None:
    robot = load_robot("snake8")
    with pytest.raises(ConfigError, match=r"^friction: expected AXIAL,LATERAL"):
        make_backend(robot, "twin", friction="x")
    with pytest.raises(ConfigError, match=r"^directional: applies to mass-spring bodies only"):
        make_backend(robot, "twin", directional="on")
    with pytest.raises(ConfigError, match="runs on the twin only"):
        make_backend(_worm(), "dynamixel")


def _worm() -> object:
    from snakebot.config.body_loader import load_body

    return load_body("worm")


NAME_TEST = re.compile(
    r"""(==|!=)\s*["'](sim|twin|dynamixel|softbody)["']|"""
    r"""in\s*\(\s*["'](sim|twin|dynamixel|softbody)["']"""
)


def test_no_module_branches_on_a_backend_name() -> None:
    offenders = [
        f"{path.relative_to(PACKAGE)}:{number}: {line.strip()}"
        for path in sorted(PACKAGE.rglob("*.py"))
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if NAME_TEST.search(line)
    ]
    assert offenders == []
