"""A minimal Foxglove WebSocket client (foxglove.sdk.v1) for the tests."""

from __future__ import annotations

import contextlib
import json
import struct
import time
from collections import defaultdict
from typing import Any

from websockets.sync.client import ClientConnection, connect

# The SDK server (0.30) speaks foxglove.sdk.v1, the successor of ws-protocol's
# foxglove.websocket.v1 (same framing); it refuses a client offering only the old name.
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
MESSAGE_DATA = 0x01


class FoxgloveClient:
    """Connects, reads the advertised channels, subscribes by topic, collects decoded JSON."""

    def __init__(self, url: str, timeout_s: float = 20.0) -> None:
        self._stack = contextlib.ExitStack()
        self.ws: ClientConnection = self._stack.enter_context(
            connect(url, subprotocols=SUBPROTOCOLS, open_timeout=timeout_s)
        )
        self.server_info: dict[str, Any] = {}
        self.channels: dict[str, dict[str, Any]] = {}  # topic -> advertisement
        self.messages: dict[str, list[tuple[int, Any]]] = defaultdict(list)  # topic -> (ns, msg)
        self._by_subscription: dict[int, str] = {}

    def read_advertisements(self, topics: set[str], timeout_s: float = 20.0) -> None:
        """Read until every topic in ``topics`` was advertised."""
        deadline = time.monotonic() + timeout_s
        while not topics <= self.channels.keys():
            self._receive(deadline - time.monotonic())

    def subscribe(self, topics: list[str]) -> None:
        """Subscribe to ``topics`` (already advertised)."""
        subscriptions = []
        for sub_id, topic in enumerate(topics, 1):
            self._by_subscription[sub_id] = topic
            subscriptions.append({"id": sub_id, "channelId": self.channels[topic]["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

    def collect(self, wanted: dict[str, int], timeout_s: float = 30.0) -> None:
        """Read until each topic has at least ``wanted[topic]`` messages."""
        deadline = time.monotonic() + timeout_s
        while any(len(self.messages[t]) < n for t, n in wanted.items()):
            left = deadline - time.monotonic()
            if left <= 0:
                counts = {t: len(self.messages[t]) for t in wanted}
                raise TimeoutError(f"wanted {wanted}, got {counts}")
            self._receive(left)

    def _receive(self, timeout_s: float) -> None:
        frame = self.ws.recv(timeout=max(timeout_s, 0.01))
        if isinstance(frame, str):
            payload = json.loads(frame)
            if payload["op"] == "serverInfo":
                self.server_info = payload
            elif payload["op"] == "advertise":
                for channel in payload["channels"]:
                    self.channels[channel["topic"]] = channel
            return
        if frame[0] == MESSAGE_DATA:
            sub_id, log_time = struct.unpack_from("<IQ", frame, 1)
            topic = self._by_subscription[sub_id]
            self.messages[topic].append((log_time, json.loads(frame[13:])))

    def close(self) -> None:
        """Close the connection."""
        self._stack.close()
