"""Build a `ServoTable` from one model data file: TOML facts; addresses from a `.model` or TOML."""

from __future__ import annotations

import importlib.util
import itertools
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
    "sign",
    "sign_bit",
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
    "axes",
    "position_mode",
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


def _base_path(source: Path, base: str) -> Path:
    """A `base = "..."` file: beside the data file first, then among the shipped data."""
    for folder in (source.parent, DATA_DIR):
        path = folder / f"{base}.toml"
        if path.is_file():
            return path
    raise ConfigError(source, "model.base", f"no data file {base}.toml beside it or in {DATA_DIR}")


def read_data_file(source: Path, _seen: tuple[Path, ...] = ()) -> dict[str, Any]:
    """The TOML of a model data file, merged over its `base` chain (the file's facts win).

    Raises ConfigError naming the file for unreadable TOML, a missing base or a base cycle.
    """
    if source in _seen:
        raise ConfigError(source, "model.base", "the base files include each other")
    try:
        with source.open("rb") as handle:
            data = tomllib.load(handle)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(source, "", f"not valid TOML: {exc}") from exc
    except OSError as exc:
        raise ConfigError(source, "", f"cannot read: {exc.strerror or exc}") from exc
    base = data.get("model", {}).pop("base", None)
    if base is None:
        return data
    merged = read_data_file(_base_path(source, str(base)), (*_seen, source))
    merged.setdefault("model", {}).update(data.get("model", {}))
    registers = merged.setdefault("registers", {})
    for key, facts in data.get("registers", {}).items():
        registers[key] = {**registers.get(key, {}), **facts}
    return merged


def _full_range(size: int, sign: str, sign_bit: int | None) -> tuple[int, int]:
    if sign_bit is not None:
        return -((1 << sign_bit) - 1), (1 << sign_bit) - 1
    bits = 8 * size
    return (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if sign == "twos" else (0, (1 << bits) - 1)


def _int(source: Path, key: str, facts: dict[str, Any], name: str, default: int) -> int:
    value = facts.get(name, default)
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(
            source, f"registers.{key}.{name}", f"must be a whole number, not {value!r}"
        )
    return value


def _sign(source: Path, key: str, facts: dict[str, Any], size: int) -> tuple[str, int | None]:
    """("unsigned" | "twos" | "magnitude", sign bit or None) from `sign`/`sign_bit`/`signed`."""
    where = f"registers.{key}"
    sign = str(facts.get("sign", "twos" if facts.get("signed") else "unsigned"))
    if sign not in ("unsigned", "twos", "magnitude"):
        raise ConfigError(
            source, f"{where}.sign", f"must be unsigned, twos or magnitude, not {sign!r}"
        )
    if "signed" in facts and bool(facts["signed"]) != (sign == "twos"):
        raise ConfigError(source, f"{where}.signed", f"contradicts sign = {sign!r}")
    if sign != "magnitude":
        if "sign_bit" in facts:
            raise ConfigError(source, f"{where}.sign_bit", 'only with sign = "magnitude"')
        return sign, None
    if "sign_bit" not in facts:
        raise ConfigError(source, f"{where}.sign_bit", 'missing; sign = "magnitude" needs it')
    sign_bit = _int(source, key, facts, "sign_bit", 0)
    if not 0 < sign_bit < 8 * size:
        raise ConfigError(source, f"{where}.sign_bit", f"must lie in 1..{8 * size - 1}")
    return sign, sign_bit


def _register(
    source: Path, key: str, facts: dict[str, Any], eeprom_end: int, byteorder: str
) -> Register:
    where = f"registers.{key}"
    unknown = set(facts) - _REGISTER_FIELDS
    if unknown:
        raise ConfigError(source, where, f"unknown field(s) {sorted(unknown)}")
    for needed in ("name", "address", "size"):
        if needed not in facts:
            raise ConfigError(
                source, f"{where}.{needed}", "missing (the model has no .model row for it)"
            )
    address, size = _int(source, key, facts, "address", 0), _int(source, key, facts, "size", 0)
    if size not in (1, 2, 4) or not 0 <= address < 65536:
        raise ConfigError(source, where, f"bad address/size {address}/{size} (size 1, 2 or 4)")
    sign, sign_bit = _sign(source, key, facts, size)
    low, high = _full_range(size, sign, sign_bit)
    register = Register(
        name=str(facts["name"]),
        key=key,
        address=address,
        size=size,
        access=str(facts.get("access", "RW")),
        eeprom=bool(facts.get("eeprom", address < eeprom_end)),
        minimum=_int(source, key, facts, "minimum", low),
        maximum=_int(source, key, facts, "maximum", high),
        default=_int(source, key, facts, "default", 0),
        unit=str(facts.get("unit", "")),
        scale=float(facts.get("scale", 1.0)),
        signed=sign == "twos",
        sign_bit=sign_bit,
        byteorder=byteorder,
    )
    if register.access not in ACCESS_MODES:
        raise ConfigError(source, f"{where}.access", f"must be R or RW, not {register.access!r}")
    if not low <= register.minimum <= register.maximum <= high:
        raise ConfigError(
            source,
            where,
            f"range {register.minimum}..{register.maximum} does not fit "
            f"{size} byte(s) {sign} ({low}..{high})",
        )
    checked = register.access == "RW" or "default" in facts
    if checked and not register.minimum <= register.default <= register.maximum:
        raise ConfigError(
            source,
            f"{where}.default",
            f"{register.default} lies outside {register.minimum}..{register.maximum}",
        )
    return register


def _check_overlaps(source: Path, registers: dict[str, Register]) -> None:
    """Raise ConfigError when two items share bytes without being aliases (same address, size)."""
    ordered = sorted(registers.values(), key=lambda r: (r.address, r.size))
    for first, second in itertools.pairwise(ordered):
        alias = (first.address, first.size) == (second.address, second.size)
        if second.address < first.address + first.size and not alias:
            raise ConfigError(
                source,
                f"registers.{second.key}",
                f"address {second.address} overlaps {first.key} "
                f"({first.address}..{first.address + first.size - 1})",
            )


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
        axes=_axes(source, model),
        position_mode=int(model.get("position_mode", 3)),
    )


