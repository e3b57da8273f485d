"""Per-cycle telemetry as CSV, one unbuffered write per cycle so a kill -9 loses nothing.

A returned ``write()`` is in the kernel's page cache, which survives a process crash; a power cut
needs ``fsync``, which ``close`` does. Only a partially written last line can be torn; the reader
drops it. (telemetry.md: CSV + per-record write lost 0 records under SIGKILL at 1 kHz.)

A failed write (disk full, a device like /dev/full, a file-size limit: CPython ignores SIGXFSZ,
so ``ulimit -f`` fails the write with EFBIG instead of killing the process) raises
:class:`~snakebot.errors.OutputError` naming the file; the rows before it stay on disk.
"""

from __future__ import annotations

import contextlib
import errno
import os
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING

import numpy as np

from snakebot.config.input_file import MAX_NAME_CHARS, read_input, text_problem
from snakebot.errors import ConfigError, OutputError

if TYPE_CHECKING:
    from snakebot.control.cycle import CycleRecord


def column_names(joint_count: int) -> list[str]:
    """CSV header: time, cycle, then per-joint command/position/velocity/effort, then the COM,
    then the head IMU (orientation quaternion w, x, y, z and the gyro's angular rate in the
    head's frame)."""
    columns = ["time_s", "cycle"]
    for prefix in ("command_rad", "position_rad", "velocity_rad_s", "effort_nm"):
        columns += [f"{prefix}_{i}" for i in range(joint_count)]
    imu = ["imu_qw", "imu_qx", "imu_qy", "imu_qz", "gyro_x_rad_s", "gyro_y_rad_s", "gyro_z_rad_s"]
    return [*columns, "com_x_m", "com_y_m", "com_z_m", *imu]


