"""Setup and scan on Protocol 1.0, through the SDK's Protocol 1.0 packet handler and the emulator.

The servos are X-series in Protocol 1.0 mode (Protocol Type 1), beside Protocol 2.0 servos on the
same wire where a test says so: what differs is what the family can do (no broadcast ping, no
Reboot, one Factory Reset that resets everything), asked of ``snakebot.families``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest

from snakebot.config import load_robot
from snakebot.emulation.bench import robot_servos
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.registry import registered
from snakebot.emulation.virtual_servo import VirtualServo
from snakebot.servo_tables import table_for_model
from tests.conftest import edit_robot
from tests.integration.setup.conftest import ROBOT_BAUD, Bus, Cli

MODEL = "XL430-W250"


def in_protocol_1(servos: list[VirtualServo]) -> list[VirtualServo]:
    """The servos switched to Protocol 1.0 (Protocol Type 1, as Dynamixel Wizard sets it)."""
    for servo in servos:
        servo.poke("protocol_type", 1)
    return servos


@pytest.fixture
def p1_snake() -> Iterator[Bus]:
    chain = EmulatedChain(
        in_protocol_1(robot_servos(MODEL, range(1, 13), ROBOT_BAUD)), baud=ROBOT_BAUD
    )
    with registered(chain) as url:
        yield Bus(chain, url)


@pytest.fixture
def p1_robot(config_dir: Path) -> Path:
    """snake12 on a Protocol 1.0 bus."""
    return edit_robot(config_dir, "snake12", "protocol = 2.0", "protocol = 1.0")


def test_scan_finds_a_mixed_chain_and_says_each_servos_protocol(cli: Cli) -> None:
    servos = in_protocol_1(robot_servos(MODEL, range(1, 5), ROBOT_BAUD))
    servos += robot_servos(MODEL, (20, 21), ROBOT_BAUD)
    chain = EmulatedChain(servos, baud=ROBOT_BAUD)
    with registered(chain) as url:
        code, out, err = cli("scan", "--port", url, "--json")
        text_code, text, _ = cli("scan", "--port", url)
    assert code == 0 and text_code == 0, err
    report = json.loads(out)
    found = [(s["id"], s["protocol"], s["model"], s["firmware"]) for s in report["servos"]]
    assert found == [
        (20, 2.0, MODEL, 46),
        (21, 2.0, MODEL, 46),
        *((i, 1.0, MODEL, 46) for i in range(1, 5)),
    ]
    assert report["mixed"] is True and report["protocols"] == [2.0, 1.0]
    assert (
        "servos of two protocols share this port (Protocol 2.0: ID(s) 20, 21; Protocol "
        "1.0: ID(s) 1, 2, 3, 4)" in err
    )
    assert "Protocol Type (address 13" in err
    assert "did not answer" not in err  # 5..19 lie between two chains, not inside one
    assert "ID   1  XL430-W250   firmware 46  Protocol 1.0 at 1000000 baud" in text


def test_a_protocol_1_sweep_says_what_it_costs_and_ids_bounds_it(p1_snake: Bus, cli: Cli) -> None:
    p1_snake.chain.add(in_protocol_1([VirtualServo(MODEL, 40, baud=ROBOT_BAUD)])[0])
    code, out, err = cli("scan", "--port", p1_snake.url, "--protocol", "1", "--json")
    assert code == 0, err
    assert [s["id"] for s in json.loads(out)["servos"]] == [*range(1, 13), 40]
    assert (
        "Protocol 1.0 has no broadcast ping: pinging IDs 0..253 one by one at 1000000 baud "
        "(about 8.7 s on a real port"
    ) in err
    code, out, err = cli(
        "scan", "--port", p1_snake.url, "--protocol", "1", "--ids", "1-12", "--json"
    )
    assert code == 0, err
    assert [s["id"] for s in json.loads(out)["servos"]] == list(range(1, 13))
    assert "pinging IDs 1..12 one by one at 1000000 baud (about 0.4 s" in err


def test_scan_protocol_1_only_does_not_list_protocol_2_servos(cli: Cli) -> None:
    chain = EmulatedChain(robot_servos(MODEL, range(1, 4), ROBOT_BAUD), baud=ROBOT_BAUD)
    with registered(chain) as url:
        code, _, err = cli("scan", "--port", url, "--protocol", "1", "--ids", "0-20")
    assert code == 1
    assert "no servo answered in Protocol 1.0 at 1000000 baud" in err


@pytest.mark.parametrize("protocol", [1.0, 2.0])
def test_a_model_number_snakebot_does_not_know_is_shown_as_such(protocol: float, cli: Cli) -> None:
    table = table_for_model(MODEL)  # a servo of a model snakebot has no data for, number 4242
    unknown = replace(
        table,
        model_number=4242,
        registers={**table.registers, "model_number": replace(table["model_number"], default=4242)},
    )
    servo = VirtualServo(unknown, 7, baud=ROBOT_BAUD)
    servo.poke("protocol_type", 1 if protocol == 1.0 else 2)
    chain = EmulatedChain([servo], baud=ROBOT_BAUD)
    with registered(chain) as url:
        code, out, err = cli("scan", "--port", url, "--ids", "0-10", "--json")
    assert code == 0, err
    (found,) = json.loads(out)["servos"]
    assert (found["id"], found["protocol"], found["model_number"]) == (7, protocol, 4242)
    assert found["model"] == "model 4242 (unknown to snakebot)"
    assert found["duplicate"] is None


def test_reboot_on_protocol_1_is_refused_with_a_power_cycle_hint(
    p1_snake: Bus, p1_robot: Path, cli: Cli
) -> None:
    for which in (("--id", "3"), ("--all",)):
        code, _, err = cli(
            "servo", "reboot", "--robot", str(p1_robot), "--port", p1_snake.url, *which, "--yes"
        )
        assert code == 1
        assert "XL430-W250 on Protocol 1.0) ha" in err
        assert "no Reboot instruction: power-cycle" in err


def test_factory_reset_on_protocol_1_resets_everything_and_says_where_the_servo_is(
    p1_snake: Bus, p1_robot: Path, cli: Cli
) -> None:
    three = p1_snake.servo(3)
    three.poke("return_delay_time", 0)
    args = ("servo", "reset", "--robot", str(p1_robot), "--port", p1_snake.url, "--id", "3")
    code, _, err = cli(*args, "--keep-id", "--yes")
    assert code == 1
    assert "its Factory Reset resets everything, the ID to 1 and the baud rate to 57600" in err
    assert three.servo_id == 3  # refused before anything was sent
    code, out, err = cli(*args, "--yes")
    assert code == 0, err
    # The emulator keeps Protocol Type 1 through the reset (ROBOTIS does not say); the reset
    # servo would be looked for in 2.0 as well.
    assert out.strip() == "servo 3: factory reset; it now answers as ID 1 at 57600 baud"
    assert "--baud 57600 --protocol 1 --ids 1` finds it" in err
    assert (three.servo_id, three.baud, three.protocol) == (1, 57600, 1.0)
    assert three.peek("return_delay_time") == 250


def test_config_diff_and_apply_bring_a_protocol_1_chain_to_its_settings(
    p1_snake: Bus, p1_robot: Path, cli: Cli
) -> None:
    p1_snake.servo(5).poke("temperature_limit", 60)
    p1_snake.servo(9).poke("torque_enable", 1)  # EEPROM needs it off
    code, out, err = cli(
        "config", "diff", "--robot", str(p1_robot), "--port", p1_snake.url, "--json"
    )
    assert code == 1, err
    diff = json.loads(out)
    assert {d["id"] for d in diff["differences"]} == set(range(1, 13))
    code, out, err = cli(
        "config", "apply", "--robot", str(p1_robot), "--port", p1_snake.url, "--yes"
    )
    assert code == 0, err
    assert "torque goes off on servo(s) 9" in err
    code, out, err = cli("config", "diff", "--robot", str(p1_robot), "--port", p1_snake.url)
    assert code == 0, err
    assert "all 12 servos hold the configured settings" in out
    assert all(s.protocol == 1.0 for s in p1_snake.chain.servos)


def test_a_latched_error_on_protocol_1_asks_for_a_power_cycle(
    p1_snake: Bus, p1_robot: Path, cli: Cli
) -> None:
    p1_snake.servo(4).latch_error(0x04)  # overheating
    code, _, err = cli("config", "apply", "--robot", str(p1_robot), "--port", p1_snake.url, "--yes")
    assert code == 1
    assert (
        "servo 4 has a latched hardware error and Protocol 1.0 has no Reboot: power-cycle it"
    ) in err


def test_assign_id_on_protocol_1_finds_a_new_servo_id_by_id(p1_robot: Path, cli: Cli) -> None:
    new = in_protocol_1([VirtualServo(MODEL, 1, baud=57600)])[0]
    chain = EmulatedChain([new], baud=57600)
    with registered(chain) as url:
        code, out, err = cli(
            "config", "assign-id", "--robot", str(p1_robot), "--port", url, "--to", "5"
        )
        assert code == 0, err
        assert out.strip() == "servo ID 1 at 57600 baud is now ID 5 at 1000000 baud"
        assert "Protocol 1.0 has no broadcast ping: every ID is pinged on its own" in err
        assert (new.servo_id, new.baud, new.protocol) == (5, ROBOT_BAUD, 1.0)
        chain.add(in_protocol_1([VirtualServo(MODEL, 1, baud=57600)])[0])
        code, _, err = cli(
            "config", "assign-id", "--robot", str(p1_robot), "--port", url, "--to", "6"
        )
        assert code == 1
        assert "2 servos answer (ID 1 at 57600 baud, ID 5 at 1000000 baud)" in err


def test_calibrate_on_protocol_1_reads_each_servo_without_sync_read(
    p1_snake: Bus, p1_robot: Path, cli: Cli
) -> None:
    assert cli("config", "apply", "--robot", str(p1_robot), "--port", p1_snake.url, "--yes")[0] == 0
    for servo, shaft in zip(
        p1_snake.chain.servos, [0.05 * (i % 3) for i in range(12)], strict=True
    ):
        servo.state = replace(servo.state, position_rad=shaft)
    code, _, err = cli("calibrate", "--robot", str(p1_robot), "--port", p1_snake.url, "--yes")
    assert code == 0, err
    offsets = [j.zero_offset_rad for j in load_robot(p1_robot).joints]
    assert offsets == pytest.approx([0.05 * (i % 3) for i in range(12)], abs=2e-3)


# --- AX-12A and MX-28: Protocol 1.0 firmware, their own control tables -------------------------

AX_SHAFTS = [0.05, -0.12, 0.0, 0.2, -0.07, 0.11, -0.2, 0.03, 0.09, -0.15, 0.01, 0.17]


@pytest.fixture
def ax_snake() -> Iterator[Bus]:
    """snake12-ax12a's twelve AX-12A at IDs 1..12, 1 Mbps, otherwise as from the factory."""
    chain = EmulatedChain(robot_servos("AX-12A", range(1, 13), ROBOT_BAUD), baud=ROBOT_BAUD)
    with registered(chain) as url:
        yield Bus(chain, url)


