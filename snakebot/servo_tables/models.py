"""Which servo models have control-table data: the shipped folder plus the user's model folders.

A model is one data file `<stem>.toml` (files whose name starts with `_` are bases, not models).
User folders come from the environment variable `SNAKEBOT_SERVO_DATA` (folders separated by
`os.pathsep`) and from :func:`add_model_dir`; a user file whose model name is a shipped one
replaces it, so a corrected table needs no code either.
"""

from __future__ import annotations

import functools
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

from snakebot.errors import ConfigError
from snakebot.servo_tables.loader import DATA_DIR, build_table
from snakebot.servo_tables.table import ServoTable, UnknownModelError, register_key

ENV_VAR = "SNAKEBOT_SERVO_DATA"
_added: list[Path] = []


@dataclass(frozen=True)
class ModelEntry:
    """One model's data file: its name, model number and where the file is.

    ``variant_of`` names the model whose number this one shares (the STS3215's 12 V version
    reports the 7.4 V version's 777): a variant is found by name only, never by number.
    """

    name: str
    model_number: int
    path: Path
    variant_of: str | None = None

    @property
    def shipped(self) -> bool:
        """Whether the file ships with snakebot (not a user model folder)."""
        return self.path.parent == DATA_DIR


def add_model_dir(path: str | Path) -> None:
    """Add a folder of model data files (`<model>.toml`), searched after `SNAKEBOT_SERVO_DATA`.

    Raises ConfigError when the folder does not exist.
    """
    folder = Path(path).expanduser().resolve()
    if not folder.is_dir():
        raise ConfigError(folder, "", "no such folder of servo model data files")
    if folder not in _added:
        _added.append(folder)


def model_dirs() -> tuple[Path, ...]:
    """The folders searched, shipped data first: later folders' models replace earlier ones.

    Raises ConfigError naming the variable when a folder in `SNAKEBOT_SERVO_DATA` is missing.
    """
    folders = [DATA_DIR]
    for part in os.environ.get(ENV_VAR, "").split(os.pathsep):
        if not part.strip():
            continue
        folder = Path(part).expanduser().resolve()
        if not folder.is_dir():
            raise ConfigError(ENV_VAR, part, "no such folder of servo model data files")
        folders.append(folder)
    folders += [f for f in _added if f not in folders]
    return tuple(dict.fromkeys(folders))


def _header(path: Path) -> tuple[str, int, str | None]:
    try:
        with path.open("rb") as handle:
            model = tomllib.load(handle).get("model", {})
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(path, "", f"not a readable TOML model data file: {exc}") from exc
    for key in ("name", "model_number"):
        if key not in model:
            raise ConfigError(path, f"model.{key}", "missing")
    number = model["model_number"]
    if isinstance(number, bool) or not isinstance(number, int):
        raise ConfigError(path, "model.model_number", f"must be a whole number, not {number!r}")
    variant = model.get("variant_of")
    return str(model["name"]), number, None if variant is None else str(variant)


@functools.cache
def _catalogue(folders: tuple[Path, ...]) -> dict[str, ModelEntry]:
    entries: dict[str, ModelEntry] = {}
    for folder in folders:
        found: dict[str, ModelEntry] = {}
        for path in sorted(folder.glob("*.toml")):
            if path.stem.startswith("_"):
                continue
            name, number, variant = _header(path)
            found[name] = ModelEntry(name, number, path, variant)
        entries.update(found)
    by_number: dict[int, ModelEntry] = {}
    for entry in entries.values():
        if entry.variant_of is not None:
            base = entries.get(entry.variant_of)
            if base is None or base.model_number != entry.model_number:
                raise ConfigError(
                    entry.path,
                    "model.variant_of",
                    f"names {entry.variant_of!r}, which is no model of number {entry.model_number}",
                )
            continue
        other = by_number.setdefault(entry.model_number, entry)
        if other is not entry:
            raise ConfigError(
                entry.path,
                "model.model_number",
                f"{entry.model_number} is also {other.name}'s ({other.path})",
            )
    return entries


def model_entries() -> list[ModelEntry]:
    """Every model with data, sorted by name (user folders included)."""
    return sorted(_catalogue(model_dirs()).values(), key=lambda e: e.name)


def supported_models() -> list[str]:
    """Return the model names that have control-table data, e.g. ["AX-12A", "XL330-M288", ...]."""
    return [entry.name for entry in model_entries()]


@functools.cache
def _table(entry: ModelEntry) -> ServoTable:
    return build_table(entry.path)


def _names(entry: ModelEntry) -> tuple[str, str]:
    return register_key(entry.name), register_key(entry.path.stem)


def table_for_model(model: str | int) -> ServoTable:
    """Return the table for a model name ("XL430-W250", "xl430_w250", "XL430-W250-T") or number.

    One instance per data file, so tables can key caches. Raises UnknownModelError listing the
    supported models, ConfigError naming the file and key when a model's data is invalid.
    """
    entries = model_entries()
    for entry in entries:
        if isinstance(model, int) and model == entry.model_number and entry.variant_of is None:
            return _table(entry)
    if not isinstance(model, int):
        wanted = register_key(model)
        # An exact name first ("MX-28-2" is not "MX-28"), then without a variant suffix ("-T").
        for name in (wanted, wanted.rsplit("_", 1)[0]):
            for entry in entries:
                if name in _names(entry):
                    return _table(entry)
    known = ", ".join(entry.name for entry in entries)
    raise UnknownModelError(f"no control-table data for servo model {model!r}; supported: {known}")
