"""docs/driving.md against the code: the CSV columns it documents are the ones a log has."""

from __future__ import annotations

import re
from pathlib import Path

from snakebot.telemetry import column_names

DOC = Path(__file__).resolve().parents[3] / "docs" / "driving.md"


def documented_columns(joint_count: int) -> list[str]:
    """The column table under "Logs people can look at", `_i` names expanded per joint."""
    section = DOC.read_text(encoding="utf-8").split("## Logs people can look at", 1)[1]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    columns: list[str] = []
    for row in rows:
        for name in re.findall(r"`([a-z_]+)`", row.split("|")[1]):
            if name.endswith("_i"):
                columns += [f"{name[:-1]}{joint}" for joint in range(joint_count)]
            else:
                columns.append(name)
    return columns


def test_the_documented_csv_columns_are_the_logs_columns_in_order() -> None:
    for joint_count in (8, 12):
        assert documented_columns(joint_count) == column_names(joint_count)
