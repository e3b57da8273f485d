"""The backend contract: what the runner needs from a twin or a real servo chain.

Everything here is SI (radians, seconds, newton-metres); servo ticks never cross this boundary.
What only some backends can do (body state, IMU, health readings, physics checks, current
sensing, reset) is not here: each is a protocol in ``capabilities.py`` a backend has or has not.
"""

from __future__ import annotations

import abc
import logging
from types import TracebackType

import numpy as np

from snakebot.errors import BackendStateError
from snakebot.types import (
    CycleStats,
    JointCommand,
    JointState,
    PDGains,
    StopPolicy,
)

log = logging.getLogger(__name__)


class Backend(abc.ABC):
    """A chain of N position-controlled joints that time passes for.

    Lifecycle: ``connect`` once, then any number of read/send/advance calls, then ``close``
    (idempotent). Use it as a context manager so ``close`` always runs and the servos end safe.
    """

    joint_count: int
    stop_policy: StopPolicy = "hold"

    def __init__(self) -> None:
        self._connected = False
        self._closed = False
        self.stats = CycleStats()
        self.torque_enabled = False
        self.last_state: JointState | None = None
        """What ``read_state`` returned last (None before the first): a reader that must not
        cost another bus transaction asks this."""
        self.hurry_stop = False
        """Set when a KeyboardInterrupt is on its way out through the context manager (a second
        Ctrl-C or SIGTERM while the runner was already ramping out): the stop ramp then runs at
        the joint speed limit. A hurried stop still ends in the stop policy."""

    # -- lifecycle -------------------------------------------------------------------------
    def connect(self) -> None:
        """Open the backend (build the model / open the port); fails if already connected."""
        if self._connected:
            raise BackendStateError(f"{type(self).__name__} is already connected")
        if self._closed:
            raise BackendStateError(f"{type(self).__name__} was closed; create a new one")
        self._connect()
        self._connected = True

    def close(self) -> None:
        """Leave the joints safe (ramp, then hold or limp per ``stop_policy``) and release.

        Raises what kept the servos from being left safe (e.g. BusError when the port is gone);
        a KeyboardInterrupt that arrived during the stop is raised after the stop policy.
        """
        if not self._connected or self._closed:
            self._closed = True
            return
        try:
            self._close()
        finally:
            self._closed = True
            self._connected = False

    @property
    def connected(self) -> bool:
        """True between a successful ``connect`` and ``close``."""
        return self._connected

    def _safe_point(self) -> None:
        """Called at the start of every cycle call: where a backend that holds the stop signals
        back while connected raises the ones that came (the Dynamixel backend does)."""
        return None

    def _require_connected(self) -> None:
        if not self._connected:
            state = "closed" if self._closed else "not connected"
            raise BackendStateError(f"{type(self).__name__} is {state}: call connect() first")

    def __enter__(self) -> Backend:
        self.connect()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc is None:
            self.close()
            return
        self.hurry_stop = self.hurry_stop or isinstance(exc, KeyboardInterrupt)
        try:
            self.close()
        except Exception as error:  # the error already on its way out says what went wrong first
            log.warning("also, while stopping: %s", error)
            exc.add_note(f"while stopping: {error}")

    # -- the cycle ---------------------------------------------------------------------------
    def read_state(self) -> JointState:
        """Measured joint positions, velocities and efforts now (kept as ``last_state``)."""
        self._require_connected()
        self._safe_point()
        self.last_state = state = self._read_state()
        return state

    def send_command(self, command: JointCommand) -> None:
        """Set goal positions (rad, shape (N,)); takes effect as time advances."""
        self._require_connected()
        self._safe_point()
        position = np.asarray(command.position_rad, dtype=float)
        if position.shape != (self.joint_count,):
            raise ValueError(
                f"command has shape {position.shape}, expected ({self.joint_count},) joint angles"
            )
        self._send_command(position)

    def set_gains(self, gains: PDGains) -> None:
        """Apply position-loop gains to every joint: stiffness (N·m/rad) and damping (N·m·s/rad).

        Each backend realises them its own way (the twin as they are, a servo chain in its
        registers, rounded and clipped to what they reach)."""
        self._require_connected()
        self._safe_point()
        self._set_gains(gains)

    def set_torque(self, enabled: bool) -> None:
        """Enable or disable the joints' torque (disabled joints go limp)."""
        self._require_connected()
        self._safe_point()
        self._set_torque(enabled)
        self.torque_enabled = enabled

    def advance(self, dt_s: float) -> None:
        """Let ``dt_s`` seconds of robot time pass (the twin steps; hardware sleeps)."""
        self._require_connected()
        self._safe_point()
        if not dt_s > 0:
            raise ValueError(f"advance needs a positive time step, got {dt_s!r} s")
        self._advance(dt_s)

    def check_rate(self, rate_hz: float) -> None:
        """Raise ConfigError (``RateTooHighError`` on a servo bus) when the backend cannot hold
        a ``rate_hz`` control rate, saying the most it can; no bus traffic, connected or not.
        The default holds any rate (a simulation takes its own time)."""
        return None

    @property
    def time_s(self) -> float:
        """Robot time now, in seconds."""
        return self.read_state().time_s

    # -- what an implementation provides ------------------------------------------------------
    @abc.abstractmethod
    def _connect(self) -> None: ...

    @abc.abstractmethod
    def _close(self) -> None: ...

    @abc.abstractmethod
    def _read_state(self) -> JointState: ...

    @abc.abstractmethod
    def _send_command(self, position_rad: np.ndarray) -> None: ...

    @abc.abstractmethod
    def _set_gains(self, gains: PDGains) -> None: ...

    @abc.abstractmethod
    def _set_torque(self, enabled: bool) -> None: ...

    @abc.abstractmethod
    def _advance(self, dt_s: float) -> None: ...
