"""Gamepad input: stick and button mapping, and a real pad through pygame-ce's SDL (virtual)."""

from __future__ import annotations

import sys
from collections.abc import Iterator

import pytest

from snakebot.drive.gamepad import GamepadSource, PadMapper, stick_value
from snakebot.drive.sources import InputDeviceError
from snakebot.errors import MissingDependencyError


def test_sticks_have_a_dead_zone_and_are_rounded() -> None:
    assert stick_value(0.1) == 0.0 and stick_value(-0.15) == 0.0
    assert stick_value(1.0) == 1.0 and stick_value(-1.0) == -1.0
    assert stick_value(0.575) == pytest.approx(0.5)
    assert stick_value(0.58) == pytest.approx(stick_value(0.59))  # a shaking hand sends nothing


def test_stick_up_is_forward_and_left_is_left_and_only_changes_are_sent() -> None:
    mapper = PadMapper(instance_id=3)
    events = [
        ("axis", {"instance_id": 3, "axis": 1, "value": -1.0}),
        ("axis", {"instance_id": 3, "axis": 1, "value": -0.999}),
        ("axis", {"instance_id": 3, "axis": 0, "value": -0.575}),
        ("axis", {"instance_id": 7, "axis": 1, "value": 1.0}),  # another pad
        ("axis", {"instance_id": 3, "axis": 4, "value": 1.0}),  # a trigger: unused
    ]
    assert mapper.keys(events) == ["speed=1", "turn=0.5"]


def test_a_stick_held_at_start_is_ignored_until_centred() -> None:
    mapper = PadMapper(instance_id=0)
    mapper.prime(1, -1.0)  # lying on its stick
    mapper.prime(0, 0.05)
    forward = ("axis", {"instance_id": 0, "axis": 1, "value": -1.0})
    centre = ("axis", {"instance_id": 0, "axis": 1, "value": 0.0})
    left = ("axis", {"instance_id": 0, "axis": 0, "value": -1.0})
    assert mapper.keys([forward, left]) == ["turn=1"]
    assert mapper.keys([centre, forward]) == ["speed=1"]


def test_buttons_and_the_d_pad_map_to_keys_and_removal_is_noticed() -> None:
    mapper = PadMapper(instance_id=0)
    events = [
        ("button", {"instance_id": 0, "button": 0}),
        ("button", {"instance_id": 0, "button": 3}),
        ("button", {"instance_id": 0, "button": 9}),
        ("hat", {"instance_id": 0, "value": (0, 1)}),
        ("hat", {"instance_id": 0, "value": (-1, 0)}),
        ("hat", {"instance_id": 0, "value": (0, 0)}),
    ]
    assert mapper.keys(events) == ["space", "q", "+", "["]
    assert not mapper.unplugged
    mapper.keys([("removed", {"instance_id": 0})])
    assert mapper.unplugged


def test_without_pygame_the_error_gives_the_install_command(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "pygame", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'snakebot\[gamepad\]'"):
        GamepadSource().open()


@pytest.fixture
def pygame(monkeypatch: pytest.MonkeyPatch) -> Iterator[object]:
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")  # no window, as GamepadSource runs SDL
    module = pytest.importorskip("pygame")
    if not sys.platform.startswith("linux"):
        pytest.skip("the virtual pad uses the Linux wheel's bundled SDL2")
    yield module


def test_no_pad_connected_is_a_clear_error(pygame: object) -> None:
    with pytest.raises(InputDeviceError, match="gamepad: no gamepad found: plug one in"):
        GamepadSource().open()


def test_a_pad_drives_and_unplugging_it_is_input_lost(pygame: object) -> None:
    from tests.virtual_gamepad import VirtualPad

    pygame.display.init()  # type: ignore[attr-defined]
    pygame.joystick.init()  # type: ignore[attr-defined]
    pad = VirtualPad(pygame)  # type: ignore[arg-type]
    try:
        with GamepadSource() as source:
            assert source.name == "gamepad 'Virtual Controller'"
            pad.axis(1, -1.0)  # stick fully up
            pad.press(0)
            assert source.poll(0.0) == ["speed=1", "space"]
            assert source.lost is None
            pad.unplug()
            assert source.poll(0.1) in ([], ["speed=0"])  # SDL may centre the stick first
            assert source.lost == "gamepad 'Virtual Controller' was unplugged"
    finally:
        pad.unplug()
