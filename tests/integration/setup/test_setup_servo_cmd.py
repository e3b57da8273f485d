"""servo reboot / reset / info, and scan's duplicate-ID report."""

from __future__ import annotations

import json
from dataclasses import replace

from snakebot.emulation.bench import new_servo
from snakebot.emulation.virtual_servo import HardwareError, VirtualServo
from tests.integration.setup.conftest import ROBOT_BAUD, Bus, Cli

SNAKE12 = ("--robot", "snake12")  # real servos: no default robot


def test_reboot_clears_a_latched_overload(snake: Bus, cli: Cli) -> None:
    snake.chain.latch_hardware_error(3, HardwareError.OVERLOAD)
    code, out, _ = cli("servo", "reboot", *SNAKE12, "--port", snake.url, "--id", "3")
    assert (code, out.strip()) == (0, "servo 3: rebooted; cleared overload")
    assert snake.servo(3).peek("hardware_error_status") == 0


def test_reboot_all_and_an_error_that_comes_back(snake: Bus, cli: Cli) -> None:
    snake.chain.latch_hardware_error(2, HardwareError.OVERLOAD)
    servo = snake.servo(9)
    servo.state = replace(servo.state, input_voltage_v=16.0)  # above the 14 V limit
    servo.step(0.001)
    code, out, err = cli("servo", "reboot", *SNAKE12, "--port", snake.url, "--all")
    assert code == 1
    assert "servo 2: rebooted; cleared overload" in out
    assert "servo 9: rebooted; still latched: input_voltage" in out
    assert "remove the cause" in err


def test_reboot_asks_before_dropping_a_joint_that_holds_torque(snake: Bus, cli: Cli) -> None:
    snake.servo(5).poke("torque_enable", 1)
    code, _, err = cli("servo", "reboot", *SNAKE12, "--port", snake.url, "--id", "5")
    assert code == 1 and "hold torque" in err and "pass --yes" in err
    assert cli("servo", "reboot", *SNAKE12, "--port", snake.url, "--id", "5", "--yes")[0] == 0
    assert not snake.servo(5).torque_enabled


def test_reset_needs_yes_and_a_consistent_keep(snake: Bus, cli: Cli) -> None:
    code, _, err = cli("servo", "reset", *SNAKE12, "--port", snake.url, "--id", "4")
    assert code == 1 and "erases every setting of servo 4: add --yes" in err
    code, _, err = cli(
        "servo", "reset", *SNAKE12, "--port", snake.url, "--id", "4", "--keep-baud", "--yes"
    )
    assert code == 2 and "add --keep-id" in err  # bad usage: refused before the port opens


def test_reset_keeping_id_and_baud_restores_factory_settings(snake: Bus, cli: Cli) -> None:
    snake.servo(4).poke("return_delay_time", 0)
    code, out, _ = cli(
        "servo",
        "reset",
        *SNAKE12,
        "--port",
        snake.url,
        "--id",
        "4",
        "--keep-id",
        "--keep-baud",
        "--yes",
    )
    assert code == 0
    assert "now answers as ID 4 at 1000000 baud" in out
    assert snake.servo(4).peek("return_delay_time") == 250


def test_full_reset_comes_back_as_id_1_at_57600_unless_that_is_taken(snake: Bus, cli: Cli) -> None:
    stray = snake.chain.add(new_servo("XL430-W250", serial=99))
    code, _, err = cli("servo", "reset", *SNAKE12, "--port", snake.url, "--id", "4", "--yes")
    assert code == 1 and "ID 1 at 57600 baud, where another servo already answers" in err
    snake.chain.remove(stray)
    code, out, _ = cli("servo", "reset", *SNAKE12, "--port", snake.url, "--id", "4", "--yes")
    assert code == 0 and "now answers as ID 1 at 57600 baud" in out


def test_info_shows_model_errors_health_and_the_table(snake: Bus, cli: Cli) -> None:
    snake.chain.latch_hardware_error(7, HardwareError.OVERLOAD | HardwareError.OVERHEATING)
    code, out, _ = cli("servo", "info", *SNAKE12, "--port", snake.url, "--id", "7")
    assert code == 0
    assert out.startswith("servo 7 at 1000000 baud: XL430-W250 (model 1060), firmware 46")
    assert "hardware error: overheating, overload; temperature 30 degC; input 11.1 V" in out
    assert "Return Delay Time" in out and "0.0005 s" in out
    code, out, _ = cli("servo", "info", *SNAKE12, "--port", snake.url, "--id", "7", "--json")
    info = json.loads(out)
    assert info["hardware_error"] == ["overheating", "overload"]
    assert info["input_voltage_v"] == 11.1
    rows = {r["key"]: r for r in info["registers"]}
    assert rows["return_delay_time"]["value"] == 250 and rows["return_delay_time"]["eeprom"]
    code, _, err = cli("servo", "info", *SNAKE12, "--port", snake.url, "--id", "40")
    assert code == 1 and "no clean answer at 1000000 baud" in err


def test_scan_lists_the_chain_and_reports_shared_ids(snake: Bus, cli: Cli) -> None:
    code, out, _ = cli("scan", "--port", snake.url, "--json")
    assert code == 0
    assert [s["id"] for s in json.loads(out)["servos"]] == list(range(1, 13))
    snake.chain.add(VirtualServo("XL430-W250", 6, baud=ROBOT_BAUD, processing_time_s=60e-6))
    code, out, err = cli("scan", "--port", snake.url)
    assert code == 1
    assert "ID   6" in out and "DUPLICATE ID" in out
    assert "ID 6 at 1000000 baud" in err and "share an ID" in err


def test_scan_all_bauds_finds_two_fresh_servos_colliding_on_id_1(snake: Bus, cli: Cli) -> None:
    snake.chain.add(new_servo("XL430-W250", serial=20))
    snake.chain.add(new_servo("XL430-W250", serial=21))
    code, out, err = cli("scan", "--port", snake.url, "--all-bauds")
    assert code == 1
    assert "ID 1 at 57600 baud" in err
    lines = [line for line in out.splitlines() if "57600" in line]
    assert len(lines) == 1 and "DUPLICATE ID" in lines[0]
