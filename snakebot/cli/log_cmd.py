"""``snakebot log``: look at a telemetry CSV: ``plot`` (PNGs), ``info`` (a summary like
``run --json``) and ``export`` (MCAP for Foxglove, or Parquet)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from snakebot.cli.common import (
    add_dry_run,
    add_force_option,
    check_folder,
    check_writable,
    make_folder,
    print_json,
    report_dry_run,
)
from snakebot.errors import ConfigError, UsageError
from snakebot.telemetry import TelemetryLog, read_log


def add_parser(subparsers: Any) -> None:
    """Register ``log plot``, ``log info`` and ``log export``."""
    parser = subparsers.add_parser(
        "log",
        help="look at a telemetry CSV (from run/drive --log): plot, info, export",
        description="Read a telemetry CSV written by `snakebot run --log` or `drive --log` "
        "(and the JSON sidecar beside it, run.csv.json).",
    )
    actions = parser.add_subparsers(dest="log_command", metavar="ACTION", required=True)

    plot = actions.add_parser(
        "plot",
        help="PNGs: command vs measured, tracking, efforts, "
        "centre-of-mass path, rate and late cycles",
    )
    plot.add_argument("log", type=Path, help="telemetry CSV")
    plot.add_argument(
        "--out", type=Path, help="folder for the PNGs (default: LOG without .csv, plus _plots)"
    )
    plot.add_argument("--json", action="store_true", help="list the PNGs as JSON")
    add_force_option(plot)
    add_dry_run(plot, "no PNGs")
    plot.set_defaults(handler=run_plot, writes=True)

    info = actions.add_parser("info", help="a summary of the run, from the file")
    info.add_argument("log", type=Path, help="telemetry CSV")
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.set_defaults(handler=run_info, writes=False)

    export = actions.add_parser("export", help="write the log as MCAP (Foxglove) or Parquet")
    export.add_argument("log", type=Path, help="telemetry CSV")
    export.add_argument("--format", choices=("mcap", "parquet"), required=True)
    export.add_argument(
        "--mcap-encoding",
        choices=("json", "ros2"),
        default="json",
        help="--format mcap: json (default: the Foxglove channels) or ros2 (standard ROS 2 "
        "messages in CDR, as run --mcap-encoding ros2 writes; extra: snakebot[ros2-mcap])",
    )
    export.add_argument(
        "--out",
        type=Path,
        help="output file (default: LOG's name with "
        ".export.mcap or .export.parquet: drive.csv -> drive.export.mcap)",
    )
    add_force_option(export)
    export.add_argument("--json", action="store_true", help="print what was written as JSON")
    add_dry_run(export, "no output file")
    export.set_defaults(handler=run_export, writes=True)


def _load(path: Path) -> tuple[TelemetryLog, dict[str, Any] | None]:
    from snakebot.telemetry.sidecar import read_sidecar

    log = read_log(path)
    if len(log.values) == 0:
        raise ConfigError(path, "", "the log has a header but no rows")
    return log, read_sidecar(path)


def run_plot(args: argparse.Namespace) -> int:
    """Write the PNGs and list them."""
    from snakebot.telemetry.plots import PLOT_FILES, plot_log, pyplot

    pyplot()  # a missing matplotlib is said before the log is read
    log, sidecar = _load(args.log)
    folder = args.out or args.log.with_name(args.log.stem + "_plots")
    check_folder(folder, "plot", replaces=PLOT_FILES, force=args.force)
    if args.dry_run:
        return report_dry_run(args, {"log": args.log, "rows": len(log.values), "out": folder})
    make_folder(folder, "plots")
    start = time.perf_counter()
    paths = plot_log(log, sidecar, folder)
    if args.json:
        print_json({"log": str(args.log), "rows": len(log.values), "plots": list(map(str, paths))})
        return 0
    print(
        f"{len(paths)} plots of {len(log.values)} rows in {folder} "
        f"({time.perf_counter() - start:.1f} s):"
    )
    for path in paths:
        print(f"  {path}")
    return 0


def run_info(args: argparse.Namespace) -> int:
    """Print the log's summary."""
    from snakebot.telemetry.log_summary import summarize

    log, sidecar = _load(args.log)
    summary = summarize(log, sidecar)
    if args.json:
        print_json(summary)
        return 0

    def fmt(key: str, unit: str = "", digits: int = 3) -> str:
        value = summary.get(key)
        if value is None:
            return "n/a"
        return f"{value:.{digits}f}{unit}" if isinstance(value, float) else f"{value}{unit}"

    gait = summary["gait"]
    gait_text = ", ".join(map(str, gait)) if isinstance(gait, list) else str(gait or "?")
    lines = [
        f"{args.log}: {summary['robot'] or '?'} / {gait_text} on {summary['backend'] or '?'} "
        f"({summary['command'] or 'no sidecar'}; snakebot {summary['snakebot_version'] or '?'})",
        f"  time         {fmt('duration_s', ' s', 2)}, {summary['rows']} rows at "
        f"{fmt('achieved_rate_hz', ' Hz', 1)} of {fmt('rate_hz', ' Hz', 1)} "
        f"({summary['late_cycles']} late)",
        f"  distance     {fmt('distance_m', ' m')} at heading {fmt('heading_deg', ' deg', 1)} "
        f"({fmt('speed_mps', ' m/s')}); path {fmt('path_length_m', ' m')}",
        f"  tracking     {fmt('tracking_rms_rad', ' rad RMS', 4)}, worst "
        f"{fmt('worst_tracking_rad', ' rad')} (joint {summary['worst_tracking_joint']}); max "
        f"command {fmt('max_abs_command_rad', ' rad')}",
        f"  effort       max {fmt('max_abs_effort_nm', ' N m')}; positive work "
        f"{fmt('positive_work_j', ' J')}; cost of transport {fmt('cost_of_transport')}",
    ]
    print("\n".join(lines))
    return 0


