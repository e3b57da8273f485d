"""`VirtualServo`: a servo's control table with the firmware's rules and a motion model.

Register semantics follow the e-Manual control-table pages (reference/dynamixel.md §2.2-2.4): EEPROM
locked while torque is on, read-only items, ranges and limits, Drive Mode reverse, Homing Offset,
Shutdown and latched hardware errors, the Bus Watchdog, reboot and factory reset; the AX/MX
Protocol 1.0 tables' in `firmware_p1`, Feetech's (Lock, offset, byte order) in `firmware_feetech`.
"""

from __future__ import annotations

import itertools
from dataclasses import replace
from typing import Protocol

from snakebot.emulation import firmware, firmware_feetech, firmware_p1
from snakebot.emulation.alarms import Fault, StepRules, faults, step_rules
from snakebot.emulation.case import SHARED_KEYS, ServoCase
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.firmware import HardwareError
from snakebot.emulation.memory import ControlTableMemory, WritePlan
from snakebot.emulation.motion import MotionModel, MotorState, ProfileMotion, ServoCommand
from snakebot.emulation.protocol import ALERT_BIT, MAX_ID, StatusError
from snakebot.servo import FACTORY_BAUD, FACTORY_ID
from snakebot.servo.ticks import centre_tick
from snakebot.servo_tables import ServoTable, table_for_model

CLEAR_MULTI_TURN = b"\x01\x44\x58\x4c\x22"
P1_ALARMS = HardwareError.INPUT_VOLTAGE | HardwareError.OVERHEATING | HardwareError.OVERLOAD
_INF = float("inf")
_serial_numbers = itertools.count(1)


class Firmware(Protocol):
    """The register semantics of one control-table layout: `firmware` (X series),
    `firmware_p1` (AX, MX with Protocol 1.0 firmware) and `firmware_feetech` (STS, SCS) are the
    modules that provide it."""

    def position_ticks(self, memory: ControlTableMemory, state: MotorState) -> int:
        """Present Position for a motor state."""

    def command(self, servo: VirtualServo) -> ServoCommand:
        """The control table's request in SI."""

    def check_write(self, servo: VirtualServo, plan: WritePlan) -> int:
        """Firmware write rules; an error number or 0."""

    def apply_side_effects(self, servo: VirtualServo, values: dict[str, int]) -> None:
        """What a successful write sets off."""

    def reset_goal_limits(self, memory: ControlTableMemory) -> None:
        """Goal limits as at boot."""

    def refresh_present(self, servo: VirtualServo) -> None:
        """Present values from the motor state."""

    def fault_bits(self, found: Fault) -> int:
        """The bits of the status byte or error register that report `found`."""


