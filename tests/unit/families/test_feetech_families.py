"""The Feetech families' facts against Feetech's documents and SDK: the status byte, what each
model can do, what a cycle costs on the wire, the EEPROM lock and the byte order."""

from __future__ import annotations

import importlib

import pytest
import scservo_sdk as scs

from snakebot.backends.dynamixel import sdk as chain
from snakebot.backends.feetech.sdk import RESULTS
from snakebot.families import FAMILIES, FeetechSCS, FeetechSTS, family_for, family_named
from snakebot.servo_tables import supported_models, table_for_model

# The module (the package's attribute of that name is its class).
pph = importlib.import_module("scservo_sdk.protocol_packet_handler")


def test_the_status_byte_is_the_servos_condition_only() -> None:
    sts = FeetechSTS()
    # FTServo_Python's ERRBIT_* constants, named as the P1 family names the same faults.
    bits = {
        pph.ERRBIT_VOLTAGE: "input voltage",
        pph.ERRBIT_ANGLE: "magnetic encoder",
        pph.ERRBIT_OVERHEAT: "overheating",
        pph.ERRBIT_OVERELE: "overcurrent",
        pph.ERRBIT_OVERLOAD: "overload",
    }
    for bit, name in bits.items():
        assert sts.status_errors(bit) == (name,)
        assert sts.instruction_error(bit) == 0  # the data that comes with it is valid
    assert sts.status_errors(0x24) == ("overheating", "overload")
    assert sts.instruction_error(0x10) == 0x10  # an undefined bit is not taken for a condition


def test_capabilities_by_model() -> None:
    sts3215 = table_for_model("STS3215")
    caps = family_for(sts3215).capabilities(sts3215)
    assert caps.read_method == "sync_read" and caps.current_sensing
    assert not (caps.bus_watchdog or caps.hardware_error_status or caps.broadcast_ping)
    assert not caps.reboot and caps.factory_reset_options == ("keep_id",)
    scs0009 = table_for_model("SCS0009")
    caps = family_for(scs0009).capabilities(scs0009)
    assert caps.read_method == "read" and not caps.current_sensing


def test_wire_cost_of_the_ft_scs_packets() -> None:
    sts, scs_family = FeetechSTS(), FeetechSCS()
    # SYNC READ of 2 IDs (wiki: FF FF FE 06 82 38 08 01 02 36) is 10 bytes: 8 + N.
    assert sts.read_cost("sync_read", 2, 8).wire_bytes == 10 + 2 * (6 + 8)
    # READ (FF FF 01 04 02 38 02 BE, 8 bytes) and its status (FF FF 01 04 00 18 05 DD).
    assert sts.read_cost("read", 1, 2).wire_bytes == 8 + 8
    assert sts.sync_write_bytes(12, 2) == 44  # reference note §5
    with pytest.raises(ValueError, match="feetech-scs has no sync read"):
        scs_family.read_cost("sync_read", 12, 6)
    with pytest.raises(ValueError, match="no bulk read"):
        sts.read_cost("bulk_read", 12, 6)


def test_lock_and_byte_order_come_with_the_family_and_agree_with_each_model() -> None:
    for family in (FeetechSTS(), FeetechSCS()):
        assert family.eeprom_lock is not None
        assert (family.eeprom_lock.unlocked, family.eeprom_lock.locked) == (0, 1)
        assert not family.restart_replies and not family.broadcast_ping
    for name in supported_models():
        table = table_for_model(name)
        family = family_for(table)
        assert table["goal_position"].byteorder == family.byte_order, name
        if table.family == "feetech":
            assert table[family.eeprom_lock.key].address == (55 if family.protocol == 0.0 else 48)  # type: ignore[union-attr]
    assert family_named("feetech-sts") in FAMILIES and family_named("feetech-scs") in FAMILIES


def test_every_sdk_result_code_has_the_chains_meaning() -> None:
    assert RESULTS[scs.COMM_SUCCESS] == chain.COMM_SUCCESS
    assert RESULTS[scs.COMM_RX_TIMEOUT] == chain.COMM_RX_TIMEOUT
    assert RESULTS[scs.COMM_RX_CORRUPT] == chain.COMM_RX_CORRUPT
    assert RESULTS[scs.COMM_PORT_BUSY] == chain.COMM_PORT_BUSY
    assert RESULTS[scs.COMM_NOT_AVAILABLE] == chain.COMM_NOT_AVAILABLE
    assert len(set(RESULTS.values())) == len(RESULTS)  # no two SDK codes merged
