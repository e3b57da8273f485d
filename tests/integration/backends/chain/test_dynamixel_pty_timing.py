"""Over a real pseudo-terminal the far end is a process: a reply a busy emulator sends 60 ms late
is still a reply, while a servo silent for longer is still reported missing.

The stock dynamixel_sdk over snakebot's own PtyServer (in-process thread), through the port
handler the backend uses for device paths.
"""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest

from snakebot.backends.chain import ServoBus
from snakebot.backends.dynamixel.sdk import is_pseudo_terminal
from snakebot.emulation import EmulatedChain, make_chain_for_ids
from snakebot.errors import BusError

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


@pytest.fixture
def served() -> Iterator[tuple[EmulatedChain, str]]:
    from snakebot.emulation.pty_server import PtyServer

    chain = make_chain_for_ids("XL430-W250", range(1, 4), baud=1_000_000)
    with PtyServer(chain) as server:
        yield chain, server.device_path


def test_a_reply_a_busy_emulator_sends_late_is_still_taken(
    served: tuple[EmulatedChain, str],
) -> None:
    chain, device = served
    assert is_pseudo_terminal(device)
    chain.delay_replies(2, 0.06)  # past the SDK's own ~34 ms timeout
    bus = ServoBus(device, 1_000_000)
    with bus:
        assert bus.read(2, "id") == 2
        assert bus.retry_counts[2] == 0
        chain.delay_replies(2, 1.0)  # a servo that is really gone (later than every retry)
        with pytest.raises(BusError, match="There is no status packet"):
            bus.read(2, "id")
