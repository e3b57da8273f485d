"""`snakebot drive --gamepad` with a pad plugged into SDL: the stick drives, unplugging stops."""

from __future__ import annotations

import json
import sys
import threading
import time

import pytest

from snakebot.cli.main import main

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="the virtual pad uses the Linux wheel's SDL2"
)


def test_the_stick_drives_and_unplugging_the_pad_stops_the_snake(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")  # no window, as GamepadSource runs SDL
    monkeypatch.setenv("PYGAME_HIDE_SUPPORT_PROMPT", "1")  # its banner would go to stdout
    pygame = pytest.importorskip("pygame")
    from tests.virtual_gamepad import VirtualPad

    pygame.display.init()
    pygame.joystick.init()
    pad = VirtualPad(pygame)

    def hand() -> None:
        for _ in range(10):  # forward and back to centre: whenever the drive opened the pad,
            pad.axis(1, -1.0)  # it sees the stick centred and then pushed
            time.sleep(0.3)
            pad.axis(1, 0.0)
            time.sleep(0.2)
        pad.unplug()

    thread = threading.Thread(target=hand)
    thread.start()
    try:
        code = main(["drive", "--gamepad", "--robot", "snake8", "--json"])
    finally:
        thread.join()
        pad.unplug()
    out, err = capsys.readouterr()
    assert out, err
    summary = json.loads(out)
    assert code == 1
    assert "gamepad 'Virtual Controller' was unplugged" in err
    assert summary["stopped_by"] == "input lost: gamepad 'Virtual Controller' was unplugged"
    assert summary["keys"] >= 1 and summary["distance_m"] > 0.05  # it drove, then stopped


def test_no_pad_plugged_in_is_exit_1_saying_to_plug_one_in(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # not a usage error (2): the command line is right, plugging a pad in fixes it
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.setenv("PYGAME_HIDE_SUPPORT_PROMPT", "1")
    pygame = pytest.importorskip("pygame")
    pygame.joystick.init()
    if pygame.joystick.get_count():
        pytest.skip("a gamepad is connected to this machine")
    assert main(["drive", "--gamepad", "--robot", "snake8"]) == 1
    err = capsys.readouterr().err
    assert "no gamepad found: plug one in" in err and "usage:" not in err
