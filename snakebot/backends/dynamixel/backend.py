"""The Backend contract on a real Dynamixel chain: SI units outside, ticks only at the bus edge.

One control cycle is one Sync Write of goal positions (``send_command``) and one (Fast) Sync Read
of load/current, velocity and position (``read_state``); every ``slow_every`` reads one extra
read fetches Hardware Error Status, or input voltage and temperature, in turn.
"""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Callable

import numpy as np

from snakebot.backends.base import Backend, JointState, ServoGains
from snakebot.backends.dynamixel import shutdown
from snakebot.backends.dynamixel.bus import DynamixelBus
from snakebot.backends.dynamixel.checks import (
    LIMIT_KEYS,
    SETTINGS_KEYS,
    chain_error,
    chain_report,
    check_settings,
    cycle_wire_time_s,
    latency_warning,
    usb_latency_timer_ms,
)
from snakebot.backends.dynamixel.faults import (
    DynamixelSettingsWarning,
    HardwareFaultError,
    ServoSettingsError,
)
from snakebot.backends.dynamixel.sdk import PortHandlerFactory
from snakebot.backends.dynamixel.state import StateDecoder
from snakebot.backends.dynamixel.ticks import TickConverter
from snakebot.backends.pacing import Pacer
from snakebot.config.schema import RobotConfig
from snakebot.errors import BackendError, BusError
from snakebot.servo_tables import supported_models, table_for_model

log = logging.getLogger(__name__)

WATCHDOG_UNIT_S = 0.02  # Bus Watchdog (98) counts in 20 ms (e-Manual control_table_buswatchdog)


