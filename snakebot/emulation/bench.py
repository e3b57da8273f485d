"""Bring-up on the emulator: factory-fresh servos plugged in one at a time, EEPROM kept on disk.

A :class:`ServoBench` wraps a chain: servos already on it (with stable serial numbers), a count of
factory-fresh servos waiting to be plugged in (each arrives as ID 1 at its factory rate with factory
defaults), and an optional state file that keeps every servo's EEPROM across emulated power
cycles. :func:`scramble` gives a chain the wrong settings a second-hand snake arrives with.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from snakebot.emulation.case import cases_of
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.state_file import SavedServo, load_state, restore, save_state
from snakebot.emulation.virtual_servo import VirtualServo
from snakebot.servo import FACTORY_BAUD, FACTORY_ID
from snakebot.servo_tables import ServoTable, table_for_model


def new_servo(
    model: str | int | ServoTable,
    serial: int,
    *,
    servo_id: int = FACTORY_ID,
    baud: int | None = None,
) -> VirtualServo:
    """A servo with factory defaults and serial number ``serial``, at ``baud`` (default: the
    model's factory rate: 57600 on X and MX, 1 Mbps on an AX).

    Units differ as real ones do: the reply timing varies by 12 µs steps (so two servos sharing an
    ID garble each other's replies) and the shaft sits within ±0.3 rad of centre, where assembly
    left it.
    """
    table = model if isinstance(model, ServoTable) else table_for_model(model)
    if baud is None:
        baud = table.baud_rates.get(table["baud_rate"].default, FACTORY_BAUD)
    servo = VirtualServo(table, servo_id, baud=baud, processing_time_s=20e-6 + 12e-6 * (serial % 3))
    servo.serial_number = serial
    angle = ((serial * 0.6180339887) % 1.0 - 0.5) * 0.6
    servo.state = replace(servo.state, position_rad=angle)
    servo.reboot()  # Goal Position = the shaft's position, as at power-up
    return servo


def robot_servos(
    model: str | int | ServoTable, ids: Sequence[int], baud: int
) -> list[VirtualServo]:
    """Factory-default servos already given the chain's IDs and baud, serials 1..N head to tail;
    the axes of a multi-axis model paired into cases in that order (`cases_of`)."""
    out = []
    for serial, servo_id in enumerate(ids, start=1):
        servo = VirtualServo(model, servo_id, baud=baud)
        servo.serial_number = serial
        out.append(servo)
    cases_of(out)
    return out


class ServoBench:
    """A chain plus ``fresh`` factory-fresh servos to plug in, with EEPROM kept in ``state_path``.

    On creation the state file (if it exists) is loaded: servos whose serial is on the chain get
    their EEPROM back; the others (plugged in during an earlier run) are put back on the bus. The
    servos plugged in (now or in an earlier run) count against ``fresh``.
    """

    def __init__(
        self,
        chain: EmulatedChain,
        model: str | int | ServoTable,
        *,
        fresh: int = 0,
        state_path: Path | None = None,
    ) -> None:
        self.chain = chain
        self.table = model if isinstance(model, ServoTable) else table_for_model(model)
        self.state_path = state_path
        self._fresh_total = fresh
        self._base = {s.serial_number for s in chain.servos}
        self._saved: dict[int, SavedServo] = {}
        if state_path is not None and state_path.exists():
            self._saved = load_state(state_path)
            by_serial = {s.serial_number: s for s in chain.servos}
            with chain.lock:
                for serial, saved in sorted(self._saved.items()):
                    servo = by_serial.get(serial)
                    if servo is None:
                        servo = chain.add(new_servo(saved.model_number, serial))
                    restore(servo, saved)

    @property
    def waiting(self) -> int:
        """Factory-fresh servos not plugged in yet."""
        plugged = sum(1 for s in self.chain.servos if s.serial_number not in self._base)
        return max(0, self._fresh_total - plugged)

    def plug(self) -> VirtualServo:
        """Connect the next factory-fresh servo (ID 1, factory rate); EmulationError if none is
        left."""
        if self.waiting <= 0:
            raise EmulationError(f"all {self._fresh_total} fresh servos are plugged in already")
        serial = max((s.serial_number for s in self.chain.servos), default=0) + 1
        servo = self.chain.add(new_servo(self.table, serial))
        self.save()
        return servo

    def power_cycle(self) -> None:
        """Switch every servo off and on: RAM back to defaults, EEPROM kept, errors cleared."""
        with self.chain.lock:
            for servo in self.chain.servos:
                servo.reboot()
        self.save()

    def save(self) -> bool:
        """Write the state file if any EEPROM changed since the last save; True if written."""
        if self.state_path is None:
            return False
        with self.chain.lock:
            servos = self.chain.servos
            images = {
                s.serial_number: bytes(s.memory.data[: s.table.specs.eeprom_end]) for s in servos
            }
            if {k: v.eeprom for k, v in self._saved.items()} == images and self.state_path.exists():
                return False
            self._saved = save_state(self.state_path, servos)
        return True


def scramble(chain: EmulatedChain, seed: int = 0) -> None:
    """Give every servo wrong settings, deterministically from ``seed``.

    Return delay, operating and drive modes, position limits, shutdown mask, temperature limit,
    homing offset, gains, one servo that answers reads only (Status Return Level 1, Feetech's 0),
    one that powers up with torque on, and two mid-chain servos at other baud rates. IDs are left
    alone.
    """
    rng = random.Random(seed)
    servos = chain.servos
    middle = len(servos) // 2
    with chain.lock:
        for index, servo in enumerate(servos):

            def poke(key: str, value: int, servo: VirtualServo = servo) -> None:
                if servo.memory.has(key):  # an AX has no drive or operating mode, no offset
                    servo.poke(key, min(value, servo.table[key].maximum))

            count = servo.table.specs.ticks.count
            poke("return_delay_time", rng.randint(50, 250))
            poke("temperature_limit", rng.randint(50, 70))
            poke("shutdown", rng.choice((0, 4, 36)))
            poke("position_p_gain", rng.randint(100, 1500))
            if index % 4 == 1:
                poke("drive_mode", 1)
            if index % 4 == 2:
                poke("operating_mode", 4)
            if index % 3 == 0:
                # Limits too narrow for the joints: 37 % to 63 % of the model's travel (1500
                # and 2600 ticks on a 4096-tick servo).
                poke("min_position_limit", round(0.366 * count))
                poke("max_position_limit", round(0.635 * count))
            if index % 5 == 3:
                poke("homing_offset", rng.randint(-200, 200))
            if index == 1:  # one level short of "every instruction": 1 of 2, or Feetech's 0 of 1
                poke("status_return_level", servo.table["status_return_level"].maximum - 1)
            if index == len(servos) - 1 and servo.memory.has("startup_configuration"):
                poke("startup_configuration", 1)
                poke("torque_enable", 1)
        if len(servos) > 2:
            servos[middle].poke("baud_rate", servos[middle].table.baud_index(FACTORY_BAUD))
        if len(servos) > 4:
            servos[middle + 2].poke("baud_rate", servos[middle + 2].table.baud_index(115200))
