"""The recorded drive shipped in docs/examples reads back whole and matches its script."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("mcap")

from snakebot.drive.sources import ScriptSource
from tests.integration.telemetry.test_mcap_record import read_mcap

EXAMPLES = Path(__file__).resolve().parents[3] / "docs" / "examples"


def test_the_example_mcap_holds_every_cycle_of_its_scripted_drive() -> None:
    mcap = EXAMPLES / "drive-tour.mcap"
    assert mcap.stat().st_size < 400_000  # small enough to ship
    topics, schema_names = read_mcap(mcap)
    cycles = [m["cycle"] for _, m in topics["/joints"]]
    assert cycles == list(range(1, len(cycles) + 1))
    assert len(cycles) == 500  # 10 s at 50 Hz: 9 s of script, then the stop's blend
    assert {len(m["position_rad"]) for _, m in topics["/joints"]} == {12}
    script = ScriptSource.load(EXAMPLES / "drive-tour.txt")
    keys = []
    while not script.exhausted:
        keys += script.poll(1e9)
    assert [k for _, m in topics["/drive"] for k in m["keys"]] == keys
    assert {m["gait"] for _, m in topics["/drive"]} == {"sidewinding", "rolling"}
    assert schema_names["/scene"] == "foxglove.SceneUpdate" and topics["/tf"]
