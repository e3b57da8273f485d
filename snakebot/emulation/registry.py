"""In-process registry of emulated chains, addressed by `dxlemu://<name>` URLs."""

from __future__ import annotations

import itertools
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import serial

from snakebot.backends.dynamixel.sdk import register_url_port_handler
from snakebot.config.ports import EMULATOR_SCHEME
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.errors import EmulationError

SCHEME = EMULATOR_SCHEME
HANDLER_PACKAGE = "snakebot.emulation.urlhandler"
TIME_MODES = ("virtual", "wall")

_chains: dict[str, EmulatedChain] = {}
_names = itertools.count()
_lock = threading.Lock()


def install_url_handler() -> None:
    """Let `serial.serial_for_url` open `dxlemu://` URLs and the chain's links open them: the
    Dynamixel link with `EmulatedPortHandler`, the Feetech link with `EmulatedScsPortHandler`
    (one scheme; idempotent)."""
    if HANDLER_PACKAGE not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append(HANDLER_PACKAGE)
    from snakebot.backends.feetech import sdk as feetech_sdk  # imports scservo_sdk
    from snakebot.emulation.port import EmulatedPortHandler  # imports dynamixel_sdk
    from snakebot.emulation.port_feetech import EmulatedScsPortHandler

    register_url_port_handler(SCHEME, EmulatedPortHandler)
    feetech_sdk.register_url_port_handler(SCHEME, EmulatedScsPortHandler)


def chain_url(name: str, *, time: str = "virtual") -> str:
    """The URL of a registered chain; `time` is "virtual" (default) or "wall" (see the handler)."""
    if time not in TIME_MODES:
        raise EmulationError(f"time mode {time!r} is not one of {', '.join(TIME_MODES)}")
    return f"{SCHEME}://{name}" + ("" if time == "virtual" else f"?time={time}")


def register_chain(chain: EmulatedChain, name: str | None = None, *, time: str = "virtual") -> str:
    """Register `chain` under `name` (a fresh "busN" if None) and return its URL."""
    install_url_handler()
    with _lock:
        if name is None:
            name = f"bus{next(_names)}"
            while name in _chains:
                name = f"bus{next(_names)}"
        elif name in _chains and _chains[name] is not chain:
            raise EmulationError(f"an emulated chain is already registered as {name!r}")
        _chains[name] = chain
    return chain_url(name, time=time)


def unregister_chain(name: str) -> None:
    """Forget the chain registered under `name` (no error if there is none)."""
    with _lock:
        _chains.pop(name, None)


def lookup_chain(name: str) -> EmulatedChain:
    """The chain registered under `name`; EmulationError listing the registered names if none."""
    with _lock:
        chain = _chains.get(name)
        known = sorted(_chains)
    if chain is None:
        raise EmulationError(
            f"no emulated chain registered as {name!r} (registered: {known or 'none'}); "
            "call snakebot.emulation.register_chain(chain, name) first"
        )
    return chain


@contextmanager
def registered(
    chain: EmulatedChain, name: str | None = None, *, time: str = "virtual"
) -> Iterator[str]:
    """Register `chain` for the duration of a `with` block; yields its URL."""
    url = register_chain(chain, name, time=time)
    try:
        yield url
    finally:
        unregister_chain(url.split("://", 1)[1].split("?", 1)[0])
