"""The C helpers' loader: compiled once into the user cache, never into the directory run from,
a new object for a new source, and a compiler's refusal reported with its output."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from snakebot.backends import native_cache

SOURCE = "int snakebot_probe(int x) { return 3 * x + 1; }\n"


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("SNAKEBOT_CACHE", str(tmp_path / "cache"))
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    return tmp_path / "cache"


def test_a_helper_is_compiled_once_into_the_cache_and_nothing_lands_here(cache: Path) -> None:
    library = native_cache.load_library("probe", SOURCE)
    assert library.snakebot_probe(4) == 13
    (built,) = cache.iterdir()
    assert re.fullmatch(r"probe_[0-9a-f]{16}\.so", built.name)
    stamp = built.stat().st_mtime_ns
    native_cache.load_library("probe", SOURCE)
    assert built.stat().st_mtime_ns == stamp  # reused, not compiled again
    assert list(Path.cwd().iterdir()) == []


def test_a_changed_source_gets_an_object_of_its_own(cache: Path) -> None:
    first = native_cache.object_path("probe", SOURCE)
    second = native_cache.object_path("probe", SOURCE.replace("3 * x", "5 * x"))
    assert first != second
    changed = native_cache.load_library("probe", SOURCE.replace("3 * x", "5 * x"))
    assert changed.snakebot_probe(4) == 21
    assert [p.name for p in cache.iterdir()] == [second.name]


def test_a_source_the_compiler_refuses_names_the_helper_and_leaves_no_object(
    cache: Path,
) -> None:
    with pytest.raises(native_cache.CompileError, match=r"failed: .*broken_[0-9a-f]{16}\.c"):
        native_cache.load_library("broken", "int broken(void) { return }\n")
    assert not cache.exists() or list(cache.iterdir()) == []
    assert list(Path.cwd().iterdir()) == []