@pytest.fixture
def ax_robot(config_dir: Path) -> Path:
    """snake12-ax12a, as a file calibrate may write."""
    return config_dir / "robots" / "snake12-ax12a.toml"


@pytest.fixture
def mx_robot(config_dir: Path) -> Path:
    """snake12-ax12a built from MX-28 (Protocol 1.0 firmware) with its P/I/D gains."""
    path = edit_robot(config_dir, "snake12-ax12a", 'servo = "AX-12A"', 'servo = "MX-28"')
    text = path.read_text().replace(
        "compliance_slope = 32", "position_p = 48\nposition_i = 0\nposition_d = 4"
    )
    path.write_text(text)
    return path


def test_scan_reads_ax_and_mx_firmware_where_their_tables_keep_it(cli: Cli) -> None:
    servos = robot_servos("AX-12A", (1, 2), ROBOT_BAUD) + robot_servos("MX-28", (3,), ROBOT_BAUD)
    servos[0].poke("firmware_version", 24)
    servos[2].poke("firmware_version", 41)
    chain = EmulatedChain(servos, baud=ROBOT_BAUD)
    with registered(chain) as url:
        code, out, err = cli("scan", "--port", url, "--ids", "0-10", "--json")
    assert code == 0, err
    found = [
        (s["id"], s["protocol"], s["model"], s["model_number"], s["firmware"])
        for s in json.loads(out)["servos"]
    ]
    # Firmware Version sits at address 2 on an AX or MX (6 on the X series).
    assert found == [
        (1, 1.0, "AX-12A", 12, 24),
        (2, 1.0, "AX-12A", 12, servos[1].peek("firmware_version")),
        (3, 1.0, "MX-28", 29, 41),
    ]
    assert json.loads(out)["mixed"] is False