class VirtualServo:
    """One emulated servo: control-table memory, firmware rules and an SI motor state.

    `baud` is the servo's configured rate in bit/s (it must be one of the model's Baud Rate
    values). `processing_time_s` is added to the Return Delay Time before replying; by default it
    is 20-36 µs and differs between units, so servos sharing an ID garble each other's replies as
    real ones do (set it equal on two servos for perfectly overlapping replies).
    """

    def __init__(
        self,
        model: str | int | ServoTable = "XL430-W250",
        servo_id: int = FACTORY_ID,
        *,
        baud: int = FACTORY_BAUD,
        motion: MotionModel | None = None,
        processing_time_s: float | None = None,
        temperature_c: float = 30.0,
    ) -> None:
        self.table = model if isinstance(model, ServoTable) else table_for_model(model)
        if not 0 <= servo_id <= MAX_ID:
            raise EmulationError(f"servo ID {servo_id} is outside 0..{MAX_ID}")
        self.memory = ControlTableMemory(self.table)
        # ID and Baud Rate are one byte each, looked up for every packet by every servo.
        self._id_address = self.memory.by_key["id"].address
        self._baud_address = self.memory.by_key["baud_rate"].address
        protocol_type = self.memory.by_key.get("protocol_type")  # one byte, where the model has it
        self._protocol_address = None if protocol_type is None else protocol_type.address
        # Feetech tables, X-series tables (Operating Mode, Drive Mode, ...) or the AX/MX
        # Protocol 1.0 layout.
        self.firmware: Firmware = _firmware_of(self.table)
        self._alarms = 0  # latched faults, on tables without Hardware Error Status
        self.motion: MotionModel = motion if motion is not None else ProfileMotion()
        self.serial_number = next(_serial_numbers)
        if processing_time_s is None:
            processing_time_s = 20e-6 + 4e-6 * (self.serial_number % 5)
        self.processing_time_s = processing_time_s
        self.state = MotorState(
            input_voltage_v=self.table.specs.nominal_voltage_v, temperature_c=temperature_c
        )
        self.uptime_s = 0.0
        self.watchdog_trips = 0
        self._since_packet_s = 0.0
        self._overload_s = 0.0
        self._overcurrent_s = 0.0
        self._watchdog_tripped = False
        self._registered: bytes | None = None
        self._registered_address = 0
        self._command: tuple[int, ServoCommand] | None = None
        # direction, homing offset, centre, rad per tick, and the goal's clamp (Feetech limits)
        self._goal_frame: tuple[int, int, int, float, float, float] = (1, 0, 0, 0.0, -_INF, _INF)
        self._rules: tuple[int, StepRules] | None = None
        self.case: ServoCase | None = None  # the other axes of a multi-axis servo (2XL430)
        self.memory.load_defaults()
        self.memory.set("id", servo_id)
        self.memory.set("baud_rate", self.table.baud_index(baud))
        self._saved_eeprom = bytes(self.memory.data[: self.table.specs.eeprom_end])
        self._backup: bytes | None = None
        self._boot()

    # ----------------------------------------------------------------- facts the bus needs
    @property
    def servo_id(self) -> int:
        """ID(7)."""
        return self.memory.data[self._id_address]

    @property
    def vendor(self) -> str:
        """The model data's family ("dynamixel", "feetech"): which codec serves the servo."""
        return self.table.family

    @property
    def saved_eeprom(self) -> bytes:
        """The EEPROM a power cycle brings back: what is in memory now, except on a model whose
        Lock decides what is saved (Feetech: only writes made while Lock reads 0)."""
        if self.firmware is firmware_feetech:
            return self._saved_eeprom
        return bytes(self.memory.data[: self.table.specs.eeprom_end])

    def save_eeprom(self) -> None:
        """Save the EEPROM as it is now: a later power cycle brings it back."""
        self._saved_eeprom = bytes(self.memory.data[: self.table.specs.eeprom_end])

    def backup_parameters(self) -> None:
        """Keep the EEPROM as it is now for a later `recover_parameters` (Feetech 0x09)."""
        self._backup = bytes(self.memory.data[: self.table.specs.eeprom_end])

    def recover_parameters(self) -> None:
        """EEPROM back to the last backup, or to the factory values when there is none
        (Feetech 0x06; the caller keeps what the instruction keeps)."""
        if self._backup is None:
            self.memory.load_defaults()
        else:
            self.memory.data[: len(self._backup)] = self._backup
            self.memory.version += 1

    def power_cycle(self) -> None:
        """Power off and on: the saved EEPROM (see `saved_eeprom`) and RAM at its defaults."""
        end = self.table.specs.eeprom_end
        self.memory.data[:end] = self.saved_eeprom
        self.memory.version += 1
        self._boot()

    @property
    def baud(self) -> int:
        """The rate the servo listens at, in bit/s, from Baud Rate(8)."""
        return self.table.baud_rates.get(self.memory.data[self._baud_address], 0)

    @property
    def return_delay_s(self) -> float:
        """Return Delay Time(9) in seconds (2 µs per unit)."""
        return self.memory.get("return_delay_time") * 2e-6

    @property
    def status_return_level(self) -> int:
        """Status Return Level(68): 0 ping only, 1 ping and reads, 2 everything."""
        return self.memory.get("status_return_level")

    @property
    def secondary_id(self) -> int | None:
        """Secondary(Shadow) ID(12), or None when disabled (253 and up) or absent (AX, MX)."""
        if not self.memory.has("secondary_shadow_id"):
            return None
        value = self.memory.get("secondary_shadow_id")
        return value if value < 253 else None

    @property
    def protocol(self) -> float:
        """The protocol the servo answers: Protocol Type(13) where the model has it (1 selects
        1.0, anything else 2.0), otherwise the model's only protocol (AX, MX 1.0 firmware)."""
        if self._protocol_address is not None:
            return 1.0 if self.memory.data[self._protocol_address] == 1 else 2.0
        return float(self.table.protocol)

    @property
    def speaks_protocol_2(self) -> bool:
        """Whether the servo answers Protocol 2.0 packets (see `protocol`)."""
        return self.protocol == 2.0

    @property
    def torque_enabled(self) -> bool:
        """Torque Enable(64)."""
        return self.memory.get("torque_enable") == 1

    @property
    def hardware_error(self) -> HardwareError:
        """Latched Hardware Error Status(70) bits."""
        if not self.memory.has("hardware_error_status"):
            return HardwareError(self._alarms)
        return HardwareError(self.memory.get("hardware_error_status"))

    @property
    def watchdog_tripped(self) -> bool:
        """Whether the Bus Watchdog has fired and not been cleared by writing 0 (how often it
        fired since the servo was made: `watchdog_trips`)."""
        return self._watchdog_tripped

    def peek(self, key: str) -> int:
        """Read item `key` as the bus would see it now (signed where the item is)."""
        self.firmware.refresh_present(self)
        return self.memory.get(key)

    def poke(self, key: str, value: int) -> None:
        """Set item `key` directly, bypassing every rule (test setup and fault injection); an
        EEPROM item is set as saved (a power cycle keeps it, whatever the Lock)."""
        self.memory.set(key, value)
        register = self.memory.by_key[key]
        if register.address + register.size <= len(self._saved_eeprom):
            start, end = register.address, register.address + register.size
            saved = bytearray(self._saved_eeprom)
            saved[start:end] = self.memory.data[start:end]
            self._saved_eeprom = bytes(saved)

    def status_error(self, error: int = 0) -> int:
        """A status packet's error byte: `error`, plus the Alert bit while a HW error is latched."""
        return error | (ALERT_BIT if self.hardware_error else 0)

    def alarm_bits(self) -> int:
        """The faults a Protocol 1.0 status byte reports on every reply: input voltage,
        overheating and overload, at the same bit positions in both protocols."""
        return int(self.hardware_error) & P1_ALARMS

    def ping_params(self) -> bytes:
        """Ping reply parameters: model number (LE) and firmware version."""
        return self.table.model_number.to_bytes(2, "little") + bytes(
            [self.memory.get("firmware_version")]
        )

    # ----------------------------------------------------------------- instructions
    def note_packet(self) -> None:
        """Record that an instruction packet for this servo arrived (feeds the Bus Watchdog)."""
        self._since_packet_s = 0.0

    def read(self, address: int, length: int) -> tuple[int, bytes]:
        """Serve a READ: (error number, data)."""
        self.firmware.refresh_present(self)
        return self.memory.read(address, length)

    def write(self, address: int, data: bytes) -> int:
        """Serve a WRITE; returns the error number (0 on success) and changes nothing on error."""
        plan = self.memory.plan_write(address, data)
        error = plan.error or self.firmware.check_write(self, plan) or self._check_case(plan)
        if error:
            return error
        follow = self._goal_only(plan.values)
        self.memory.store(plan)
        self._after_write(plan.values)
        if follow is not None and self.memory.version == follow + 1:
            self._follow_goal(follow)
        return 0

    def reg_write(self, address: int, data: bytes) -> int:
        """Serve a REG WRITE: check now, apply on ACTION; sets Registered Instruction(69)."""
        plan = self.memory.plan_write(address, data)
        error = plan.error or self.firmware.check_write(self, plan) or self._check_case(plan)
        if not error:
            self._registered, self._registered_address = bytes(data), address
            if self.memory.has("registered_instruction"):
                self.memory.set("registered_instruction", 1)
        return error

    def action(self) -> int:
        """Serve an ACTION: apply the registered write (Instruction Error if there is none)."""
        if self._registered is None:
            return StatusError.INSTRUCTION
        data, self._registered = self._registered, None
        if self.memory.has("registered_instruction"):
            self.memory.set("registered_instruction", 0)
        return self.write(self._registered_address, data)

    def reboot(self) -> None:
        """REBOOT: RAM back to defaults, torque off, errors cleared, multi-turn count lost."""
        self._boot()

    def factory_reset(self, option: int) -> int:
        """FACTORY RESET: 0xFF all, 0x01 all but ID, 0x02 all but ID and baud; then reboot."""
        keep = {0xFF: (), 0x01: ("id",), 0x02: ("id", "baud_rate")}.get(option)
        if keep is None:
            return StatusError.DATA_RANGE
        self.memory.load_defaults(keep)
        self._registered = None
        self._boot()
        if self.case is not None:
            self.case.follow(self)  # the reset baud and protocol are the module's
        return 0

    def clear(self, params: bytes) -> int:
        """CLEAR multi-turn: fold Present Position into one turn (Result Fail while moving)."""
        if params != CLEAR_MULTI_TURN:
            return StatusError.DATA_RANGE
        if self.peek("moving"):
            return StatusError.RESULT_FAIL
        self.state = replace(self.state, position_rad=firmware.wrap_turn(self.state.position_rad))
        return 0

    def clear_alarms(self) -> None:
        """Forget latched faults (a Protocol 1.0 servo does on Torque Enable 1; an X servo only
        on reboot). A cause still present latches again on the next step."""
        if self.memory.has("hardware_error_status"):
            self.memory.set("hardware_error_status", 0)
        self._alarms = 0

    def latch_fault(self, fault: Fault) -> None:
        """Latch `fault` in the bits the servo's firmware reports it by (Hardware Error Status
        on an X, the status byte on an AX or a Feetech servo)."""
        self.latch_error(self.firmware.fault_bits(fault))

    def latch_error(self, bits: int) -> None:
        """Latch hardware error bits; bits in the Shutdown(63) mask also force torque off,
        except an overload on a model with a Holding Torque (Feetech 34/37): its output drops
        to that share of Max Torque instead (wiki memory-sts.md, Holding torque)."""
        latched = int(self.hardware_error) | bits
        memory = self.memory
        if memory.has("hardware_error_status"):
            memory.set("hardware_error_status", latched)
        else:
            self._alarms = latched
        unload = bits & memory.get("shutdown")
        overload = self.firmware.fault_bits(Fault.OVERLOAD)
        if unload & overload and memory.has("holding_torque"):
            unload &= ~overload
            if memory.has("torque_limit"):
                held = memory.get("holding_torque") * memory.get("max_torque") // 100
                memory.set("torque_limit", min(memory.get("torque_limit"), held))
        if unload:
            memory.set("torque_enable", 0)

    # ----------------------------------------------------------------- time
    def step(self, dt_s: float, *, judge_watchdog: bool = True) -> None:
        """Let `dt_s` seconds pass: motion, Bus Watchdog and fault detection.

        With `judge_watchdog` False the time still counts towards the Bus Watchdog, but it fires
        no earlier than the next step: instruction bytes that arrived within `dt_s` are still
        to be fed (see `EmulatedChain.advance`).
        """
        if dt_s <= 0.0:
            return
        self.uptime_s += dt_s
        rules = self._step_rules()
        # The watchdog only runs while torque is on (e-Manual bus watchdog).
        self._since_packet_s = self._since_packet_s + dt_s if rules.torque_enabled else 0.0
        self.motion.step(self, dt_s)
        rules = self._step_rules()  # the motion model may have changed the table
        if (
            judge_watchdog
            and rules.torque_enabled
            and not self._watchdog_tripped
            and rules.watchdog_s > 0
            and self._since_packet_s > rules.watchdog_s
        ):
            self._trip_watchdog()
        self._detect_faults(dt_s, self._step_rules())

    def command(self) -> ServoCommand:
        """The control table's current request in SI, in the motor's frame (see motion.py)."""
        if self._command is not None and self._command[0] == self.memory.version:
            return self._command[1]
        memory = self.memory
        command = self.firmware.command(self)
        self._command = (memory.version, command)
        if self.firmware is firmware:
            self._goal_frame = (
                firmware.direction(memory),
                firmware.homing_offset(memory),
                centre_tick(self.table.specs.ticks),
                memory.by_key["goal_position"].scale,
                -_INF,
                _INF,
            )
        elif self.firmware is firmware_feetech:
            self._goal_frame = firmware_feetech.goal_frame(memory)
        return command

    # ----------------------------------------------------------------- internals
    def _boot(self) -> None:
        eeprom_end = self.table.specs.eeprom_end
        eeprom = [r.key for r in self.memory.items.values() if r.address < eeprom_end]
        self.memory.load_defaults(keep=eeprom)
        self.memory.set("model_number", self.table.model_number)
        self.memory.set("firmware_version", self.table.specs.firmware_version)
        self.state = replace(
            self.state, position_rad=firmware.wrap_turn(self.state.position_rad), velocity_rad_s=0.0
        )
        self.memory.set("goal_position", self.firmware.position_ticks(self.memory, self.state))
        self.firmware.reset_goal_limits(self.memory)
        self._alarms = 0
        self.uptime_s = 0.0
        self._since_packet_s = 0.0
        self._overload_s = 0.0
        self._overcurrent_s = 0.0
        self._watchdog_tripped = False
        self._registered = None
        if self.memory.has("startup_configuration"):
            self.memory.set("torque_enable", self.memory.get("startup_configuration") & 0x01)
        self.firmware.refresh_present(self)

    def _goal_only(self, values: dict[str, int]) -> int | None:
        """The memory version before a write of Goal Position alone, when the command and the
        step rules of that version are cached (a control cycle's write: see `_follow_goal`)."""
        version = self.memory.version
        if len(values) != 1 or "goal_position" not in values or self._command is None:
            return None
        if self.firmware is firmware_p1:  # the X-series and Feetech decodes (see `command`)
            return None
        return version if self._command[0] == version else None

    def _follow_goal(self, version: int) -> None:
        """Carry the cached command and step rules over a Goal Position write: only the goal
        changed, so the rest of `firmware.command`'s work (a dozen registers) is not redone."""
        assert self._command is not None
        sign, offset, centre, scale, low, high = self._goal_frame
        goal = max(low, min(high, self.memory.get("goal_position")))
        # The expression of firmware.command, so the value is bit for bit the same.
        goal_rad = sign * (goal - offset - centre) * scale
        # A field-for-field copy: `dataclasses.replace` re-runs __init__ over every field, six
        # times slower, once per servo per control cycle.
        command = object.__new__(ServoCommand)
        command.__dict__.update(self._command[1].__dict__, goal_position_rad=goal_rad)
        self._command = (self.memory.version, command)
        if self._rules is not None and self._rules[0] == version:
            self._rules = (self.memory.version, self._rules[1])

    def _check_case(self, plan: WritePlan) -> int:
        return 0 if self.case is None else self.case.check_write(self, plan)

    def _after_write(self, values: dict[str, int]) -> None:
        self.firmware.apply_side_effects(self, values)
        if self.case is not None and not SHARED_KEYS.isdisjoint(values):
            self.case.follow(self)
        if values.get("bus_watchdog") == 0:
            self._watchdog_tripped = False
        if "bus_watchdog" in values:
            self._since_packet_s = 0.0

    def _trip_watchdog(self) -> None:
        """Bus Watchdog fired: stop where it is; reads -1 until 0 is written (e-Manual §2.4)."""
        self._watchdog_tripped = True
        self.watchdog_trips += 1
        self.memory.set("bus_watchdog", -1)
        self.memory.set("goal_position", self.firmware.position_ticks(self.memory, self.state))
        self.memory.set("goal_velocity", 0)
        self.state = replace(self.state, velocity_rad_s=0.0)

    def _step_rules(self) -> StepRules:
        """The writable items `step` checks, decoded once per change of the table."""
        version = self.memory.version
        if self._rules is None or self._rules[0] != version:
            self._rules = (version, step_rules(self.memory))
        return self._rules[1]

    def _detect_faults(self, dt_s: float, rules: StepRules) -> None:
        found, self._overload_s, self._overcurrent_s = faults(
            self.state, rules, dt_s, self._overload_s, self._overcurrent_s
        )
        bits = self.firmware.fault_bits(found) if found else 0
        if bits & ~int(self.hardware_error):
            self.latch_error(bits)


def _firmware_of(table: ServoTable) -> Firmware:
    if table.family == "feetech":
        return firmware_feetech
    return firmware if "operating_mode" in table else firmware_p1
