"""The Backend contract on a real Dynamixel chain: SI units outside, ticks only at the bus edge.

One control cycle is one Sync Write of goal positions (``send_command``) and one group read of
load/current, velocity and position (``read_state``) by the servo family's read method: Fast Sync
Read (X, Protocol 2.0), Bulk Read (MX and X in Protocol 1.0) or one Read per servo (AX). What the
backend does beyond that follows the model's capabilities (``snakebot.families``). Every
``slow_every`` reads one extra read fetches Hardware Error Status where the model has it (else
the faults come from the status packets' error bits: see ``_check_faults``), and the tracking
check runs on what the cycle read; half-way between, one extra read fetches input voltage and
temperature, or the Bus Watchdog (where there is one), in turn.
Stopping (``close``, a failed ``connect``) is in ``stopping.py``, connect-time checks in
``checks.py``, the tracking check in ``supervision.py``.
"""

from __future__ import annotations

import dataclasses
import logging
import time
import warnings
from collections.abc import Callable, Iterable, Sequence

import numpy as np
import numpy.typing as npt

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import torque_caps
from snakebot.backends.chain.bus import ServoBus
from snakebot.backends.chain.checks import (
    CURRENT_POSITION_MODE,
    LIMIT_KEYS,
    chain_error,
    chain_report,
    check_settings,
    current_position_mode,
    has_current_position,
    latency_warning,
    settings_keys,
    shutdown_name,
    usb_latency_timer_ms,
)
from snakebot.backends.chain.faults import (
    ExtraServosWarning,
    HardwareFaultError,
    PoseOutsideLimitsError,
    ServoSettingsError,
    ServoSettingsWarning,
)
from snakebot.backends.chain.plans import Row, SyncWritePlan
from snakebot.backends.chain.rate import (
    CycleBudget,
    check_rate,
    cycle_budget,
    fastest_baud,
    usb_tail_s,
    wanted_return_delay_s,
)
from snakebot.backends.chain.state import StateDecoder
from snakebot.backends.chain.stopping import StopSequence
from snakebot.backends.chain.supervision import CatchUp, TrackingLimits, TrackingMonitor
from snakebot.backends.chain.ticks import TickConverter
from snakebot.backends.dynamixel.sdk import PortHandlerFactory
from snakebot.backends.pacing import Pacer
from snakebot.config.schema import PID_GAIN_KEYS, GainRegisters, RobotConfig
from snakebot.errors import BusError
from snakebot.interrupts import deferred_interrupts
from snakebot.servo_tables import supported_models, table_for_model
from snakebot.types import JointState, PDGains

log = logging.getLogger(__name__)

WATCHDOG_UNIT_S = 0.02  # Bus Watchdog (98) counts in 20 ms (e-Manual control_table_buswatchdog)
GoalTerms = list[tuple[float, float, int, int]]