class DynamixelBackend(Backend):
    """A chain of position-controlled Dynamixel X-series servos behind the Backend contract.

    ``port``/``baud`` override the robot's ``[bus]``; ``port_handler_factory`` builds the SDK port
    handler (tests pass the emulator's). ``read_current=False`` drops load/current from the cycle
    read (``effort_nm`` is then zeros). ``enable_torque`` turns torque on at the end of
    ``connect`` (Goal Position = Present Position first). ``watchdog_s`` is the Bus Watchdog armed
    while torque is on. ``clock``/``sleep`` are the wall clock the pacing and the stop ramp use.
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
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        super().__init__()
        if robot.bus.protocol != 2.0:
            raise BackendError("the Dynamixel backend drives Protocol 2.0 (X-series) servos only")
        if not 1 <= round(watchdog_s / WATCHDOG_UNIT_S) <= 127:
            raise ValueError(f"watchdog_s must be 0.02..2.54 s, got {watchdog_s}")
        self.robot = robot
        self.joint_count = robot.joint_count
        self.stop_policy = robot.safety.stop_policy
        self.ids = robot.servo_ids
        self.bus = DynamixelBus(
            port or robot.bus.port, baud or robot.bus.baud, protocol=robot.bus.protocol,
            model=robot.servo.name, port_handler_factory=port_handler_factory, retries=retries,
            clock=clock,
        )
        self.converter = TickConverter.for_robot(robot)
        self.watchdog_ticks = round(watchdog_s / WATCHDOG_UNIT_S)
        self._watchdog_margin_s = (self.watchdog_ticks - 1) * WATCHDOG_UNIT_S
        self.slow_every = max(2, slow_every)
        self.enable_torque = enable_torque
        self.fast_read = True
        """Whether the cycle uses Fast Sync Read (decided by a probe at connect)."""
        self.torque_enabled = False
        """Whether the backend has the chain's torque on (set by connect, set_torque, close)."""
        self.health: dict[str, np.ndarray] = {}
        """Latest slow-rate readings, shape (N,): ``input_voltage_v``, ``temperature_c``."""
        self._clock, self._sleep = clock, sleep
        self._pacer: Pacer | None = None
        self._cycle = 0
        self._last_state: JointState | None = None
        self._last_goal_ticks: list[int] | None = None
        self._fed_s = 0.0  # clock() at the start of the last transaction to every servo
        self._warned_slow = False
        self._position_limits: list[tuple[int, int]] = []  # EEPROM Min/Max per servo, head first

        self._decoder = StateDecoder(robot, self.bus.table, self.converter, read_current)
        self._state_plan = self.bus.sync_read_plan(self._decoder.keys, self.ids)
        self._goal_plan = self.bus.sync_write_plan("goal_position", self.ids)

    @property
    def port(self) -> str:
        """The serial port (or emulator URL)."""
        return self.bus.port

    # -- lifecycle -------------------------------------------------------------------------------
    def _connect(self) -> None:
        self.bus.open()
        try:
            self._check_chain()
            self._probe_fast_read()
            self._check_faults()
            self._check_settings()
            self._write_watchdog(0)  # clears a trip left by a dead session
            self._set_gains(self.robot.gains)
            torque = self.bus.sync_read("torque_enable", self.ids)
            self.torque_enabled = all(v["torque_enable"] for v in torque.values())
            if self.torque_enabled:  # left holding by a previous session: guard it again
                self._write_watchdog(self.watchdog_ticks)
            self._pacer = Pacer(self.stats, clock=self._clock, sleep=self._sleep)
            if self.enable_torque and not self.torque_enabled:
                self._set_torque(True)
            self._read_state()
        except BaseException:
            self.bus.close()
            raise

    def _check_chain(self) -> None:
        found = self.bus.ping_all(self.ids)
        report = chain_report(self.ids, self.robot.servo.model_number, found)
        if report.ok:
            return
        on_bus = {i: model for i, (model, _) in self.bus.broadcast_ping().items()}
        report = chain_report(self.ids, self.robot.servo.model_number, found, on_bus)
        names = {}
        for name in supported_models():
            names[table_for_model(name).model_number] = name
        raise chain_error(self.port, self.bus.baud, report, names)

    def _check_faults(self) -> None:
        status = self.bus.sync_read("hardware_error_status", self.ids, fast=self.fast_read)
        faults = {i: v["hardware_error_status"] for i, v in status.items()}
        if any(faults.values()):
            raise HardwareFaultError(self.port, {i: v for i, v in faults.items() if v})

    def _check_settings(self) -> None:
        settings = self.bus.sync_read(SETTINGS_KEYS, self.ids)
        for servo_id, limits in self.bus.sync_read(LIMIT_KEYS, self.ids).items():
            settings[servo_id].update(limits)
        errors, notes = check_settings(settings, self.ids, self.converter)
        self._position_limits = [
            (settings[i]["min_position_limit"], settings[i]["max_position_limit"]) for i in self.ids
        ]
        if errors:
            raise ServoSettingsError(self.port, errors)
        latency = usb_latency_timer_ms(self.port)
        if latency is not None:
            wire = cycle_wire_time_s(len(self.ids), self._state_plan.block.size, self.bus.baud,
                                     fast=True)
            note = latency_warning(self.port, latency, wire)
            notes += [note] if note else []
        for note in notes:
            warnings.warn(note, DynamixelSettingsWarning, stacklevel=4)

    def _probe_fast_read(self) -> None:
        fallbacks = self.bus.group_fallbacks
        self._state_plan.read_rows(fast=True)
        if self.bus.group_fallbacks > fallbacks:
            self.fast_read = False
            log.warning("%s: Fast Sync Read got no valid reply (firmware too old?); using Sync "
                        "Read, which costs one status packet per servo", self.port)

    def _close(self) -> None:
        """Ramp to the safe pose, then hold or limp; with torque off nothing moves or energises."""
        try:
            if self.torque_enabled:
                try:
                    self._ramp_to_safe_pose()
                except BusError as exc:  # still apply the stop policy below
                    log.warning("%s: stop ramp interrupted: %s", self.port, exc)
                if self.stop_policy == "limp":
                    self._set_torque(False)
                else:  # hold: stay on at the safe pose; nobody will feed the watchdog now
                    self._write_watchdog(0)
        finally:
            self.bus.close()

    def _ramp_to_safe_pose(self) -> None:
        try:
            start = self._decoder.decode(self._state_plan.read_rows(fast=self.fast_read))[0]
        except BusError:
            if self._last_state is not None:
                start = self._last_state.position_rad
            elif self._last_goal_ticks is not None:
                start = self.converter.to_rad(np.array(self._last_goal_ticks))
            else:
                raise
        t0 = self._clock()
        target = shutdown.safe_pose(self.robot)
        for at_s, pose in shutdown.ramp_poses(start, target, self.robot.safety.ramp_s):
            self._write_goals(self.converter.goal_ticks(pose)[0])
            remaining = t0 + at_s - self._clock()
            if remaining > 0:
                self._sleep(remaining)

    # -- the cycle -------------------------------------------------------------------------------
    def _read_state(self) -> JointState:
        self._fed_s = self._clock()
        position, velocity, effort = self._decoder.decode(
            self._state_plan.read_rows(fast=self.fast_read)
        )
        assert self._pacer is not None
        state = JointState(self._pacer.now_s(), position, velocity, effort)
        self._last_state = state
        self._cycle += 1
        phase = self._cycle % self.slow_every
        if phase == 0:
            self._check_faults()
        elif phase == self.slow_every // 2:
            self._read_health()
        return state

    def _read_health(self) -> None:
        keys = ("present_input_voltage", "present_temperature")
        values = self.bus.sync_read(keys, self.ids, fast=self.fast_read)
        table = self.bus.table
        volts = np.array([values[i]["present_input_voltage"] for i in self.ids], dtype=float)
        temps = np.array([values[i]["present_temperature"] for i in self.ids], dtype=float)
        self.health["input_voltage_v"] = volts * table["present_input_voltage"].scale
        self.health["temperature_c"] = temps * table["present_temperature"].scale
        self.stats.extra["max_temperature_c"] = float(self.health["temperature_c"].max())
        self.stats.extra["min_input_voltage_v"] = float(self.health["input_voltage_v"].min())

    def _send_command(self, position_rad: np.ndarray) -> None:
        ticks, clipped = self.converter.goal_ticks(position_rad)
        if clipped:
            self.stats.extra["clipped_commands"] = self.stats.extra.get("clipped_commands", 0) + 1
        self._write_goals(ticks)

    def _write_goals(self, ticks: list[int]) -> None:
        """One Sync Write of N goal ticks, re-arming the Bus Watchdog first after a long pause.

        The pause counts from the start of the last transaction that addressed every servo (single
        reads and retries to one servo feed only that one). After more than the watchdog period
        the servos have stopped and ignore Goal Position until register 98 is written 0 (e-Manual
        control_table_buswatchdog). The margin is one 20 ms watchdog unit short of the period.
        """
        now = self._clock()
        if self.torque_enabled and now - self._fed_s > self._watchdog_margin_s:
            self._write_watchdog(0)
            self._write_watchdog(self.watchdog_ticks)
            self.stats.extra["watchdog_rearms"] = self.stats.extra.get("watchdog_rearms", 0) + 1
        self._fed_s = now
        self._goal_plan.write(ticks, checked=False)  # clipped to the joint limits
        self._last_goal_ticks = ticks

    def _write_watchdog(self, value: int) -> None:
        """Bus Watchdog (98) of every servo: 0 disarms (and clears a trip), 1..127 x 20 ms arms."""
        self._fed_s = self._clock()
        self.bus.sync_write("bus_watchdog", dict.fromkeys(self.ids, value))

    def _set_gains(self, gains: ServoGains) -> None:
        pid = (gains.position_d, gains.position_i, gains.position_p)
        keys = ("position_d_gain", "position_i_gain", "position_p_gain")
        self.bus.sync_write(keys, dict.fromkeys(self.ids, pid))

    def _set_torque(self, enabled: bool) -> None:
        if not enabled:
            self.bus.sync_write("torque_enable", dict.fromkeys(self.ids, 0))
            self._write_watchdog(0)
            self.torque_enabled = False
            return
        self._write_watchdog(0)
        present = [row[-1] for row in self._state_plan.read_rows(fast=self.fast_read)]
        # Goal = Present before torque on, or the servo jumps to a stale goal. A goal outside
        # Min/Max Position Limit is refused (Data Limit Error, silent in a Sync Write), which
        # would leave the stale goal in place: use the nearest limit instead.
        present = [min(max(p, low), high) for p, (low, high) in zip(
            present, self._position_limits, strict=True)]
        self._goal_plan.write(present)
        self._last_goal_ticks = present
        self._write_watchdog(self.watchdog_ticks)
        self.bus.sync_write("torque_enable", dict.fromkeys(self.ids, 1))
        self.torque_enabled = True
        state = self.bus.sync_read("torque_enable", self.ids)
        off = [i for i, v in state.items() if not v["torque_enable"]]
        if off:
            self._check_faults()
            raise BusError(self.port, off, "torque did not turn on (Torque Enable reads 0)")

    def _advance(self, dt_s: float) -> None:
        assert self._pacer is not None
        if dt_s > self._watchdog_margin_s and not self._warned_slow:
            self._warned_slow = True
            log.warning("%s: control period %.3f s exceeds the Bus Watchdog (%.2f s): the servos "
                        "stop between cycles; raise watchdog_s", self.port, dt_s,
                        self.watchdog_ticks * WATCHDOG_UNIT_S)
        self._pacer.wait(dt_s)
