"""Open registries by name: built-in entries, entry-point plugins and runtime registrations.

A ``Registry`` maps names to objects of one kind (gait specs, backend factories). Entries come
from three places:

- built-ins, given when the registry is made; a ``"module:attr"`` string is imported on first use;
- installed distributions that declare an entry point in the registry's group (pytest and
  Gymnasium plugins work the same way), e.g. in a plugin's ``pyproject.toml``::

      [project.entry-points."snakebot.gaits"]
      standing_wave = "my_package.gaits:STANDING_WAVE"

  The group is read on the first lookup, not at import; each plugin is imported only when its
  entry is used, or when every entry is listed (``load_all``);
- ``register(name, obj)`` for code that is not a package (a script, a notebook).

Name clashes (checked when the group is read, from metadata alone):

- a plugin that offers a built-in name is ignored with a ``PluginWarning`` naming it: a built-in
  name always means the built-in, so installing a package cannot change what a tested gait or
  backend does on the robot;
- two plugins offering one name: neither is used. A ``PluginWarning`` names both distributions,
  and asking for the name raises the registry's error naming both (uninstall one, or
  ``register`` the one you want with ``replace=True``);
- ``register`` over a name that is taken raises the registry's error naming the entry in the way,
  unless ``replace=True``; ``unregister`` brings back what was underneath.

A plugin that fails to import, or whose object fails the registry's check, breaks only its own
entry: listing every entry warns (``PluginWarning``, naming the distribution and entry point) and
skips it, and asking for it by name raises the registry's error with the reason.
"""

from __future__ import annotations

import difflib
import importlib
import re
import threading
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, Literal, TypeVar

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

T = TypeVar("T")

__all__ = ["BUILT_IN", "RUNTIME", "Origin", "PluginWarning", "Registry"]


class PluginWarning(UserWarning):
    """A plugin entry was ignored or failed to load; every other entry still works."""


@dataclass(frozen=True)
class Origin:
    """Where a registry entry came from.

    ``kind`` is "built-in", "plugin" (with its ``distribution``, ``version`` and ``entry_point``,
    the ``name = module:attr`` line that declares it) or "runtime" (``Registry.register``).
    ``str(origin)`` is the short form ``snakebot gaits`` prints.
    """

    kind: Literal["built-in", "plugin", "runtime"]
    distribution: str = ""
    version: str = ""
    entry_point: str = ""

    def __str__(self) -> str:
        if self.kind == "plugin":
            return f"plugin {self.distribution} {self.version}"
        return "registered at runtime" if self.kind == "runtime" else "built-in"

    def describe(self) -> str:
        """The long form for messages: with the entry point, where there is one."""
        return f"{self} (entry point {self.entry_point})" if self.entry_point else str(self)


BUILT_IN = Origin("built-in")
RUNTIME = Origin("runtime")


_REFERENCE = re.compile(r"[A-Za-z_][\w.]*:[A-Za-z_][\w.]*")


@dataclass
class _Entry(Generic[T]):
    origin: Origin
    load: Callable[[], object]  # imports the object on first use (or returns it)
    value: T | None = None
    failure: str = ""
    rivals: tuple[Origin, ...] = ()
    warned: bool = False


