"""`snakebot emulate` serves the robot's protocol, `--protocol 1` on X-series, and mixed chains."""

from __future__ import annotations

import os
from pathlib import Path

import dynamixel_sdk as dxl
import pytest

from snakebot.cli.main import main
from tests.pty_emulator import emulator, patient

ROBOTS = Path(__file__).resolve().parents[3] / "firmware_configs" / "robots"


def _robot_with(servo: str, tmp_path: Path) -> Path:
    text = (ROBOTS / "snake8.toml").read_text().replace('"XL430-W250"', f'"{servo}"')
    path = tmp_path / "xl330-snake.toml"
    path.write_text(text)
    return path


def test_protocol_1_on_an_xl330_robot_is_a_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robot = _robot_with("XL330-M288", tmp_path)
    assert main(["emulate", "--pty", "--robot", str(robot), "--protocol", "1"]) == 1
    err = capsys.readouterr().err
    assert str(robot) in err and "XL330-M288 servos speak Protocol 2.0 only, not 1.0" in err


def test_also_checks_model_ids_and_protocol_without_a_robot_named(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # No --robot: the default robot (this crashed with exit 3 before).
    assert main(["emulate", "--pty", "--also", "XL330-M288:20:1"]) == 2
    assert "--also" in capsys.readouterr().err
    assert main(["emulate", "--pty", "--also", "XL430-W250:5"]) == 2
    assert "IDs [5] are on the chain already" in capsys.readouterr().err
    assert main(["emulate", "--pty", "--also", "NO-SUCH-SERVO:40"]) == 2
    assert main(["emulate", "--pty", "--also", "XL430-W250:1-x"]) == 2
    assert "MODEL:IDS[:PROTOCOL]" in capsys.readouterr().err


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_protocol_1_robot_and_a_protocol_2_servo_on_one_pty() -> None:
    with emulator("--robot", "snake8", "--protocol", "1", "--also", "XL430-W250:20") as emu:
        listed = {(s["id"], s["protocol"]) for s in emu.first["servos"]}
        assert listed == {*((i, 1.0) for i in range(1, 9)), (20, 2.0)}
        port = dxl.PortHandler(emu.port)
        assert port.openPort() and port.setBaudRate(emu.first["baud"])
        try:
            p1, p2 = dxl.PacketHandler(1.0), dxl.PacketHandler(2.0)
            for servo_id in range(1, 9):
                assert patient(lambda i=servo_id: p1.ping(port, i)) == (1060, dxl.COMM_SUCCESS, 0)
            assert patient(lambda: p2.ping(port, 20)) == (1060, dxl.COMM_SUCCESS, 0)
            assert p2.ping(port, 1)[1] == dxl.COMM_RX_TIMEOUT
            assert p1.ping(port, 20)[1] == dxl.COMM_RX_TIMEOUT
            # The X table in 1.0 mode: Goal Position at 116, four bytes.
            assert patient(lambda: p1.write1ByteTxRx(port, 3, 64, 1)) == (dxl.COMM_SUCCESS, 0)
            assert patient(lambda: p1.write4ByteTxRx(port, 3, 116, 2100)) == (dxl.COMM_SUCCESS, 0)
        finally:
            port.closePort()


@pytest.mark.pty
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_the_ax_robot_is_served_as_its_own_servos() -> None:
    with emulator("--robot", "snake12-ax12a") as emu:
        assert {(s["model"], s["protocol"]) for s in emu.first["servos"]} == {("AX-12A", 1.0)}
        assert emu.first["servo_ids"] == list(range(1, 13)) and emu.first["baud"] == 1_000_000
        port = dxl.PortHandler(emu.port)
        assert port.openPort() and port.setBaudRate(1_000_000)
        try:
            p1 = dxl.PacketHandler(1.0)
            assert patient(lambda: p1.ping(port, 12)) == (12, dxl.COMM_SUCCESS, 0)
            assert patient(lambda: p1.read2ByteTxRx(port, 7, 36)) == (512, dxl.COMM_SUCCESS, 0)
            assert dxl.PacketHandler(2.0).ping(port, 12)[1] == dxl.COMM_RX_TIMEOUT
        finally:
            port.closePort()
