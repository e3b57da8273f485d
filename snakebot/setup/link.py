"""One serial port for the setup tools: a ServoBus whose baud rate they switch, raw probes.

The link under it is the family's vendor's (``snakebot.backends.chain.links``: the Dynamixel
SDK, or Feetech's ``scservo_sdk``). Device paths (``/dev/ttyUSB0``, ``COM3``) open through the
vendor SDK's port handler, the emulator's ``dxlemu://NAME`` URLs through pyserial's
``serial_for_url``. Any other URL is refused before
anything opens (snakebot.config.ports, checked by ServoBus): ``socket://`` would connect to a
host, ``spy://...?file=`` truncate a file.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from types import TracebackType
from typing import Any

from snakebot.backends.chain import links
from snakebot.backends.chain.bus import ServoBus
from snakebot.backends.chain.faults import ServoStatusError
from snakebot.backends.dynamixel import sdk
from snakebot.errors import BusError
from snakebot.families import ServoFamily, family_for
from snakebot.servo import FACTORY_BAUD
from snakebot.servo_tables import supported_models, table_for_model
from snakebot.setup.errors import VerifyError

SEARCH_BAUDS = (FACTORY_BAUD, 1_000_000, 115200, 2_000_000, 3_000_000, 4_000_000, 9600)
"""Rates searched for a servo, factory default first (4.5 Mbps needs a custom port handler)."""


def model_of(family: ServoFamily) -> str:
    """A model that speaks ``family`` (its control table names the registers a search reads):
    the XL430-W250 where it can, else the first by name of the models snakebot has data for."""
    for name in ("XL430-W250", *sorted(supported_models())):
        if family.speaks(table_for_model(name)):
            return name
    raise LookupError(f"no servo model speaks {family.name}")  # every family ships one


def search_order(first: int) -> tuple[int, ...]:
    """:data:`SEARCH_BAUDS` with ``first`` tried first."""
    return (first, *(b for b in SEARCH_BAUDS if b != first))


@dataclass(frozen=True)
class Probe:
    """What ``tries`` raw pings of one ID got: clean replies (model numbers), corrupt, silent."""

    servo_id: int
    baud: int
    models: tuple[int, ...]
    corrupt: int
    silent: int

    @property
    def model(self) -> int | None:
        """The model number if every reply was clean and agreed, else None."""
        if self.corrupt or len(set(self.models)) != 1:
            return None
        return self.models[0]

    @property
    def collides(self) -> bool:
        """Whether the replies look like two servos answering at once."""
        return self.corrupt > 0 or len(set(self.models)) > 1

    def clash(self) -> str:
        """Why the replies look like several servos ("" when they do not)."""
        if self.corrupt:
            total = self.corrupt + len(self.models) + self.silent
            return f"{self.corrupt} of {total} ping replies were corrupt"
        models = sorted(set(self.models))
        if len(models) > 1:
            return f"ping replies name different models ({', '.join(map(str, models))})"
        return ""


class Link:
    """A port opened for setup: ``bus`` (registers by name, typed errors) at a switchable rate.

    ``model`` picks the control table register names resolve in (X-series servos share it;
    default: a model ``family`` speaks, else the XL430-W250); ``protocol`` the family spoken
    (None: the model's default; ConfigError if the model cannot speak it), or ``family`` names
    it. :meth:`speak` switches the family on the same open port (``scan`` tries each).
    """

    def __init__(
        self,
        port: str,
        baud: int,
        *,
        model: str | int | None = None,
        protocol: float | None = None,
        family: ServoFamily | None = None,
        retries: int = 2,
    ) -> None:
        self.port = port
        self.handler: Any
        if model is None:
            model = "XL430-W250" if family is None else model_of(family)
        if family is not None:
            protocol = family.protocol
        self.family: ServoFamily = family_for(table_for_model(model), protocol)
        # The bus checks the port (snakebot.config.ports) before it builds the handler.
        self.bus = ServoBus(
            port,
            baud,
            model=model,
            family=self.family,
            retries=retries,
            port_handler_factory=self._make_handler,
        )
        self._raw: links.Link = links.link_for(self.handler, self.family)
        self._open = False

    def speak(self, family: ServoFamily) -> None:
        """Talk ``family``'s protocol from now on, on the same port at the same rate (the
        bus keeps its retries, and its control table where ``family`` speaks the model). A
        family of another vendor has its own SDK: the port is reopened through its handler."""
        if family == self.family:
            return
        old = self.bus
        model = old.table.model if family.speaks(old.table) else model_of(family)
        same_sdk = family.vendor == self.family.vendor
        if not same_sdk:
            old.close()
            self._open = False
        self.family = family
        self.bus = ServoBus(
            self.port,
            old.baud,
            family=family,
            model=model,
            retries=old.retries,
            port_handler_factory=(lambda _port: self.handler) if same_sdk else self._make_handler,
        )
        self._raw = links.link_for(self.handler, family)

    def _make_handler(self, port: str) -> Any:
        self.handler = links.port_handler_for(port, self.family)
        return self.handler

    def __enter__(self) -> Link:
        self.at(self.bus.baud)
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """Close the port (idempotent)."""
        self.bus.close()
        self._open = False

    @property
    def baud(self) -> int:
        """The rate the port is at."""
        return self.bus.baud

    def clock_s(self) -> float:
        """Seconds on the port's clock: the SDK's ``getCurrentTime`` (wall time on a real port,
        the emulated bus clock behind ``dxlemu://``, where time passes only with traffic)."""
        now_ms: float = getattr(self.handler, "getCurrentTime")()  # noqa: B009 - SDK, untyped
        return now_ms / 1000.0

    def at(self, baud: int) -> ServoBus:
        """The bus, with the port (re)opened at ``baud`` if it is not there already."""
        if not self._open or self.bus.baud != baud:
            self.bus.baud = baud
            self.bus.open()
            self._open = True
        return self.bus

    @contextmanager
    def retries(self, count: int) -> Iterator[ServoBus]:
        """The bus with ``retries`` set to ``count`` for the block (searches fail fast)."""
        saved = self.bus.retries
        self.bus.retries = count
        try:
            yield self.bus
        finally:
            self.bus.retries = saved

    def probe(self, servo_id: int, baud: int, tries: int = 2, *, patient: bool = False) -> Probe:
        """Ping ``servo_id`` at ``baud`` up to ``tries`` times without retries; classify replies.

        Unless ``patient``, a first ping that gets no reply at all ends the probe (an absent ID
        costs one timeout, about 35 ms on a real port).
        """
        self.at(baud)
        models, corrupt, silent = [], 0, 0
        for attempt in range(tries):
            if attempt and silent == attempt and not patient:
                break
            model, result, _error = self.bus.run(
                [servo_id], "ping", lambda: self._raw.ping(servo_id)
            )
            if result == sdk.COMM_SUCCESS:
                models.append(model)
            elif result in (sdk.COMM_RX_CORRUPT, sdk.COMM_RX_FAIL):
                corrupt += 1
            elif result == sdk.COMM_PORT_BUSY:
                self._raw.release()
                silent += 1
            else:
                silent += 1
        return Probe(servo_id, baud, tuple(models), corrupt, silent)

    def broadcast(self, baud: int) -> tuple[dict[int, tuple[int, int]], bool]:
        """A broadcast ping at ``baud``: ``({id: (model number, firmware)}, garbled)``.

        ``garbled`` says the SDK was left with bytes it could not parse (a reply slot garbled by
        a collision or noise; the SDK drops that slot). Slow: the SDK always waits its whole
        window (about 0.8 s at 1 Mbps).
        """
        self.at(baud)
        found, result = self.bus.run([], "broadcast ping", self._raw.broadcast_ping)
        if result == sdk.COMM_PORT_BUSY:
            self._raw.release()
        pinged = {int(i): (int(v[0]), int(v[1])) for i, v in found.items()}
        return pinged, result in (sdk.COMM_RX_CORRUPT, sdk.COMM_RX_FAIL)

    def listening(self, baud: int) -> set[int]:
        """The IDs answering at ``baud``: a broadcast ping (about a second), or in a family without
        one (Protocol 1.0) every ID pinged on its own (one SDK timeout, about 34 ms, per silent
        ID: some 9 s for all 254)."""
        if self.family.broadcast_ping:
            return set(self.at(baud).broadcast_ping())
        return {
            i
            for i in range(self.family.max_id + 1)
            if (probe := self.probe(i, baud, tries=1)).models or probe.corrupt
        }

    def unlock(self, servo_id: int, baud: int) -> None:
        """Open the family's EEPROM lock on one servo, so the EEPROM writes that follow are
        saved (Feetech Lock 0); nothing where the family has no such lock. Verified."""
        lock = self.family.eeprom_lock
        if lock is not None and lock.key in self.bus.table:
            self._write_lock(servo_id, baud, lock.key, lock.unlocked)

    def relock(self, servo_id: int, baud: int) -> None:
        """Close the family's EEPROM lock again (Feetech Lock 1, its power-on value), after the
        EEPROM writes that :meth:`unlock` opened it for; nothing where there is none."""
        lock = self.family.eeprom_lock
        if lock is not None and lock.key in self.bus.table:
            self._write_lock(servo_id, baud, lock.key, lock.locked)

    def _write_lock(self, servo_id: int, baud: int, key: str, value: int) -> None:
        bus = self.at(baud)
        bus.write(servo_id, key, value)
        back = bus.read(servo_id, key)
        if back != value:
            raise VerifyError(self.port, servo_id, key, value, back)

    def raw_read(self, servo_id: int, address: int, length: int) -> tuple[list[int], int]:
        """One Read without retries: (data, SDK result code); for collision checks."""
        data, result, _error = self.bus.run(
            [servo_id], "read", lambda: self._raw.read(servo_id, address, length)
        )
        return data, result

    def ping_clean(self, servo_id: int, baud: int, tries: int = 2) -> int | None:
        """The model number if ``servo_id`` answers cleanly at ``baud`` (None if silent)."""
        probe = self.probe(servo_id, baud, tries)
        return probe.models[0] if probe.models and not probe.collides else None


def answering(probes: Sequence[Probe]) -> list[Probe]:
    """The probes that got any reply at all (clean or corrupt)."""
    return [p for p in probes if p.models or p.corrupt]


@contextmanager
def unanswered_ok() -> Iterator[None]:
    """Ignore a missing or garbled status (an ID or baud change may lose it); not a servo error.

    The caller then verifies by finding the servo again.
    """
    try:
        yield
    except ServoStatusError:
        raise
    except BusError:
        pass
