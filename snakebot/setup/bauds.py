"""Which baud rates to look for servos at: each model's own Baud Rate table, as the port opens them.

A model's table (``snakebot.servo_tables``) lists the rates its Baud Rate register selects. Protocol
1.0 models count them as 2 000 000 / (value + 1) bit/s, so an AX-12A at value 34 runs 57 143 bit/s,
which a host UART opened at 57 600 hears (0.8 % apart; a UART frame tolerates a few per cent). The
rates here are the ones each vendor's port handler can open: ``dynamixel_sdk``'s, and
``scservo_sdk``'s with Feetech's own 76 800 (index 5), which the stock SDK refuses.
"""

from __future__ import annotations

from collections.abc import Iterable

from snakebot.families import ServoFamily
from snakebot.servo_tables import ServoTable, supported_models, table_for_model

PORT_BAUDS = (
    9600,
    19200,
    38400,
    57600,
    115200,
    230400,
    460800,
    500000,
    576000,
    921600,
    1_000_000,
    1_152_000,
    2_000_000,
    2_500_000,
    3_000_000,
    3_500_000,
    4_000_000,
)
"""Rates dynamixel_sdk's PortHandler opens (``getCFlagBaud``; 4.5 Mbps needs a custom handler)."""
FEETECH_PORT_BAUDS = (
    4800,
    9600,
    14400,
    19200,
    38400,
    57600,
    76800,
    115200,
    128000,
    250000,
    500000,
    1_000_000,
)
"""Rates snakebot's Feetech port handler opens: scservo_sdk's own list (ftservo-python-sdk 2.0.1
``getCFlagBaud``) and Feetech's 76 800 (baud index 5), which the stock list lacks
(``snakebot.backends.feetech.sdk``)."""
VENDOR_PORT_BAUDS = {"dynamixel": PORT_BAUDS, "feetech": FEETECH_PORT_BAUDS}
"""The rates the port handler of each vendor's SDK opens, by the model data's ``family``."""
TOLERANCE = 0.03
"""How far a servo's rate may lie from the port's for the two to hear each other."""
SLOW = 57600
"""Rates below this are searched last (a snake bus never runs that slow on purpose)."""


def port_rate(rate: int, opens: tuple[int, ...] = PORT_BAUDS) -> int | None:
    """The rate the port is opened at to talk to a servo running ``rate`` bit/s, of the rates
    the port handler ``opens`` (None: none)."""
    nearest = min(opens, key=lambda b: abs(b - rate))
    return nearest if abs(nearest - rate) <= TOLERANCE * rate else None


def port_bauds(table: ServoTable) -> tuple[int, ...]:
    """The rates the port handler of the SDK that talks to servos of ``table`` opens."""
    return VENDOR_PORT_BAUDS.get(table.family, PORT_BAUDS)


def factory_baud(table: ServoTable) -> int:
    """The rate a servo of this model answers at straight from the factory (or after a full
    Factory Reset), as the port opens it."""
    rate = table.baud_rates[table["baud_rate"].default]
    return port_rate(rate, port_bauds(table)) or rate


def baud_value(table: ServoTable, baud: int) -> int:
    """The Baud Rate register value that puts a servo of ``table`` at ``baud`` as the port opens
    it (1 Mbps -> 1 on an AX, 3 on an X); RegisterValueError listing the model's rates if none."""
    rates = sorted(table.baud_rates.items())
    opens = port_bauds(table)
    matches = [v for v, r in rates if r == baud] + [
        v for v, r in rates if port_rate(r, opens) == baud
    ]
    return matches[0] if matches else table.baud_index(baud)  # raises, naming the model's rates


def preferred(rates: Iterable[int], first: int | None = None) -> tuple[int, ...]:
    """``rates`` in search order: ``first``, then 1 Mbps, then upwards, the slow ones last."""
    pool = set(rates)
    head = [r for r in (first, 1_000_000) if r is not None and r in pool]
    rest = sorted(pool - set(head), key=lambda r: (r < SLOW, r))
    return (*dict.fromkeys(head), *rest)


def model_bauds(table: ServoTable) -> tuple[int, ...]:
    """Every rate a servo of ``table`` can be at, its factory rate first."""
    rates = {port_rate(r, port_bauds(table)) for r in table.baud_rates.values()} - {None}
    return preferred((r for r in rates if r is not None), factory_baud(table))


def family_bauds(family: ServoFamily, models: Iterable[str] | None = None) -> tuple[int, ...]:
    """Every rate any model speaking ``family`` can be at (of ``models``; default every model
    snakebot has data for), in search order, the most common factory rate first."""
    tables = [table_for_model(m) for m in (supported_models() if models is None else models)]
    speaking = [t for t in tables if family.speaks(t)]
    rates: set[int] = set()
    factory: dict[int, int] = {}
    for table in speaking:
        rates.update(model_bauds(table))
        rate = factory_baud(table)
        factory[rate] = factory.get(rate, 0) + 1
    first = max(factory, key=lambda r: (factory[r], r)) if factory else None
    return preferred(rates, first)