def test_config_apply_writes_an_ax_chains_compliance_and_angle_limits(
    ax_snake: Bus, cli: Cli
) -> None:
    code, out, err = cli(
        "config", "diff", "--robot", "snake12-ax12a", "--port", ax_snake.url, "--json"
    )
    assert code == 1, err
    wanted = {d["setting"] for d in json.loads(out)["differences"]}
    assert {"min_position_limit", "max_position_limit", "return_delay_time"} <= wanted
    code, _, err = cli(
        "config", "apply", "--robot", "snake12-ax12a", "--port", ax_snake.url, "--yes"
    )
    assert code == 0, err
    assert cli("config", "diff", "--robot", "snake12-ax12a", "--port", ax_snake.url)[0] == 0
    six = ax_snake.servo(6)
    assert (six.peek("min_position_limit"), six.peek("max_position_limit")) == (137, 887)
    assert (six.peek("cw_compliance_slope"), six.peek("lock")) == (32, 0)


def test_a_locked_ax_eeprom_is_refused_with_a_power_cycle_hint(ax_snake: Bus, cli: Cli) -> None:
    ax_snake.servo(6).poke("lock", 1)
    code, _, err = cli(
        "config", "apply", "--robot", "snake12-ax12a", "--port", ax_snake.url, "--yes"
    )
    assert code == 1
    assert "servo 6 has its EEPROM locked (Lock = 1)" in err and "power-cycle it" in err
    assert ax_snake.servo(1).peek("return_delay_time") == 250  # nothing was written


