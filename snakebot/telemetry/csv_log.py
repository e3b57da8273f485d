"""Per-cycle telemetry as CSV, one unbuffered write per cycle so a kill -9 loses nothing.

A returned ``write()`` is in the kernel's page cache, which survives a process crash; a power cut
needs ``fsync``, which ``close`` does. Only a partially written last line can be torn; the reader
drops it. (telemetry.md: CSV + per-record write lost 0 records under SIGKILL at 1 kHz.)
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType

import numpy as np

from snakebot.errors import ConfigError


def column_names(joint_count: int) -> list[str]:
    """CSV header: time, cycle, then per-joint command/position/velocity/effort, then the COM."""
    columns = ["time_s", "cycle"]
    for prefix in ("command_rad", "position_rad", "velocity_rad_s", "effort_nm"):
        columns += [f"{prefix}_{i}" for i in range(joint_count)]
    return [*columns, "com_x_m", "com_y_m", "com_z_m"]


class CsvTelemetryWriter:
    """Appends one row per control cycle to ``path`` (created or truncated)."""

    def __init__(self, path: str | Path, joint_count: int) -> None:
        self.path = Path(path)
        self.joint_count = joint_count
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        except OSError as exc:
            raise ConfigError(str(path), "", f"cannot write log file: {exc.strerror}") from exc
        values = 4 * joint_count + 3
        self._format = "%.6f,%d," + ",".join(["%.6g"] * values) + "\n"
        os.write(self._fd, (",".join(column_names(joint_count)) + "\n").encode())
        self.rows = 0

    def write(
        self,
        time_s: float,
        cycle: int,
        command: np.ndarray,
        position: np.ndarray,
        velocity: np.ndarray,
        effort: np.ndarray,
        com: np.ndarray | None,
    ) -> None:
        """Write one cycle; ``com`` None (hardware) is written as NaN."""
        if self._fd is None:
            raise ValueError(f"telemetry log {self.path} is closed")
        com_values = _NAN3 if com is None else com
        row = np.concatenate((command, position, velocity, effort, com_values)).tolist()
        os.write(self._fd, (self._format % (time_s, cycle, *row)).encode())
        self.rows += 1

    def close(self) -> None:
        """Flush to disk and close; idempotent."""
        if self._fd is not None:
            os.fsync(self._fd)
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> CsvTelemetryWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


_NAN3 = np.full(3, np.nan)


@dataclass(frozen=True)
class TelemetryLog:
    """A log read back: column names and a (rows, columns) float array."""

    columns: list[str]
    values: np.ndarray

    def column(self, name: str) -> np.ndarray:
        """One column by name."""
        return self.values[:, self.columns.index(name)]

    def joints(self, prefix: str) -> np.ndarray:
        """All per-joint columns with ``prefix`` (e.g. ``position_rad``), shape (rows, N)."""
        index = [i for i, c in enumerate(self.columns) if c.rsplit("_", 1)[0] == prefix]
        return self.values[:, index]


def read_log(path: str | Path) -> TelemetryLog:
    """Read a telemetry CSV, dropping a torn last line left by a killed writer."""
    text = Path(path).read_text()
    lines = text.split("\n")
    if not lines or not lines[0]:
        raise ConfigError(str(path), "", "empty telemetry log (no header)")
    columns = lines[0].split(",")
    # The last element is "" after a complete file, or a line torn by a kill: drop it either way.
    rows = [line.split(",") for line in lines[1:-1] if line]
    rows = [r for r in rows if len(r) == len(columns)]
    values = np.array(rows, dtype=float).reshape(len(rows), len(columns))
    return TelemetryLog(columns, values)
