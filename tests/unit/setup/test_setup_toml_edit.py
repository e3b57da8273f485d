from __future__ import annotations

import pytest

from snakebot.setup.toml_edit import format_float, set_in_joints

TEXT = """\
name = "x"   # a robot

[joint_defaults]
zero_offset_rad = 0.0

# head
[[joints]]
servo_id = 1      # yaw
axis = "yaw"

[[joints]]
  servo_id = 2
  zero_offset_rad = 0.25   # measured last spring
axis = "pitch"

[twin]
timestep_s = 0.002
"""


def test_values_are_replaced_or_added_and_comments_kept() -> None:
    out = set_in_joints(TEXT, "zero_offset_rad", ["-0.1", "0.02"])
    assert out == TEXT.replace(
        "servo_id = 1      # yaw\n", "servo_id = 1      # yaw\nzero_offset_rad = -0.1\n"
    ).replace("zero_offset_rad = 0.25   # measured", "zero_offset_rad = 0.02   # measured")


def test_line_endings_are_kept() -> None:
    crlf = TEXT.replace("\n", "\r\n")
    out = set_in_joints(crlf, "zero_offset_rad", ["1.0", "2.0"])
    assert "\n" not in out.replace("\r\n", "")
    assert "zero_offset_rad = 1.0\r\n" in out


def test_inline_joints_are_refused() -> None:
    with pytest.raises(ValueError, match="found 0 \\[\\[joints\\]\\] tables, expected 2"):
        set_in_joints("joints = [{servo_id = 1}, {servo_id = 2}]\n", "zero_offset_rad", ["0", "0"])


def test_floats_are_rounded_without_negative_zero() -> None:
    assert [format_float(v) for v in (0.123456, -0.00001, 0.0, -1.5)] == [
        "0.1235",
        "0.0",
        "0.0",
        "-1.5",
    ]