class CsvTelemetryWriter:
    """Appends one row per control cycle to ``path`` (created or truncated): a
    :class:`~snakebot.control.cycle.CycleSink`, called with each cycle's record.

    OutputError naming the file if it cannot be created or a write fails.
    """

    def __init__(self, path: str | Path, joint_count: int) -> None:
        self.path = Path(path)
        self.joint_count = joint_count
        self.rows = 0
        self._fd: int | None = None
        try:
            if self.path.parent.exists() and not self.path.parent.is_dir():
                raise NotADirectoryError(errno.ENOTDIR, "Not a directory", str(self.path.parent))
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            _write_all(self._fd, (",".join(column_names(joint_count)) + "\n").encode())
        except OSError as exc:
            self._close_quietly()
            raise OutputError(self.path, f"cannot write log file: {_reason(exc)}") from exc
        values = 4 * joint_count + 3 + 7
        # bytes %-formatting: the same text as str's, and no encode (a third of a row's cost)
        self._format = ("%.6f,%d," + ",".join(["%.6g"] * values) + "\n").encode()

    def __call__(self, record: CycleRecord) -> None:
        """Write one cycle's record as a row: its ``cycle`` counted from 0, the command sent,
        the measured state, and the body's COM and head IMU, NaN where the backend has none
        (hardware: no COM; a twin without a gyro)."""
        if self._fd is None:
            raise ValueError(f"telemetry log {self.path} is closed")
        state, body = record.state, record.body
        if body is None:
            com, quat, gyro = _NAN3, _NAN4, _NAN3
        else:
            com, quat = body.com_m, body.head_quat
            gyro = _NAN3 if body.head_gyro_rad_s is None else body.head_gyro_rad_s
        row = np.concatenate(
            (
                record.command_rad,
                state.position_rad,
                state.velocity_rad_s,
                state.effort_nm,
                com,
                quat,
                gyro,
            )
        ).tolist()
        try:
            _write_all(self._fd, self._format % (state.time_s, record.cycle - 1, *row))
        except OSError as exc:
            raise OutputError(
                self.path,
                f"cannot write telemetry row {self.rows}: {_reason(exc)}; the {self.rows} rows "
                "before it are on disk",
            ) from exc
        self.rows += 1

    def close(self) -> None:
        """Flush to disk and close; idempotent. OutputError if the flush fails (the file is
        closed all the same)."""
        if self._fd is None:
            return
        try:
            os.fsync(self._fd)
        except OSError as exc:
            if exc.errno not in (errno.EINVAL, errno.EROFS):  # a pipe or device: nothing to sync
                self._close_quietly()
                raise OutputError(self.path, f"cannot flush log file: {_reason(exc)}") from exc
        self._close_quietly()

    def _close_quietly(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            with contextlib.suppress(OSError):
                os.close(fd)

    def __enter__(self) -> CsvTelemetryWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


_NAN4 = np.full(4, np.nan)
_NAN3 = np.full(3, np.nan)


def _write_all(fd: int, data: bytes) -> None:
    # A write cut short (a file-size limit reached mid-row) is retried so that the error of the
    # next attempt surfaces; the reader drops the torn row it leaves.
    written = os.write(fd, data)
    if written == len(data):  # the one write of every cycle
        return
    view = memoryview(data)[written:]
    while view:
        view = view[os.write(fd, view) :]


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


@dataclass(frozen=True)
class TelemetryLog:
    """A log read back: column names and a (rows, columns) float array; ``source`` its file."""

    columns: list[str]
    values: np.ndarray
    source: str = ""

    def column(self, name: str) -> np.ndarray:
        """One column by name; ConfigError naming the file if the log has no such column."""
        if name not in self.columns:
            raise ConfigError(
                self.source or "telemetry log", name, "missing column (not a snakebot log?)"
            )
        return self.values[:, self.columns.index(name)]

    def joints(self, prefix: str) -> np.ndarray:
        """All per-joint columns with ``prefix`` (e.g. ``position_rad``), shape (rows, N)."""
        index = [i for i, c in enumerate(self.columns) if c.rsplit("_", 1)[0] == prefix]
        return self.values[:, index]


MAX_LOG_BYTES = 1 << 30
"""Largest telemetry CSV read (1 GiB: about six hours of a 12-joint snake at 100 Hz)."""

MAX_LOG_VALUE = 1e9
"""Largest magnitude of a logged value: no angle, speed, torque, position or time comes near it;
1e308 in a log is corruption, and would overflow the summaries' squares to inf."""

NAN_FREE_COLUMNS = ("time_s", "cycle")
"""Columns that are never empty (NaN); the centre of mass is NaN on hardware, for example."""


def read_log(path: str | Path) -> TelemetryLog:
    """Read a telemetry CSV, dropping a torn last line left by a killed writer.

    ConfigError naming the file (and the line and column) if it is not a regular file of at
    most MAX_LOG_BYTES, is not UTF-8 text, has a header with empty, repeated or unprintable
    names, holds a value that is not a number, is infinite or beyond +-MAX_LOG_VALUE, a NaN in
    ``time_s`` or ``cycle``, or a ``time_s`` that runs backwards.
    """
    source = str(path)
    data = read_input(path, what="telemetry log", limit_bytes=MAX_LOG_BYTES)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(
            source, "", f"not a telemetry log: not UTF-8 text (byte {exc.start}: {exc.reason})"
        ) from None
    lines = text.split("\n")
    if not lines[0]:
        raise ConfigError(source, "", "empty telemetry log (no header)")
    columns = lines[0].split(",")
    _check_header(source, columns)
    # The last element is "" after a complete file, or a line torn by a kill: drop it either way.
    rows = [(number, line.split(",")) for number, line in enumerate(lines[1:-1], 2) if line]
    rows = [(number, cells) for number, cells in rows if len(cells) == len(columns)]
    values = np.empty((len(rows), len(columns)))
    for index, (number, cells) in enumerate(rows):
        try:
            values[index] = [float(cell) for cell in cells]
        except ValueError:
            column, cell = next(
                (c, v) for c, v in zip(columns, cells, strict=True) if not _is_number(v)
            )
            raise ConfigError(
                source, f"line {number}, column {column}", f"expected a number, got {cell[:40]!r}"
            ) from None
    _check_values(source, columns, values, [number for number, _ in rows])
    return TelemetryLog(columns, values, source)


def _check_header(source: str, columns: list[str]) -> None:
    for index, name in enumerate(columns):
        problem = text_problem(name, max_chars=MAX_NAME_CHARS) if name else "an empty name"
        if problem is not None:
            raise ConfigError(
                source, f"line 1, column {index + 1}", f"not a column name: {problem}"
            )
        if name in columns[:index]:
            raise ConfigError(source, f"line 1, column {name}", "the column appears twice")


def _check_values(source: str, columns: list[str], values: np.ndarray, lines: list[int]) -> None:
    def refuse(row: int, col: int, why: str) -> None:
        raise ConfigError(
            source,
            f"line {lines[row]}, column {columns[col]}",
            f"{why}, got {float(values[row, col])!r}",
        )

    with np.errstate(invalid="ignore"):
        bad = np.isinf(values) | (np.abs(values) > MAX_LOG_VALUE)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        refuse(row, col, f"expected a finite number within +-{MAX_LOG_VALUE:g}")
    for name in NAN_FREE_COLUMNS:
        if name not in columns:
            continue
        col = columns.index(name)
        missing = np.isnan(values[:, col])
        if missing.any():
            refuse(int(np.argmax(missing)), col, "expected a number (never empty or NaN here)")
    if "time_s" in columns and len(values) > 1:
        col = columns.index("time_s")
        backwards = np.diff(values[:, col]) < 0
        if backwards.any():
            row = int(np.argmax(backwards)) + 1
            raise ConfigError(
                source,
                f"line {lines[row]}, column time_s",
                f"time runs backwards: {float(values[row, col])!r} s after "
                f"{float(values[row - 1, col])!r} s",
            )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
