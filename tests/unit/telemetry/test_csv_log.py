from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from snakebot.errors import ConfigError
from snakebot.telemetry import CsvTelemetryWriter, column_names, read_log


def test_rows_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    with CsvTelemetryWriter(path, 3) as log:
        for cycle in range(5):
            q = np.array([0.1, -0.2, 0.3]) * cycle
            log.write(cycle * 0.01, cycle, q, q + 0.01, q * 2, q * 3, np.array([cycle, 0.0, 0.02]))
        log.write(0.05, 5, q, q, q, q, None)
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
            log.write(cycle * 0.01, cycle, np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2), None)
    with path.open("a") as handle:
        handle.write("0.03,3,0.1,0.2")  # a writer killed mid-line
    assert read_log(path).values.shape[0] == 3


def test_unwritable_log_is_a_config_error(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(ConfigError, match="cannot write log file"):
        CsvTelemetryWriter(blocker / "sub" / "run.csv", 2)
