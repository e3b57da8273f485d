"""Every way out of a connected Dynamixel backend, and the recoveries short of one.

Once any servo may have torque on, every exit applies the stop policy to the servos that still
answer: ``close`` ramps to the safe pose first (hold: torque on, Bus Watchdog disarmed; limp:
torque off), a failed ``connect`` applies it where the servos stand (nothing has moved yet).

- The stop signals (SIGINT, SIGTERM, SIGHUP) are held back from the connect's first torque
  write (``interrupts.py``), so none can cut a transaction, the way into the stop, or skip the
  policy; the stop counts those still waiting.
  One during the ramp finishes it at the joint speed limit; a second one skips to the final state.
  A KeyboardInterrupt already on its way out when ``close`` starts (a second Ctrl-C during the
  runner's ramp-out) starts with the fast ramp. The signals are raised after the policy.
- Any other exception in the ramp still ends in the policy, then is raised; a BusError in the
  ramp (a servo gone) is logged, and the policy goes to the servos that answer.
- A tripped Bus Watchdog refuses goals (e-Manual control_table_buswatchdog): it is cleared before
  the ramp, and the ramp's last goal is read back; a servo that did not take it gets the ramp
  again once, then StopIncompleteError (hold) after the policy.
- A model without a Bus Watchdog (AX, MX in Protocol 1.0) has nothing to clear or disarm: hold
  leaves torque on at the safe pose, limp turns it off; docs/hardware.md says what protects such
  servos when the host dies.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from snakebot.backends.chain.checks import shutdown_name
from snakebot.backends.chain.faults import (
    StopIncompleteError,
    SyncReadError,
    TrackingError,
    WatchdogTripError,
)
from snakebot.backends.chain.shutdown import (
    fastest_ramp_s,
    ramp_duration_s,
    ramp_poses,
    safe_pose,
)
from snakebot.backends.chain.supervision import CatchUp, Stall, TrackingLimits, TripCounter
from snakebot.errors import BusError
from snakebot.interrupts import DeferredInterrupts

if TYPE_CHECKING:
    from snakebot.backends.chain.backend import ServoChainBackend

log = logging.getLogger(__name__)

SETTLED_RAD = 0.005
"""A stop that starts this close to the safe pose writes it at once instead of ramping."""

POLICY_TRIES = 3
"""How often the policy writes start again after a KeyboardInterrupt raised inside them."""


class StopSequence:
    """The stop path and the watchdog/tracking recoveries of one backend (its friend class)."""

    def __init__(self, backend: ServoChainBackend, limits: TrackingLimits) -> None:
        self.b = backend
        self.limits = limits
        self.trips = TripCounter(limits.trip_window_s)

    # -- ways out --------------------------------------------------------------------------------
    def abort_connect(self) -> None:
        """A connect failed (or was interrupted): apply the policy where the servos stand, close.

        Errors here are logged, and a signal during it is not raised: the exception that failed
        the connect is the one to report.
        """
        b = self.b
        try:
            with b.interrupts as signals:
                try:
                    if b.torque_may_be_on:
                        error = self._policy(signals)
                        if error is not None:
                            log.warning(
                                "%s: stop policy after the failed connect: %s", b.port, error
                            )
                finally:
                    b.bus.close()
        except KeyboardInterrupt:
            pass  # the connect's own exception is already on its way out

    def close(self, *, hurry: bool) -> None:
        """Ramp out (fast if ``hurry``), apply the policy, close the port; see the module doc.

        From the first transaction to the last the stop signals are deferred: they shorten the
        ramp and are raised after the policy went out, so no number of them skips it.
        """
        with self.b.interrupts as signals:  # held back since the connect
            error = self._stop(hurry, signals)
        if error is not None:
            raise error

    def _stop(self, hurry: bool, signals: DeferredInterrupts) -> Exception | None:
        """The whole stop; returns the error to raise once the signals are delivered."""
        b = self.b
        failure: Exception | None = None
        unreached: list[int] = []
        policy_error: BusError | None = None
        try:
            if b.torque_may_be_on and b.bus.vanished is None:
                b.catch_up = None
                try:
                    unreached = self._ramp_out(hurry, signals)
                except BusError as exc:  # a servo or the port is gone: the policy still goes out
                    if b.bus.vanished is None:
                        log.warning("%s: stop ramp interrupted: %s", b.port, exc)
                except Exception as exc:
                    failure = exc
            if b.torque_may_be_on and b.bus.vanished is None:
                policy_error = self._policy(signals)
            if b.torque_may_be_on and b.bus.vanished is not None:
                policy_error = self._vanished_error()
        finally:
            b.bus.close()
        if failure is not None:
            return failure
        if policy_error is not None:
            return policy_error
        if unreached and b.stop_policy == "hold":
            return StopIncompleteError(
                b.port,
                unreached,
                "their Goal Position is not the safe pose after the ramp "
                "(a Bus Watchdog that keeps tripping, or a servo refusing goals)",
            )
        return None

    def _policy(self, signals: DeferredInterrupts) -> BusError | None:
        """:meth:`apply_policy`, started again if a KeyboardInterrupt is raised inside it (not by
        a deferred signal: by hand, or from a thread), a few times at most."""
        for _ in range(POLICY_TRIES - 1):
            try:
                return self.apply_policy()
            except KeyboardInterrupt as exc:
                signals.note(exc)
        return self.apply_policy()

    def _vanished_error(self) -> BusError:
        b = self.b
        if not b.capabilities.bus_watchdog:
            return BusError(
                b.port,
                b.ids,
                f"the port vanished, so the stop policy ({b.stop_policy}) could "
                f"not be sent: {b.robot.servo.name} servos have no Bus Watchdog, so they hold "
                "their last goal, torque on, until they are power-cycled or a new session "
                f"connects (their {shutdown_name(b.bus.table)} turns torque off on overload or "
                "overheating)",
            )
        return BusError(
            b.port,
            b.ids,
            f"the port vanished, so the stop policy ({b.stop_policy}) could not be "
            f"sent: the servos stopped when their Bus Watchdog tripped "
            f"({b.watchdog_ticks * 0.02:.2f} s) and hold where they are, torque on, until they "
            "are power-cycled or a new session connects",
        )

    def apply_policy(self) -> BusError | None:
        """Hold (watchdog disarmed) or limp (torque off) every servo; read back, write again to
        those that did not take it. The error if nothing could be sent."""
        b = self.b
        try:
            watchdog = b.capabilities.bus_watchdog
            if b.stop_policy == "limp":
                b.bus.sync_write("torque_enable", dict.fromkeys(b.ids, 0))
                b.torque_enabled = False
                if watchdog:
                    b.bus.sync_write("bus_watchdog", dict.fromkeys(b.ids, 0))
                self._confirm("torque_enable", 0)
            elif watchdog:
                b.bus.sync_write("bus_watchdog", dict.fromkeys(b.ids, 0))
                self._confirm("bus_watchdog", 0)
        except BusError as exc:
            if b.bus.vanished is not None:
                return self._vanished_error()
            log.warning("%s: could not apply the stop policy (%s): %s", b.port, b.stop_policy, exc)
            return exc
        b.torque_may_be_on = b.stop_policy == "hold"
        return None

    def _confirm(self, key: str, value: int) -> None:
        """Write ``key`` again, one servo at a time, where it does not read back ``value``."""
        b = self.b
        for servo_id, values in self._read_answering(key).items():
            if values[key] != value:
                try:
                    b.bus.write(servo_id, key, value)
                except BusError as exc:
                    log.warning("%s: servo %d: %s", b.port, servo_id, exc)

    def _read_answering(self, key: str) -> dict[int, Mapping[str, int]]:
        """``key`` from every servo that answers (the silent ones are left out)."""
        try:
            return dict(self.b.bus.sync_read(key, self.b.ids))
        except SyncReadError as exc:
            return dict(exc.partial)

    # -- the ramp --------------------------------------------------------------------------------
    def _ramp_out(self, hurry: bool, signals: DeferredInterrupts) -> list[int]:
        """Ramp to the safe pose and check every servo took it; the IDs that did not.

        Urgency is ``hurry`` plus the interruptions so far: 1 ramps at the joint speed limit, 2
        skips to the final state. A KeyboardInterrupt raised inside counts as one and starts
        the ramp again from where the servos are.
        """
        while True:
            try:
                return self._ramp_out_once(hurry, signals)
            except KeyboardInterrupt as exc:
                signals.note(exc)

    def _skipping(self, hurry: bool, signals: DeferredInterrupts) -> bool:
        if hurry + signals.count < 2:
            return False
        log.warning(
            "%s: interrupted again: skipping the rest of the stop ramp, applying the "
            "stop policy (%s)",
            self.b.port,
            self.b.stop_policy,
        )
        return True

    def _ramp_out_once(self, hurry: bool, signals: DeferredInterrupts) -> list[int]:
        b = self.b
        target = safe_pose(b.robot)
        want = b.converter.goal_ticks(target, b.goal_terms)[0]
        unreached: list[int] = []
        for attempt in range(2):
            if self._skipping(hurry, signals):
                return []
            before = signals.count
            self._clear_tripped()
            if not self._ramp(self._start_pose(), target, hurry, signals):
                return []
            goals = self._read_answering("goal_position")
            unreached = [
                i
                for j, i in enumerate(b.ids)
                if i in goals and goals[i]["goal_position"] != want[j] and i not in b.unloaded
            ]
            if not unreached or signals.count > before or attempt:
                break
            log.warning(
                "%s: servo(s) %s did not take the stop ramp's goals; ramping again",
                b.port,
                ", ".join(map(str, unreached)),
            )
            hurry = True
        return unreached

    def _start_pose(self) -> np.ndarray:
        b = self.b
        try:
            return b.converter.to_rad(np.array(b.read_present_ticks()))
        except BusError:
            if b.last_state is not None:
                return b.last_state.position_rad
            if b.last_goal_ticks is not None:
                return b.converter.to_rad(np.array(b.last_goal_ticks))
            raise

    def _ramp(
        self, start: np.ndarray, target: np.ndarray, hurry: bool, signals: DeferredInterrupts
    ) -> bool:
        """Cosine ramp of goals; a signal hurries it (the rest at the joint speed limit), one
        more stops it. False if it stopped short."""
        b = self.b
        vmax = b.robot.max_speed_rad_s
        span = float(np.max(np.abs(target - start)))
        if span < SETTLED_RAD:
            b.write_goals(b.converter.goal_ticks(target, b.goal_terms)[0])
            return True
        urgency = hurry + signals.count
        duration = (
            fastest_ramp_s(span, vmax)
            if urgency
            else ramp_duration_s(span, vmax, b.robot.safety.ramp_s)
        )
        poses, last = ramp_poses(start, target, duration), start
        t0, k = b.clock(), 0
        while k < len(poses):
            if hurry + signals.count > urgency:
                if self._skipping(hurry, signals):
                    return False
                urgency = hurry + signals.count
                log.warning(
                    "%s: interrupted again: finishing the stop ramp at the joint speed limit",
                    b.port,
                )
                span = float(np.max(np.abs(target - last)))
                poses, t0, k = ramp_poses(last, target, fastest_ramp_s(span, vmax)), b.clock(), 0
            at_s, pose = poses[k]
            b.write_goals(b.converter.goal_ticks(pose, b.goal_terms)[0])
            last = pose
            remaining = t0 + at_s - b.clock()
            if remaining > 0:
                b.sleep(remaining)
            k += 1
        return True

    # -- the Bus Watchdog and tracking -----------------------------------------------------------
    def _clear_tripped(self) -> None:
        if not self.b.capabilities.bus_watchdog:
            return
        tripped = [
            i for i, v in self._read_answering("bus_watchdog").items() if v["bus_watchdog"] < 0
        ]
        if tripped:
            log.warning(
                "%s: Bus Watchdog tripped on servo(s) %s; cleared before the stop ramp",
                self.b.port,
                ", ".join(map(str, tripped)),
            )
            self._rearm()

    def _rearm(self) -> None:
        b = self.b
        b.write_watchdog(0)  # clears the trip (e-Manual control_table_buswatchdog)
        b.write_watchdog(b.watchdog_ticks)

    def check_watchdog(self) -> None:
        """Slow-rate read of the Bus Watchdog; a trip (reads -1) is cleared and recovered from."""
        b = self.b
        if not b.capabilities.bus_watchdog:
            return
        values = b.bus.sync_read("bus_watchdog", b.ids, fast=b.fast_read)
        tripped = [i for i, v in values.items() if v["bus_watchdog"] < 0]
        if tripped:
            self.recover_watchdog(tripped)

    def recover_watchdog(self, tripped: Sequence[int]) -> None:
        """Clear and re-arm, then slew the goals from where the servos stopped to the commands.

        WatchdogTripError when trips come more often than ``limits.max_watchdog_trips`` within
        ``limits.trip_window_s``.
        """
        b = self.b
        count = self.trips.add(b.clock())
        b.stats.extra["watchdog_trips"] = self.trips.total
        if count > self.limits.max_watchdog_trips:
            raise WatchdogTripError(
                b.port, tripped, count, self.limits.trip_window_s, b.watchdog_ticks * 0.02
            )
        log.warning(
            "%s: Bus Watchdog tripped on servo(s) %s (the servos stopped): cleared, "
            "re-armed, catching up at the joint speed limit",
            b.port,
            ", ".join(map(str, tripped)),
        )
        self._rearm()
        present = b.read_present_ticks()
        b.catch_up = CatchUp(present, b.max_ticks_per_s, b.clock())
        b.reset_tracking()

    def diagnose(self, stalls: Sequence[Stall]) -> None:
        """Joints stood still while their goals moved: recover a tripped watchdog, else raise."""
        b = self.b
        if b.capabilities.bus_watchdog:
            watchdog = b.bus.sync_read("bus_watchdog", b.ids)
            tripped = [i for i, v in watchdog.items() if v["bus_watchdog"] < 0]
            if tripped:
                self.recover_watchdog(tripped)
                return
        if b.capabilities.hardware_error_status:
            status = b.bus.sync_read(("torque_enable", "hardware_error_status"), b.ids)
            faults = {
                i: v["hardware_error_status"]
                for i, v in status.items()
                if v["hardware_error_status"]
            }
            if faults:
                raise b.fault_error(faults)
        else:
            status = b.bus.sync_read("torque_enable", b.ids)
            b.check_faults(every_servo=True)
        joints = [s.joint for s in stalls]
        ids = [b.ids[j] for j in joints]
        off = [i for i in ids if not status[i]["torque_enable"]]
        if off:
            reason = (
                f"Torque Enable reads 0 on servo(s) {', '.join(map(str, off))}: it rebooted "
                "(a supply dip or a loose cable?). Check power and wiring, then run again"
            )
        else:
            reason = (
                f"Torque is on and no fault is latched, yet the reading stood still for "
                f"{max(s.still_for_s for s in stalls):.1f} s while the goal moved: the "
                "joint is blocked or jammed, or its horn slipped. Free it and run again"
            )
        gain = b.converter.state_terms()
        present = [s.present_ticks * gain[s.joint][0] + gain[s.joint][1] for s in stalls]
        goal = [s.goal_ticks * gain[s.joint][0] + gain[s.joint][1] for s in stalls]
        raise TrackingError(b.port, joints, ids, present, goal, reason)
