"""Change one key in every ``[[joints]]`` table of a TOML file, keeping comments and layout."""

from __future__ import annotations

import os
import re
import stat
import tempfile
from collections.abc import Sequence
from pathlib import Path

_HEADER = re.compile(r"^\s*\[\[\s*joints\s*\]\]\s*(#.*)?$")
_TABLE = re.compile(r"^\s*\[")
_ANCHOR = re.compile(r"^(\s*)servo_id\s*=")


def format_float(value: float, digits: int = 4) -> str:
    """A TOML float rounded to ``digits`` decimals, without a negative zero."""
    rounded = round(value, digits)
    return "0.0" if rounded == 0 else repr(rounded)


def set_in_joints(text: str, key: str, values: Sequence[str]) -> str:
    """``text`` with ``key = values[i]`` in the i-th ``[[joints]]`` table (replaced or added).

    A replaced value keeps the line's indentation and trailing comment; an added line goes right
    after the table's ``servo_id``. ValueError if the file's joints are not ``[[joints]]`` tables.
    """
    lines = text.splitlines(keepends=True)
    starts = [i for i, line in enumerate(lines) if _HEADER.match(line)]
    if len(starts) != len(values):
        raise ValueError(
            f"found {len(starts)} [[joints]] tables, expected {len(values)} (joints "
            "written as an inline array cannot be edited in place)"
        )
    pattern = re.compile(rf"^(\s*{re.escape(key)}\s*=\s*)([^#]*?)(\s*(#.*)?)$")
    for start, value in reversed(list(zip(starts, values, strict=True))):
        end = next((i for i in range(start + 1, len(lines)) if _TABLE.match(lines[i])), len(lines))
        newline = "\r\n" if lines[start].endswith("\r\n") else "\n"
        anchor = start
        for i in range(start + 1, end):
            body = lines[i].rstrip("\r\n")
            ending = lines[i][len(body) :]
            match = pattern.match(body)
            if match:
                lines[i] = f"{match.group(1)}{value}{match.group(3)}{ending}"
                break
            if _ANCHOR.match(body):
                anchor = i
        else:
            indent = _ANCHOR.match(lines[anchor])
            prefix = indent.group(1) if indent else ""
            if not lines[anchor].endswith(("\n", "\r")):
                lines[anchor] += newline
            lines.insert(anchor + 1, f"{prefix}{key} = {value}{newline}")
    return "".join(lines)


def write_atomic(path: Path, text: str) -> None:
    """Replace ``path`` with ``text`` in one rename (a crash leaves the old or the new file).

    The file keeps its permission bits (the temporary file would be 0600), and a symbolic link
    stays a link: the file it points to is replaced.
    """
    target = path.resolve() if path.is_symlink() else path
    try:
        mode = stat.S_IMODE(target.stat().st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    handle, temp = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
    try:
        with os.fdopen(handle, "w", encoding="utf-8", newline="") as out:
            out.write(text)
            out.flush()
            os.fsync(out.fileno())
        os.chmod(temp, mode)
        os.replace(temp, target)
    except BaseException:
        Path(temp).unlink(missing_ok=True)
        raise
