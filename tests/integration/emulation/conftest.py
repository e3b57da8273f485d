"""Fixtures: a 12-servo emulated snake bus behind the unmodified ROBOTIS SDK."""

from collections.abc import Iterator

import dynamixel_sdk as dxl
import pytest

from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler

BAUD = 1_000_000
IDS = list(range(1, 13))


@pytest.fixture
def chain() -> EmulatedChain:
    return make_chain_for_ids("XM430-W350", IDS, BAUD)


@pytest.fixture
def port(chain: EmulatedChain) -> Iterator[EmulatedPortHandler]:
    with registered(chain) as url:
        handler = EmulatedPortHandler(url)
        assert handler.openPort() and handler.setBaudRate(BAUD)
        yield handler
        handler.closePort()


@pytest.fixture
def packet_handler() -> dxl.Protocol2PacketHandler:
    return dxl.PacketHandler(2.0)
