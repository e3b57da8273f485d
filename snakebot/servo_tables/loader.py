"""Build `ServoTable`s: addresses and sizes from the SDK's `.model` files, the rest from TOML."""

from __future__ import annotations

import functools
import importlib.util
import tomllib
from pathlib import Path
from types import MappingProxyType
from typing import Any

from snakebot.errors import ConfigError, MissingDependencyError
from snakebot.servo.ticks import TickModel
from snakebot.servo_tables.table import (
    ACCESS_MODES,
    Register,
    ServoSpecs,
    ServoTable,
    UnknownModelError,
    register_key,
)

DATA_DIR = Path(__file__).resolve().parent / "data"
SDK_INSTALL = "pip install 'dynamixel-sdk>=4.0'"
_REGISTER_FIELDS = {
    "name",
    "address",
    "size",
    "access",
    "eeprom",
    "minimum",
    "maximum",
    "default",
    "unit",
    "scale",
    "signed",
    "fix_model_file",
}
_SPEC_FIELDS = {
    "firmware_version",
    "eeprom_end",
    "resolution",
    "ticks",
    "fast_sync_read",
    "bulk_read",
    "gains",
    "operating_modes",
    "baud_rates",
    "indirect_banks",
    "nominal_voltage_v",
    "no_load_speed_rad_s",
    "stall_torque_nm",
    "stall_current_a",
}


def model_file_dir() -> Path:
    """Return the folder of the SDK's `.model` control-table files, without importing the SDK."""
    spec = importlib.util.find_spec("dynamixel_easy_sdk")
    locations = list(spec.submodule_search_locations or []) if spec else []
    folder = Path(locations[0]) / "control_table" if locations else None
    if folder is None or not folder.is_dir():
        raise MissingDependencyError(
            "the Dynamixel control tables ship with the ROBOTIS SDK (dynamixel_easy_sdk/"
            f"control_table/*.model), which is not installed: {SDK_INSTALL}"
        )
    return folder


def read_model_file(path: Path) -> list[tuple[int, int, str]]:
    """Parse the `[control table]` section of a `.model` file into (address, size, name) rows."""
    rows: list[tuple[int, int, str]] = []
    section = ""
    for line in path.read_text(encoding="utf-8").splitlines():
        text = line.strip()
        if text.startswith("["):
            section = text.strip("[]").strip().lower()
            continue
        parts = text.split("\t")
        if section != "control table" or len(parts) < 3 or not parts[0].isdigit():
            continue
        rows.append((int(parts[0]), int(parts[1]), parts[2].strip()))
    if not rows:
        raise ConfigError(path, "[control table]", "no control-table rows found")
    return rows


def _read_toml(name: str) -> dict[str, Any]:
    path = DATA_DIR / f"{name}.toml"
    with path.open("rb") as handle:
        data = tomllib.load(handle)
    base = data.get("model", {}).pop("base", None)
    if base is None:
        return data
    merged = _read_toml(str(base))
    merged.setdefault("model", {}).update(data.get("model", {}))
    registers = merged.setdefault("registers", {})
    for key, facts in data.get("registers", {}).items():
        registers[key] = {**registers.get(key, {}), **facts}
    return merged


def _full_range(size: int, signed: bool) -> tuple[int, int]:
    bits = 8 * size
    return (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)


def _register(source: Path, key: str, facts: dict[str, Any], eeprom_end: int) -> Register:
    unknown = set(facts) - _REGISTER_FIELDS
    if unknown:
        raise ConfigError(source, f"registers.{key}", f"unknown field(s) {sorted(unknown)}")
    for needed in ("name", "address", "size"):
        if needed not in facts:
            raise ConfigError(source, f"registers.{key}", f"missing {needed!r}; not in the .model")
    size, signed = int(facts["size"]), bool(facts.get("signed", False))
    low, high = _full_range(size, signed)
    register = Register(
        name=str(facts["name"]),
        key=key,
        address=int(facts["address"]),
        size=size,
        access=str(facts.get("access", "RW")),
        eeprom=bool(facts.get("eeprom", int(facts["address"]) < eeprom_end)),
        minimum=int(facts.get("minimum", low)),
        maximum=int(facts.get("maximum", high)),
        default=int(facts.get("default", 0)),
        unit=str(facts.get("unit", "")),
        scale=float(facts.get("scale", 1.0)),
        signed=signed,
    )
    if register.access not in ACCESS_MODES or size not in (1, 2, 4):
        raise ConfigError(source, f"registers.{key}", f"bad access/size {register.access!r}/{size}")
    if register.access == "RW" and not register.minimum <= register.default <= register.maximum:
        raise ConfigError(source, f"registers.{key}", "default lies outside minimum..maximum")
    return register


def _bank(values: list[int]) -> tuple[int, int, int]:
    address, data, count = (int(v) for v in values)
    return address, data, count


