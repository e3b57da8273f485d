"""Reading a file a user hands snakebot (a config, a log, a sidecar) without trusting it.

Only a regular file is read, and only up to a size limit: a FIFO in its place would block the
command forever, ``/dev/zero`` would fill memory, a directory has no bytes to read. Every refusal
is a ConfigError naming the file.
"""

from __future__ import annotations

import os
import stat
import unicodedata
from pathlib import Path

from snakebot.errors import ConfigError

MAX_CONFIG_BYTES = 1 << 20
"""Largest robot, servo, body or gait file read (1 MiB; the shipped ones are a few kB)."""

MAX_NAME_CHARS = 128
"""Longest name a config file may give (a robot's, a body's): names are printed back."""

MAX_TEXT_CHARS = 4096
"""Longest other string value in a config file (a port path is at most PATH_MAX)."""


def read_input(path: str | Path, *, what: str, limit_bytes: int) -> bytes:
    """The bytes of the regular file ``path``, at most ``limit_bytes`` of them.

    ConfigError naming ``path`` (``what`` says what it should be, e.g. "telemetry log") if it
    cannot be opened, is not a regular file, or is larger than the limit.
    """
    source = Path(path)
    try:
        # O_NONBLOCK: opening a FIFO for reading must not wait for a writer.
        fd = os.open(source, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise ConfigError(source, "", f"cannot read {what}: {exc.strerror or exc}") from exc
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise ConfigError(
                source, "", f"not a regular file ({_kind(info.st_mode)}); expected a {what}"
            )
        if info.st_size > limit_bytes:
            raise ConfigError(
                source,
                "",
                f"{info.st_size} bytes is larger than a {what} may be ({limit_bytes} bytes)",
            )
        chunks = []
        left = limit_bytes + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
    except OSError as exc:
        raise ConfigError(source, "", f"cannot read {what}: {exc.strerror or exc}") from exc
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if len(data) > limit_bytes:  # it grew while being read
        raise ConfigError(source, "", f"larger than a {what} may be ({limit_bytes} bytes)")
    return data


def _kind(mode: int) -> str:
    for test, name in (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a plain file"


def text_problem(value: str, *, max_chars: int) -> str | None:
    """Why ``value`` may not be printed back as a name or a config string, or None if it may.

    Refused: more than ``max_chars`` characters, control characters (C0, DEL, C1) and Unicode
    format characters, which include the bidirectional overrides (U+202E shows text reversed)
    and invisible ones (U+200B), and line or paragraph separators.
    """
    if len(value) > max_chars:
        return f"expected at most {max_chars} characters, got {len(value)}"
    for index, char in enumerate(value):
        if unicodedata.category(char) in ("Cc", "Cf", "Zl", "Zp"):
            name = unicodedata.name(char, "a control character")
            return (
                f"expected no control or bidirectional characters, got U+{ord(char):04X} "
                f"({name}) at character {index}"
            )
    return None
