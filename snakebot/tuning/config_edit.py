"""Set keys of one table in a TOML file by editing its text, so comments and layout survive.

Only ``key = value`` lines of the named table change; a missing key is added at the end of the
table, a missing table before the first ``[[array]]`` table (or at the end of the file).
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Mapping
from pathlib import Path

from snakebot.errors import ConfigError

_HEADER = re.compile(r"^\s*\[(\[)?\s*([A-Za-z0-9_.\- ]+?)\s*\]")
_KEY = re.compile(r"^(\s*)([A-Za-z0-9_-]+)(\s*=\s*)([^#\n]*?)(\s*)(#.*)?$")


def format_value(value: object) -> str:
    """A TOML literal for an int, float or bool."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    raise TypeError(f"cannot write {type(value).__name__} values")


def set_table_values(path: Path, table: str, values: Mapping[str, object]) -> str:
    """Write ``values`` into ``[table]`` of the TOML file at ``path``; returns the new text.

    The result is parsed back and checked, so a write never leaves a broken file.
    """
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(path, table, f"cannot read: {exc.strerror or exc}") from exc
    lines = text.splitlines(keepends=True)
    start, end = _find_table(lines, table)
    pending = dict(values)
    if start is None:
        block = [f"[{table}]\n", *(f"{k} = {format_value(v)}\n" for k, v in pending.items())]
        parent_start, parent_end = _find_table(lines, table.rpartition(".")[0])
        insert = parent_end if parent_start is not None else _first_array_table(lines)
        if insert is None:
            prefix = "" if not lines or lines[-1].endswith("\n") else "\n"
            lines += [prefix + "\n", *block]
        else:
            lines[insert:insert] = [*block, "\n"]
    else:
        last_key = start
        for i in range(start + 1, end):
            match = _KEY.match(lines[i].rstrip("\n"))
            if not match:
                continue
            last_key = i
            indent, key, eq, _old, space, comment = match.groups()
            if key in pending:
                newline = "\n" if lines[i].endswith("\n") else ""
                tail = f"{space or ' '}{comment}" if comment else ""
                lines[i] = f"{indent}{key}{eq}{format_value(pending.pop(key))}{tail}{newline}"
        added = [f"{k} = {format_value(v)}\n" for k, v in pending.items()]
        lines[last_key + 1 : last_key + 1] = added
    new_text = "".join(lines)
    _check(path, table, new_text, values)
    try:
        path.write_text(new_text, encoding="utf-8")
    except OSError as exc:
        raise ConfigError(path, table, f"cannot write: {exc.strerror or exc}") from exc
    return new_text


def _find_table(lines: list[str], table: str) -> tuple[int | None, int]:
    start = None
    for i, line in enumerate(lines):
        match = _HEADER.match(line)
        if not match:
            continue
        if start is not None:
            return start, i
        if not match.group(1) and match.group(2).replace(" ", "") == table:
            start = i
    return start, len(lines)


def _first_array_table(lines: list[str]) -> int | None:
    for i, line in enumerate(lines):
        match = _HEADER.match(line)
        if match and match.group(1):
            while i > 0 and lines[i - 1].lstrip().startswith("#"):
                i -= 1
            return i
    return None


def _check(path: Path, table: str, text: str, values: Mapping[str, object]) -> None:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(path, table, f"editing the table would break the file ({exc})") from exc
    node: object = data
    for part in table.split("."):
        node = node.get(part, {}) if isinstance(node, dict) else {}
    if not isinstance(node, dict) or any(node.get(k) != v for k, v in values.items()):
        raise ConfigError(path, table, "the edited table does not read back as written")