def _ticks(source: Path, model: dict[str, Any]) -> TickModel:
    facts = dict(model.get("ticks", {}))
    count = int(facts.pop("count", model.get("resolution", 4096)))
    unknown = set(facts) - {"travel_deg", "centre", "minimum", "maximum", "sign", "sign_bit"}
    if unknown:
        raise ConfigError(source, "model.ticks", f"unknown field(s) {sorted(unknown)}")
    try:
        return TickModel(
            count=count,
            travel_deg=float(facts.get("travel_deg", 360.0)),
            centre=int(facts.get("centre", count // 2)),
            minimum=int(facts.get("minimum", 0)),
            maximum=int(facts.get("maximum", count - 1)),
            sign=str(facts.get("sign", "unsigned")),
            sign_bit=int(facts.get("sign_bit", 15)),
        )
    except ValueError as exc:
        raise ConfigError(source, "model.ticks", str(exc)) from exc


def _specs(source: Path, model: dict[str, Any]) -> ServoSpecs:
    rates = {int(index): int(rate) for index, rate in model.get("baud_rates", {}).items()}
    gains = str(model.get("gains", "pid"))
    if gains not in ("pid", "compliance"):
        raise ConfigError(source, "model.gains", f"must be 'pid' or 'compliance', not {gains!r}")
    return ServoSpecs(
        firmware_version=int(model.get("firmware_version", 46)),
        eeprom_end=int(model.get("eeprom_end", 64)),
        ticks=_ticks(source, model),
        fast_sync_read=bool(model.get("fast_sync_read", True)),
        bulk_read=bool(model.get("bulk_read", True)),
        gains=gains,
        operating_modes=tuple(int(m) for m in model.get("operating_modes", (3,))),
        baud_rates=MappingProxyType(rates),
        indirect_banks=tuple(_bank(bank) for bank in model.get("indirect_banks", ())),
        nominal_voltage_v=float(model.get("nominal_voltage_v", 12.0)),
        no_load_speed_rad_s=float(model.get("no_load_speed_rad_s", 5.0)),
        stall_torque_nm=float(model.get("stall_torque_nm", 1.0)),
        stall_current_a=float(model.get("stall_current_a", 1.0)),
    )


def _build(stem: str) -> ServoTable:
    source = DATA_DIR / f"{stem}.toml"
    data = _read_toml(stem)
    model = data["model"]
    unknown = set(model) - _SPEC_FIELDS - {
        "name", "model_number", "protocol", "protocols", "family", "model_file"
    }
    if unknown:
        raise ConfigError(source, "model", f"unknown field(s) {sorted(unknown)}")
    specs = _specs(source, model)
    facts_by_key: dict[str, dict[str, Any]] = {
        key: dict(facts)
        for key, facts in data.get("registers", {}).items()
        if not facts.get("absent")
    }
    registers: dict[str, Register] = {}
    for address, size, name in read_model_file(model_file_dir() / str(model["model_file"])):
        key = register_key(name)
        if key in registers:
            continue
        facts = facts_by_key.pop(key, None)
        if facts is None:
            raise ConfigError(source, f"registers.{key}", f"no facts for .model item {name!r}")
        if facts.get("address", address) != address and "fix_model_file" not in facts:
            raise ConfigError(source, f"registers.{key}", "address differs from the .model file")
        facts.setdefault("address", address)
        facts.update(name=name, size=size)
        registers[key] = _register(source, key, facts, specs.eeprom_end)
    for key, facts in facts_by_key.items():
        registers[key] = _register(source, key, facts, specs.eeprom_end)
    return ServoTable(
        model=str(model["name"]),
        model_number=int(model["model_number"]),
        protocol=float(model.get("protocol", 2.0)),
        registers=registers,
        specs=specs,
        family=str(model.get("family", "dynamixel")),
        protocols=tuple(float(p) for p in model.get("protocols", [model.get("protocol", 2.0)])),
    )


@functools.cache
def _index() -> dict[str, tuple[str, int]]:
    """Model name -> (data file stem, model number) for every TOML data file (not `_base` files)."""
    index: dict[str, tuple[str, int]] = {}
    for path in sorted(DATA_DIR.glob("*.toml")):
        if path.stem.startswith("_"):
            continue
        with path.open("rb") as handle:
            model = tomllib.load(handle)["model"]
        index[str(model["name"])] = (path.stem, int(model["model_number"]))
    return index


def supported_models() -> list[str]:
    """Return the model names that have control-table data, e.g. ["XL330-M288", ...]."""
    return sorted(_index())


def _normalise(name: str) -> str:
    return register_key(name)


@functools.cache
def _table_for_stem(stem: str) -> ServoTable:
    return _build(stem)


def table_for_model(model: str | int) -> ServoTable:
    """Return the table for a model name ("XL430-W250", "xl430_w250", "XL430-W250-T") or number.

    Raises UnknownModelError listing the supported models.
    """
    for name, (stem, number) in _index().items():
        if isinstance(model, int):
            if model == number:
                return _table_for_stem(stem)
            continue
        names = (_normalise(name), stem)
        wanted = _normalise(model)
        if wanted in names or wanted.rsplit("_", 1)[0] in names:
            return _table_for_stem(stem)
    known = ", ".join(supported_models())
    raise UnknownModelError(f"no control-table data for servo model {model!r}; supported: {known}")