class ServoChainBackend(Backend):
    """A chain of position-controlled Dynamixel servos (X, MX, AX; Protocol 2.0 or 1.0, as
    the robot's ``[bus] protocol`` says) behind the Backend contract.

    ``port``/``baud`` override the robot's ``[bus]``; ``port_handler_factory`` builds the SDK port
    handler (tests pass the emulator's). ``read_current=False`` drops load/current from the cycle
    read (``effort_nm`` is then zeros). ``enable_torque`` turns torque on at the end of
    ``connect`` (Goal Position = Present Position first). ``watchdog_s`` is the Bus Watchdog armed
    while torque is on (models without one: nothing is armed; docs/hardware.md says what
    protects them). ``allow_extra_servos`` accepts servos on the bus that the robot does not
    name (otherwise connect refuses, naming them). ``tracking`` sets when joints count as no longer
    following their goals (None switches that check off). ``clock``/``sleep`` are the wall clock
    the pacing and the stop ramp use.

    Raises at connect: ChainMismatchError, ServoSettingsError, HardwareFaultError,
    PoseOutsideLimitsError, BusError; during the cycle: BusError, HardwareFaultError,
    TrackingError, WatchdogTripError.
    """

    def __init__(
        self,
        robot: RobotConfig,
        *,
        port: str | None = None,
        baud: int | None = None,
        port_handler_factory: PortHandlerFactory | None = None,
        read_current: bool = True,
        enable_torque: bool = True,
        watchdog_s: float = 0.1,
        slow_every: int = 10,
        retries: int = 2,
        allow_extra_servos: bool = False,
        tracking: TrackingLimits | None = TrackingLimits(),  # noqa: B008 - frozen, shared safely
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        super().__init__()
        if not 1 <= round(watchdog_s / WATCHDOG_UNIT_S) <= 127:
            raise ValueError(f"watchdog_s must be 0.02..2.54 s, got {watchdog_s}")
        self.robot = robot
        self.joint_count = robot.joint_count
        self.stop_policy = robot.safety.stop_policy
        self.ids = robot.servo_ids
        self.bus = ServoBus(
            port or robot.bus.port,
            baud or robot.bus.baud,
            protocol=robot.bus.protocol,
            model=robot.servo.name,
            port_handler_factory=port_handler_factory,
            retries=retries,
            clock=clock,
        )
        self.capabilities = self.bus.capabilities
        """What the model can do on the robot's bus (``snakebot.families.Capabilities``)."""
        self.converter = TickConverter.for_robot(robot)
        self.watchdog_ticks = round(watchdog_s / WATCHDOG_UNIT_S)
        self._watchdog_margin_s = (self.watchdog_ticks - 1) * WATCHDOG_UNIT_S
        self.slow_every = max(2, slow_every)
        self.enable_torque = enable_torque
        self.allow_extra_servos = allow_extra_servos
        self.tracking = tracking
        self.fast_read = self.capabilities.fast_sync_read
        """Whether the cycle uses Fast Sync Read (where the model has it: decided by a probe at
        connect)."""
        self.torque_enabled = False
        """Whether the backend has the chain's torque on (set by connect, set_torque, close)."""
        self.torque_may_be_on = False
        """Whether any servo may have torque on: from just before Torque Enable goes out until
        the stop policy has been applied. While it is set, every way out applies the policy."""
        self._health: dict[str, np.ndarray] = {}
        """Latest slow-rate readings, shape (N,): ``input_voltage_v``, ``temperature_c``."""
        self.clock, self.sleep = clock, sleep
        self.max_ticks_per_s = robot.max_speed_rad_s / self.converter.rad_per_tick
        self.last_state: JointState | None = None
        self.last_rows: list[Row] | None = None
        self.last_goal_ticks: list[int] | None = None
        self.goal_terms: GoalTerms = self.converter.goal_terms
        """Goal bounds in use: the joint limits, widened for a joint found outside them."""
        self.catch_up: CatchUp | None = None
        self.position_i_gain = robot.position_i_gain
        """The Position I Gain register written with every ``set_gains`` (Dynamixel only)."""
        self.gain_registers: GainRegisters | None = None
        """The Position P/I/D Gain registers last written: ``set_gains``'s SI gains rounded and
        clipped to the control table's maxima."""
        self._pacer: Pacer | None = None
        self._cycle = 0
        self._fed_s = 0.0  # clock() at the start of the last transaction to every servo
        self._warned_slow = False
        self._position_limits: list[tuple[int, int]] = []  # EEPROM Min/Max per servo, head first
        self._outside: list[int] = []  # joints being brought inside their limits
        self._shutdown: dict[int, int] = {}  # Alarm Shutdown per servo (status-byte families)
        self._fault_turn = 0  # the next servo whose status byte the slow check reads
        self._monitor = (
            None
            if tracking is None
            else TrackingMonitor(tracking, self.joint_count, self.converter.rad_per_tick)
        )
        self._decoder = StateDecoder(robot, self.bus.table, self.converter, read_current)
        if self._decoder.measures_current:
            self.present_current_a = self._present_current_a  # SensesCurrent: this model
            self.measured_torque_nm = self._measured_torque_nm  # SensesTorque: kt * current
        self._torque_cap_nm: np.ndarray | None = None
        if has_current_position(self.bus.table):
            self.limit_torque = self._limit_torque  # LimitsTorque: current-based position
        self._state_plan = self.bus.sync_read_plan(self._decoder.keys, self.ids)
        self._goal_plan: SyncWritePlan | None = self.bus.sync_write_plan("goal_position", self.ids)
        self.unloaded: set[int] = set()
        """Servos whose firmware cut their torque for a fault (a HardwareFaultError named them):
        every later goal leaves them out, the stop ramp's too, since a Goal Position write turns
        a Feetech servo's torque back on (FTServo_Python's examples rely on it)."""
        self.stopper = StopSequence(self, tracking or TrackingLimits())
        self.interrupts = deferred_interrupts()
        """Holds the stop signals back from before the first torque write until the stop policy
        is out (``interrupts.py``); they raise at the start of the next cycle call instead."""

    @property
    def port(self) -> str:
        """The serial port (or emulator URL)."""
        return self.bus.port

    def rate_budget(self) -> CycleBudget:
        """Where one control cycle's bus time goes on this chain: its servos, baud, read method,
        the Return Delay Time the robot's settings give them (default: the model's factory
        value) and the port's USB latency (``rate.py``)."""
        table = self.bus.table
        tail, assumed = usb_tail_s(self.port)
        return cycle_budget(
            self.bus.family,
            self._state_plan.method,
            len(self.ids),
            self._state_plan.block.size,
            table["goal_position"].size,
            self.bus.baud,
            wanted_return_delay_s(self.robot, table),
            tail,
            usb_assumed=assumed,
            fastest_baud=fastest_baud(table),
        )

    def check_rate(self, rate_hz: float) -> None:
        """RateTooHighError (a ConfigError naming ``rate_hz``) above :meth:`rate_budget`'s
        ceiling, with the highest rate the bus holds and how to get more."""
        check_rate(self.rate_budget(), rate_hz)

    # -- lifecycle -------------------------------------------------------------------------------
    def _connect(self) -> None:
        self.bus.open()
        try:
            self._check_chain()
            self._probe_fast_read()
            if self.capabilities.hardware_error_status:
                self.check_faults()
            self._check_settings()
            if self._torque_cap_nm is not None:
                self._write_goal_current()  # torque still off: capped from the first push
            if not self.capabilities.hardware_error_status:
                self.check_faults()  # the pings' status bytes, against each Alarm Shutdown
            self.write_watchdog(0)  # clears a trip left by a dead session (where there is one)
            self._set_gains(self.robot.gains)
            self.interrupts.arm()  # from here the servos may be energised
            torque = self.bus.sync_read("torque_enable", self.ids)
            on = [i for i, v in torque.items() if v["torque_enable"]]
            self.torque_may_be_on = bool(on)
            self.torque_enabled = len(on) == len(self.ids)
            if self.torque_enabled:  # left holding by a previous session: guard it again
                self.write_watchdog(self.watchdog_ticks)
            self._pacer = Pacer(self.stats, clock=self.clock, sleep=self.sleep)
            if self.enable_torque and not self.torque_enabled:
                self._set_torque(True)
            self._read_state()
            assert self.last_rows is not None
            self._open_bounds(self._positions(self.last_rows))
            self.interrupts.deliver()  # a Ctrl-C during the connect fails it, policy applied
        except BaseException:
            self.stopper.abort_connect()
            raise

    def _close(self) -> None:
        """Ramp to the safe pose, then hold or limp; with torque off nothing moves or energises."""
        self.stopper.close(hurry=self.hurry_stop)

    def _safe_point(self) -> None:
        self.interrupts.deliver()

    def _check_chain(self) -> None:
        """One broadcast ping finds every servo; IDs it missed (garbled replies) get pinged.

        A family without broadcast ping (Protocol 1.0) pings the robot's IDs one by one, so
        servos the robot does not name go unseen; each ping's status byte also reports the
        servo's condition (overload, overheating, input voltage) for ``_check_faults``.
        """
        if self.capabilities.broadcast_ping:
            on_bus = {i: model for i, (model, _) in self.bus.broadcast_ping().items()}
        else:
            on_bus = {}
        found = {i: on_bus[i] for i in self.ids if i in on_bus}
        found.update(self.bus.ping_all([i for i in self.ids if i not in on_bus]))
        on_bus = on_bus or dict(found)
        report = chain_report(self.ids, self.robot.servo.model_number, found, on_bus)
        if report.ok and (not report.unexpected or self.allow_extra_servos):
            if report.unexpected:
                extra = ", ".join(map(str, report.unexpected))
                warnings.warn(
                    f"{self.port}: servo ID(s) {extra} are on the bus but not in the "
                    f"robot file; they are left alone",
                    ExtraServosWarning,
                    stacklevel=4,
                )
            return
        names = {}
        for name in supported_models():
            names[table_for_model(name).model_number] = name
        raise chain_error(self.port, self.bus.baud, report, names)

    def check_faults(self, *, every_servo: bool = False) -> None:
        """HardwareFaultError for latched faults: Hardware Error Status where the model has it;
        else the condition bits of the servos' last status packets (Protocol 1.0: overload,
        overheating, input voltage) that their Alarm Shutdown turns torque off for.

        Status bytes come with every Read (the AX cycle) and ping; a Bulk Read's are not handed
        out by the SDK, so there one servo per call is read alone, in turn (all with
        ``every_servo``).
        """
        if self.capabilities.hardware_error_status:
            status = self.bus.sync_read("hardware_error_status", self.ids, fast=self.fast_read)
            faults = {i: v["hardware_error_status"] for i, v in status.items()}
            if any(faults.values()):
                raise self.fault_error({i: v for i, v in faults.items() if v})
            return
        if every_servo or self.capabilities.read_method != "read":
            turn = self.ids if every_servo else [self.ids[self._fault_turn % len(self.ids)]]
            self._fault_turn += 1
            for servo_id in turn:
                self.bus.read(servo_id, "present_temperature")
        conditions = self.bus.conditions
        faults = {
            i: conditions[i] & self._shutdown.get(i, 0xFF) for i in self.ids if i in conditions
        }
        if any(faults.values()):
            raise self.fault_error({i: v for i, v in faults.items() if v})

    def fault_error(self, faults: dict[int, int]) -> HardwareFaultError:
        """The HardwareFaultError for ``{id: fault bits}`` (Hardware Error Status, or the
        status byte's condition bits where the model has no such register), with the remedy
        the family allows (a Reboot instruction, or a power cycle)."""
        self._leave_out(faults)
        caps, family = self.capabilities, self.bus.family
        if caps.reboot:
            return HardwareFaultError(self.port, faults)
        cause = "remove the cause (stalled or overloaded joint, supply voltage, heat)"
        if caps.hardware_error_status:
            return HardwareFaultError(
                self.port,
                faults,
                remedy=(
                    f"Its torque is off until it restarts: {cause}, then power-cycle it "
                    f"({family.name} has no Reboot)"
                ),
            )
        shutdown = shutdown_name(self.bus.table)
        return HardwareFaultError(
            self.port,
            faults,
            decode=family.status_errors,
            remedy=(
                f"Its torque is off where its {shutdown} names the fault: {cause}, let it "
                f"cool, then power-cycle it ({family.name} has no Reboot) and run again"
            ),
        )

    def _check_settings(self) -> None:
        settings = self.bus.sync_read(settings_keys(self.bus.table), self.ids)
        for servo_id, limits in self.bus.sync_read(LIMIT_KEYS, self.ids).items():
            settings[servo_id].update(limits)
        if not self.capabilities.hardware_error_status and "shutdown" in self.bus.table:
            for servo_id, values in self.bus.sync_read("shutdown", self.ids).items():
                settings[servo_id].update(values)
                self._shutdown[servo_id] = values["shutdown"]
        errors, notes = check_settings(
            settings,
            self.ids,
            self.converter,
            watchdog=self.capabilities.bus_watchdog,
            position_mode=self.bus.table.specs.position_mode,
            current_position_mode=current_position_mode(self.bus.table),
            shutdown_register=shutdown_name(self.bus.table),
        )
        self._position_limits = [
            (settings[i]["min_position_limit"], settings[i]["max_position_limit"]) for i in self.ids
        ]
        if errors:
            raise ServoSettingsError(self.port, errors)
        latency = usb_latency_timer_ms(self.port)
        if latency is not None:
            budget = self.rate_budget()  # waits per cycle: one per Read, else one
            note = latency_warning(self.port, latency, budget.wire_s, budget.round_trips)
            notes += [note] if note else []
        for note in notes:
            warnings.warn(note, ServoSettingsWarning, stacklevel=4)

    def _limit_torque(self, torque_nm: npt.ArrayLike) -> None:
        """LimitsTorque: cap each joint's torque at ``torque_nm`` (a scalar or (N,) N*m, > 0)
        by its servo's Goal Current (torque / kt, kt = stall torque / stall current from the
        servo file, at most the servo's Current Limit) in current-based position control.
        Before connect it is written at connect, before torque comes on. ValueError for a bad
        value; ServoSettingsError naming the servos not in Operating Mode 5."""
        self._torque_cap_nm = torque_caps(torque_nm, self.joint_count)
        if self.connected:
            self._write_goal_current()

    def _write_goal_current(self) -> None:
        assert self._torque_cap_nm is not None
        modes = self.bus.sync_read("operating_mode", self.ids)
        wrong = [i for i in self.ids if modes[i]["operating_mode"] != CURRENT_POSITION_MODE]
        if wrong:
            raise ServoSettingsError(
                self.port,
                [
                    f"servo {i}: Operating Mode is {modes[i]['operating_mode']}; a torque limit "
                    f"needs {CURRENT_POSITION_MODE} (current-based position control): set "
                    f"operating_mode = {CURRENT_POSITION_MODE} in the robot file's [settings]"
                    for i in wrong
                ],
            )
        table = self.bus.table
        kt = self.robot.servo.physics.stall_torque_nm / table.specs.stall_current_a
        limits = self.bus.sync_read("current_limit", self.ids)
        per_tick = table["goal_current"].scale
        goal = {
            servo_id: min(
                max(1, round(float(cap) / kt / per_tick)), limits[servo_id]["current_limit"]
            )
            for servo_id, cap in zip(self.ids, self._torque_cap_nm, strict=True)
        }
        self.bus.sync_write("goal_current", goal)

    def _probe_fast_read(self) -> None:
        if not self.capabilities.fast_sync_read:
            return
        fallbacks = self.bus.group_fallbacks
        self._state_plan.read_rows(fast=True)
        if self.bus.group_fallbacks > fallbacks:
            self.fast_read = False
            log.warning(
                "%s: Fast Sync Read got no valid reply (firmware too old?); using Sync "
                "Read, which costs one status packet per servo",
                self.port,
            )

    def _open_bounds(self, present: Sequence[int]) -> None:
        """Widen the goal bounds of joints found outside their limits to where they stand.

        Goal = Present at torque on holds them there; the safety layer then brings them inside at
        its slew limit and the bounds close behind them (``_close_bounds``), never a clipped step.
        """
        terms = self.converter.goal_terms
        for j, ((gain, bias, low, high), p) in enumerate(zip(terms, present, strict=True)):
            if p > high or p < low:
                terms[j] = (gain, bias, min(low, p), max(high, p))
                self._outside.append(j)
        self.goal_terms = terms
        if self._outside:
            angles = self.converter.to_rad(np.array(present))
            where = ", ".join(
                f"joint {j} at {angles[j]:.3f} rad (limits "
                f"{self.converter.lower_rad[j]:.3f}..{self.converter.upper_rad[j]:.3f}"
                ")"
                for j in self._outside
            )
            log.warning(
                "%s: %s outside the joint limits: brought inside at the joint speed limit",
                self.port,
                where,
            )

    def _close_bounds(self, ticks: Sequence[int]) -> None:
        limits = self.converter.goal_terms
        outside = []
        for j in self._outside:
            gain, bias, low, high = self.goal_terms[j]
            limit_low, limit_high = limits[j][2], limits[j][3]
            low, high = min(limit_low, max(low, ticks[j])), max(limit_high, min(high, ticks[j]))
            self.goal_terms[j] = (gain, bias, low, high)
            if low < limit_low or high > limit_high:
                outside.append(j)
        self._outside = outside

    # -- the cycle -------------------------------------------------------------------------------
    def _read_state(self) -> JointState:
        self._fed_s = self.clock()
        rows = self._state_plan.read_rows(fast=self.fast_read)
        position, velocity, effort = self._decoder.decode(rows)
        assert self._pacer is not None
        state = JointState(self._pacer.now_s(), position, velocity, effort)
        self.last_state, self.last_rows = state, rows
        self._cycle += 1
        phase = self._cycle % self.slow_every
        if phase == 0:
            self.check_faults()
            if self._monitor is not None and self.torque_enabled and self.catch_up is None:
                self._supervise(rows)
        elif phase == self.slow_every // 2:
            if (self._cycle // self.slow_every) % 2 and self.capabilities.bus_watchdog:
                self.stopper.check_watchdog()
            else:
                self._read_health()
        return state

    def _supervise(self, rows: list[Row]) -> None:
        assert self._monitor is not None
        if self.last_goal_ticks is None:
            return
        stalls = self._monitor.check(self.clock(), self._positions(rows), self.last_goal_ticks)
        if stalls:
            self.stopper.diagnose(stalls)
            self._monitor.reset()

    def reset_tracking(self) -> None:
        """Forget the tracking history (after a recovery)."""
        if self._monitor is not None:
            self._monitor.reset()

    def _read_health(self) -> None:
        keys = ("present_input_voltage", "present_temperature")
        values = self.bus.sync_read(keys, self.ids, fast=self.fast_read)
        table = self.bus.table
        volts = np.array([values[i]["present_input_voltage"] for i in self.ids], dtype=float)
        temps = np.array([values[i]["present_temperature"] for i in self.ids], dtype=float)
        self._health["input_voltage_v"] = volts * table["present_input_voltage"].scale
        self._health["temperature_c"] = temps * table["present_temperature"].scale
        self.stats.extra["max_temperature_c"] = float(self._health["temperature_c"].max())
        self.stats.extra["min_input_voltage_v"] = float(self._health["input_voltage_v"].min())

    def _measured_torque_nm(self) -> np.ndarray:
        """Output torque per joint (N,) N*m from the last cycle's Present Current (torque
        constant = stall torque / stall current, from the servo file); zeros before the first."""
        state = self.last_state
        if state is None:
            return np.zeros(self.joint_count)
        return state.effort_nm.copy()

    def _present_current_a(self) -> np.ndarray:
        """Present Current per joint (N,) A, in the joints' sense, from the last cycle read
        (no bus traffic); zeros before the first."""
        if self.last_rows is None:
            return np.zeros(self.joint_count)
        return self._decoder.current_a(self.last_rows)

    def health(self) -> dict[str, np.ndarray]:
        """The servos' slow readings, head to tail, as of the last slow read (every
        ``slow_every`` cycles): ``input_voltage_v`` (N,) and ``temperature_c`` (N,); empty
        before the first."""
        return dict(self._health)

    def _send_command(self, position_rad: np.ndarray) -> None:
        ticks, clipped = self.converter.goal_ticks(position_rad, self.goal_terms)
        if clipped:
            self.stats.extra["clipped_commands"] = self.stats.extra.get("clipped_commands", 0) + 1
        if self.catch_up is not None:
            ticks = self.catch_up.limit(ticks, self.clock())
            if self.catch_up.done:
                self.catch_up = None
        if self._outside:
            self._close_bounds(ticks)
        self.write_goals(ticks)

    def _leave_out(self, ids: Iterable[int]) -> None:
        """Send no more goals to ``ids`` (see :attr:`unloaded`), and turn their torque off
        again: a goal sent between the fault and its report (the status bits are checked at a
        slow rate) turned a Feetech servo's torque back on. Best effort: the fault is what the
        caller reports."""
        new = set(ids) - self.unloaded
        if not new:
            return
        self.unloaded |= new
        keep = [i for i in self.ids if i not in self.unloaded]
        self._goal_plan = self.bus.sync_write_plan("goal_position", keep) if keep else None
        try:
            self.bus.sync_write("torque_enable", dict.fromkeys(sorted(new), 0))
        except BusError as exc:
            log.warning("%s: could not turn torque off on faulted servo(s): %s", self.port, exc)

    def write_goals(self, ticks: list[int]) -> None:
        """One Sync Write of N goal ticks, re-arming the Bus Watchdog first after a long pause.

        The pause counts from the start of the last transaction that addressed every servo (single
        reads and retries to one servo feed only that one). After more than the watchdog period
        the servos have stopped and ignore Goal Position until register 98 is written 0 (e-Manual
        control_table_buswatchdog). The margin is one 20 ms watchdog unit short of the period.
        """
        now = self.clock()
        if (
            self.torque_enabled
            and now - self._fed_s > self._watchdog_margin_s
            and self.capabilities.bus_watchdog
        ):
            self.write_watchdog(0)
            self.write_watchdog(self.watchdog_ticks)
            self.stats.extra["watchdog_rearms"] = self.stats.extra.get("watchdog_rearms", 0) + 1
        self._fed_s = now
        self._send_goals(ticks, checked=False)  # clipped to the goal bounds
        self.last_goal_ticks = ticks

    def _send_goals(self, ticks: list[int], *, checked: bool) -> None:
        """One Sync Write of the goals, leaving out the :attr:`unloaded` servos."""
        sent = ticks
        if self.unloaded:
            sent = [t for i, t in zip(self.ids, ticks, strict=True) if i not in self.unloaded]
        if self._goal_plan is not None:
            self._goal_plan.write(sent, checked=checked)

    def write_watchdog(self, value: int) -> None:
        """Bus Watchdog (98) of every servo: 0 disarms (and clears a trip), 1..127 x 20 ms arms.

        Nothing on a model without one (AX, MX in Protocol 1.0)."""
        if not self.capabilities.bus_watchdog:
            return
        self._fed_s = self.clock()
        self.bus.sync_write("bus_watchdog", dict.fromkeys(self.ids, value))

    def read_present_ticks(self) -> list[int]:
        """Present Position of every servo, head to tail (one group read; BusError if one is
        silent)."""
        rows = self._state_plan.read_rows(fast=self.fast_read)
        self.last_rows = rows
        return self._positions(rows)

    def _positions(self, rows: list[Row]) -> list[int]:
        """Present Position (ticks) of each row of the cycle read."""
        k = self._decoder.position_index
        return [row[k] for row in rows]

    def _set_gains(self, gains: PDGains) -> None:
        servo = self.robot.servo
        writes = servo.gain_writes(gains, position_i=self.position_i_gain)
        table = self.bus.table
        # A P/D model (SCS0009: no Position I register) gets its P and D; the I it has not is 0.
        keys = sorted((k for k in writes if k in table), key=lambda key: table[key].address)
        self.bus.sync_write(keys, dict.fromkeys(self.ids, tuple(writes[key] for key in keys)))
        if servo.gain_kind == "pid":
            self.gain_registers = GainRegisters(
                *(writes[key] if key in table else 0 for key in PID_GAIN_KEYS)
            )
        log.debug(
            "%s: %s for kp %.4g N·m/rad, kd %.4g N·m·s/rad",
            self.port,
            ", ".join(f"{self.bus.table[k].name} {writes[k]}" for k in keys),
            gains.kp_nm_per_rad,
            gains.kd_nms_per_rad,
        )

    def set_position_i_gain(self, position_i: int) -> None:
        """Write the Position I Gain register of every servo (a Dynamixel-only setting: the
        Backend contract's gains are PD); ValueError beyond the control table's range."""
        self._require_connected()
        if self.robot.servo.gain_kind != "pid":
            raise ValueError(
                f"{self.robot.servo.name} has no Position I Gain (its loop is Compliance Slope)"
            )
        maximum = self.robot.servo.gain_max.position_i
        if not 0 <= position_i <= maximum:
            raise ValueError(f"Position I Gain must be 0..{maximum}, got {position_i}")
        self.bus.sync_write("position_i_gain", dict.fromkeys(self.ids, position_i))
        self.position_i_gain = position_i
        if self.gain_registers is not None:
            self.gain_registers = dataclasses.replace(self.gain_registers, position_i=position_i)

    def _set_torque(self, enabled: bool) -> None:
        if not enabled:
            self.bus.sync_write("torque_enable", dict.fromkeys(self.ids, 0))
            self.write_watchdog(0)
            self.torque_enabled = self.torque_may_be_on = False
            return
        self.write_watchdog(0)
        present = self.read_present_ticks()
        # Goal = Present before torque on, or the servo jumps to a stale goal. A servo standing
        # beyond its Min/Max Position Limit refuses that goal (Data Limit Error, silent in a Sync
        # Write) and would jump to the limit: refuse instead, naming the joint.
        for j, (p, (low, high)) in enumerate(zip(present, self._position_limits, strict=True)):
            if not low <= p <= high:
                limit = high if p > high else low
                angle, bound = self._joint_angles(j, p, limit)
                raise PoseOutsideLimitsError(self.port, j, self.ids[j], angle, bound)
        self._send_goals(present, checked=True)
        self.last_goal_ticks = present
        self.write_watchdog(self.watchdog_ticks)
        self.torque_may_be_on = True
        self.bus.sync_write("torque_enable", dict.fromkeys(self.ids, 1))
        self.torque_enabled = True
        state = self.bus.sync_read("torque_enable", self.ids)
        off = [i for i, v in state.items() if not v["torque_enable"]]
        if off:
            self.check_faults(every_servo=True)
            raise BusError(self.port, off, "torque did not turn on (Torque Enable reads 0)")

    def _joint_angles(self, joint: int, *ticks: int) -> tuple[float, ...]:
        gain, bias = self.converter.state_terms()[joint]
        return tuple(t * gain + bias for t in ticks)

    def _advance(self, dt_s: float) -> None:
        assert self._pacer is not None
        if (
            dt_s > self._watchdog_margin_s
            and not self._warned_slow
            and self.capabilities.bus_watchdog
        ):
            self._warned_slow = True
            log.warning(
                "%s: control period %.3f s exceeds the Bus Watchdog (%.2f s): the servos "
                "stop between cycles; raise watchdog_s",
                self.port,
                dt_s,
                self.watchdog_ticks * WATCHDOG_UNIT_S,
            )
        self._pacer.wait(dt_s)
