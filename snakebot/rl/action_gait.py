"""A policy's action held as a gait: what both the learning environments and ``run --policy``
play through the runner's control cycle.

The action (d,) becomes a ``PhasedGait`` through the env's encoding; the gait is played at
phases that ``GaitClock`` turns by the gait time between control cycles, so the wave never jumps
when the next action changes the frequency. The environments hold each action for
``cycles_per_action`` cycles of a ``CycleLoop`` (``snakebot.rl.episode``); ``PolicyGait``
(``snakebot.rl.policy_gait``) is this gait deciding the action itself every 1/action_hz s. One
gait, one cycle: a policy plays in ``snakebot run`` as it was trained, by construction.
"""

from __future__ import annotations

import numpy.typing as npt

from snakebot.errors import GaitError
from snakebot.gaits import Gait, PhasedGait
from snakebot.gaits.base import FloatArray
from snakebot.rl.encodings import Encoding, GaitClock


class ActionGait(Gait):
    """The gait of the action last given to ``hold``, at phases integrated cycle by cycle.

    ``reset`` starts every phase at ``start_phase_rad`` with no action held; ``command(t)``
    turns the phases by the gait time since the previous command (``advance_to``) and returns
    the held gait's targets (N,) rad there.
    """

    def __init__(self, encoding: Encoding, start_phase_rad: float = 0.0) -> None:
        self.encoding = encoding
        self.joint_count = encoding.joint_count
        self.clock = GaitClock(encoding)
        self.start_phase_rad = float(start_phase_rad)
        self.held: PhasedGait | None = None
        self._last_time_s = 0.0
        self.reset()

    @property
    def uses_measured_pose(self) -> bool:
        """Between actions the targets depend on time only (the action is given)."""
        return False

    def reset(self) -> None:
        """Phases at ``start_phase_rad``, gait time 0, no action held."""
        self.clock.reset(self.start_phase_rad)
        self.held = None
        self._last_time_s = 0.0

    def hold(self, action: FloatArray) -> None:
        """Play ``action`` (d,) from the next command on."""
        self.held = self.encoding.gait(action)

    def advance_to(self, time_s: float) -> None:
        """Turn the phases at the held gait's rates up to gait time ``time_s``."""
        if self.held is not None and time_s > self._last_time_s:
            self.clock.advance(self.held, time_s - self._last_time_s)
        self._last_time_s = time_s

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Not defined: the targets depend on the actions as they come."""
        raise GaitError(
            "a policy's action gait has targets only as it runs (use command(), as the runner does)"
        )

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """Targets (N,) rad of the held action at gait time ``time_s``."""
        self.advance_to(time_s)
        if self.held is None:
            raise GaitError("no action held: hold(action) before the first cycle")
        return self.clock.targets(self.held)