def _axes(source: Path, model: dict[str, Any]) -> int:
    axes = model.get("axes", 1)
    if not isinstance(axes, int) or isinstance(axes, bool) or axes < 1:
        raise ConfigError(source, "model.axes", f"must be a whole number >= 1, not {axes!r}")
    return axes


def _model_file_rows(
    source: Path, model_file: str, facts_by_key: dict[str, dict[str, Any]]
) -> dict[str, dict[str, Any]]:
    """Merge the `.model` file's (address, size, name) rows into the register facts."""
    rows: dict[str, dict[str, Any]] = {}
    for address, size, name in read_model_file(model_file_dir() / model_file):
        key = register_key(name)
        if key in rows:
            continue
        facts = facts_by_key.pop(key, None)
        if facts is None:
            raise ConfigError(source, f"registers.{key}", f"no facts for .model item {name!r}")
        if facts.get("address", address) != address and "fix_model_file" not in facts:
            raise ConfigError(source, f"registers.{key}", "address differs from the .model file")
        facts.setdefault("address", address)
        facts.update(name=name, size=size)
        rows[key] = facts
    return rows


PROTOCOLS = {"dynamixel": (1.0, 2.0), "feetech": (0.0, 1.0)}
"""The protocol numbers each vendor's model data may list: Dynamixel Protocol 1.0/2.0; Feetech's
SDK protocol_end, 0 for STS/SMS (little-endian words) and 1 for SCS (big-endian)."""


def _protocols(source: Path, model: dict[str, Any]) -> tuple[float, ...]:
    vendor = str(model.get("family", "dynamixel"))
    allowed = PROTOCOLS.get(vendor)
    if allowed is None:
        known = ", ".join(PROTOCOLS)
        raise ConfigError(source, "model.family", f"unknown vendor {vendor!r}; known: {known}")
    protocols = model.get("protocols", [model.get("protocol", 2.0)])
    if not isinstance(protocols, list) or not protocols or any(p not in allowed for p in protocols):
        have = " and/or ".join(f"{p:.1f}" for p in allowed)
        raise ConfigError(source, "model.protocols", f"must list {have}, not {protocols!r}")
    return tuple(float(p) for p in protocols)


def _byteorder(facts_by_key: dict[str, dict[str, Any]]) -> str:
    """How the model's words go on the wire: big-endian where its END register (key
    ``byte_order``, Feetech address 2) powers up 1 (the SCS series), else little-endian."""
    end = facts_by_key.get("byte_order", {})
    return "big" if end.get("default") == 1 else "little"


def build_table(source: Path) -> ServoTable:
    """Build the `ServoTable` of one model data file (`[model]` + `[registers]`).

    With `model_file` the addresses and sizes come from the SDK's `.model` file; without it
    (Protocol 1.0 models, which have none) every register gives `name`, `address` and `size`.
    Raises ConfigError naming the file and key for a missing or bad field, a register outside
    its size, a default outside its range or two overlapping registers.
    """
    data = read_data_file(source)
    model = data.get("model", {})
    unknown = (
        set(model)
        - _SPEC_FIELDS
        - {"name", "model_number", "protocol", "protocols", "family", "model_file", "variant_of"}
    )
    if unknown:
        raise ConfigError(source, "model", f"unknown field(s) {sorted(unknown)}")
    for needed in ("name", "model_number"):
        if needed not in model:
            raise ConfigError(source, f"model.{needed}", "missing")
    specs = _specs(source, model)
    facts_by_key: dict[str, dict[str, Any]] = {
        key: dict(facts)
        for key, facts in data.get("registers", {}).items()
        if not facts.get("absent")
    }
    rows = (
        _model_file_rows(source, str(model["model_file"]), facts_by_key)
        if "model_file" in model
        else {}
    )
    merged = {**rows, **facts_by_key}
    byteorder = _byteorder(merged)
    registers = {
        key: _register(source, key, facts, specs.eeprom_end, byteorder)
        for key, facts in merged.items()
    }
    _check_overlaps(source, registers)
    protocols = _protocols(source, model)
    protocol = model.get("protocol", protocols[0])
    if protocol not in protocols:
        raise ConfigError(source, "model.protocol", f"{protocol!r} is not in protocols {protocols}")
    return ServoTable(
        model=str(model["name"]),
        model_number=int(model["model_number"]),
        protocol=float(protocol),
        registers=registers,
        specs=specs,
        family=str(model.get("family", "dynamixel")),
        protocols=protocols,
    )
