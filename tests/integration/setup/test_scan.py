"""``snakebot scan`` says what really happened on the bus: faults injected through the chain."""

from __future__ import annotations

import json

import pytest

from snakebot.emulation.virtual_servo import VirtualServo
from tests.integration.setup.conftest import ROBOT_BAUD, Bus, Cli

MODEL = "XL430-W250"


def said(err: str) -> list[str]:
    """What scan said on stderr beyond its progress lines (``scan: ...``, e.g. a sweep's cost)."""
    return [line for line in err.splitlines() if not line.startswith("scan: ")]


def scan_json(cli: Cli, bus: Bus) -> tuple[int, list[dict[str, object]], str]:
    code, out, err = cli("scan", "--port", bus.url, "--json")
    return code, json.loads(out)["servos"] if out else [], err


def test_a_servo_that_missed_its_broadcast_slot_is_listed(snake: Bus, cli: Cli) -> None:
    snake.chain.drop_replies(5, next_n=1)  # its broadcast-ping reply is lost on the wire
    code, servos, _ = scan_json(cli, snake)
    assert code == 0
    assert [s["id"] for s in servos] == list(range(1, 13))
    five = servos[4]
    assert (five["model"], five["firmware"], five["duplicate"]) == (MODEL, 46, None)


def test_a_shared_id_above_the_chain_is_reported_not_left_out(snake: Bus, cli: Cli) -> None:
    for processing_s in (20e-6, 60e-6):  # two servos on ID 30, their replies collide
        snake.chain.add(VirtualServo(MODEL, 30, baud=ROBOT_BAUD, processing_time_s=processing_s))
    code, out, err = cli("scan", "--port", snake.url)
    assert code == 1
    assert "ID  30" in out and "DUPLICATE ID" in out
    assert "ID 30 at 1000000 baud: all 4 ping replies were corrupt" in err
    assert "share an ID" in err


def test_a_line_that_garbles_every_reply_is_reported_as_corrupt(snake: Bus, cli: Cli) -> None:
    for servo in snake.chain.servos:
        snake.chain.corrupt_replies(servo, probability=1.0)
    code, out, err = cli("scan", "--port", snake.url)
    assert code == 1
    assert "every reply was corrupt (12 IDs answered, none cleanly)" in err
    assert "no servo answered" not in err and "share an ID" not in err
    assert "DUPLICATE" not in out
    assert out.count("all 4 ping replies were corrupt") == 12


def test_one_servo_whose_replies_are_always_corrupt_is_named(snake: Bus, cli: Cli) -> None:
    snake.chain.corrupt_replies(3, probability=1.0)
    code, servos, err = scan_json(cli, snake)
    assert code == 1
    assert [s["id"] for s in servos] == list(range(1, 13))
    assert servos[2]["duplicate"] == "all 4 ping replies were corrupt"
    assert "ID 3 at 1000000 baud" in err and "cable or connector is damaged" in err


@pytest.mark.parametrize("seed", range(8))
def test_ten_percent_line_noise_is_noise_not_a_shared_id(seed: int, cli: Cli) -> None:
    from snakebot.emulation.bench import robot_servos
    from snakebot.emulation.chain import EmulatedChain
    from snakebot.emulation.registry import registered

    chain = EmulatedChain(robot_servos(MODEL, range(1, 13), ROBOT_BAUD), baud=ROBOT_BAUD, seed=seed)
    for servo in chain.servos:
        chain.corrupt_replies(servo, probability=0.1)
    with registered(chain) as url:
        code, out, err = cli("scan", "--port", url, "--json")
    servos = json.loads(out)["servos"]
    assert code == 0, err
    assert [s["id"] for s in servos] == list(range(1, 13))
    assert all(s["duplicate"] is None and s["model"] == MODEL for s in servos)
    corrupt = sum(int(s["corrupt_replies"]) for s in servos)  # type: ignore[call-overload]
    if corrupt:
        assert "the line is noisy" in err and "not shared IDs" in err


def test_a_servo_that_answers_pings_only_is_listed_cleanly(snake: Bus, cli: Cli) -> None:
    snake.servo(4).poke("status_return_level", 0)  # reads get no reply at all
    code, servos, err = scan_json(cli, snake)
    assert code == 0, err
    assert [s["id"] for s in servos] == list(range(1, 13))
    assert servos[3]["duplicate"] is None and servos[3]["model"] == MODEL


def test_a_scrambled_chain_with_servos_at_other_bauds_hints_at_all_bauds(
    snake: Bus, cli: Cli
) -> None:
    """issue 19: `emulate --scramble 1` leaves servos 7 and 9 at other rates; scan found 10 of 12
    and said nothing."""
    from snakebot.emulation.bench import scramble

    scramble(snake.chain, 1)
    code, out, err = cli("scan", "--port", snake.url)
    assert code == 0
    assert "10 servo(s)" in out
    assert "ID(s) 7, 9 did not answer, between IDs 6 and 10 that did" in err
    assert "--all-bauds" in err
    code, out, err = cli("scan", "--port", snake.url, "--robot", "snake12", "--json")
    assert json.loads(out)["missing"] == [7, 9]
    assert "snake12 has servo(s) 7, 9, which did not answer at 1000000 baud" in err
    assert "--all-bauds" in err
    code, out, err = cli("scan", "--port", snake.url, "--all-bauds", "--json")
    assert code == 0 and len(json.loads(out)["servos"]) == 12 and "missing" not in err


def test_the_robots_servos_past_the_last_one_found_are_named(snake: Bus, cli: Cli) -> None:
    for servo_id in (11, 12):
        snake.servo(servo_id).poke("baud_rate", 1)  # 57600, as a servo not set up yet
    code, _, err = cli("scan", "--port", snake.url)
    assert code == 0 and said(err) == []  # 1..10 without gaps: nothing to say without the robot
    code, _, err = cli("scan", "--port", snake.url, "--robot", "snake12")
    assert code == 0
    assert "servo(s) 11, 12, which did not answer at 1000000 baud" in err


def test_a_complete_chain_gets_no_hint(snake: Bus, cli: Cli) -> None:
    code, _, err = cli("scan", "--port", snake.url, "--robot", "snake12")
    assert (code, said(err)) == (0, [])