def test_calibrate_an_ax_chain_with_its_1024_ticks_over_300_degrees(
    ax_snake: Bus, ax_robot: Path, cli: Cli
) -> None:
    assert cli("config", "apply", "--robot", str(ax_robot), "--port", ax_snake.url, "--yes")[0] == 0
    for servo, shaft in zip(ax_snake.chain.servos, AX_SHAFTS, strict=True):
        servo.state = replace(servo.state, position_rad=shaft)
    code, out, err = cli("calibrate", "--robot", str(ax_robot), "--port", ax_snake.url, "--yes")
    assert code == 0, err
    ticks = [s.peek("present_position") for s in ax_snake.chain.servos]
    assert ticks[3] == 512 + round(0.2 / (math.radians(300) / 1024))  # 552: 0.293 deg a tick
    offsets = [j.zero_offset_rad for j in load_robot(ax_robot).joints]
    half_tick = math.radians(300) / 1024 / 2
    assert offsets == pytest.approx(AX_SHAFTS, abs=half_tick)
    assert "wrote 12 zero offsets" in out


def test_factory_reset_of_an_ax_and_an_mx_lands_at_their_own_factory_rates(
    ax_snake: Bus, mx_robot: Path, cli: Cli
) -> None:
    reset = ("servo", "reset", "--robot", "snake12-ax12a", "--id", "4", "--yes")
    code, _, err = cli(*reset, "--port", ax_snake.url)
    assert code == 1  # servo 1 of the chain is where a reset AX lands
    assert "answers as ID 1 at 1000000 baud, where another servo already answers" in err
    assert ax_snake.servo(4).peek("return_delay_time") == 250

    ax = VirtualServo("AX-12A", 4, baud=57600)
    chain = EmulatedChain([ax], baud=57600)
    with registered(chain) as url:
        code, out, err = cli(*reset, "--port", url, "--baud", "57600")
    assert code == 0, err
    assert out.strip() == "servo 4: factory reset; it now answers as ID 1 at 1000000 baud"
    assert "`snakebot scan --port" in err and "--ids 1` finds it" in err
    assert (ax.servo_id, ax.baud, ax.protocol) == (1, ROBOT_BAUD, 1.0)

    mx = VirtualServo("MX-28", 9, baud=ROBOT_BAUD)
    chain = EmulatedChain([mx], baud=ROBOT_BAUD)
    with registered(chain) as url:
        code, out, err = cli(
            "servo", "reset", "--robot", str(mx_robot), "--port", url, "--id", "9", "--yes"
        )
    assert code == 0, err
    assert out.strip() == "servo 9: factory reset; it now answers as ID 1 at 57600 baud"
    assert (mx.servo_id, mx.baud) == (1, 57600)


