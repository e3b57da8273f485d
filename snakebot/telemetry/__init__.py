"""Crash-safe per-cycle telemetry: a CSV writer and its reader."""

from snakebot.telemetry.csv_log import CsvTelemetryWriter, TelemetryLog, column_names, read_log

__all__ = ["CsvTelemetryWriter", "TelemetryLog", "column_names", "read_log"]
