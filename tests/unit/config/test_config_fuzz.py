"""Any TOML value at any key of a robot, servo or body file: loaded, or a ConfigError naming the
file; never another exception (which the CLI would report as a bug, exit 3)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snakebot.config import load_robot
from snakebot.config.body_loader import load_body
from snakebot.errors import ConfigError
from tests.conftest import CONFIGS


def _toml(value: object) -> str:
    """``value`` written as a TOML value (whatever tomllib then makes of it)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)  # JSON's escapes are TOML's, a lone surrogate aside
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    assert isinstance(value, dict)
    return "{ " + ", ".join(f"{json.dumps(k)} = {_toml(v)}" for k, v in value.items()) + " }"


SCALARS = (
    st.floats(allow_nan=True, allow_infinity=True)
    | st.integers(min_value=-(10**40), max_value=10**40)
    | st.text(max_size=40)
    | st.booleans()
    | st.sampled_from([0, -0.0, 1e308, -1e308, 1e-300, 2**63, "", "\u202e", "\x00"])
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=5), inner, max_size=2)
    ),
    max_leaves=6,
)


def _lines_with_values(text: str) -> list[int]:
    return [
        i
        for i, line in enumerate(text.split("\n"))
        if "=" in line and not line.lstrip().startswith("#")
    ]


def _replace_value(text: str, index: int, value: object) -> str:
    lines = text.split("\n")
    key = lines[index].split("=", 1)[0].rstrip()
    lines[index] = f"{key} = {_toml(value)}"
    return "\n".join(lines)


FILES = {
    "robot": ("robots/snake12.toml", load_robot),
    "servo": ("servos/xl430-w250.toml", None),
    "body": ("bodies/worm.toml", load_body),
}


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(kind=st.sampled_from(sorted(FILES)), line=st.integers(min_value=0), value=VALUES)
def test_any_value_at_any_key_loads_or_is_a_config_error(
    config_dir: Path, kind: str, line: int, value: object
) -> None:
    for other, _ in FILES.values():  # the fixture's folder outlives one example
        (config_dir / other).write_bytes((CONFIGS / other).read_bytes())
    relative, loader = FILES[kind]
    path = config_dir / relative
    good = (CONFIGS / relative).read_text(encoding="utf-8")
    lines = _lines_with_values(good)
    path.write_text(_replace_value(good, lines[line % len(lines)], value), encoding="utf-8")
    robot = config_dir / "robots" / "snake12.toml"
    try:
        if loader is None:  # a servo file is read through the robot naming its model
            load_robot(robot)
        else:
            loader(path)
    except ConfigError as exc:
        # A servo value can be refused where the robot file uses it (its gains, its settings).
        assert exc.source in (str(path), str(robot)), str(exc)
        assert len(str(exc)) < 5_000
