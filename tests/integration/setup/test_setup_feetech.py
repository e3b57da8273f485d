"""Setup of a Feetech STS3215 snake through the stock scservo_sdk and the emulator (``dxlemu://``).

What a Feetech servo adds to setup: its EEPROM keeps a write only while Lock (55) reads 0, and
Lock is 1 at every power-up, so a write that is not unlocked first acts until the next power-off
and is gone after it (the ID too: the servo is back at ID 1). The emulator keeps the saved EEPROM
apart from the live one (``VirtualServo.power_cycle``), so each test here power-cycles the servos
and looks again. Calibration writes each servo's Position Offset (31): Present = Actual - Offset,
sign-magnitude with the sign in bit 11 (the issues LeRobot users report: huggingface/lerobot#1296,
pollen-robotics/rustypot#96).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from snakebot.config import load_robot
from snakebot.emulation import EmulatedChain, VirtualServo, make_chain_for_ids
from snakebot.emulation.registry import registered
from snakebot.servo_tables import table_for_model
from tests.integration.setup.conftest import Bus, Cli

MODEL = "STS3215"
ROBOT = "snake12-sts3215"
BAUD = 1_000_000
TICKS = 4096
# Where each servo's shaft sits with its joint straight (ticks, the encoder's own reading):
# near the centre, near either end of the turn, and at 0 (which no ±2047 offset centres).
ACTUAL = [2048, 2100, 1990, 300, 3900, 2048 + 227, 2048 - 228, 0, 4095, 2000, 2200, 1800]


def raw(servo: VirtualServo, key: str) -> int:
    """The bits item ``key`` holds, as the wire carries them."""
    register = servo.table[key]
    data = servo.memory.data[register.address : register.address + register.size]
    return int.from_bytes(data, servo.memory.order)


def first_json(out: str) -> dict[str, Any]:
    """The JSON document an output starts with (lines of text may follow it)."""
    document, _ = json.JSONDecoder().raw_decode(out)
    assert isinstance(document, dict)
    return document


def power_cycle(chain: EmulatedChain) -> None:
    for servo in chain.servos:
        servo.power_cycle()


def at_actual(servo: VirtualServo, ticks: int) -> None:
    """Put the servo's shaft where the encoder reads ``ticks`` (before any offset)."""
    servo.state = replace(servo.state, position_rad=(ticks - 2048) * 2 * math.pi / TICKS)


@pytest.fixture
def sts_snake() -> Iterator[Bus]:
    """Twelve STS3215s as they come from the box, already given IDs 1..12: every other setting
    at its factory value (Return Delay 500 us, the factory angle limits)."""
    chain = make_chain_for_ids(MODEL, range(1, 13), BAUD)
    with registered(chain) as url:
        yield Bus(chain, url)


@pytest.fixture
def robot_file(config_dir: Path) -> Path:
    return config_dir / "robots" / f"{ROBOT}.toml"


def test_config_apply_unlocks_the_eeprom_so_the_settings_survive_a_power_cycle(
    sts_snake: Bus, cli: Cli
) -> None:
    code, out, _ = cli("config", "diff", "--robot", ROBOT, "--port", sts_snake.url, "--json")
    assert code == 1
    assert "return_delay_time" in {d["setting"] for d in json.loads(out)["differences"]}
    code, out, err = cli("config", "apply", "--robot", ROBOT, "--port", sts_snake.url, "--yes")
    assert code == 0, err
    assert "servo 1: unlock EEPROM (lock 0" in out and "servo 1: lock EEPROM (lock 1" in out
    assert all(s.peek("lock") == 1 for s in sts_snake.chain.servos)  # locked again, as found
    power_cycle(sts_snake.chain)
    code, out, err = cli("config", "diff", "--robot", ROBOT, "--port", sts_snake.url)
    assert code == 0, out + err
    assert "all 12 servos hold the configured settings" in out
    assert all(s.peek("return_delay_time") == 0 for s in sts_snake.chain.servos)


def test_a_factory_lock_is_no_reason_to_refuse_and_no_power_cycle_is_asked_for(
    sts_snake: Bus, cli: Cli
) -> None:
    code, out, err = cli("config", "diff", "--robot", ROBOT, "--port", sts_snake.url, "--json")
    assert code == 1
    assert json.loads(out)["notes"] == []
    assert "power-cycle" not in err


def test_assign_id_from_the_factory_id_1_keeps_the_new_id_after_a_power_cycle(cli: Cli) -> None:
    fresh = VirtualServo(MODEL, 1, baud=BAUD)  # from the box: ID 1 at 1 Mbps, Lock 1
    chain = EmulatedChain([fresh], baud=BAUD)
    with registered(chain) as url:
        code, out, err = cli("config", "assign-id", "--robot", ROBOT, "--port", url, "--to", "7")
        assert code == 0, err
        assert out.strip() == "servo ID 1 at 1000000 baud is now ID 7 at 1000000 baud"
        assert fresh.peek("lock") == 1
        fresh.power_cycle()
        assert fresh.servo_id == 7
        code, out, err = cli("scan", "--port", url, "--robot", ROBOT, "--ids", "0-10", "--json")
    assert code == 0, err
    assert [(s["id"], s["model"]) for s in json.loads(out)["servos"]] == [(7, MODEL)]


