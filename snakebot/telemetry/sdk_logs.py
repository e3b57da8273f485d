"""What the Foxglove SDK logs (through Python's logging): a failed MCAP write shown once, failed
WebSocket sends counted instead of printed one line each."""

from __future__ import annotations

import logging


class _Once(logging.Filter):
    """Lets each distinct message through once: a failed MCAP write is logged by the SDK for
    every message after it; the flush that follows raises it as an OutputError."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: set[str] = set()

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        if text in self.seen:
            return False
        self.seen.add(text)
        return True


def quiet_sink_errors() -> None:
    """Show each failed MCAP write once (idempotent)."""
    logger = logging.getLogger("foxglove.log_sink_set")
    if not any(isinstance(f, _Once) for f in logger.filters):
        logger.addFilter(_Once())


class SendErrors(logging.Handler):
    """Counts what the SDK's WebSocket side logs (a failed send to a client that went away is
    one ERROR per message: tens of thousands a run) instead of printing it."""

    LOGGER = "foxglove.websocket"

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.count = 0
        self._propagate = True

    @classmethod
    def install(cls) -> SendErrors:
        """A counter taking the SDK's WebSocket records (they no longer reach stderr)."""
        handler = cls()
        logger = logging.getLogger(cls.LOGGER)
        handler._propagate, logger.propagate = logger.propagate, False
        logger.addHandler(handler)
        return handler

    def remove(self) -> None:
        """Give the records back to the loggers above."""
        logger = logging.getLogger(self.LOGGER)
        logger.removeHandler(self)
        logger.propagate = self._propagate

    def emit(self, record: logging.LogRecord) -> None:
        """Count ``record``."""
        self.count += 1
