"""Servo maintenance: reboot (clears a latched hardware error), factory reset, and servo info.

What a servo can do comes from its family (``link.family.capabilities``): Protocol 1.0 has no
Reboot instruction (a shutdown clears only with a power cycle) and one Factory Reset, which resets
everything, ID and baud rate included (e-Manual protocol1.md, FACTORY_RESET 0x06); Protocol 2.0
resets with the ID and baud rate kept, the ID kept, or nothing kept (options 0x02, 0x01, 0xFF).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from snakebot.backends.chain.faults import decode_hardware_error
from snakebot.errors import BusError
from snakebot.families import ServoFamily, family_for
from snakebot.servo_tables import Register, ServoTable, table_for_model
from snakebot.setup.bauds import factory_baud
from snakebot.setup.errors import SetupError
from snakebot.setup.link import Link, unanswered_ok

BOOT_TIMEOUT_S = 3.0
RESET_KEEP = {(False, False): "all", (True, False): "keep_id", (True, True): "keep_id_baud"}
"""(keep ID, keep baud) -> ServoBus.factory_reset option (e-Manual Factory Reset 0xFF/01/02)."""


def wait_for_boot(link: Link, servo_id: int, baud: int, timeout_s: float = BOOT_TIMEOUT_S) -> int:
    """Ping until the servo answers again after a reboot; its model number."""
    deadline = time.monotonic() + timeout_s
    while True:
        model = link.ping_clean(servo_id, baud, tries=1)
        if model is not None:
            return model
        if time.monotonic() > deadline:
            raise SetupError(
                f"{link.port}: servo {servo_id} did not answer at {baud} baud within "
                f"{timeout_s:.0f} s of a reboot; power-cycle it"
            )
        time.sleep(0.05)


def _protocol(link: Link) -> str:
    return f"{link.bus.table.model} on {link.family.label}"


def check_reboot(link: Link, servo_id: int | None = None) -> None:
    """SetupError unless servos of the link's model and family have a Reboot instruction."""
    if not link.family.capabilities(link.bus.table).reboot:
        who = "the servos" if servo_id is None else f"servo {servo_id}"
        have = "have" if servo_id is None else "has"
        raise SetupError(
            f"{link.port}: {who} ({_protocol(link)}) {have} no Reboot instruction: power-cycle "
            "(switch the supply off and on) to restart and clear a shutdown"
        )


def hardware_error(link: Link, servo_id: int, baud: int) -> int:
    """The servo's Hardware Error Status (0 where its model has no such register)."""
    if "hardware_error_status" not in link.bus.table:
        return 0
    return link.at(baud).read(servo_id, "hardware_error_status")


def reboot(link: Link, servo_id: int, baud: int) -> int:
    """Reboot one servo, wait until it answers, return its Hardware Error Status (0 = clear).

    SetupError where the family has no Reboot (Protocol 1.0: power-cycle instead).
    """
    check_reboot(link, servo_id)
    bus = link.at(baud)
    bus.reboot(servo_id)
    wait_for_boot(link, servo_id, baud)
    return hardware_error(link, servo_id, baud)


def reset_option(link: Link, *, keep_id: bool, keep_baud: bool) -> str:
    """The Factory Reset option keeping what is asked; SetupError naming what the model's family
    has where it cannot (the baud rate is kept only with the ID; Protocol 1.0 keeps nothing)."""
    if keep_baud and not keep_id:
        raise SetupError(
            "the firmware keeps the baud rate only together with the ID (Factory "
            "Reset option 0x02): keep the ID too, or do not keep the baud rate"
        )
    option = RESET_KEEP[(keep_id, keep_baud)]
    table = link.bus.table
    options = link.family.capabilities(table).factory_reset_options
    if option not in options and options == ("keep_id",):
        raise SetupError(
            f"{_protocol(link)}: its one reset (parameter recovery, 0x06) keeps the ID and "
            f"restores everything else, the baud rate to {factory_baud(table)} included; reset "
            "keeping the ID, then give the servo its rate back with assign-id"
        )
    if option not in options:
        raise SetupError(
            f"{_protocol(link)}: its Factory Reset resets everything, the ID to "
            f"{table['id'].default} and the baud rate to {factory_baud(table)} included; it has "
            "no option that keeps the ID or the baud rate. Reset without keeping them, then give "
            "the servo its ID and rate back with assign-id"
        )
    return option


