"""Terminal bytes to key names, and the names scripts may use."""

from __future__ import annotations

import itertools

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snakebot.drive.keys import KeyDecoder, analog, normalise


def test_letters_arrows_and_control_keys_decode() -> None:
    decoder = KeyDecoder()
    assert decoder.feed(b"wA1 \x1b[A\x1b[B\x1b[C\x1b[D\x03\x04\t\r") == [
        "w",
        "A",
        "1",
        "space",
        "up",
        "down",
        "right",
        "left",
        "ctrl-c",
        "ctrl-d",
        "tab",
        "enter",
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
    [
        ("W", "W"),
        ("Space", "space"),
        ("UP", "up"),
        ("Ctrl-C", "ctrl-c"),
        ("speed=+0.50", "speed=0.5"),
        ("turn=-1", "turn=-1"),
    ],
)
def test_script_names_normalise(text: str, name: str) -> None:
    assert normalise(text) == name


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("jump", "unknown key 'jump'.*speed=V / turn=V"),
        ("speed=2", "-1..1, got '2'"),
        ("turn=nan", "-1..1"),
    ],
)
def test_bad_key_names_say_what_a_key_looks_like(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        normalise(text)


def test_analog_keys_carry_their_value() -> None:
    assert analog("speed=0.5") == ("speed", 0.5)
    assert analog("w") is None


def test_a_sequence_cut_after_its_parameters_waits_for_the_rest() -> None:
    # ctrl-up (ESC [ 1 ; 5 A) across two reads: nothing leaks out as keys, nothing raises
    decoder = KeyDecoder()
    assert decoder.feed(b"\x1b[1;") == []
    assert decoder.feed(b"5Aw") == ["w"]


def test_a_control_key_inside_a_broken_sequence_still_counts() -> None:
    # a sequence cut short by ctrl-c (line noise, a half-sent key): the stop key is not eaten
    assert KeyDecoder().feed(b"\x1b[1;\x03w") == ["ctrl-c", "w"]


def _chunked(data: bytes, cuts: list[int]) -> list[bytes]:
    bounds = sorted({min(cut, len(data)) for cut in cuts} | {0, len(data)})
    return [data[a:b] for a, b in itertools.pairwise(bounds)]


_TERMINAL_BYTES = st.lists(
    st.one_of(
        st.binary(max_size=8),
        st.sampled_from(
            [
                b"\x1b",
                b"\x1b[",
                b"\x1bO",
                b"\x1b[1;5A",
                b"\x1b[15~",
                b"\x1b[A",
                b"\x1bOD",
                b"\xe2\x82\xac",
                b"\xe2",
                b"\x03",
                b"[",
                b";",
                b"5",
            ]
        ),
    ),
    max_size=40,
).map(b"".join)


@settings(max_examples=400, deadline=None)
@given(data=_TERMINAL_BYTES, cuts=st.lists(st.integers(min_value=0, max_value=400), max_size=12))
def test_any_chunking_of_any_bytes_gives_the_keys_of_the_whole(
    data: bytes, cuts: list[int]
) -> None:
    whole = KeyDecoder()
    expected = whole.feed(data) + whole.flush()
    pieces = KeyDecoder()
    got: list[str] = []
    for chunk in _chunked(data, cuts):
        got += pieces.feed(chunk)
    assert got + pieces.flush() == expected