class Registry(Generic[T]):
    """Names to objects of one ``kind`` ("gait", "backend"), open to the entry-point ``group``.

    ``error`` builds the domain error raised for unknown, clashing or broken entries (GaitError
    for gaits). ``check(name, obj)`` validates a loaded object and returns it typed; it raises
    TypeError or ValueError saying what was expected. ``builtins`` maps names to objects or to
    ``"module:attr"`` strings imported on first use. Safe to use from several threads.
    """

    def __init__(
        self,
        kind: str,
        group: str,
        *,
        error: Callable[[str], Exception],
        check: Callable[[str, object], T],
        builtins: Mapping[str, T | str] | None = None,
    ) -> None:
        self.kind = kind
        self.group = group
        self._error = error
        self._check = check
        self._builtins = dict(builtins or {})
        self._runtime: dict[str, _Entry[T]] = {}
        self._installed: dict[str, _Entry[T]] | None = None
        self._lock = threading.RLock()

    def names(self) -> list[str]:
        """Every known name, sorted: built-ins, plugins (loaded or not) and runtime entries."""
        with self._lock:
            return sorted(self._installed_entries().keys() | self._runtime.keys())

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self.names()

    def origin(self, name: str) -> Origin:
        """Where entry ``name`` comes from (nothing is imported); the error if it is unknown."""
        with self._lock:
            return self._entry(name).origin

    def get(self, name: str) -> T:
        """The object registered as ``name``, imported on first use.

        Raises the registry's error for an unknown name (with the closest match and every known
        name), a name two plugins offer, or a plugin that fails to import or to pass the check.
        """
        with self._lock:
            entry = self._entry(name)
            if entry.rivals:
                raise self._error(
                    f"{self.kind} {name!r} is offered by {_several(entry)}; uninstall all but "
                    f"one, or register the one you want at runtime with replace=True"
                )
            return self._load(name, entry)

    def load_all(self) -> dict[str, T]:
        """Every entry that loads, by sorted name; a PluginWarning for each one that does not."""
        loaded: dict[str, T] = {}
        with self._lock:
            for name in self.names():
                entry = self._entry(name)
                if entry.rivals:
                    continue  # warned about when the group was read
                try:
                    loaded[name] = self._load(name, entry)
                except Exception as exc:
                    if entry.origin.kind == "built-in":
                        raise
                    if not entry.warned:
                        entry.warned = True
                        warnings.warn(
                            f"{exc}; the other {self.kind}s still work", PluginWarning, stacklevel=2
                        )
        return loaded

    def register(self, name: str, obj: T | str, *, replace: bool = False) -> None:
        """Add ``obj`` (or a ``"module:attr"`` string, imported on first use) as ``name``.

        Raises the registry's error when ``obj`` fails the check (a string: when it is not
        ``module:attr``), or when ``name`` is taken and ``replace`` is false; with ``replace``
        it hides the entry until ``unregister(name)``.
        """
        if not isinstance(name, str) or not name.strip():
            raise self._error(f"a {self.kind} name must be non-empty text, got {name!r}")
        with self._lock:
            taken = self._runtime.get(name) or self._installed_entries().get(name)
            if taken is not None and not replace:
                raise self._error(
                    f"{self.kind} {name!r} is already registered ({taken.origin.describe()}); "
                    f"pick another name, or pass replace=True to use yours instead"
                )
            if isinstance(obj, str):
                if not _REFERENCE.fullmatch(obj):
                    raise self._error(
                        f"cannot register {self.kind} {name!r}: expected an object or a "
                        f"'module:attr' reference, got {obj!r}"
                    )
                entry = _Entry[T](Origin("runtime", entry_point=f"{name} = {obj}"), _importer(obj))
            else:
                try:
                    value = self._check(name, obj)
                except (TypeError, ValueError) as exc:
                    raise self._error(f"cannot register {self.kind} {name!r}: {exc}") from exc
                entry = _Entry[T](RUNTIME, _constant(obj), value)
            self._runtime[name] = entry

    def unregister(self, name: str) -> None:
        """Remove a runtime registration, bringing back any entry it replaced."""
        with self._lock:
            if name not in self._runtime:
                origin = self.origin(name)
                raise self._error(
                    f"{self.kind} {name!r} is {origin.describe()}; only runtime registrations "
                    f"can be removed"
                )
            del self._runtime[name]

    def refresh(self) -> None:
        """Read the entry-point group again on the next lookup (after installing a plugin)."""
        importlib.invalidate_caches()  # the import system caches folder listings
        with self._lock:
            self._installed = None

    def _entry(self, name: str) -> _Entry[T]:
        entry = self._runtime.get(name) if isinstance(name, str) else None
        if entry is None and isinstance(name, str):
            entry = self._installed_entries().get(name)
        if entry is None:
            known = self.names()
            close = difflib.get_close_matches(str(name), known, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise self._error(
                f"unknown {self.kind} {name!r}{hint}; known {self.kind}s: {', '.join(known)}"
            )
        return entry

    def _load(self, name: str, entry: _Entry[T]) -> T:
        if entry.value is not None:
            return entry.value
        if entry.failure:
            raise self._error(entry.failure)
        if entry.origin.kind == "built-in":  # our own code: its errors are bugs, not plugin faults
            entry.value = self._check(name, entry.load())
            return entry.value
        try:
            entry.value = self._check(name, entry.load())
        except Exception as exc:  # a plugin may raise anything on import; keep it to its entry
            origin = entry.origin.describe()
            where = f"from {origin}" if entry.origin.kind == "plugin" else origin
            entry.failure = (
                f"{self.kind} {name!r} {where} failed to load: {type(exc).__name__}: {exc}"
            )
            raise self._error(entry.failure) from exc
        return entry.value

    def _installed_entries(self) -> dict[str, _Entry[T]]:
        if self._installed is None:
            self._installed = self._discover()
        return self._installed

    def _discover(self) -> dict[str, _Entry[T]]:
        from importlib import metadata  # here, not at import: it costs 20 ms

        entries: dict[str, _Entry[T]] = {
            name: _Entry[T](BUILT_IN, _importer(obj) if isinstance(obj, str) else _constant(obj))
            for name, obj in self._builtins.items()
        }
        for point in metadata.entry_points(group=self.group):
            origin = _plugin_origin(point)
            entry = entries.get(point.name)
            if entry is None:
                entries[point.name] = _Entry[T](origin, point.load)
            elif entry.origin.kind == "built-in":
                warnings.warn(
                    f"{origin.describe()} offers {self.kind} {point.name!r}, a built-in "
                    f"{self.kind} name; the built-in is kept and the plugin's is ignored",
                    PluginWarning,
                    stacklevel=2,
                )
            else:
                entry.rivals += (origin,)
        for name, entry in entries.items():
            if entry.rivals:
                warnings.warn(
                    f"{self.kind} {name!r} is offered by {_several(entry)}; none of them is "
                    f"used until all but one are uninstalled",
                    PluginWarning,
                    stacklevel=2,
                )
        return entries


def _plugin_origin(point: EntryPoint) -> Origin:
    dist = point.dist
    name = dist.name if dist is not None else "an unknown distribution"
    version = dist.version if dist is not None else "?"
    return Origin("plugin", name, version, f"{point.name} = {point.value}")


def _several(entry: _Entry[T]) -> str:
    origins = [o.describe() for o in (entry.origin, *entry.rivals)]
    return f"{len(origins)} plugins, " + ", ".join(origins[:-1]) + " and " + origins[-1]


def _constant(obj: object) -> Callable[[], object]:
    return lambda: obj


def _importer(reference: str) -> Callable[[], object]:
    """A loader for ``"package.module:attr.attr"`` (the entry-point grammar)."""

    def load() -> object:
        module, _, attrs = reference.partition(":")
        obj: object = importlib.import_module(module)
        for attr in attrs.split("."):
            obj = getattr(obj, attr)
        return obj

    return load
