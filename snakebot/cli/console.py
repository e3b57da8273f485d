"""Asking the user before something irreversible; refuses when nobody can be asked."""

from __future__ import annotations

import sys

from snakebot.setup.errors import SetupError


def confirm(question: str, *, assume_yes: bool, what: str) -> None:
    """Return if the user answers yes (or ``assume_yes``); SetupError otherwise.

    Without a terminal on stdin nobody can answer, so it refuses and names ``--yes``.
    """
    if assume_yes:
        return
    if not sys.stdin.isatty():
        raise SetupError(
            f"{what} needs your confirmation and stdin is not a terminal: pass --yes to go ahead"
        )
    answer = input(f"{question} [y/N] ")
    if answer.strip().lower() not in ("y", "yes"):
        raise SetupError(f"{what}: cancelled, nothing was written")
