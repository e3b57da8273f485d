"""Per-servo fault settings of the emulated bus and the seeded decisions that apply them."""

from __future__ import annotations

import random
from dataclasses import dataclass, replace

from snakebot.emulation.virtual_servo import VirtualServo

HEADER_BYTES = 7


@dataclass(frozen=True)
class Faults:
    """What goes wrong with one servo's traffic.

    `silent`: off the bus (hears nothing, answers nothing). `drop_next`/`drop_probability`: replies
    lost on the wire after the instruction ran. `corrupt_next`/`corrupt_probability`: one byte after
    the header flipped. `delay_s`: extra latency before each reply.
    """

    silent: bool = False
    drop_next: int = 0
    drop_probability: float = 0.0
    corrupt_next: int = 0
    corrupt_probability: float = 0.0
    delay_s: float = 0.0


NO_FAULTS = Faults()


class FaultBook:
    """Fault settings by servo, with one seeded random source so runs repeat exactly."""

    def __init__(self, seed: int = 0) -> None:
        self._faults: dict[VirtualServo, Faults] = {}
        self._rng = random.Random(seed)

    def get(self, servo: VirtualServo) -> Faults:
        """The settings for `servo` (no faults unless set)."""
        return self._faults.get(servo, NO_FAULTS)

    def update(self, servo: VirtualServo, **changes: float | int | bool) -> None:
        """Change some settings of `servo`, keeping the others."""
        self._faults[servo] = replace(self.get(servo), **changes)  # type: ignore[arg-type]

    def clear(self, servo: VirtualServo | None = None) -> None:
        """Remove the faults of `servo`, or of every servo."""
        if servo is None:
            self._faults.clear()
        else:
            self._faults.pop(servo, None)

    def hears(self, servo: VirtualServo) -> bool:
        """Whether the servo is on the bus at all."""
        return not self.get(servo).silent

    def filter_reply(self, servo: VirtualServo, data: bytes) -> bytes | None:
        """Apply drop and corruption to one reply; None means the bytes never arrive."""
        faults = self.get(servo)
        if faults == NO_FAULTS:
            return data
        if faults.drop_next > 0:
            self.update(servo, drop_next=faults.drop_next - 1)
            return None
        if faults.drop_probability and self._rng.random() < faults.drop_probability:
            return None
        corrupt = faults.corrupt_next > 0
        if corrupt:
            self.update(servo, corrupt_next=faults.corrupt_next - 1)
        elif faults.corrupt_probability:
            corrupt = self._rng.random() < faults.corrupt_probability
        if not corrupt or len(data) <= HEADER_BYTES:
            return data
        garbled = bytearray(data)
        garbled[self._rng.randrange(HEADER_BYTES, len(data))] ^= self._rng.randrange(1, 256)
        return bytes(garbled)

    def delay_s(self, servo: VirtualServo) -> float:
        """Extra latency of the servo's replies."""
        return self.get(servo).delay_s