def test_two_factory_servos_on_id_1_are_a_duplicate_not_a_corrupt_sync_read(cli: Cli) -> None:
    chain = EmulatedChain([VirtualServo(MODEL, 1, baud=BAUD) for _ in range(2)], baud=BAUD)
    with registered(chain) as url:
        code, out, err = cli("scan", "--port", url, "--robot", ROBOT, "--ids", "0-5")
    assert code == 1
    assert "DUPLICATE ID" in out and "ID 1 at 1000000 baud" in err


def test_scan_pings_each_id_across_the_feetech_rates_and_names_the_model(cli: Cli) -> None:
    servos = [VirtualServo(MODEL, i, baud=BAUD) for i in (1, 2, 3)]
    servos.append(VirtualServo(MODEL, 4, baud=115200))
    chain = EmulatedChain(servos, baud=BAUD)
    with registered(chain) as url:
        code, out, err = cli(
            "scan", "--port", url, "--robot", ROBOT, "--all-bauds", "--ids", "0-6", "--json"
        )
    assert code == 0, err
    found = [(s["id"], s["model"], s["baud"], s["family"]) for s in json.loads(out)["servos"]]
    assert found == [
        *((i, MODEL, BAUD, "feetech-sts") for i in (1, 2, 3)),
        (4, MODEL, 115200, "feetech-sts"),
    ]
    assert "no broadcast ping: pinging IDs 0..6 one by one" in err


def test_calibrate_writes_each_offset_by_the_sign_rule_and_the_servos_then_read_the_centre(
    sts_snake: Bus, cli: Cli, robot_file: Path
) -> None:
    assert (
        cli("config", "apply", "--robot", str(robot_file), "--port", sts_snake.url, "--yes")[0] == 0
    )
    for servo, ticks in zip(sts_snake.chain.servos, ACTUAL, strict=True):
        at_actual(servo, ticks)
    args = ("calibrate", "--robot", str(robot_file), "--port", sts_snake.url)
    code, out, err = cli(*args, "--max-offset-deg", "180", "--yes", "--json")
    assert code == 0, err
    offsets = [j["homing_offset"] for j in first_json(out)["joints"]]
    # Present = Actual - Offset; the offset fits ±2047 (sign bit 11), an actual 0 gets -2047.
    assert offsets == [0, 52, -58, -1748, 1852, 227, -228, -2047, 2047, -48, 152, -248]
    bits = [raw(s, "homing_offset") for s in sts_snake.chain.servos]
    assert bits[3] == 0x800 | 1748 and bits[4] == 1852 and bits[7] == 0x800 | 2047
    power_cycle(sts_snake.chain)  # the offsets were written unlocked: they are kept
    for servo, ticks in zip(sts_snake.chain.servos, ACTUAL, strict=True):
        at_actual(servo, ticks)
    present = [s.peek("present_position") for s in sts_snake.chain.servos]
    assert present == [2048] * 7 + [2047, 2048] + [2048] * 3
    robot = load_robot(robot_file)
    residual = [j.zero_offset_rad for j in robot.joints]
    assert residual[7] == pytest.approx(-2 * math.pi / TICKS, abs=1e-4)  # the tick -2047 lacks
    assert max(abs(r) for i, r in enumerate(residual) if i != 7) < 1e-9
    # Calibrating again measures Actual = Present + Offset: the same offsets, nothing moves.
    code, out, err = cli(*args, "--max-offset-deg", "180", "--yes", "--json")
    assert code == 0, err
    assert [j["homing_offset"] for j in first_json(out)["joints"]] == offsets
    assert (
        code == 0
        and cli("config", "diff", "--robot", str(robot_file), "--port", sts_snake.url)[0] == 0
    )


def test_an_offset_another_tool_left_is_measured_through_not_added_to(
    sts_snake: Bus, cli: Cli, robot_file: Path
) -> None:
    assert (
        cli("config", "apply", "--robot", str(robot_file), "--port", sts_snake.url, "--yes")[0] == 0
    )
    two, three = sts_snake.servo(2), sts_snake.servo(3)
    two.poke("homing_offset", -1500)  # e.g. a LeRobot calibration of another mounting
    at_actual(two, 2100)
    three.poke("homing_offset", 1500)
    at_actual(three, 1000)  # Present = 1000 - 1500: negative, sign-magnitude (bit 15)
    assert three.peek("present_position") == -500
    assert raw(three, "present_position") == 0x8000 | 500  # not 65036, not 32268
    code, out, err = cli(
        "calibrate",
        "--robot",
        str(robot_file),
        "--port",
        sts_snake.url,
        "--max-offset-deg",
        "95",
        "--yes",
        "--json",
    )
    assert code == 0, err
    joint = first_json(out)["joints"][1]
    assert (joint["old_homing_offset"], joint["actual_ticks"], joint["homing_offset"]) == (
        -1500,
        2100,
        52,
    )
    assert two.peek("present_position") == 2048
    joint = first_json(out)["joints"][2]
    assert (joint["present_ticks"], joint["actual_ticks"], joint["homing_offset"]) == (
        -500,
        1000,
        -1048,
    )
    assert three.peek("present_position") == 2048