FORMAT_NAMES = {"mcap": "MCAP", "parquet": "Parquet"}


def export_path(log: Path, fmt: str) -> Path:
    """``log export``'s default output: the log's name with ``.export.FORMAT``
    (``drive.csv`` -> ``drive.export.mcap``), never the ``drive.mcap`` a ``--mcap`` recording
    beside it is usually called."""
    return log.with_name(f"{log.stem}.export.{fmt}")


def run_export(args: argparse.Namespace) -> int:
    """Write the MCAP or Parquet file."""
    from snakebot.telemetry.export import export_mcap, export_parquet, export_ros2_mcap

    ros2 = args.mcap_encoding == "ros2"
    if ros2 and args.format != "mcap":
        raise UsageError("--mcap-encoding ros2 goes with --format mcap")
    if ros2:
        from snakebot.telemetry.ros2_mcap import mcap_writer_module

        mcap_writer_module()  # a missing extra is said before the log is read
    elif args.format == "mcap":
        from snakebot.telemetry.foxglove_live import foxglove_module

        foxglove_module()  # a missing SDK is said before the log is read
    out = args.out or export_path(args.log, args.format)
    if out.resolve() == args.log.resolve():
        raise ConfigError("--out", "", f"{out} is the log itself; name another file")
    log, sidecar = _load(args.log)
    check_writable(out, f"{FORMAT_NAMES[args.format]} file", force=args.force)
    if args.dry_run:
        return report_dry_run(
            args, {"log": args.log, "rows": len(log.values), "out": out, "format": args.format}
        )
    export = export_mcap if args.format == "mcap" else export_parquet
    rows = (export_ros2_mcap if ros2 else export)(log, sidecar, out)
    if args.json:
        print_json({"log": str(args.log), "out": str(out), "format": args.format, "rows": rows})
    else:
        print(f"{out}: {rows} cycles as {args.format}")
    return 0
