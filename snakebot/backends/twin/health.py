"""Physics health of a twin run: is what MuJoCo computed something a real snake could do?

Sampled once per control period (never inside MuJoCo's step, so the physics is untouched):
floor and self penetration, time with no ground contact, time upside down, joint chatter,
stall time and joint speed against the servo's no-load speed; the mechanical work the servos
put in comes integrated over every physics step of the period (``readouts.step_work_j``).
Past a warning threshold the run's summary lists a warning; past a hard one the run stops with
``PhysicsHealthError`` at the time it happened. Thresholds and why: docs/physics.md.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass

import mujoco
import numpy as np

from snakebot.backends.native_cache import CompileError
from snakebot.backends.twin.health_c import ContactScan
from snakebot.backends.twin.readouts import Capsules, as_slice, positive_power_w
from snakebot.errors import PhysicsHealthError


@dataclass(frozen=True)
class HealthLimits:
    """Warning and hard thresholds of the twin's physics checks (docs/physics.md).

    Penetrations are fractions of the module's capsule radius; speeds fractions of the servo's
    no-load speed at the supply voltage; power the mean positive mechanical power of one joint
    over ``power_window_s``, as a fraction of the servo's peak power tau_stall * omega_0 / 4.
    ``chatter_warn`` is the share of control cycles in which a joint reverses (1.0 = at the
    control Nyquist rate). A cycle is airborne when no module touches the ground and the lowest
    module is more than ``contact_tolerance_m`` above z = 0 (contacts flicker on and off under
    a resting snake). ``hard`` False turns hard limits into warnings.
    """

    penetration_warn: float = 0.25
    penetration_error: float = 0.5
    airborne_warn: float = 0.05
    upside_down_warn: float | None = None
    chatter_warn: float = 0.25
    speed_warn: float = 1.05
    speed_error: float = 1.5
    power_warn: float = 0.5
    power_error: float = 1.0
    power_window_s: float = 1.0
    contact_tolerance_m: float = 0.002
    stall_warn_s: float = 2.0
    stall_torque_fraction: float = 0.95
    moving_fraction: float = 0.05
    hard: bool = True


DEFAULT_LIMITS = HealthLimits()
_ROWS = 512  # cycles judged per vectorised pass at most


class PythonScan:
    """The per-cycle scan of MjData in Python: what health_c.ContactScan does in C, the
    reference it is held to and the path without a compiler. ``scan(data)`` returns (floor
    penetration m, module-module penetration m, grounded, lowest capsule point m or None when
    grounded, fastest joint rad/s); the penetrations are -inf where there is no such contact."""

    def __init__(self, capsules: Capsules, is_link: np.ndarray, dof_index: np.ndarray) -> None:
        self._capsules = capsules
        self._is_link: list[bool] = is_link.tolist()
        self._dof = as_slice(dof_index)

    def scan(self, data: mujoco.MjData) -> tuple[float, float, bool, float | None, float]:
        """The scan of ``data`` now (see the class)."""
        floor = other = -math.inf
        grounded = False
        ncon = data.ncon
        if ncon:
            # A few dozen contacts: a Python pass over them costs less than numpy's reductions.
            contact = data.contact
            is_link = self._is_link
            for (first, second), dist in zip(
                contact.geom[:ncon].tolist(), contact.dist[:ncon].tolist(), strict=True
            ):
                if is_link[first] and is_link[second]:
                    if -dist > other:
                        other = -dist
                else:
                    grounded = True
                    if -dist > floor:
                        floor = -dist
        clearance = (
            None if grounded else float(self._capsules.clearance_m(data.geom_xpos, data.geom_xmat))
        )
        dof = self._dof
        velocity = data.qvel[dof]
        return floor, other, grounded, clearance, max(map(abs, velocity.tolist()))


class HealthMonitor:
    """Accumulates the health of one twin run; ``sample`` after every control period.

    ``capsules`` are the modules (readouts.Capsules); every other geom is ground.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        capsules: Capsules,
        dof_index: np.ndarray,
        head_id: int,
        *,
        no_load_speed_rad_s: float,
        torque_limit_nm: float,
        limits: HealthLimits = DEFAULT_LIMITS,
        compiled: bool = True,
    ) -> None:
        self.limits = limits
        # At most 30 attributes: past that CPython 3.11 stops sharing the instance dict's keys
        # and every attribute read in ``sample`` gets slower (callgrind counted it).
        is_link = np.zeros(model.ngeom, dtype=bool)
        is_link[capsules.geoms] = True
        self._scanner: ContactScan | PythonScan = PythonScan(capsules, is_link, dof_index)
        if compiled:  # without a compiler, the Python pass: the same figures, a little slower
            with contextlib.suppress(CompileError):
                self._scanner = ContactScan(model, capsules, is_link, dof_index)
        self._radius = float(capsules.radius_m.max())
        self._dof = as_slice(dof_index)
        self._head = head_id
        self._no_load = no_load_speed_rad_s
        self._torque_limit = torque_limit_nm
        self._peak_power_w = torque_limit_nm * no_load_speed_rad_s / 4.0
        joints = len(dof_index)
        self.cycles = 0
        self.time_s = 0.0
        self.max_floor_penetration_m = 0.0
        self.max_self_penetration_m = 0.0
        self._airborne_cycles = 0
        self._upside_down_cycles = 0
        self._reversals = np.zeros(joints)
        self._last_sign = np.zeros(joints)
        self._work_j = np.zeros(joints)
        self._window_work_j = np.zeros(joints)
        self._window_s = 0.0
        self.max_power_w = 0.0
        self.max_speed_rad_s = 0.0
        self._stall_carry_s = np.zeros(joints)
        self.longest_stall_s = 0.0
        self.total_stall_s = 0.0
        # Per-cycle velocities, torques and periods wait here and are judged in one vectorised
        # pass per power window: the per-cycle cost stays a few numpy calls.
        self._velocity = np.zeros((_ROWS, joints))
        self._torque = np.zeros((_ROWS, joints))
        self._work_rows = np.zeros((_ROWS, joints))
        self._dt = np.zeros(_ROWS)
        self._rows = 0
        # The data sampled last and views into it (joint speeds, head orientation), made once.
        self._views: tuple[mujoco.MjData, np.ndarray, np.ndarray] | None = None

    @property
    def scans_in_c(self) -> bool:
        """Whether this monitor scans MjData with the compiled scan (health_c), so a scan the
        twin's compiled period made of the same data (``sample``'s ``scanned``) is its own."""
        return type(self._scanner) is ContactScan

    def sample(
        self,
        data: mujoco.MjData,
        dt_s: float,
        force_nm: np.ndarray,
        work_j: np.ndarray | None = None,
        scanned: np.ndarray | None = None,
    ) -> None:
        """Account one control period ending now; raise PhysicsHealthError past a hard limit.

        ``force_nm`` (N,) is each servo's output torque now, ``work_j`` (N,) each joint's
        positive work over the period's physics steps (None: torque times speed now times
        ``dt_s``, the sampled estimate). ``scanned`` (5,) is the compiled scan of ``data`` now
        (``health_c.SCAN_FIELDS``, as the twin's compiled period makes it; only where
        ``scans_in_c``); None: the monitor scans ``data`` itself.
        """
        limits = self.limits
        views = self._views
        if views is None or views[0] is not data:
            views = self._views = (data, data.qvel[self._dof], data.xquat[self._head])
        _, qvel, head_quat = views
        self.cycles += 1
        self.time_s += dt_s
        if scanned is None:
            floor, other, _, clearance, speed = self._scanner.scan(data)
        else:
            floor, other, grounded, clearance, speed = scanned.tolist()
            if grounded:
                clearance = None
        if floor > self.max_floor_penetration_m:
            self.max_floor_penetration_m = floor
        if other > self.max_self_penetration_m:
            self.max_self_penetration_m = other
        if clearance is not None and clearance > limits.contact_tolerance_m:  # not grounded
            self._airborne_cycles += 1
        _, x, y, _ = head_quat.tolist()
        if 1.0 - 2.0 * (x * x + y * y) < -0.5:  # the head's up axis points down
            self._upside_down_cycles += 1

        # A fancy index (joints not at consecutive addresses) copies: read it every cycle.
        velocity = qvel if isinstance(self._dof, slice) else data.qvel[self._dof]
        row = self._rows
        self._velocity[row] = velocity
        self._torque[row] = force_nm
        if work_j is None:
            self._work_rows[row] = positive_power_w(force_nm, velocity) * dt_s
        else:
            self._work_rows[row] = work_j
        self._dt[row] = dt_s
        self._rows = row + 1
        if speed > self.max_speed_rad_s:
            self.max_speed_rad_s = speed
        self._window_s += dt_s

        time_s = float(data.time)
        depth_limit = limits.penetration_error * self._radius
        worst = max(self.max_floor_penetration_m, self.max_self_penetration_m)
        if limits.hard and worst > depth_limit:
            raise PhysicsHealthError(
                time_s,
                "penetration",
                f"{worst * 1e3:.1f} mm into the ground or another "
                f"module (capsule radius {self._radius * 1e3:.1f} mm; limit "
                f"{depth_limit * 1e3:.1f} mm)",
            )
        if limits.hard and self.max_speed_rad_s > limits.speed_error * self._no_load:
            raise PhysicsHealthError(
                time_s,
                "joint speed",
                f"{self.max_speed_rad_s:.2f} rad/s, above "
                f"{limits.speed_error:g} x the servo's no-load speed {self._no_load:.2f} rad/s",
            )
        window_done = self._window_s >= limits.power_window_s - 1e-9
        if window_done or self._rows == _ROWS:
            self._judge_rows()
        if window_done:
            power_w = float(self._window_work_j.max(initial=0.0)) / self._window_s
            self.max_power_w = max(self.max_power_w, power_w)
            self._window_work_j[:] = 0.0
            self._window_s = 0.0
            if limits.hard and power_w > limits.power_error * self._peak_power_w:
                raise PhysicsHealthError(
                    time_s,
                    "energy injected",
                    f"a joint put in {power_w:.2f} W over "
                    f"{limits.power_window_s:g} s; the servo's peak is {self._peak_power_w:.2f} W",
                )

    def _judge_rows(self) -> None:
        """Work, chatter and stall of the cycles waiting since the last pass."""
        rows = self._rows
        if rows == 0:
            return
        self._rows = 0
        limits = self.limits
        velocity, torque, dt = self._velocity[:rows], self._torque[:rows], self._dt[:rows]
        work = self._work_rows[:rows].sum(axis=0)
        self._work_j += work
        self._window_work_j += work
        moving = np.abs(velocity) > limits.moving_fraction * self._no_load
        # Chatter: a reversal is a moving sign opposite to the last moving sign before it.
        signs = np.vstack([self._last_sign, np.where(moving, np.sign(velocity), 0.0)])
        index = np.arange(rows + 1)[:, None]
        last = np.maximum.accumulate(np.where(signs != 0, index, 0), axis=0)
        held = np.take_along_axis(signs, last, axis=0)
        self._reversals += ((signs[1:] * held[:-1]) < 0).sum(axis=0)
        self._last_sign = held[-1].copy()
        # Stall: time since the last cycle that was not stalled (or before this pass, carried).
        stalled = (np.abs(torque) >= limits.stall_torque_fraction * self._torque_limit) & ~moving
        self.total_stall_s += float((stalled * dt[:, None]).sum())
        ends = np.concatenate([[0.0], np.cumsum(dt)])
        free = np.vstack([np.ones((1, stalled.shape[1]), dtype=bool), ~stalled])
        since = np.maximum.accumulate(np.where(free, index, 0), axis=0)
        streak = ends[:, None] - ends[since] + np.where(since == 0, self._stall_carry_s, 0.0)
        streak = np.where(stalled, streak[1:], 0.0)
        self.longest_stall_s = max(self.longest_stall_s, float(streak.max(initial=0.0)))
        self._stall_carry_s = streak[-1].copy()

    @property
    def chatter(self) -> float:
        """Worst joint's share of control cycles with a velocity reversal (1 = Nyquist)."""
        self._judge_rows()
        return float(self._reversals.max(initial=0.0)) / max(self.cycles, 1)

    def summary(self) -> dict[str, object]:
        """JSON-ready health figures and the warnings past ``limits`` (docs/physics.md)."""
        self._judge_rows()
        limits = self.limits
        cycles = max(self.cycles, 1)
        airborne = self._airborne_cycles / cycles
        upside_down = self._upside_down_cycles / cycles
        out: dict[str, object] = {
            "max_floor_penetration_mm": self.max_floor_penetration_m * 1e3,
            "max_self_penetration_mm": self.max_self_penetration_m * 1e3,
            "airborne_fraction": airborne,
            "upside_down_fraction": upside_down,
            "chatter": self.chatter,
            "energy_injected_j": float(self._work_j.sum()),
            "max_joint_power_w": self.max_power_w,
            "servo_peak_power_w": self._peak_power_w,
            "max_joint_speed_rad_s": self.max_speed_rad_s,
            "no_load_speed_rad_s": self._no_load,
            "longest_stall_s": self.longest_stall_s,
            "total_stall_s": self.total_stall_s,
        }
        warnings: list[str] = []
        radius_mm = self._radius * 1e3
        depths = (("floor", self.max_floor_penetration_m), ("self", self.max_self_penetration_m))
        for what, depth in depths:
            if depth > limits.penetration_warn * self._radius:
                warnings.append(
                    f"{what} penetration {depth * 1e3:.1f} mm is over "
                    f"{limits.penetration_warn:.0%} of the {radius_mm:.1f} mm capsule radius"
                )
        if airborne > limits.airborne_warn:
            warnings.append(f"no ground contact for {airborne:.0%} of the control cycles")
        if limits.upside_down_warn is not None and upside_down > limits.upside_down_warn:
            warnings.append(f"the head was upside down {upside_down:.0%} of the time")
        if self.chatter > limits.chatter_warn:
            warnings.append(
                f"joints chatter: a joint reversed in {self.chatter:.0%} of the control cycles "
                "(100 % = the control rate's Nyquist frequency)"
            )
        if self.max_speed_rad_s > limits.speed_warn * self._no_load:
            warnings.append(
                f"joint speed {self.max_speed_rad_s:.2f} rad/s beyond the servo's no-load speed "
                f"{self._no_load:.2f} rad/s"
            )
        if self.max_power_w > limits.power_warn * self._peak_power_w:
            warnings.append(
                f"a joint put in {self.max_power_w:.2f} W on average over "
                f"{limits.power_window_s:g} s, over {limits.power_warn:.0%} of the servo's "
                f"{self._peak_power_w:.2f} W peak"
            )
        if self.longest_stall_s > limits.stall_warn_s:
            warnings.append(f"a servo stalled at its torque limit for {self.longest_stall_s:.1f} s")
        out["warnings"] = warnings
        return out
