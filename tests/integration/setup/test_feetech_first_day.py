"""Issue 22's Done-when, as a new user runs it: `snakebot emulate --robot snake12-sts3215 --pty`,
then scan, config diff, config apply, calibrate and runs of three gaits on that port, each given
the robot and the port only (a Feetech robot needs nothing else: no backend, no protocol).

Every command exits 0 (diff 1 while settings differ); every goal a run commanded lies inside the
joint limits (its telemetry log); after each run the servos are as the stop policy says (torque
on for "hold", read back over the pty with Feetech's own scservo_sdk), and a power cycle of the
emulated servos keeps what setup wrote (the EEPROM lock was opened for it).
"""

from __future__ import annotations

import csv
import json
import os
import time
from pathlib import Path

import pytest
import scservo_sdk as scs

from snakebot.config import load_robot
from tests.integration.setup.conftest import Cli
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

ROBOT = "snake12-sts3215"
GAITS = ("sidewinding", "lateral_undulation", "rolling")
TORQUE_ENABLE = 40  # memory-sts.md
HOLD = "hold"


def torques(port: str, ids: list[int]) -> dict[int, int]:
    """Torque Enable of each servo, read with the stock SDK (asked again while a loaded machine
    delays the emulator's answer)."""
    handler = scs.PortHandler(port)
    assert handler.openPort() and handler.setBaudRate(1_000_000)
    packets = scs.sms_sts(handler)
    out: dict[int, int] = {}
    try:
        for servo_id in ids:
            deadline = time.monotonic() + 10.0
            while True:
                value, result, _error = packets.read1ByteTxRx(servo_id, TORQUE_ENABLE)
                if result == scs.COMM_SUCCESS or time.monotonic() > deadline:
                    break
            assert result == scs.COMM_SUCCESS, packets.getTxRxResult(result)
            out[servo_id] = value
    finally:
        handler.closePort()
    return out


def commanded_within_limits(log: Path, robot_file: Path) -> int:
    """How many commanded joint angles the log holds; fails on any outside the joint limits."""
    robot = load_robot(robot_file)
    with log.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert rows, f"{log}: no cycles logged"
    columns = [f"command_rad_{i}" for i in range(robot.joint_count)]
    count = 0
    for row in rows:
        for joint, column in zip(robot.joints, columns, strict=True):
            angle = float(row[column])
            assert joint.lower_rad - 1e-9 <= angle <= joint.upper_rad + 1e-9, (column, angle)
            count += 1
    return count


def test_a_feetech_snake_from_scan_to_three_gaits_needs_only_its_port(
    tmp_path: Path, config_dir: Path, cli: Cli
) -> None:
    robot_file = config_dir / "robots" / f"{ROBOT}.toml"
    robot = load_robot(robot_file)
    assert robot.safety.stop_policy == HOLD
    ids = list(robot.servo_ids)
    with emulator("--robot", ROBOT, "--scramble", "3") as emu:
        port = emu.port
        where = ("--robot", str(robot_file), "--port", port)
        code, out, err = cli("scan", *where, "--ids", "0-13", "--json")
        assert code == 0, err
        found = json.loads(out)["servos"]  # scrambled: some listen at other rates
        assert {(s["model"], s["family"], s["baud"]) for s in found} == {
            ("STS3215", "feetech-sts", 1_000_000)
        }
        assert 0 < len(found) < len(ids) and "did not answer at 1000000 baud" in err
        code, out, err = cli("config", "diff", *where)
        assert code == 1, err  # scrambled: the settings differ
        code, out, err = cli("config", "apply", *where, "--yes")
        assert code == 0, err
        assert cli("config", "diff", *where)[0] == 0
        code, out, err = cli("scan", *where, "--ids", "0-13", "--json")
        assert code == 0, err
        assert [(s["id"], s["baud"]) for s in json.loads(out)["servos"]] == [
            (i, 1_000_000) for i in ids
        ]
        code, out, err = cli("calibrate", *where, "--yes")
        assert code == 0, err
        assert "Homing Offsets into the servos" in out
        assert emu.command("power")["event"] == "power_cycled"  # setup saved what it wrote
        code, out, err = cli("config", "diff", *where)
        assert code == 0, out + err
        for gait in GAITS:
            log = tmp_path / f"{gait}.csv"
            code, out, err = cli(
                "run", *where, "--gait", gait, "--duration", "1.5", "--log", str(log), "--json"
            )
            assert code == 0, err
            assert json.loads(out)["control_cycles"] > 20, out
            assert commanded_within_limits(log, robot_file) > 20 * robot.joint_count
            assert torques(port, ids) == dict.fromkeys(ids, 1)  # "hold": torque on, at rest
