from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from snakebot.errors import ConfigError, OutputError
from snakebot.telemetry import CsvTelemetryWriter, column_names, read_log
from tests.records import record


def test_rows_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    with CsvTelemetryWriter(path, 3) as log:
        for cycle in range(5):
            q = np.array([0.1, -0.2, 0.3]) * cycle
            log(record(cycle, cycle * 0.01, q, q + 0.01, q * 2, q * 3, np.array([cycle, 0, 0.02])))
        log(record(5, 0.05, q))
    data = read_log(path)
    assert data.columns == column_names(3)
    assert data.values.shape == (6, len(column_names(3)))
    np.testing.assert_allclose(data.joints("command_rad")[4], [0.4, -0.8, 1.2])
    np.testing.assert_allclose(data.column("com_x_m")[:5], np.arange(5))
    assert np.isnan(data.column("com_x_m")[5])


def test_torn_last_line_is_dropped(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    with CsvTelemetryWriter(path, 2) as log:
        for cycle in range(3):
            log(record(cycle, cycle * 0.01, np.zeros(2)))
    with path.open("a") as handle:
        handle.write("0.03,3,0.1,0.2")  # a writer killed mid-line
    assert read_log(path).values.shape[0] == 3


def test_unwritable_log_is_an_output_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(OutputError, match="cannot write log file"):
        CsvTelemetryWriter(blocker / "sub" / "run.csv", 2)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_full_device_is_an_output_error_naming_it() -> None:
    with pytest.raises(OutputError, match=r"^/dev/full: cannot write log file: No space left"):
        CsvTelemetryWriter("/dev/full", 2)


# Writes rows until the file-size limit stops it (CPython ignores SIGXFSZ: the write fails).
WRITER = """
import sys
import numpy as np
from snakebot.errors import OutputError
from snakebot.control.cycle import CycleRecord
from snakebot.telemetry import CsvTelemetryWriter
from snakebot.types import JointState
q = np.full(4, 0.123456)
with CsvTelemetryWriter(sys.argv[1], 4) as log:
    try:
        for cycle in range(100000):
            state = JointState(cycle * 0.01, q, q, q)
            log(CycleRecord(cycle + 1, state.time_s, q, q, state, None, 1, True, 0.01, False, 1))
    except OutputError as exc:
        print(log.rows)
        print(exc)
"""


@pytest.mark.skipif(os.name != "posix", reason="RLIMIT_FSIZE is POSIX")
def test_a_file_size_limit_is_an_output_error_and_the_rows_before_it_stay(tmp_path: Path) -> None:
    import resource

    path = tmp_path / "run.csv"

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))

    done = subprocess.run(
        [sys.executable, "-c", WRITER, str(path)],
        preexec_fn=limit,
        capture_output=True,
        text=True,
        timeout=60,
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
    )
    assert done.returncode == 0, done.stderr
    rows, message = done.stdout.splitlines()
    assert message.startswith(f"{path}: cannot write telemetry row {rows}: File too large")
    assert path.stat().st_size == 20_000  # up to the limit, the last row torn
    data = read_log(path)
    assert data.values.shape[0] == int(rows) > 50
    np.testing.assert_array_equal(data.column("cycle"), np.arange(int(rows)))


def test_reading_a_missing_log_names_it(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read telemetry log") as info:
        read_log(tmp_path / "nope.csv")
    assert info.value.source == str(tmp_path / "nope.csv")


def test_a_binary_file_is_not_a_log(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_bytes(b"time_s,cycle\n\xff\xfe\x00\x01")
    with pytest.raises(ConfigError, match="not UTF-8") as info:
        read_log(path)
    assert info.value.source == str(path)


def test_a_value_that_is_not_a_number_names_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_text("time_s,cycle,position_rad_0\n0.0,0,0.1\n0.01,1,abc\n")
    with pytest.raises(ConfigError, match="expected a number, got 'abc'") as info:
        read_log(path)
    assert info.value.key == "line 3, column position_rad_0"
    assert info.value.source == str(path)


def test_a_missing_column_names_file_and_column(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_text("cycle,position_rad_0\n0,0.1\n")
    with pytest.raises(ConfigError, match="missing column") as info:
        read_log(path).column("time_s")
    assert (info.value.source, info.value.key) == (str(path), "time_s")


def _log(tmp_path: Path, rows: int = 4) -> Path:
    path = tmp_path / "run.csv"
    with CsvTelemetryWriter(path, 2) as log:
        for cycle in range(rows):
            q = np.full(2, 0.1 * cycle)
            log(record(cycle, cycle * 0.01, q, q, q, q, np.zeros(3)))
    return path


def _set_cell(path: Path, line: int, column: str, value: str) -> None:
    lines = path.read_text().split("\n")
    index = lines[0].split(",").index(column)
    cells = lines[line - 1].split(",")
    cells[index] = value
    lines[line - 1] = ",".join(cells)
    path.write_text("\n".join(lines))


@pytest.mark.parametrize(
    ("column", "value", "reason"),
    [
        ("time_s", "nan", "never empty or NaN"),
        ("cycle", "nan", "never empty or NaN"),
        ("position_rad_1", "1e308", "finite number within"),
        ("effort_nm_0", "-inf", "finite number within"),
        ("time_s", "inf", "finite number within"),
        ("time_s", "0.0", "time runs backwards"),
    ],
)
def test_a_corrupt_value_names_file_line_and_column(
    tmp_path: Path, column: str, value: str, reason: str
) -> None:
    path = _log(tmp_path)
    _set_cell(path, 4, column, value)  # line 4: the third row, time 0.02 s
    with pytest.raises(ConfigError) as info:
        read_log(path)
    assert (info.value.source, info.value.key) == (str(path), f"line 4, column {column}")
    assert reason in info.value.reason


def test_nan_where_the_hardware_has_no_value_still_reads(tmp_path: Path) -> None:
    path = _log(tmp_path)
    _set_cell(path, 3, "com_x_m", "nan")
    assert np.isnan(read_log(path).column("com_x_m")[1])


@pytest.mark.parametrize("header", ["time_s,,cycle", "time_s,time_s", "time_s,cy\u202ecle"])
def test_a_header_that_is_not_column_names_is_refused(tmp_path: Path, header: str) -> None:
    path = tmp_path / "run.csv"
    path.write_text(header + "\n")
    with pytest.raises(ConfigError) as info:
        read_log(path)
    assert info.value.source == str(path) and info.value.key.startswith("line 1, column ")


def test_only_a_regular_file_is_read(tmp_path: Path) -> None:
    # /dev/zero would be read without end; a FIFO with no writer would block for ever.
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    for path in (Path("/dev/zero"), fifo, tmp_path):
        with pytest.raises(ConfigError, match="not a regular file") as info:
            read_log(path)
        assert info.value.source == str(path)
