"""config diff / apply on emulated chains: scrambled settings, baud moves, dry run, interruption."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.faults import ServoSettingsWarning
from snakebot.config import load_robot
from snakebot.emulation.bench import scramble
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.emulation.virtual_servo import HardwareError, VirtualServo
from snakebot.setup import Link, Step, apply, load_settings, plan_apply, survey
from tests.conftest import edit_robot
from tests.integration.setup.conftest import ROBOT_BAUD, Bus, Cli

SETTINGS_KEYS = (
    "return_delay_time",
    "drive_mode",
    "operating_mode",
    "min_position_limit",
    "max_position_limit",
    "shutdown",
    "status_return_level",
    "position_p_gain",
)


def connect_backend(bus: Bus) -> list[str]:
    """Connect and close ServoChainBackend on the bus; the settings warnings it gave."""
    chain = bus.chain
    backend = ServoChainBackend(
        load_robot("snake12"),
        port=bus.url,
        baud=ROBOT_BAUD,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: chain.now_s,
        sleep=chain.advance,
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ServoSettingsWarning)
        backend.connect()
        backend.close()
    return [str(w.message) for w in caught if issubclass(w.category, ServoSettingsWarning)]


def test_apply_on_a_scrambled_chain_leaves_diff_empty_and_run_accepts_it(
    snake: Bus, cli: Cli
) -> None:
    scramble(snake.chain, seed=7)
    code, out, _ = cli("config", "diff", "--robot", "snake12", "--port", snake.url)
    assert code == 1
    assert "return_delay_time" in out and "difference(s) on 12 of 12 servos" in out
    code, out, err = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 0, err
    assert "the final diff is empty" in out
    assert "torque goes off on servo(s) 12" in err  # scramble left 12 holding torque
    code, out, _ = cli("config", "diff", "--robot", "snake12", "--port", snake.url)
    assert (code, out.strip()) == (
        0,
        f"snake12 on {snake.url}: all 12 servos hold the configured settings",
    )
    for servo in snake.chain.servos:
        assert (servo.peek("return_delay_time"), servo.baud, servo.torque_enabled) == (
            0,
            ROBOT_BAUD,
            False,
        )
    assert connect_backend(snake) == []


def test_default_emulator_runs_with_a_warning_naming_config_apply(snake: Bus) -> None:
    messages = connect_backend(snake)
    assert any("Return Delay Time" in m and "snakebot config apply" in m for m in messages)


def test_baud_change_mid_chain_is_found_and_fixed_last(snake: Bus, cli: Cli) -> None:
    snake.servo(5).poke("baud_rate", 1)  # 57600
    snake.servo(9).poke("baud_rate", 2)  # 115200
    code, out, _ = cli("config", "diff", "--robot", "snake12", "--port", snake.url, "--json")
    assert code == 1
    rows = {(r["id"], r["setting"]): r for r in json.loads(out)["differences"]}
    assert rows[(5, "baud_rate")]["servo_value"] == "57600"
    assert rows[(9, "baud_rate")]["wanted_value"] == "1000000"
    assert rows[(9, "baud_rate")]["unit"] == "bit/s"
    code, out, _ = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 0
    steps = [line for line in out.splitlines() if line.startswith("  [")]
    assert [s.split("] ")[1] for s in steps[-2:]] == [
        "servo 5: baud rate 57600 -> 1000000 bit/s",
        "servo 9: baud rate 115200 -> 1000000 bit/s",
    ]
    assert {s.baud for s in snake.chain.servos} == {ROBOT_BAUD}


def test_dry_run_writes_nothing(snake: Bus, cli: Cli) -> None:
    scramble(snake.chain, seed=3)
    before = snake.eeprom(), [[s.peek(k) for k in SETTINGS_KEYS] for s in snake.chain.servos]
    code, out, _ = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--dry-run")
    assert code == 0
    assert "servo 1: return_delay_time" in out and out.rstrip().endswith("nothing was written")
    after = snake.eeprom(), [[s.peek(k) for k in SETTINGS_KEYS] for s in snake.chain.servos]
    assert after == before


class UnpluggedError(Exception):
    """Stands in for Ctrl-C or a pulled cable half-way through."""


@pytest.mark.parametrize("stop_at", [3, 40, -1])
def test_interrupted_apply_is_completed_by_a_rerun(snake: Bus, cli: Cli, stop_at: int) -> None:
    scramble(snake.chain, seed=11)
    chain = load_settings(load_robot("snake12"))
    with Link(snake.url, ROBOT_BAUD) as link:
        diff = survey(link, chain)
        plan = plan_apply(chain, diff)
        stop = plan.steps[stop_at]
        assert stop_at != -1 or stop.action == "baud"

        def interrupt(step: Step) -> None:
            if step is stop:
                raise UnpluggedError

        with pytest.raises(UnpluggedError):
            apply(link, chain, plan, diff, on_step=interrupt)
        assert not survey(link, chain).identical
    code, _, err = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 0, err
    assert cli("config", "diff", "--robot", "snake12", "--port", snake.url)[0] == 0


def test_apply_reboots_a_servo_with_a_latched_overload(snake: Bus, cli: Cli) -> None:
    snake.chain.latch_hardware_error(8, HardwareError.OVERLOAD)
    code, _, err = cli("config", "diff", "--robot", "snake12", "--port", snake.url)
    assert code == 1 and "servo 8 has a latched hardware error (overload)" in err
    code, out, _ = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 0
    assert "servo 8: reboot (clears the latched hardware error)" in out
    assert snake.servo(8).peek("hardware_error_status") == 0


def test_a_quiet_servo_status_return_level_1_is_still_written(snake: Bus, cli: Cli) -> None:
    snake.servo(4).poke("status_return_level", 1)
    snake.servo(4).poke("drive_mode", 1)
    code, _, err = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 0, err
    assert (snake.servo(4).peek("status_return_level"), snake.servo(4).peek("drive_mode")) == (2, 0)


def test_per_joint_override_reaches_one_servo(snake: Bus, cli: Cli, config_dir: Path) -> None:
    path = edit_robot(
        config_dir,
        "snake12",
        "servo_id = 4\n",
        "servo_id = 4\nsettings = { return_delay_time_us = 20 }\n",
    )
    code, _, err = cli("config", "apply", "--robot", str(path), "--port", snake.url, "--yes")
    assert code == 0, err
    delays = {s.servo_id: s.peek("return_delay_time") for s in snake.chain.servos}
    assert delays == {**dict.fromkeys(range(1, 13), 0), 4: 10}


def test_without_yes_and_without_a_terminal_apply_refuses(snake: Bus, cli: Cli) -> None:
    before = snake.eeprom()
    code, _, err = cli("config", "apply", "--robot", "snake12", "--port", snake.url)
    assert code == 1
    assert "stdin is not a terminal: pass --yes" in err
    assert snake.eeprom() == before


def test_a_missing_servo_is_named(snake: Bus, cli: Cli) -> None:
    snake.chain.silence(4)
    code, _, err = cli("config", "diff", "--robot", "snake12", "--port", snake.url)
    assert code == 1
    assert "no servo answers as ID 4 at any baud rate" in err


def test_a_shared_id_and_a_wrong_model_are_refused(snake: Bus, cli: Cli) -> None:
    snake.chain.add(VirtualServo("XL430-W250", 3, baud=ROBOT_BAUD, processing_time_s=60e-6))
    code, _, err = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 1
    assert "ID 3 at 1000000 baud" in err and "share an ID" in err
    snake.chain.remove(snake.chain.servos[-1])
    snake.chain.remove(snake.servo(7))
    snake.chain.add(VirtualServo("XM430-W350", 7, baud=ROBOT_BAUD))
    code, _, err = cli("config", "diff", "--robot", "snake12", "--port", snake.url)
    assert code == 1
    assert "ID 7 at 1000000 baud is a XM430-W350" in err
