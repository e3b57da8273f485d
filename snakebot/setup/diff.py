"""Find a robot's servos (at whatever baud rate each listens) and compare their settings.

A servo is known by its ID: the chain's IDs are searched for at the robot's baud rate first, then
at every other rate, so a servo left at the factory 57600 (or half-way through a baud change) is
still found and its Baud Rate shows up as a difference.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from snakebot.backends.chain.faults import decode_hardware_error
from snakebot.errors import BusError
from snakebot.servo_tables import table_for_model
from snakebot.setup.bauds import factory_baud, model_bauds, preferred
from snakebot.setup.errors import DuplicateIdError, SetupError
from snakebot.setup.link import Link
from snakebot.setup.settings import ChainSettings, Setting

STATE_KEYS = ("torque_enable", "hardware_error_status", "lock")
"""Read beside the settings where the model has them (an AX has no Hardware Error Status, an X
no Lock). A family's own EEPROM lock (Feetech, :attr:`ServoFamily.eeprom_lock`) is not a lock
that holds until a power cycle: setup opens it around its writes."""


@dataclass(frozen=True)
class Difference:
    """One setting of one servo that differs: raw register values now and wanted."""

    servo_id: int
    setting: Setting
    current: int

    @property
    def key(self) -> str:
        """The register key."""
        return self.setting.key

    @property
    def wanted(self) -> int:
        """The raw register value the settings want."""
        return self.setting.raw

    def row(self) -> dict[str, object]:
        """The difference as a JSON-ready dict (values in the setting's unit, raw values too)."""
        have, unit = self.setting.show(self.current)
        want, _ = self.setting.show(self.wanted)
        return {
            "id": self.servo_id,
            "setting": self.key,
            "servo_value": have,
            "wanted_value": want,
            "unit": unit,
            "servo_raw": self.current,
            "wanted_raw": self.wanted,
            "eeprom": self.setting.eeprom,
            "source": self.setting.source,
        }


@dataclass(frozen=True)
class ServoState:
    """One servo as found: the rate it answered at, its settings' values, torque and faults;
    ``locked``: its EEPROM Lock is set (AX/MX: no EEPROM write until a power cycle)."""

    servo_id: int
    baud: int
    values: dict[str, int]
    torque_on: bool
    hardware_error: int
    locked: bool = False


@dataclass(frozen=True)
class ChainDiff:
    """Every servo of the chain as found, and every setting that differs, head to tail."""

    servos: dict[int, ServoState]
    differences: tuple[Difference, ...]
    notes: tuple[str, ...] = field(default=())

    @property
    def identical(self) -> bool:
        """True when every servo holds every wanted setting."""
        return not self.differences

    def for_id(self, servo_id: int) -> list[Difference]:
        """The differences of one servo."""
        return [d for d in self.differences if d.servo_id == servo_id]


def locate(link: Link, ids: Sequence[int], model_number: int, first_baud: int) -> dict[int, int]:
    """``{id: baud}`` for every ID, searching every rate; SetupError naming what is wrong."""
    found: dict[int, int] = {}
    remaining = list(ids)
    collisions: list[tuple[int, int, str]] = []
    wrong_model: list[str] = []
    for baud in preferred(model_bauds(link.bus.table), first_baud):
        for servo_id in list(remaining):
            probe = link.probe(servo_id, baud, patient=True)
            if probe.collides:
                collisions.append((servo_id, baud, probe.clash()))
            elif probe.model is None:
                continue
            elif probe.model != model_number:
                name = _model_name(probe.model)
                wrong_model.append(f"ID {servo_id} at {baud} baud is a {name}")
            else:
                found[servo_id] = baud
            remaining.remove(servo_id)
        if not remaining:
            break
    if collisions:
        raise DuplicateIdError(link.port, collisions)
    problems = wrong_model
    if remaining:
        problems.append(
            f"no servo answers as ID {', '.join(map(str, remaining))} at any baud rate (check "
            "power and cables; `snakebot scan --all-bauds` lists who is there; a new "
            f"{link.bus.table.model} is ID {link.bus.table['id'].default} at "
            f"{factory_baud(link.bus.table)}: give it its ID with `snakebot config assign-id`)"
        )
    if problems:
        expected = _model_name(model_number)
        raise SetupError(
            f"{link.port}: the chain is not the configured {expected} chain: " + "; ".join(problems)
        )
    return found


def _model_name(number: int) -> str:
    try:
        return table_for_model(number).model
    except LookupError:
        return f"model {number}"


def read_servo(link: Link, servo_id: int, baud: int, settings: Sequence[Setting]) -> ServoState:
    """Read every setting of one servo (one Read for EEPROM items, one for RAM items)."""
    bus = link.at(baud)
    keys = [s.key for s in settings]
    state_keys = [k for k in STATE_KEYS if k in bus.table]
    values: dict[str, int] = {}
    try:
        for group in (
            [k for k in keys if bus.table[k].eeprom],
            [k for k in (*keys, *state_keys) if not bus.table[k].eeprom],
        ):
            if group:
                values.update(bus.read_block(servo_id, group))
    except BusError as exc:
        raise SetupError(
            f"{link.port}: servo {servo_id} answers ping at {baud} baud but not reads ({exc}). "
            "Its Status Return Level may be 0: `snakebot servo reset` or Dynamixel Wizard fixes it"
        ) from exc
    state = {k: values.pop(k) for k in state_keys}
    sticky_lock = link.family.eeprom_lock is None
    return ServoState(
        servo_id,
        baud,
        values,
        bool(state["torque_enable"]),
        state.get("hardware_error_status", 0),
        sticky_lock and bool(state.get("lock", 0)),
    )


VOLTAGE_KEYS = ("present_input_voltage", "min_voltage_limit", "max_voltage_limit")


def condition_note(link: Link, servo_id: int, bits: int) -> str:
    """What a status byte's condition bits say about one servo (a family without a Hardware
    Error Status register reports the servo's faults in every reply), with the supply's reading
    where the input voltage is out of range."""
    faults = link.family.status_errors(bits)
    text = f"servo {servo_id} reports {', '.join(faults)} in its status"
    table = link.bus.table
    if "input voltage" in faults and all(k in table for k in VOLTAGE_KEYS):
        volts, low, high = (link.bus.read(servo_id, k) * 0.1 for k in VOLTAGE_KEYS)
        text += f": its supply reads {volts:.1f} V, outside its limits {low:.1f}..{high:.1f} V"
        if volts > high:
            text += (
                f". A {table.model} made for a lower voltage is damaged by this one (a 7.4 V "
                "servo on 12 V: huggingface/lerobot#1010): switch the supply off and use the "
                "servo's own voltage, or the robot file of the model made for it"
            )
    return text


def survey(link: Link, chain: ChainSettings) -> ChainDiff:
    """Find every servo of ``chain`` and compare what it holds with what the chain wants."""
    robot = chain.robot
    where = locate(link, robot.servo_ids, robot.servo.model_number, chain.baud)
    servos: dict[int, ServoState] = {}
    differences: list[Difference] = []
    notes: list[str] = []
    for wanted in chain.servos:
        servo_id = wanted.servo_id
        state = read_servo(link, servo_id, where[servo_id], wanted.settings)
        servos[servo_id] = state
        for setting in wanted.settings:
            current = state.values[setting.key]
            if current != setting.raw:
                differences.append(Difference(servo_id, setting, current))
        if state.hardware_error:
            flags = ", ".join(decode_hardware_error(state.hardware_error))
            fix = (
                f"`snakebot servo reboot --port {link.port} --id {servo_id}` clears it"
                if link.family.capabilities(link.bus.table).reboot
                else "a power cycle clears it (no Reboot in this protocol)"
            )
            notes.append(f"servo {servo_id} has a latched hardware error ({flags}); {fix}")
        bits = link.bus.conditions.get(servo_id, 0)
        if bits and not link.family.capabilities(link.bus.table).hardware_error_status:
            notes.append(condition_note(link, servo_id, bits))
        if state.locked:
            notes.append(
                f"servo {servo_id} has its EEPROM locked (Lock = 1): it takes no EEPROM "
                "write until it is power-cycled"
            )
    return ChainDiff(servos, tuple(differences), tuple(notes))