def factory_reset(
    link: Link, servo_id: int, baud: int, *, keep_id: bool, keep_baud: bool
) -> tuple[int, int, ServoFamily]:
    """Factory-reset one servo; the (ID, baud, family) it answers at afterwards.

    The firmware keeps the baud only together with the ID (option 0x02); without the ID the servo
    comes back as ID 1 at its model's factory rate (57600 on the X series and the MX, 1 Mbps on
    the AX), looked for in the protocol it spoke and in its model's factory one
    (:func:`reset_families`). Protocol 1.0 servos always come back that way (SetupError if asked
    to keep either). The link is left speaking the family the servo answers in.
    """
    option = reset_option(link, keep_id=keep_id, keep_baud=keep_baud)
    bus = link.at(baud)
    table = bus.table
    if bus.read(servo_id, "torque_enable"):
        bus.write(servo_id, "torque_enable", 0)
    families = reset_families(link, option)
    link.unlock(servo_id, baud)  # Feetech: "unlock the EEPROM first" (ft-scs.md, 0x06)
    if option == "all":
        with unanswered_ok():  # the status may already come as ID 1, at the factory rate
            bus.factory_reset(servo_id, keep=option)
    else:
        bus.factory_reset(servo_id, keep=option)
    new_id = servo_id if keep_id else table["id"].default
    new_baud = baud if keep_baud else factory_baud(table)
    family = _find_after_reset(link, new_id, new_baud, families)
    link.relock(new_id, new_baud)
    return new_id, new_baud, family


def reset_families(link: Link, option: str) -> tuple[ServoFamily, ...]:
    """The families a servo may answer in after a Factory Reset with ``option``: the one it
    speaks, and after a full reset also its model's factory protocol (whether an X-series servo
    in Protocol 1.0 mode keeps Protocol Type 1 through a reset, ROBOTIS does not say)."""
    if option != "all":
        return (link.family,)
    return tuple(dict.fromkeys((link.family, family_for(link.bus.table))))


def _find_after_reset(
    link: Link, servo_id: int, baud: int, families: tuple[ServoFamily, ...]
) -> ServoFamily:
    """Ping ``servo_id`` at ``baud`` in each of ``families`` until it answers; the link is left
    speaking the family it answered in."""
    deadline = time.monotonic() + BOOT_TIMEOUT_S
    while True:
        for family in families:
            link.speak(family)
            if link.ping_clean(servo_id, baud, tries=1) is not None:
                return family
        if time.monotonic() > deadline:
            spoken = " or ".join(f"{f.protocol:.1f}" for f in families)
            raise SetupError(
                f"{link.port}: servo {servo_id} did not answer at {baud} baud in "
                f"Protocol {spoken} within {BOOT_TIMEOUT_S:.0f} s of a factory "
                "reset; power-cycle it"
            )
        time.sleep(0.05)


@dataclass(frozen=True)
class ServoInfo:
    """One servo's identity, health and full control table (raw register values)."""

    servo_id: int
    baud: int
    table: ServoTable
    values: dict[str, int]

    @property
    def hardware_errors(self) -> tuple[str, ...]:
        """Names of the latched Hardware Error Status bits (empty when clear)."""
        return decode_hardware_error(self.values.get("hardware_error_status", 0))

    def registers(self) -> list[Register]:
        """The registers read, in address order."""
        return sorted((self.table[k] for k in self.values), key=lambda r: r.address)


def servo_info(link: Link, servo_id: int, baud: int) -> ServoInfo:
    """Read the whole control table of one servo (indirect address/data entries left out)."""
    model = link.ping_clean(servo_id, baud)
    if model is None:
        raise BusError(
            link.port,
            [servo_id],
            f"no clean answer at {baud} baud; `snakebot scan "
            f"--port {link.port} --all-bauds` shows where the servos are",
        )
    try:
        table = table_for_model(model)
    except LookupError as exc:
        raise SetupError(f"{link.port}: servo {servo_id} is model {model}: {exc}") from exc
    link.bus.table = table
    keys = [
        k
        for k, r in table.registers.items()
        if r.key == k and not k.startswith("indirect") and table.by_address(r.address) is r
    ]
    values: dict[str, int] = {}
    for group in ([k for k in keys if table[k].eeprom], [k for k in keys if not table[k].eeprom]):
        values.update(link.at(baud).read_block(servo_id, group))
    return ServoInfo(servo_id, baud, table, values)
