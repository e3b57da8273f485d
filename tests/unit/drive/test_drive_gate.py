"""The key gate: a few keys a cycle, typing never dropped, a paste dropped but its stop kept."""

from __future__ import annotations

from snakebot.drive.gate import BACKLOG, PER_CYCLE, QUIET_S, KeyGate

PERIOD_S = 0.01


def test_keys_typed_ahead_are_applied_a_few_a_cycle_in_order() -> None:
    gate = KeyGate()
    typed = list("ww1aa")
    first = gate.admit(typed, 0.0)
    assert first == typed[:PER_CYCLE]
    assert gate.admit([], PERIOD_S) == typed[PER_CYCLE:]
    assert gate.admit([], 2 * PERIOD_S) == [] and gate.dropped == 0


def test_a_held_key_repeating_is_never_dropped() -> None:
    gate = KeyGate()
    applied = []
    for cycle in range(1000):  # 10 s at 100 Hz, a repeat every third cycle (33 a second)
        applied += gate.admit(["w"] if cycle % 3 == 0 else [], cycle * PERIOD_S)
    assert len(applied) == 334 and gate.dropped == 0 and not gate.flooding


def test_a_paste_is_dropped_whole_but_its_stop_key_is_kept() -> None:
    gate = KeyGate(lambda key: key == "q")
    paste = ["w", "1"] * 1000 + ["q"] + ["a"] * 10
    assert gate.admit(paste, 0.0) == ["q"]
    assert gate.dropped == len(paste) - 1 and gate.flooding
    assert "ignored 2010 keys" in gate.notice and "paste" in gate.notice


def test_a_paste_arriving_over_many_cycles_is_dropped_until_the_input_is_quiet() -> None:
    gate = KeyGate()
    applied = []
    now = 0.0
    for _ in range(20):  # 20 keys a cycle for 20 cycles: a slow paste
        applied += gate.admit(["w"] * 20, now)
        now += PERIOD_S
    assert len(applied) < BACKLOG  # what passed before the backlog filled; the rest dropped
    assert gate.dropped == 400 - len(applied)
    assert gate.admit(["a"], now) == [] and gate.flooding  # too soon: still the paste
    quiet = now + QUIET_S
    assert gate.admit([], quiet) == [] and not gate.flooding
    assert gate.admit(["d"], quiet + PERIOD_S) == ["d"]  # the next key typed acts


def test_a_script_burst_is_played_a_few_keys_a_cycle_and_never_dropped() -> None:
    gate = KeyGate(backlog=None)  # a script's keys are all meant
    burst = ["w", "a"] * 50
    applied = gate.admit(burst, 0.0)
    for cycle in range(1, 30):
        applied += gate.admit([], cycle * PERIOD_S)
    assert applied == burst and gate.dropped == 0
