"""The hardware path end to end with no hardware: the twin, driven through the emulated bus.

`snakebot emulate --physics --pty` backs each virtual servo with the twin in real time; the
distance it reports after `snakebot run --backend dynamixel` must match `--backend sim`.
"""

from __future__ import annotations

import json
import os

import pytest

from snakebot.backends.chain import ServoSettingsWarning
from snakebot.cli.main import main
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

ARGS = ["--robot", "snake12", "--gait", "sidewinding", "--duration", "8", "--json"]


def test_twin_through_the_bus_travels_like_the_twin(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--backend", "sim", *ARGS]) == 0
    direct = json.loads(capsys.readouterr().out)
    with emulator("--robot", "snake12", "--physics") as emu:
        with pytest.warns(ServoSettingsWarning, match="config apply"):  # factory settings
            assert main(["run", "--backend", "dynamixel", "--port", emu.port, *ARGS]) == 0
        over_bus = json.loads(capsys.readouterr().out)
        twin = emu.stop()[-1]  # the twin's summary, printed on exit
    assert over_bus["distance_m"] is None  # hardware cannot measure it; the twin can
    assert over_bus["interrupted"] is False
    assert twin["distance_m"] == pytest.approx(direct["distance_m"], rel=0.15)
    assert abs(twin["heading_deg"] - direct["heading_deg"]) < 15
