"""The shipped Foxglove layout plots fields the channels really carry."""

from __future__ import annotations

import importlib.util
import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from snakebot.telemetry import schemas

REPO = Path(__file__).resolve().parents[3]
LAYOUT = REPO / "docs" / "foxglove" / "snakebot-layout.json"


def paths(node: Any) -> Iterator[str]:
    """Every message path a panel reads (Plot series values, Raw Messages topic paths)."""
    if isinstance(node, dict):
        for key, value in node.items():
            if key in ("value", "topicPath") and isinstance(value, str):
                yield value
            else:
                yield from paths(value)
    elif isinstance(node, list):
        for item in node:
            yield from paths(item)


def test_every_plotted_path_is_a_field_of_a_snakebot_channel() -> None:
    layout = json.loads(LAYOUT.read_text())
    found = list(paths(layout))
    assert len(found) > 30
    for path in found:
        match = re.fullmatch(r"(/[a-z_]+)(?:\.([a-z_]+))?(\[(\d+|:)\])?", path)
        assert match, path
        topic, field = match.group(1), match.group(2)
        assert topic in schemas.CHANNELS, path
        if field is not None:
            assert field in schemas.CHANNELS[topic]["properties"], path
    assert "/joints.position_rad[11]" in found and "/joints.command_rad[0]" in found


def test_the_3d_view_follows_the_head_in_the_world_frame_of_the_scene() -> None:
    layout = json.dumps(json.loads(LAYOUT.read_text()))
    assert '"panelType": "ThreeDee"' in layout
    assert '"followTf": "link0"' in layout and '"fixedFrame": "world"' in layout


def test_the_shipped_layout_is_what_the_tool_writes() -> None:
    pytest.importorskip("foxglove.layouts")
    spec = importlib.util.spec_from_file_location(
        "make_layout", REPO / "tools" / "make_foxglove_layout.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert LAYOUT.read_text() == module.render(12)