def test_calibrate_refuses_multi_turn_feedback_naming_the_phase_bit(
    sts_snake: Bus, cli: Cli, robot_file: Path
) -> None:
    assert (
        cli("config", "apply", "--robot", str(robot_file), "--port", sts_snake.url, "--yes")[0] == 0
    )
    sts_snake.servo(5).poke("phase", 0x10)
    code, _, err = cli("calibrate", "--robot", str(robot_file), "--port", sts_snake.url, "--yes")
    assert code == 1
    assert "servo 5 has Phase (address 18) bit 4 set, multi-turn position feedback" in err
    assert all(s.peek("homing_offset") == 0 for s in sts_snake.chain.servos)  # nothing written


def test_the_servo_settings_may_not_set_the_offset_calibrate_owns(config_dir: Path) -> None:
    from snakebot.errors import ConfigError
    from snakebot.setup import load_settings

    path = config_dir / "servos" / "sts3215.toml"
    text = path.read_text()
    path.write_text(text.replace("[settings]\n", "[settings]\nhoming_offset = 0\n", 1))
    with pytest.raises(ConfigError, match=r"settings\.homing_offset") as caught:
        load_settings(load_robot(config_dir / "robots" / f"{ROBOT}.toml"))
    assert "`snakebot calibrate` writes each one's Homing Offset" in str(caught.value)
    assert table_for_model(MODEL)["homing_offset"].sign_bit == 11


def test_feetech_and_dynamixel_servos_on_one_wire_are_each_named_once_in_their_family(
    cli: Cli,
) -> None:
    # Both answer a ping of the other's (the same framing); each names a model in its own only.
    servos = [VirtualServo(MODEL, i, baud=BAUD) for i in (1, 2)]
    servos += [VirtualServo("AX-12A", i, baud=BAUD) for i in (10, 11)]
    chain = EmulatedChain(servos, baud=BAUD)
    with registered(chain) as url:
        code, out, err = cli("scan", "--port", url, "--ids", "0-12", "--json")
    assert code == 0, err
    report = first_json(out)
    found = sorted((s["id"], s["model"], s["family"]) for s in report["servos"])
    assert found == [
        (1, MODEL, "feetech-sts"),
        (2, MODEL, "feetech-sts"),
        (10, "AX-12A", "dynamixel-p1"),
        (11, "AX-12A", "dynamixel-p1"),
    ]
    assert report["mixed"] is True
    assert "give each family its own port" in err
    assert err.count("one by one") == 1  # one ping sweep serves both families of that framing


def test_servo_reset_on_feetech_keeps_the_id_as_its_one_reset_does_and_says_so(
    sts_snake: Bus, cli: Cli
) -> None:
    three = sts_snake.servo(3)
    three.poke("return_delay_time", 0)
    three.save_eeprom()  # as if set up before: saved, so a power cycle keeps it
    args = ("servo", "reset", "--robot", ROBOT, "--port", sts_snake.url, "--id", "3", "--yes")
    code, _, err = cli(*args)
    assert code == 1
    assert "its one reset (parameter recovery, 0x06) keeps the ID" in err
    assert "use --keep-id alone" in err and three.peek("return_delay_time") == 0  # nothing sent
    code, out, err = cli(*args, "--keep-id")
    assert code == 0, err
    assert out.strip() == "servo 3: factory reset; it now answers as ID 3 at 1000000 baud"
    assert three.peek("return_delay_time") == 250 and three.peek("lock") == 1
    three.power_cycle()  # the restored values were saved: the EEPROM was unlocked for them
    assert three.peek("return_delay_time") == 250


def test_a_7v4_servo_on_12_volts_is_named_with_its_supply_and_calibration_refused(
    sts_snake: Bus, cli: Cli, robot_file: Path
) -> None:
    # huggingface/lerobot#1010: "Incorrect status packet" on calibrate, from 12 V on 7.4 V servos.
    assert (
        cli("config", "apply", "--robot", str(robot_file), "--port", sts_snake.url, "--yes")[0] == 0
    )
    four = sts_snake.servo(4)
    four.state = replace(four.state, input_voltage_v=12.0)
    sts_snake.chain.advance(0.05)  # the firmware sees it
    code, _, err = cli("config", "diff", "--robot", str(robot_file), "--port", sts_snake.url)
    assert code == 0, err
    note = (
        "servo 4 reports input voltage in its status: its supply reads 12.0 V, outside its "
        "limits 4.0..8.4 V"
    )
    assert note in err and "huggingface/lerobot#1010" in err
    code, _, err = cli("calibrate", "--robot", str(robot_file), "--port", sts_snake.url, "--yes")
    assert code == 1
    assert "calibration refused, nothing written: " + note in err
    assert all(s.peek("homing_offset") == 0 for s in sts_snake.chain.servos)
