"""Every backend by name: the one table the CLI's ``--backend`` and ``snakebot.connect`` read.

A backend is a :class:`BackendSpec`: a name, a one-line summary, a factory ``(robot, **options)
-> Backend`` (unconnected), the options it takes and whether it drives real hardware. Entries
come from the built-ins below, from installed plugins (entry-point group ``snakebot.backends``,
each entry naming a BackendSpec) and from :func:`register_backend`; the clash and failure rules
are snakebot.plugins'. Nothing here imports a backend: a factory given as ``"module:attr"`` is
imported when a backend is made.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from snakebot.errors import BackendError, BackendOptionError
from snakebot.plugins import Origin, Registry

if TYPE_CHECKING:
    from snakebot.backends.base import Backend

__all__ = [
    "BACKENDS",
    "BackendOption",
    "BackendSpec",
    "backend_names",
    "backend_origin",
    "get_backend_spec",
    "make_backend",
    "register_backend",
]

ENTRY_POINT_GROUP = "snakebot.backends"

BackendFactory = Callable[..., "Backend"]


@dataclass(frozen=True)
class BackendOption:
    """One keyword a backend's factory takes.

    ``name`` is the keyword (``port``; the CLI flag is ``--port``); ``help`` says what it does
    and its unit; ``flag`` is true for an on/off option (the CLI flag takes no value).
    ``metavar`` names the value in the CLI's help (``AXIAL,LATERAL``). A factory accepts the
    value as text (what a command line gives) or already typed, and raises ConfigError whose
    ``source`` is ``name`` for a bad one.
    """

    name: str
    help: str = ""
    flag: bool = False
    metavar: str = ""

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ValueError(
                f"a backend option name must be a Python identifier, got {self.name!r}"
            )


@dataclass(frozen=True)
class BackendSpec:
    """A backend under a name: what ``snakebot.connect(robot, backend=name, **options)`` makes.

    ``factory`` is a callable ``(robot, **options) -> Backend`` returning an unconnected backend,
    or a ``"module:attr"`` reference to one (imported on first use, so listing backends imports
    none). ``options`` are the keywords it takes; any other is refused before the factory runs.
    ``hardware`` means it moves real servos: the CLI then requires an explicit robot and never
    falls back to a default one. ``aliases`` are other names for the same backend.
    """

    name: str
    summary: str
    factory: BackendFactory | str
    options: tuple[BackendOption, ...] = ()
    hardware: bool = False
    aliases: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError(f"a backend name must be non-empty text, got {self.name!r}")
        names = [option.name for option in self.options]
        if len(set(names)) != len(names):
            raise ValueError(f"backend {self.name!r} declares an option twice: {names}")
        if not callable(self.factory) and not (
            isinstance(self.factory, str) and ":" in self.factory
        ):
            raise ValueError(
                f"backend {self.name!r}: factory must be a callable or a 'module:attr' "
                f"reference, got {self.factory!r}"
            )

    @property
    def option_names(self) -> tuple[str, ...]:
        """The keywords this backend takes, in declaration order."""
        return tuple(option.name for option in self.options)

    def check_options(self, options: Mapping[str, object]) -> dict[str, object]:
        """The options to pass on: those not None. BackendOptionError naming the first one this
        backend does not take (and the ones it does)."""
        given = {key: value for key, value in options.items() if value is not None}
        for key in given:
            if key not in self.option_names:
                raise BackendOptionError(self.name, key, self.option_names)
        return given

    def make(self, robot: object, **options: object) -> Backend:
        """A new, unconnected backend for ``robot`` (a RobotConfig, or a BodyConfig where the
        backend drives mass-spring bodies). Raises BackendOptionError for an option this
        backend does not take, ConfigError for a bad value or a robot it cannot drive."""
        given = self.check_options(options)
        return self.load_factory()(robot, **given)

    def load_factory(self) -> BackendFactory:
        """The factory, imported if it is a ``"module:attr"`` reference."""
        if callable(self.factory):
            return self.factory
        module, _, attrs = self.factory.partition(":")
        obj: Any = importlib.import_module(module)
        for attr in attrs.split("."):
            obj = getattr(obj, attr)
        if not callable(obj):
            raise BackendError(f"backend {self.name!r}: {self.factory} is not callable")
        return obj  # type: ignore[no-any-return]


def _check_spec(name: str, obj: object) -> BackendSpec:
    if not isinstance(obj, BackendSpec):
        raise TypeError(
            f"expected a snakebot.backends.registry.BackendSpec, got {type(obj).__name__}"
        )
    if name != obj.name and name not in obj.aliases:
        raise ValueError(f"its BackendSpec is named {obj.name!r}; the names must match")
    return obj


_TERRAIN = BackendOption(
    "terrain",
    "a terrain of snakebot.backends.terrains by name (flat by default; terrain_names() lists "
    "them, plugins' too), with key=value options, e.g. pegs:layout=row,spacing_m=0.15 "
    "(docs/terrain.md); a mass-spring body takes flat or cliff (BODY_TERRAINS)",
    metavar="NAME[:KEY=VALUE,...]",
)
_REALTIME = BackendOption("realtime", "pace the simulation to the wall clock", flag=True)
_DIRECTIONAL = BackendOption(
    "directional",
    "mass-spring bodies: Miller's directional friction on or off (default: the body file)",
    metavar="on|off",
)


def _serial_chain_options(sdk: str) -> tuple[BackendOption, ...]:
    """The options of a servo chain on a serial port driven through the vendor SDK ``sdk``."""
    return (
        BackendOption("port", "serial port (default: the robot file's bus.port)", metavar="PORT"),
        BackendOption("baud", "baud rate (default: the robot file's bus.baud)", metavar="BAUD"),
        BackendOption(
            "allow_extra_servos",
            "servos on the bus that the robot file does not name are expected (left alone); "
            "without it connecting refuses, naming them",
            flag=True,
        ),
        BackendOption("port_handler_factory", f"a {sdk} PortHandler class (tests, tools)"),
        BackendOption("clock", "a monotonic clock in s (tests, tools)"),
        BackendOption("sleep", "a sleep in s (tests, tools)"),
    )


TWIN = BackendSpec(
    name="twin",
    summary="the MuJoCo digital twin of the robot file (a mass-spring body's too)",
    factory="snakebot.backends.twin.factory:make_twin",
    options=(
        BackendOption(
            "friction",
            "ground friction along and across each module, AXIAL,LATERAL (equal values: "
            "isotropic; overrides the robot's ground model); one number for a mass-spring "
            "body's floor",
            metavar="AXIAL,LATERAL",
        ),
        _TERRAIN,
        BackendOption(
            "friction_model",
            "ground friction: pairs (capsule-plane pairs, floor plane only), scale (directional "
            "friction in each link's frame, any ground) or auto (default: the robot file's)",
            metavar="auto|pairs|scale",
        ),
        _REALTIME,
        _DIRECTIONAL,
        BackendOption("timestep_s", "physics timestep in s (default: the robot file's)"),
    ),
    aliases=("sim",),
)

SOFTBODY = BackendSpec(
    name="softbody",
    summary="Miller's mass-spring body in MuJoCo (firmware_configs/bodies/)",
    factory="snakebot.backends.softbody.factory:make_softbody",
    options=(
        BackendOption(
            "friction", "the floor's friction coefficient, one number >= 0", metavar="MU"
        ),
        _TERRAIN,
        _REALTIME,
        _DIRECTIONAL,
    ),
)

DYNAMIXEL = BackendSpec(
    name="dynamixel",
    summary="the Dynamixel servo chain on a serial port (Protocol 2.0 or 1.0)",
    factory="snakebot.backends.chain.factory:make_dynamixel",
    options=_serial_chain_options("dynamixel_sdk"),
    hardware=True,
)

FEETECH = BackendSpec(
    name="feetech",
    summary="the Feetech servo chain on a serial port (STS/SCS, scservo_sdk)",
    factory="snakebot.backends.chain.factory:make_feetech",
    options=_serial_chain_options("scservo_sdk"),
    hardware=True,
)

BACKENDS: Registry[BackendSpec] = Registry(
    "backend",
    ENTRY_POINT_GROUP,
    error=BackendError,
    check=_check_spec,
    builtins={
        **{spec.name: spec for spec in (TWIN, SOFTBODY, DYNAMIXEL, FEETECH)},
        **{alias: spec for spec in (TWIN, SOFTBODY, DYNAMIXEL, FEETECH) for alias in spec.aliases},
    },
)


def register_backend(spec: BackendSpec, *, replace: bool = False) -> None:
    """Make backend ``spec.name`` (and its aliases) available to ``snakebot.connect`` and the
    CLI's ``--backend`` in this process.

    Raises BackendError when a name is taken (a built-in, a plugin or an earlier registration)
    and ``replace`` is false; BACKENDS.unregister(name) undoes a registration.
    """
    if not isinstance(spec, BackendSpec):
        raise BackendError(f"register_backend expects a BackendSpec, got {type(spec).__name__}")
    for name in (spec.name, *spec.aliases):
        BACKENDS.register(name, spec, replace=replace)


def backend_names(*, aliases: bool = False) -> list[str]:
    """Names of the registered backends, sorted, plugins included; with ``aliases``, every name
    ``--backend`` accepts (``sim`` for the twin, say) without importing any plugin. Without it
    each plugin's spec is imported to tell its aliases apart (one that fails to import is left
    out with a PluginWarning)."""
    if aliases:
        return BACKENDS.names()
    return [name for name, spec in BACKENDS.load_all().items() if spec.name == name]


def get_backend_spec(name: str) -> BackendSpec:
    """The spec registered as ``name`` (an alias gives its backend's spec); BackendError naming
    the known backends otherwise, or saying why a plugin's backend could not be loaded."""
    return BACKENDS.get(name)


def backend_origin(name: str) -> Origin:
    """Where backend ``name`` comes from: built-in, a plugin (distribution, version) or runtime."""
    return BACKENDS.origin(name)


def make_backend(robot: object, backend: str | BackendSpec = "twin", **options: object) -> Backend:
    """A new, unconnected backend ``backend`` (a name or a spec) for ``robot``; see
    :meth:`BackendSpec.make` for what is raised."""
    spec = backend if isinstance(backend, BackendSpec) else get_backend_spec(backend)
    return spec.make(robot, **options)
