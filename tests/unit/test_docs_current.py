"""Docs that list what the code has stay in step with it: a new doc, command or message cannot
leave them stale unnoticed."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from snakebot.cli.main import COMMANDS, main

DOCS = Path(__file__).resolve().parents[2] / "docs"
README = DOCS.parent / "README.md"


def test_the_readme_layout_table_links_every_doc() -> None:
    row = next(line for line in README.read_text().splitlines() if line.startswith("| `docs/` |"))
    linked = set(re.findall(r"\(docs/([\w-]+\.md)\)", row))
    assert linked == {path.name for path in DOCS.glob("*.md")}


def test_the_completion_snippet_offers_every_command() -> None:
    text = (DOCS / "cli.md").read_text()
    words = re.search(r'words="([a-z0-9 ]+)"', text)
    assert words is not None
    assert sorted(words.group(1).split()) == sorted(COMMANDS)


def test_the_terrain_doc_quotes_the_error_the_command_prints(
    capsys: pytest.CaptureFixture[str],
) -> None:
    text = (DOCS / "terrain.md").read_text()
    quoted = re.search(r"\$ snakebot (run --terrain \S+)\n(snakebot.*)\n", text)
    assert quoted is not None
    assert main(quoted.group(1).split()) == 2
    assert quoted.group(2) in capsys.readouterr().err.splitlines()
