"""`snakebot ports`: the serial ports pyserial reports, as text or JSON; none is not an error."""

from __future__ import annotations

import json

import pytest
from serial.tools import list_ports

from snakebot.cli.main import main


def test_ports_lists_what_the_operating_system_reports(capsys: pytest.CaptureFixture[str]) -> None:
    devices = sorted(p.device for p in list_ports.comports())
    assert main(["ports", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)["ports"]
    assert [p["device"] for p in listed] == devices
    assert all(set(p) >= {"device", "description", "vid", "pid", "serial_number"} for p in listed)
    assert main(["ports"]) == 0
    text = capsys.readouterr().out
    if devices:
        assert all(device in text for device in devices)
    else:
        assert "no serial ports found" in text
