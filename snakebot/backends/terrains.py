"""Every terrain by name: the one table ``--terrain`` and ``parse_terrain`` read.

A terrain is a :class:`~snakebot.backends.twin.terrain.Terrain` subclass (a frozen dataclass
whose fields are its ``key=value`` options) registered under its ``name``. Entries come from the
built-ins below, from installed plugins (entry-point group ``snakebot.terrains``, each entry
naming a Terrain subclass) and from :func:`register_terrain`; the clash and failure rules are
snakebot.plugins'. Nothing here imports a terrain (or MuJoCo): a built-in is a ``"module:attr"``
reference imported when it is used, so the command line's help lists the names cheaply.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from snakebot.errors import TerrainError
from snakebot.plugins import Origin, Registry

if TYPE_CHECKING:
    from snakebot.backends.twin.terrain.base import Terrain

__all__ = [
    "BODY_TERRAINS",
    "BUILT_IN_TERRAINS",
    "DEFAULT_TERRAIN",
    "ENTRY_POINT_GROUP",
    "TERRAINS",
    "get_terrain",
    "register_terrain",
    "terrain_help",
    "terrain_names",
    "terrain_origin",
]

ENTRY_POINT_GROUP = "snakebot.terrains"
DEFAULT_TERRAIN = "flat"

_PACKAGE = "snakebot.backends.twin.terrain"
_BUILTINS = {
    "flat": f"{_PACKAGE}.flat:Flat",
    "slope": f"{_PACKAGE}.slope:Slope",
    "pegs": f"{_PACKAGE}.pegs:Pegs",
    "rough": f"{_PACKAGE}.rough:Rough",
    "step": f"{_PACKAGE}.step:Step",
    "pipe": f"{_PACKAGE}.pipe:Pipe",
    "pole": f"{_PACKAGE}.pole:Pole",
    "cliff": f"{_PACKAGE}.cliff:Cliff",
}

BUILT_IN_TERRAINS: tuple[str, ...] = tuple(_BUILTINS)
"""The terrains snakebot ships, in the order the docs and the help list them."""

BODY_TERRAINS = ("flat", "cliff")
"""The terrains a mass-spring body (the ``softbody`` backend) lies on; the rigid twin takes
every terrain."""


def _check_terrain(name: str, obj: object) -> type[Terrain]:
    from snakebot.backends.twin.terrain.base import Terrain

    if not (isinstance(obj, type) and issubclass(obj, Terrain)):
        raise TypeError(
            f"expected a subclass of snakebot.backends.twin.terrain.Terrain, got {obj!r}"
        )
    if obj.name != name:
        raise ValueError(f"its Terrain is named {obj.name!r}; the names must match")
    return obj


TERRAINS: Registry[type[Terrain]] = Registry(
    "terrain", ENTRY_POINT_GROUP, error=TerrainError, check=_check_terrain, builtins=_BUILTINS
)


def register_terrain(kind: type[Terrain], *, replace: bool = False) -> None:
    """Make terrain ``kind`` (a Terrain subclass) available as ``kind.name`` to
    ``parse_terrain``, the twin's ``terrain`` option and the CLI's ``--terrain`` in this process.

    Raises TerrainError when the name is taken (a built-in, a plugin or an earlier
    registration) and ``replace`` is false, or when ``kind`` is no Terrain subclass;
    ``TERRAINS.unregister(name)`` undoes a registration.
    """
    name = getattr(kind, "name", None) if isinstance(kind, type) else None
    if not isinstance(name, str) or not name:
        raise TerrainError(f"register_terrain expects a Terrain subclass with a name, got {kind!r}")
    TERRAINS.register(name, kind, replace=replace)


def terrain_names() -> list[str]:
    """Every terrain name, built-ins first in their order, then plugins and runtime ones sorted;
    imports no terrain."""
    names = TERRAINS.names()
    return [n for n in _BUILTINS if n in names] + [n for n in names if n not in _BUILTINS]


def get_terrain(name: str) -> type[Terrain]:
    """The Terrain subclass registered as ``name``; TerrainError naming the known terrains (or
    why a plugin's terrain could not be loaded) otherwise."""
    return TERRAINS.get(name)


def terrain_origin(name: str) -> Origin:
    """Where terrain ``name`` comes from: built-in, a plugin (distribution, version) or runtime."""
    return TERRAINS.origin(name)


def terrain_help(example: str = "pegs:layout=row,spacing_m=0.15") -> str:
    """The ``--terrain`` help, from the registry: every name (plugins' too, the default
    marked), an example, and the ones a mass-spring body takes."""
    names = terrain_names()
    listed = ", ".join(f"{n} (default)" if n == DEFAULT_TERRAIN else n for n in names)
    return (
        f"{listed}, with key=value options, e.g. {example} (keys and ranges: docs/terrain.md); "
        f"a mass-spring body takes {' or '.join(BODY_TERRAINS)}"
    )
