"""Terminal bytes to key names, and the names scripts may use."""

from __future__ import annotations

import pytest

from snakebot.drive.keys import KeyDecoder, analog, normalise


def test_letters_arrows_and_control_keys_decode() -> None:
    decoder = KeyDecoder()
    assert decoder.feed(b"wA1 \x1b[A\x1b[B\x1b[C\x1b[D\x03\x04\t\r") == [
        "w", "A", "1", "space", "up", "down", "right", "left", "ctrl-c", "ctrl-d", "tab", "enter",
    ]


def test_application_cursor_mode_arrows_decode_too() -> None:
    assert KeyDecoder().feed(b"\x1bOA\x1bOD") == ["up", "left"]


def test_an_arrow_split_across_two_reads_is_one_key() -> None:
    decoder = KeyDecoder()
    assert decoder.feed(b"w\x1b") == ["w"]
    assert decoder.feed(b"[") == []
    assert decoder.feed(b"Dq") == ["left", "q"]


def test_a_lone_escape_is_esc_once_nothing_follows() -> None:
    decoder = KeyDecoder()
    assert decoder.feed(b"\x1b") == []
    assert decoder.flush() == ["esc"]
    assert decoder.flush() == []


def test_unknown_sequences_are_dropped_whole() -> None:
    # ctrl-up and F5 are not keys of the drive: nothing of them may leak out as letters
    assert KeyDecoder().feed(b"\x1b[1;5A\x1b[15~w") == ["w"]


@pytest.mark.parametrize(
    ("text", "name"),
    [("W", "W"), ("Space", "space"), ("UP", "up"), ("Ctrl-C", "ctrl-c"),
     ("speed=+0.50", "speed=0.5"), ("turn=-1", "turn=-1")],
)
def test_script_names_normalise(text: str, name: str) -> None:
    assert normalise(text) == name


@pytest.mark.parametrize(
    ("text", "message"),
    [("jump", "unknown key 'jump'.*speed=V / turn=V"), ("speed=2", "-1..1, got '2'"),
     ("turn=nan", "-1..1")],
)
def test_bad_key_names_say_what_a_key_looks_like(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        normalise(text)


def test_analog_keys_carry_their_value() -> None:
    assert analog("speed=0.5") == ("speed", 0.5)
    assert analog("w") is None
