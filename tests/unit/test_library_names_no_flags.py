"""The library speaks in its own keywords; only ``snakebot/cli`` names command-line flags.

A script calling ``snakebot.connect(...).run(...)`` or ``tune(...)`` never typed ``--budget``,
so an error that says ``--budget: ...`` sends it looking for a flag it does not have. The CLI
names the flag itself (``cli/main.as_flag_error``). A whole command to run, quoted in backticks
(```snakebot scan --all-bauds```), is advice for anyone and may stay.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import snakebot

PACKAGE = Path(snakebot.__file__).parent
FLAG = re.compile(r"(?<![\w`-])--[a-z][a-z-]*")
QUOTED_COMMAND = re.compile(r"`[^`]*`")


def _text(node: ast.AST) -> str:
    """The literal text of a string or f-string node (formatted values as {})."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(_text(v) if isinstance(v, ast.Constant) else "{}" for v in node.values)
    return ""


def _flags_in_raises(source: str, where: str) -> list[str]:
    tree = ast.parse(source, filename=where)
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Raise) and node.exc is not None:
            inner = [n for n in ast.walk(node.exc) if isinstance(n, ast.JoinedStr)]
            parts = {id(v) for f in inner for v in ast.walk(f) if v is not f}
            texts = [_text(n) for n in ast.walk(node.exc) if id(n) not in parts]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            # a flag standing alone is an error source handed around ("--friction")
            texts = [node.value] if FLAG.fullmatch(node.value) else []
        else:
            continue
        for text in texts:
            for flag in FLAG.findall(QUOTED_COMMAND.sub("", text)):
                found.add(f"{where}:{node.lineno}: {flag}")
    return sorted(found)


def test_no_library_error_names_a_command_line_flag() -> None:
    offenders = [
        hit
        for path in sorted(PACKAGE.rglob("*.py"))
        # snakebot/testing starts other programs (Ray's nodes) with their own flags
        if path.relative_to(PACKAGE).parts[0] not in ("cli", "testing")
        for hit in _flags_in_raises(
            path.read_text(encoding="utf-8"), str(path.relative_to(PACKAGE.parent))
        )
    ]
    assert offenders == []


def test_the_check_sees_a_flag_in_an_error() -> None:
    source = (
        'SOURCE = "--friction"\n'
        'raise ConfigError("budget", "", f"need {n}, use --method grid")\n'
        'raise BusError(port, [], "run `snakebot scan --all-bauds` to find it")\n'
    )
    hits = _flags_in_raises(source, "probe.py")
    assert hits == ["probe.py:1: --friction", "probe.py:2: --method"]
