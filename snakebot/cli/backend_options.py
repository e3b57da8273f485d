"""``--backend`` and the backend option flags, read from the backend registry.

The choices are the registry's names (plugins included); each flag is a registry option
(``--port`` is option ``port``). A flag given to a backend that does not declare its option is
refused (exit 2): ``--port does nothing with the twin backend``. Library errors about an option
name the option (``friction: ...``); the CLI names the flag (``cli/main.as_flag_error``).
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

from snakebot.backends.registry import (
    BackendOption,
    BackendSpec,
    backend_names,
    get_backend_spec,
)
from snakebot.cli.common import baud_arg, port_arg
from snakebot.cli.terrain_options import terrain_help
from snakebot.errors import BackendOptionError, ConfigError, UsageError
from snakebot.session import DEFAULT_BACKEND

# argparse types where the command line checks a value before any backend is made
_TYPES: dict[str, Callable[[str], Any]] = {"port": port_arg, "baud": baud_arg}
# help made from a registry when the parser is built (plugins' entries included)
_GENERATED_HELP: dict[str, Callable[[], str]] = {"terrain": terrain_help}
_CHOICES: dict[str, tuple[str, ...]] = {
    "directional": ("on", "off"),
    "friction_model": ("auto", "pairs", "scale"),
}


def flag(option: str) -> str:
    """The command-line flag of backend option ``option``: ``allow_extra_servos`` ->
    ``--allow-extra-servos``."""
    return "--" + option.replace("_", "-")


def add_backend_argument(parser: argparse.ArgumentParser, *, help_prefix: str = "") -> None:
    """``--backend NAME``, its choices every registered backend name and alias."""
    names = backend_names(aliases=True)
    parser.add_argument(
        "--backend",
        choices=names,
        default=DEFAULT_BACKEND,
        metavar="{" + ",".join(names) + "}",
        help=f"{help_prefix}where to run: twin (alias sim, the MuJoCo twin; default), dynamixel "
        "(the servo chain), softbody, or a plugin's backend",
    )


def add_option_flags(
    parser: argparse.ArgumentParser, options: Sequence[str], *, helps: dict[str, str] | None = None
) -> None:
    """One flag per backend option name in ``options``; help from the built-in spec declaring
    it (or ``helps``)."""
    declared = _declared_options()
    for name in options:
        option = declared[name]
        generated = _GENERATED_HELP.get(name)
        text = (helps or {}).get(name) or (generated() if generated else option.help)
        if option.flag:
            parser.add_argument(flag(name), action="store_true", default=None, help=text)
        else:
            parser.add_argument(
                flag(name),
                type=_TYPES.get(name, str),
                choices=_CHOICES.get(name),
                metavar=None if name in _CHOICES else option.metavar or None,
                help=text,
            )


def backend_spec(args: argparse.Namespace) -> BackendSpec:
    """The spec ``--backend`` names."""
    return get_backend_spec(args.backend)


def given_options(
    args: argparse.Namespace, spec: BackendSpec, options: Sequence[str]
) -> dict[str, object]:
    """The backend options given on the command line among ``options`` (flags set, values not
    None); UsageError naming the first flag that does nothing with ``spec``'s backend."""
    given: dict[str, object] = {}
    for name in options:
        value = getattr(args, name, None)
        if value is None or value is False:
            continue
        if name not in spec.option_names:
            raise UsageError(f"{flag(name)} does nothing with the {spec.name} backend")
        given[name] = value
    return given


@contextlib.contextmanager
def flag_errors(flags: Mapping[str, str] | None = None) -> Iterator[None]:
    """Re-label a backend's refusal of an option as a usage error about its flag, and a
    ConfigError about library keyword ``k`` as one about ``flags[k]``: only for keywords whose
    flag :func:`snakebot.cli.main.as_flag_error` cannot find among the command's destinations
    (``command``, whose destination is ``policy_command``); it names every other flag itself."""
    names = dict(flags or {})
    try:
        yield
    except BackendOptionError as exc:
        raise UsageError(f"{flag(exc.option)} does nothing with the {exc.backend} backend") from exc
    except ConfigError as exc:
        if exc.source not in names:
            raise
        raise ConfigError(names[exc.source], exc.key, exc.reason) from exc


def _declared_options() -> dict[str, BackendOption]:
    from snakebot.backends.registry import DYNAMIXEL, SOFTBODY, TWIN

    declared: dict[str, BackendOption] = {}
    for spec in (TWIN, DYNAMIXEL, SOFTBODY):
        for option in spec.options:
            declared.setdefault(option.name, option)
    return declared
