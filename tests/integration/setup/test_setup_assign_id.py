"""assign-id: one, zero and two servos; a taken ID; twelve fresh servos become snake12."""

from __future__ import annotations

import json
from pathlib import Path

from snakebot.emulation.bench import ServoBench
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.registry import registered
from tests.integration.setup.conftest import MODEL, ROBOT_BAUD, Bus, Cli

SNAKE12 = ("--robot", "snake12")  # real servos: no default robot

Fresh = tuple[Bus, ServoBench]


def assign(cli: Cli, *argv: str) -> tuple[int, str, str]:
    return cli("config", "assign-id", *SNAKE12, *argv)


def test_one_fresh_servo_gets_its_id_and_baud_and_keeps_its_eeprom(fresh: Fresh, cli: Cli) -> None:
    bus, bench = fresh
    servo = bench.plug()
    code, out, err = assign(cli, "--port", bus.url, "--to", "7")
    assert code == 0, err
    assert out.strip() == "servo ID 1 at 57600 baud is now ID 7 at 1000000 baud"
    assert (servo.servo_id, servo.baud) == (7, ROBOT_BAUD)
    assert servo.peek("return_delay_time") == 250  # nothing else was touched


def test_no_servo_is_refused_with_the_reason(fresh: Fresh, cli: Cli) -> None:
    code, _, err = assign(cli, "--port", fresh[0].url, "--to", "2")
    assert code == 1
    assert "no servo answered at any baud rate" in err and "power" in err


def test_two_fresh_servos_collide_and_are_refused(fresh: Fresh, cli: Cli) -> None:
    bus, bench = fresh
    bench.plug()
    bench.plug()
    for extra in ([], ["--from", "1"]):
        code, _, err = assign(cli, "--port", bus.url, "--to", "2", *extra)
        assert code == 1
        assert "ID 1 at 57600 baud" in err and "share an ID" in err
    assert [s.servo_id for s in bus.chain.servos] == [1, 1]


def test_two_servos_with_their_own_ids_need_from(fresh: Fresh, cli: Cli) -> None:
    bus, bench = fresh
    bench.plug()
    assert assign(cli, "--port", bus.url, "--to", "5")[0] == 0
    bench.plug()
    code, _, err = assign(cli, "--port", bus.url, "--to", "6")
    assert code == 1
    assert "2 servos answer (ID 1 at 57600 baud, ID 5 at 1000000 baud)" in err
    assert "--from" in err
    code, _, err = assign(cli, "--port", bus.url, "--from", "1", "--to", "5")
    assert code == 1
    assert "ID 5 is taken" in err
    assert assign(cli, "--port", bus.url, "--from", "1", "--to", "6")[0] == 0
    assert sorted(s.servo_id for s in bus.chain.servos) == [5, 6]


def test_an_unsupported_baud_is_refused(fresh: Fresh, cli: Cli) -> None:
    bus, bench = fresh
    bench.plug()
    code, _, err = assign(cli, "--port", bus.url, "--to", "3", "--new-baud", "300000")
    assert code == 2 and "--new-baud" in err and "'300000'" in err  # no port opens it
    # A rate a port opens (Feetech's 250 kbit/s) that the XL430 has not: named with its rates.
    code, _, err = assign(cli, "--port", bus.url, "--to", "3", "--new-baud", "250000")
    assert code == 1 and "baud rate 250000" in err and "1000000" in err
    assert sorted(s.servo_id for s in bus.chain.servos) == [1]  # refused before any write


def test_twelve_fresh_servos_become_the_snake12_chain(tmp_path: Path, cli: Cli) -> None:
    state = tmp_path / "servos.json"
    chain = EmulatedChain(baud=57600)
    bench = ServoBench(chain, MODEL, fresh=12, state_path=state)
    with registered(chain) as url:
        for servo_id in range(12, 0, -1):  # the tail first, so ID 1 is only ever the new one
            bench.plug()
            code, _, err = cli(
                "config",
                "assign-id",
                "--port",
                url,
                "--from",
                "1",
                "--to",
                str(servo_id),
                "--robot",
                "snake12",
            )
            assert code == 0, err
        code, out, _ = cli("scan", "--port", url, "--json")
        assert code == 0
        assert [s["id"] for s in json.loads(out)["servos"]] == list(range(1, 13))
        assert cli("config", "diff", *SNAKE12, "--port", url)[0] == 1
        assert cli("config", "apply", *SNAKE12, "--port", url, "--yes")[0] == 0
        assert cli("config", "diff", *SNAKE12, "--port", url)[0] == 0
    assert bench.save() or state.exists()
    # Power-cycle: a new emulator run from the state file; every servo kept its EEPROM.
    again = EmulatedChain(baud=ROBOT_BAUD)
    ServoBench(again, MODEL, fresh=12, state_path=state)
    assert sorted(s.servo_id for s in again.servos) == list(range(1, 13))
    with registered(again) as url:
        assert cli("config", "diff", *SNAKE12, "--port", url)[0] == 0
