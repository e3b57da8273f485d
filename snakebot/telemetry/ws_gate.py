"""A gate in front of the Foxglove SDK's WebSocket server: Origin checked, clients bounded, a
client that stops reading disconnected.

The SDK (0.30) serves every client that asks: it has no hook to refuse one by its ``Origin`` or by
their number, nor to drop one that never reads. So the SDK server listens on a loopback port of
its own and this gate owns the address the user asked for. It reads each client's HTTP upgrade
request, refuses a browser page from another site (403) and a client beyond the limit (503), and
then copies the bytes both ways unchanged, so the client speaks to the SDK itself. The copy
applies back-pressure: while a client does not read, the gate stops reading the SDK's side for
it, so the SDK drops that client's oldest messages (its per-client backlog) and the control loop
never waits; a client that takes nothing for ``stall_s`` is disconnected and frees its place.
Everything runs on one asyncio thread; the control loop pays only for the SDK's queues of at
most ``max_clients`` clients.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import socket
import threading
from dataclasses import asdict, dataclass
from urllib.parse import urlsplit

FOXGLOVE_ORIGINS = ("https://app.foxglove.dev",)
MAX_CLIENTS = 8
STALL_S = 5.0  # a client that takes no byte for this long is gone
HANDSHAKE_S = 5.0  # to send the upgrade request
HEAD_LIMIT = 16 * 1024  # bytes of request line and headers
CHUNK = 64 * 1024
# What the kernel may hold for a client that does not read: small, so one that stops reading
# is noticed in seconds (Linux grows a socket's default send buffer to megabytes).
SEND_BUFFER = 64 * 1024
# The SDK writes one frame per message (about 1 kB each, 100+ a second): gathering what arrives
# within this long into one copy keeps the gate's wake-ups (and its share of the interpreter the
# control loop runs in) near 1 / COALESCE_S per client whatever the message rate. A live view
# does not notice 20 ms.
COALESCE_S = 0.02


@dataclass
class GateCounts:
    """What the gate did with its clients: ``accepted`` (passed to the SDK), ``refused_origin``
    (a browser page from another site), ``refused_full`` (beyond the limit), ``dropped_slow``
    (stopped reading for ``stall_s``), ``bad_request`` (no well-formed upgrade request in time)."""

    accepted: int = 0
    refused_origin: int = 0
    refused_full: int = 0
    dropped_slow: int = 0
    bad_request: int = 0

    def as_dict(self) -> dict[str, int]:
        """The counts by name."""
        return asdict(self)


def origin_allowed(origin: str | None, extra: tuple[str, ...] = ()) -> bool:
    """Whether a client sending ``Origin: origin`` may connect.

    None (no header: not a browser, e.g. the Foxglove desktop app or a script) and pages served
    from this machine (``http(s)://localhost``, ``127.x.y.z``, ``[::1]``, any port) may, as may
    Foxglove's web app and the origins in ``extra`` (exact, e.g. ``https://viz.example.org``).
    ``null`` (a sandboxed frame of any site) may not.
    """
    if origin is None:
        return True
    text = origin.strip().rstrip("/").lower()
    if text in FOXGLOVE_ORIGINS or text in {o.rstrip("/").lower() for o in extra}:
        return True
    try:
        parts = urlsplit(text)
        host = parts.hostname
    except ValueError:
        return False
    if parts.scheme not in ("http", "https") or not host:
        return False
    if host == "localhost" or host.endswith(".localhost"):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def listening_socket(host: str, port: int) -> socket.socket:
    """A TCP socket listening on ``host:port`` (0: any free port); OSError if it cannot."""
    family, kind, proto, _, address = socket.getaddrinfo(
        host.strip("[]"), port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
    )[0]
    sock = socket.socket(family, kind, proto)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(128)
        sock.setblocking(False)
    except BaseException:
        sock.close()
        raise
    return sock


class WebSocketGate:
    """Serves ``host:port`` in front of the SDK server on ``127.0.0.1:upstream_port``.

    Binding happens here, in the caller's thread: OSError when the address cannot be bound.
    ``stop`` closes the listener and every connection; idempotent.
    """

    def __init__(
        self,
        host: str,
        port: int,
        upstream_port: int,
        *,
        origins: tuple[str, ...] = (),
        max_clients: int = MAX_CLIENTS,
        stall_s: float = STALL_S,
    ) -> None:
        self.upstream_port = upstream_port
        self.origins = origins
        self.max_clients = max_clients
        self.stall_s = stall_s
        self.counts = GateCounts()
        self._clients = 0
        self._pending = 0
        self._sock = listening_socket(host, port)
        self.port = int(self._sock.getsockname()[1])
        self._loop = asyncio.new_event_loop()
        self._tasks: set[asyncio.Task[None]] = set()
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._run, name="foxglove-gate", daemon=True)
        self._thread.start()
        self._ready.wait()

    @property
    def clients(self) -> int:
        """Clients connected through the gate now."""
        return self._clients

    def _run(self) -> None:
        loop = self._loop
        asyncio.set_event_loop(loop)
        try:
            server = loop.run_until_complete(
                asyncio.start_server(self._serve, sock=self._sock, limit=HEAD_LIMIT)
            )
        finally:
            self._ready.set()
        try:
            loop.run_forever()
        finally:
            server.close()
            for task in list(self._tasks):
                task.cancel()
            loop.run_until_complete(asyncio.gather(*self._tasks, return_exceptions=True))
            loop.run_until_complete(server.wait_closed())
            loop.close()

    def stop(self) -> None:
        """Close the listener and every connection; idempotent."""
        if self._loop.is_closed():
            return
        with contextlib.suppress(RuntimeError):  # the loop has stopped already
            self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=10.0)

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        try:
            await self._handle(reader, writer)
        except (ConnectionError, OSError):
            pass
        except asyncio.CancelledError:
            pass  # stopping: ends the task quietly (3.11's stream callback re-raises otherwise)
        finally:
            self._tasks.discard(task)
            writer.close()

    async def _handle(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if self._pending >= 4 * self.max_clients + 16:  # a flood of half-open connections
            self.counts.refused_full += 1
            return
        self._pending += 1
        try:
            head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), HANDSHAKE_S)
            origins = _header_values(head, "origin")
        except (TimeoutError, asyncio.IncompleteReadError, asyncio.LimitOverrunError, ValueError):
            self.counts.bad_request += 1
            return
        finally:
            self._pending -= 1
        if len(origins) > 1 or not origin_allowed(origins[0] if origins else None, self.origins):
            self.counts.refused_origin += 1
            await _refuse(writer, 403, "Forbidden", "this origin may not connect to snakebot")
            return
        if self._clients >= self.max_clients:
            self.counts.refused_full += 1
            await _refuse(
                writer,
                503,
                "Service Unavailable",
                f"snakebot serves at most {self.max_clients} Foxglove clients",
            )
            return
        self._clients += 1
        try:
            self.counts.accepted += 1
            sock = writer.get_extra_info("socket")
            if sock is not None:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
            up_reader, up_writer = await asyncio.open_connection(
                "127.0.0.1", self.upstream_port, limit=CHUNK
            )
            try:
                up_writer.write(head)
                await self._pipe(reader, writer, up_reader, up_writer)
            finally:
                up_writer.close()
        finally:
            self._clients -= 1

    async def _pipe(
        self,
        reader: asyncio.StreamReader,
        writer: asyncio.StreamWriter,
        up_reader: asyncio.StreamReader,
        up_writer: asyncio.StreamWriter,
    ) -> None:
        up = asyncio.ensure_future(_copy(reader, up_writer, None, 0.0))
        down = asyncio.ensure_future(_copy(up_reader, writer, self.stall_s, COALESCE_S))
        try:
            await asyncio.wait({up, down}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            up.cancel()
            down.cancel()
        outcomes = await asyncio.gather(up, down, return_exceptions=True)
        if outcomes[1] is True:
            self.counts.dropped_slow += 1


async def _copy(
    source: asyncio.StreamReader,
    sink: asyncio.StreamWriter,
    stall_s: float | None,
    coalesce_s: float,
) -> bool:
    """Copy until ``source`` ends, at most one write per ``coalesce_s``; True when ``sink``
    took nothing for ``stall_s``."""
    high_water = sink.transport.get_write_buffer_limits()[1]
    while data := await source.read(CHUNK):
        sink.write(data)
        if coalesce_s:
            await asyncio.sleep(coalesce_s)
        if sink.transport.get_write_buffer_size() <= high_water:
            continue  # the common case, without wait_for's task per message
        try:
            await asyncio.wait_for(sink.drain(), stall_s)
        except TimeoutError:
            return True
    return False


def _header_values(head: bytes, name: str) -> list[str]:
    """The values of header ``name`` (lower case) in an HTTP request head; ValueError if the
    head is not one."""
    lines = head.decode("latin-1").split("\r\n")
    if not lines[0].startswith("GET ") or " HTTP/1." not in lines[0]:
        raise ValueError("not an HTTP GET")
    values = []
    for line in lines[1:]:
        key, sep, value = line.partition(":")
        if sep and key.strip().lower() == name:
            values.append(value.strip())
    return values


async def _refuse(writer: asyncio.StreamWriter, status: int, reason: str, text: str) -> None:
    body = (text + "\n").encode()
    writer.write(
        f"HTTP/1.1 {status} {reason}\r\nContent-Type: text/plain\r\n"
        f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n".encode()
        + body
    )
    with contextlib.suppress(ConnectionError, asyncio.TimeoutError):
        await asyncio.wait_for(writer.drain(), 1.0)
