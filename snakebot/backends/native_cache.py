"""Small C helpers linked against MuJoCo: compiled at first use, cached, loaded with ctypes.

The twin's scale friction (twin/friction/scale_c.py), its control period (twin/period_c.py: steps,
work, readouts) and the soft body's friction loop (softbody/friction_c.py) each keep their C source
as a string, so the wheel needs no package data. This module turns such a source into a loaded
library: the shared object is cached under the user cache folder (never the directory the program
runs from), named ``{stem}_{hash}.so`` with the hash of the source, MuJoCo's version and the
libmujoco it links, so a new source or a new MuJoCo compiles afresh and two versions never share an
object.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import mujoco

__all__ = [
    "CompileError",
    "cache_dir",
    "compile_object",
    "libmujoco",
    "load_library",
    "object_path",
]


class CompileError(RuntimeError):
    """No C compiler, or it refused the source, or the object would not load; the caller's
    Python or numpy path takes over."""


def cache_dir() -> Path:
    """Where the compiled objects are kept: $SNAKEBOT_CACHE, else the platform's user cache."""
    override = os.environ.get("SNAKEBOT_CACHE")
    if override:
        return Path(override)
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "snakebot"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "snakebot"


def _mujoco_dir() -> Path:
    return Path(mujoco.__file__).resolve().parent


def libmujoco() -> Path:
    """The libmujoco shared library the Python bindings load (the helpers link the same).

    CompileError if there is none next to the bindings.
    """
    found = sorted(_mujoco_dir().glob("libmujoco.so*")) + sorted(
        _mujoco_dir().glob("libmujoco*.dylib")
    )
    if not found:
        raise CompileError(f"no libmujoco shared library next to {_mujoco_dir()}")
    return found[0]


def object_path(stem: str, source_text: str) -> Path:
    """The cached shared object for ``source_text`` and this MuJoCo: ``{stem}_{hash}.so``."""
    key = hashlib.sha256(f"{source_text}{mujoco.__version__}{libmujoco()}".encode()).hexdigest()
    return cache_dir() / f"{stem}_{key[:16]}.so"


def compile_object(target: Path, source_text: str) -> Path:
    """Compile ``source_text`` into the shared object ``target`` with the first of $CC, cc, gcc,
    clang on PATH, linked against libmujoco; returns ``target``.

    CompileError if there is no compiler or it fails (its output in the message).
    """
    compiler = next(
        (c for c in (os.environ.get("CC"), "cc", "gcc", "clang") if c and shutil.which(c)), None
    )
    if compiler is None:
        raise CompileError("no C compiler on PATH (cc, gcc or clang)")
    lib = libmujoco()
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        source = Path(scratch) / f"{target.stem}.c"
        source.write_text(source_text)
        built = Path(scratch) / target.name
        command = [
            compiler, "-O2", "-shared", "-fPIC", "-std=c99",
            f"-I{_mujoco_dir() / 'include'}", str(source), "-o", str(built),
            str(lib), f"-Wl,-rpath,{lib.parent}", "-lm",
        ]  # fmt: skip
        done = subprocess.run(command, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            raise CompileError(f"{compiler} failed: {done.stderr.strip()[:2000]}")
        # Atomic: two processes compiling at once each rename a whole file into place.
        os.replace(built, target)
    return target


def load_library(stem: str, source_text: str) -> ctypes.CDLL:
    """``source_text`` as a loaded library: the cached object (``object_path``), compiled
    first if it is not there yet. The caller declares the functions' argument types.

    CompileError if it cannot be compiled or loaded.
    """
    path = object_path(stem, source_text)
    if not path.exists():
        compile_object(path, source_text)
    try:
        return ctypes.CDLL(str(path))
    except OSError as exc:
        raise CompileError(f"cannot load {path}: {exc}") from exc
