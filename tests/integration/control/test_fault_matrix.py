"""A reduced fault matrix (tools/fault_matrix.py --quick) in CI: its must-be-zero figures are 0.

Every fault mode once, both stop policies, 2 s of gait each, real SDK over the emulator in
virtual time (a few seconds of CPU). The checker itself is tested too: it must see a goal
outside the limits and a servo left in the wrong state.
"""

from __future__ import annotations

import struct

from snakebot.config import load_robot
from snakebot.emulation import make_chain_for_ids, protocol1
from snakebot.emulation.protocol import Instruction, build_instruction
from snakebot.servo_tables import table_for_model
from tools.fault_matrix import Fault, GoalAudit, faults, final_mismatches, run_matrix, totals


def test_reduced_fault_matrix_has_no_untyped_errors_bad_goals_or_wrong_final_states() -> None:
    results = run_matrix(faults(quick=True), duration_s=2.0)
    figures = totals(results)
    details = [(r.fault, r.policy, r.outcome, r.final_mismatches) for r in results if not r.ok]
    assert figures["untyped_errors"] == 0, details
    assert figures["out_of_limit_goals"] == 0, details
    assert figures["final_state_mismatches"] == 0, details
    assert figures["goals_audited"] > 10_000
    outcomes = {r.fault: r.outcome for r in results}
    assert outcomes["none"] == "completed"
    assert outcomes["silence"] == "SyncReadError"
    assert outcomes["hardware_error(overload)"] == "HardwareFaultError"
    assert outcomes["watchdog_trip(every 25 cycles)"] == "WatchdogTripError"
    assert outcomes["jam"] == "TrackingError"


def test_reduced_fault_matrix_on_a_feetech_snake_leaves_a_faulted_servo_limp() -> None:
    """snake12-sts3215 through scservo_sdk: no watchdog, and a Goal Position write turns a
    Feetech servo's torque on, so a servo that unloaded itself for overload must get no goal
    after the fault is seen, the stop ramp's included, and its torque off again."""
    results = run_matrix(faults(quick=True), duration_s=2.0, robot_name="snake12-sts3215")
    figures = totals(results)
    details = [(r.fault, r.policy, r.outcome, r.final_mismatches) for r in results if not r.ok]
    assert figures["untyped_errors"] == 0, details
    assert figures["out_of_limit_goals"] == 0, details
    assert figures["final_state_mismatches"] == 0, details
    assert figures["goals_audited"] > 10_000
    outcomes = {r.fault: r.outcome for r in results}
    assert outcomes["none"] == "completed"
    assert outcomes["silence"] == "SyncReadError"
    assert outcomes["hardware_error(overload)"] == "HardwareFaultError"
    assert outcomes["jam"] == "TrackingError"


def test_the_goal_audit_reads_feetech_sign_magnitude_goals() -> None:
    robot = load_robot("snake12-sts3215")
    audit = GoalAudit(robot, table_for_model("STS3215"))
    low, high = audit.limits[robot.servo_ids[0]]
    params = bytes([42, 2, 1]) + (2048).to_bytes(2, "little")
    params += bytes([2]) + (0x8000 | 5).to_bytes(2, "little")  # -5: bit 15 is the sign
    audit.feed(protocol1.build_instruction(0xFE, protocol1.Instruction.SYNC_WRITE, params))
    assert audit.goals == 2
    assert audit.out_of_limits == [(2, -5)]
    assert low <= 2048 <= high


def test_the_goal_audit_sees_a_goal_outside_the_joint_limits() -> None:
    audit = GoalAudit(load_robot("snake12"), table_for_model("XL430-W250"))  # ticks 1071..3025
    params = struct.pack("<HH", 116, 4) + bytes([1]) + struct.pack("<i", 2048)
    params += bytes([2]) + struct.pack("<i", 3100)
    audit.feed(build_instruction(0xFE, Instruction.SYNC_WRITE, params))
    audit.feed(build_instruction(3, Instruction.WRITE, struct.pack("<Hi", 116, 1000)))
    assert audit.goals == 3
    assert audit.out_of_limits == [(2, 3100), (3, 1000)]


def test_the_goal_audit_reads_protocol_1_goals_of_an_ax_robot() -> None:
    robot = load_robot("snake12-ax12a")
    audit = GoalAudit(robot, table_for_model("AX-12A"))
    low, high = audit.limits[robot.servo_ids[0]]
    assert 0 < low < 512 < high < 1023  # ten-bit ticks around the AX centre
    params = (
        bytes([30, 2, 1])
        + (512).to_bytes(2, "little")
        + bytes([2])
        + high.to_bytes(2, "little")
        + bytes([3])
        + (high + 1).to_bytes(2, "little")
    )
    audit.feed(protocol1.build_instruction(0xFE, protocol1.Instruction.SYNC_WRITE, params))
    audit.feed(protocol1.build_instruction(4, protocol1.Instruction.WRITE, bytes([30, 0, 0])))
    assert audit.goals == 4
    assert audit.out_of_limits == [(3, high + 1), (4, 0)]


def test_the_final_state_check_sees_a_servo_left_wrong() -> None:
    chain = make_chain_for_ids("XL430-W250", range(1, 13), baud=1_000_000)
    none = Fault("none", "", lambda c, h, k: None)
    assert final_mismatches(chain, "limp", none) == []
    chain.servo(4).poke("torque_enable", 1)
    chain.servo(4).poke("bus_watchdog", 5)
    assert final_mismatches(chain, "limp", none) == [
        "servo 4: torque on with limp",
        "servo 4: Bus Watchdog left armed",
    ]
