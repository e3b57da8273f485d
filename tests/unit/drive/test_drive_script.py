"""Drive scripts: the format, errors naming file:line, replay timing and recording."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from snakebot.drive.sources import InputEvent, ScriptRecorder, ScriptSource, parse_script
from snakebot.errors import ConfigError

SCRIPT = """\
# a tour
0     1        # sidewinding
0.5   w
0.5   UP
2.25  speed=-0.5
3\tspace\t# pause
4 q
"""


def test_lines_become_timed_keys_in_order() -> None:
    assert parse_script(SCRIPT) == [
        InputEvent(0.0, "1"),
        InputEvent(0.5, "w"),
        InputEvent(0.5, "up"),
        InputEvent(2.25, "speed=-0.5"),
        InputEvent(3.0, "space"),
        InputEvent(4.0, "q"),
    ]


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("w", r"drive\.txt:3: expected '<time_s> <key>'"),
        ("abc w", r"drive\.txt:3: expected a time in seconds >= 0 first, got 'abc'"),
        ("-1 w", r"drive\.txt:3: expected a time in seconds >= 0"),
        ("0.5 w", r"drive\.txt:3: time 0.5 s is before the line above \(1 s\)"),
        ("2 jump", r"drive\.txt:3: unknown key 'jump'"),
        ("2 z", r"drive\.txt:3: key 'z' does nothing while driving"),
        ("2 w s", r"drive\.txt:3: expected '<time_s> <key>'"),
    ],
)
def test_a_bad_line_is_named_by_file_and_line(tmp_path: Path, line: str, message: str) -> None:
    path = tmp_path / "drive.txt"
    path.write_text(f"# header\n1 w\n{line}\n")
    with pytest.raises(ConfigError, match=message):
        ScriptSource.load(path)


def test_a_missing_script_says_so(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"nope\.txt: cannot read the drive script"):
        ScriptSource.load(tmp_path / "nope.txt")


def test_poll_hands_out_each_key_once_when_its_time_has_come() -> None:
    source = ScriptSource(parse_script(SCRIPT))
    assert source.poll(0.0) == ["1"]
    assert source.poll(0.49) == []
    assert source.poll(0.4999999999) == ["w", "up"]  # float sums of control periods
    assert not source.exhausted
    assert source.poll(10.0) == ["speed=-0.5", "space", "q"]
    assert source.exhausted and source.poll(11.0) == []


def test_a_recording_replays_as_the_same_events() -> None:
    stream = io.StringIO()
    record = ScriptRecorder(stream, "robot snake12\nreplay it")
    events = [InputEvent(0.01, "w"), InputEvent(1.2345678, "left"), InputEvent(3.0, "turn=0.25")]
    for event in events:
        record(event)
    assert stream.getvalue().startswith("# robot snake12\n# replay it\n")
    assert parse_script(stream.getvalue()) == [
        InputEvent(0.01, "w"),
        InputEvent(1.234568, "left"),
        InputEvent(3.0, "turn=0.25"),
    ]
