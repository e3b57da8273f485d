"""Emulated servos' EEPROM across emulated power cycles: a JSON file, one entry per serial number.

Format (``version`` 1)::

    {"format": "snakebot-emulator-state", "version": 1,
     "servos": {"3": {"model_number": 1060, "eeprom": "<hex of control-table bytes 0..63>"}}}

Only EEPROM (addresses below the model's ``eeprom_end``) is kept, as a power cycle would bring
it back (a Feetech servo keeps only what was written while its Lock read 0); RAM comes back at
its power-up defaults, as on a real servo. Files are replaced atomically (temporary file,
fsync, rename).
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from snakebot.emulation.errors import EmulationError
from snakebot.emulation.virtual_servo import VirtualServo
from snakebot.errors import OutputError

FORMAT = "snakebot-emulator-state"
VERSION = 1


@dataclass(frozen=True)
class SavedServo:
    """One servo's saved EEPROM image and model number."""

    model_number: int
    eeprom: bytes


def eeprom_image(servo: VirtualServo) -> SavedServo:
    """The servo's EEPROM bytes as a power cycle would bring them back (on a Feetech servo only
    what was written while Lock read 0)."""
    return SavedServo(servo.table.model_number, servo.saved_eeprom)


MAX_STATE_BYTES = 16 << 20
"""Largest state file read (16 MiB; 253 servos' EEPROM take about 40 kB)."""


def save_state(path: Path, servos: Iterable[VirtualServo]) -> dict[int, SavedServo]:
    """Write every servo's EEPROM to ``path`` atomically; returns what was written.

    The new state goes to a temporary file beside ``path``, is flushed to the disk, and only
    then replaces ``path``: a full disk or a read-only folder leaves the previous state file as
    it was. OutputError naming ``path`` when it cannot be written, or is not a regular file
    (a device such as /dev/full must not be replaced by a state file).
    """
    images = {s.serial_number: eeprom_image(s) for s in servos}
    payload = {
        "format": FORMAT,
        "version": VERSION,
        "servos": {
            str(serial): {"model_number": image.model_number, "eeprom": image.eeprom.hex()}
            for serial, image in sorted(images.items())
        },
    }
    data = (json.dumps(payload, indent=1) + "\n").encode("utf-8")
    kept = " (the previous state file is kept)" if path.is_file() else ""
    if os.path.lexists(path) and not path.is_file():
        raise OutputError(
            path,
            "cannot save the emulated servos' EEPROM here: not a regular "
            "file; give a state file path",
        )
    temp: Path | None = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        temp = Path(name)
        try:
            view = memoryview(data)
            while view:
                view = view[os.write(handle, view) :]
            os.fsync(handle)
        finally:
            os.close(handle)
        os.replace(temp, path)
        temp = None
    except OSError as exc:
        raise OutputError(
            path, f"cannot save the emulated servos' EEPROM: {exc.strerror or exc}{kept}"
        ) from exc
    finally:
        if temp is not None:
            temp.unlink(missing_ok=True)
    return images


def load_state(path: Path) -> dict[int, SavedServo]:
    """``{serial: SavedServo}`` from a state file; EmulationError saying what is wrong with it
    (not a regular file of at most MAX_STATE_BYTES, not JSON, not a state file)."""
    try:
        if not path.is_file():
            raise ValueError("not a regular file")
        if path.stat().st_size > MAX_STATE_BYTES:
            raise ValueError(f"larger than {MAX_STATE_BYTES} bytes")
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, Mapping):
            raise ValueError("expected a JSON object")
        if data.get("format") != FORMAT or data.get("version") != VERSION:
            raise ValueError(f"expected format {FORMAT!r} version {VERSION}")
        servos = data["servos"]
        if not isinstance(servos, Mapping):
            raise ValueError("'servos' must be an object keyed by serial number")
        return {
            int(serial): SavedServo(int(entry["model_number"]), bytes.fromhex(entry["eeprom"]))
            for serial, entry in servos.items()
        }
    except (OSError, ValueError, KeyError, TypeError, RecursionError) as exc:
        raise EmulationError(f"{path}: not a usable emulator state file: {exc}") from exc


def restore(servo: VirtualServo, saved: SavedServo) -> None:
    """Load a saved EEPROM image into ``servo`` and power it up (RAM at its defaults)."""
    if saved.model_number != servo.table.model_number:
        raise EmulationError(
            f"serial {servo.serial_number} was saved as model "
            f"{saved.model_number}, not {servo.table.model_number}"
        )
    end = servo.table.specs.eeprom_end
    if len(saved.eeprom) != end:
        raise EmulationError(
            f"serial {servo.serial_number}: {len(saved.eeprom)} EEPROM bytes "
            f"saved, the model has {end}"
        )
    servo.memory.data[:end] = saved.eeprom
    servo.memory.version += 1
    servo.save_eeprom()
    servo.reboot()
