"""How many keys a drive cycle applies: a few a cycle, and a flood (a paste) dropped.

A person types a few keys a second; a key held down repeats at about 30 a second. A paste
delivers thousands at once, and each key may plan a gait blend (milliseconds), so applying them
all in one cycle would stall the control loop for seconds, and playing them out over the
following cycles would keep the snake moving for as long after the paste. The gate passes up to
``per_cycle`` keys a cycle from a short backlog; when more than ``backlog`` keys wait, the input
is a flood: what waits is dropped, and so is every key until the input has been quiet for
``quiet_s``. Keys that make the snake safer (stop, halt) are never dropped. With ``backlog``
None (a script: every key is meant) nothing is dropped; the keys play out a few a cycle.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence

PER_CYCLE = 4
"""Keys applied in one control cycle at most (400 a second at 100 Hz)."""
BACKLOG = 32
"""Keys waiting at most: more at once than anyone types ahead."""
QUIET_S = 0.25
"""Drive seconds without a key that end a flood."""


class KeyGate:
    """Bounds the keys a cycle applies; ``dropped`` counts the keys of floods dropped so far,
    ``notice`` says what the last flood dropped (for the display). ``keeps(key)`` is true for
    the keys a flood never drops."""

    def __init__(
        self,
        keeps: Callable[[str], bool] = lambda key: False,
        *,
        per_cycle: int = PER_CYCLE,
        backlog: int | None = BACKLOG,
        quiet_s: float = QUIET_S,
    ) -> None:
        self.keeps = keeps
        self.per_cycle, self.backlog, self.quiet_s = per_cycle, backlog, quiet_s
        self.dropped = 0
        self.notice = ""
        self._waiting: deque[str] = deque()
        self._flood_until: float | None = None
        self._flood_dropped = 0

    @property
    def flooding(self) -> bool:
        """True while keys are being dropped (until the input has been quiet for ``quiet_s``)."""
        return self._flood_until is not None

    @property
    def waiting(self) -> int:
        """Keys admitted but not yet passed (a burst playing out)."""
        return len(self._waiting)

    def admit(self, keys: Sequence[str], now_s: float) -> list[str]:
        """The keys to apply at drive time ``now_s`` (s), given the ``keys`` that just arrived."""
        if self._flood_until is not None and not keys and now_s >= self._flood_until:
            self._flood_until = None
        backlog = self.backlog
        if (
            keys
            and backlog is not None
            and (self.flooding or len(self._waiting) + len(keys) > backlog)
        ):
            self._drop([*self._waiting, *keys], now_s)
        else:
            self._waiting.extend(keys)
        count = min(self.per_cycle, len(self._waiting))
        return [self._waiting.popleft() for _ in range(count)]

    def _drop(self, keys: Sequence[str], now_s: float) -> None:
        if self._flood_until is None:
            self._flood_dropped = 0
        kept = [key for key in keys if self.keeps(key)][: self.per_cycle]
        dropped = len(keys) - len(kept)
        self._waiting = deque(kept)
        self._flood_until = now_s + self.quiet_s
        self._flood_dropped += dropped
        self.dropped += dropped
        self.notice = f"ignored {self._flood_dropped} keys that came at once (a paste?)"