def test_jog_an_ax_joint_at_its_moving_speed_then_hold_it(ax_snake: Bus, cli: Cli) -> None:
    robot = ("--robot", "snake12-ax12a", "--port", ax_snake.url)
    assert cli("config", "apply", *robot, "--yes")[0] == 0
    servo = ax_snake.servo(4)
    start = servo.peek("present_position")
    code, out, err = cli("servo", "jog", *robot, "4", "15", "--json")
    assert code == 0, err
    result = json.loads(out)
    per_deg = 1024 / 300
    assert abs(servo.peek("present_position") - (512 + 15 * per_deg)) <= 6
    assert abs(result["end_deg"] - 15.0) < 1.5
    # Moving Speed limited the move to about 30 deg/s; it is back to the settings' 0 afterwards.
    assert result["seconds"] >= 0.8 * abs(512 + 15 * per_deg - start) / (30 * per_deg)
    assert servo.torque_enabled and servo.peek("moving_speed") == 0
    code, _, err = cli("servo", "torque", "off", *robot, "--all", "--yes", "--json")
    assert code == 0, err  # --all: every ID pinged on its own, no broadcast ping in 1.0
    assert not any(s.torque_enabled for s in ax_snake.chain.servos)
    assert cli("config", "diff", *robot)[0] == 0


def test_config_apply_writes_an_mx_chains_pid_gains(mx_robot: Path, cli: Cli) -> None:
    chain = EmulatedChain(robot_servos("MX-28", range(1, 13), ROBOT_BAUD), baud=ROBOT_BAUD)
    with registered(chain) as url:
        robot = ("--robot", str(mx_robot), "--port", url)
        assert cli("config", "diff", *robot)[0] == 1
        code, _, err = cli("config", "apply", *robot, "--yes")
        assert code == 0, err
        assert cli("config", "diff", *robot)[0] == 0
    wanted = load_robot(mx_robot).gain_writes
    assert wanted["position_p_gain"] == 48 and wanted["position_d_gain"] == 4  # not the defaults
    assert {k: chain.servo(7).peek(k) for k in wanted} == dict(wanted)


def test_assign_id_gives_a_new_ax_its_id_at_its_factory_1_mbps(cli: Cli) -> None:
    chain = EmulatedChain(robot_servos("AX-12A", range(2, 13), ROBOT_BAUD), baud=ROBOT_BAUD)
    new = chain.add(VirtualServo("AX-12A", 1, baud=ROBOT_BAUD))  # from the box: ID 1, 1 Mbps
    chain.servo(12).poke("id", 13)  # make room: the chain is 2..11 and 13
    with registered(chain) as url:
        code, out, err = cli(
            "config",
            "assign-id",
            "--robot",
            "snake12-ax12a",
            "--port",
            url,
            "--from",
            "1",
            "--to",
            "12",
        )
    assert code == 0, err
    assert out.strip() == "servo ID 1 at 1000000 baud is now ID 12 at 1000000 baud"
    assert "no broadcast ping" not in err  # --from 1 pings only ID 1
    assert (new.servo_id, new.baud) == (12, ROBOT_BAUD)
