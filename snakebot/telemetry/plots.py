"""PNG plots of a telemetry log (``snakebot log plot``), matplotlib on the headless Agg backend.

joints.png (command and measured, one panel per joint), tracking.png (command - measured),
efforts.png, com_path.png (the centre of mass seen from above; twin logs only) and timing.png
(the period between rows and the late ones). About a second for a 20 s log
(tools/bench_log_plot.py).
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

from snakebot.errors import MissingDependencyError
from snakebot.telemetry.csv_log import TelemetryLog
from snakebot.telemetry.log_summary import LATE_FACTOR, com_path, nominal_period_s

INSTALL = "pip install 'snakebot[logs]'"
DPI = 100
_MARGINS = {"left": 0.09, "right": 0.97, "bottom": 0.11, "top": 0.88, "hspace": 0.12}


def pyplot() -> Any:
    """matplotlib.pyplot on Agg; MissingDependencyError with the install command."""
    try:
        import matplotlib
    except ImportError as exc:
        raise MissingDependencyError(f"snakebot log plot needs matplotlib: {INSTALL}") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


PLOT_FILES = ("joints.png", "tracking.png", "efforts.png", "com_path.png", "timing.png")
"""The PNGs :func:`plot_log` writes (com_path.png only for a log with the centre of mass)."""


def plot_log(log: TelemetryLog, sidecar: dict[str, Any] | None, folder: Path) -> list[Path]:
    """Write the PNGs into ``folder`` (which exists) and return their paths."""
    plt = pyplot()
    title = _title(log, sidecar)
    time_s = log.column("time_s") - log.column("time_s")[0]
    command, position = log.joints("command_rad"), log.joints("position_rad")
    paths = [
        _joint_grid(plt, time_s, command, position, title, folder / "joints.png"),
        _per_joint(
            plt,
            time_s,
            command - position,
            "tracking error (command - measured) [rad]",
            title,
            folder / "tracking.png",
            rms=True,
        ),
        _per_joint(
            plt, time_s, log.joints("effort_nm"), "effort [N m]", title, folder / "efforts.png"
        ),
    ]
    com = com_path(log)
    if com is not None:
        paths.append(_com(plt, com, title, folder / "com_path.png"))
    paths.append(_timing(plt, log, sidecar, title, folder / "timing.png"))
    return paths


def _title(log: TelemetryLog, sidecar: dict[str, Any] | None) -> str:
    name = Path(log.source).name
    if not sidecar:
        return name
    robot = sidecar.get("robot", {}).get("name", "?")
    gait = sidecar.get("gait", {}).get("name") if isinstance(sidecar.get("gait"), dict) else None
    gaits = [g.get("name") for g in sidecar.get("gaits", []) if isinstance(g, dict)]
    what = gait or ", ".join(str(g) for g in gaits) or sidecar.get("command", "")
    return f"{name}: {robot} / {what} on {sidecar.get('backend', '?')}"


def _wrap(title: str, width_in: float) -> str:
    """``title`` in lines that fit a figure ``width_in`` inches wide at font size 9."""
    return textwrap.fill(title, width=int(width_in * 12), break_on_hyphens=False)


def _save(plt: Any, fig: Any, path: Path) -> Path:
    fig.savefig(path, dpi=DPI, bbox_inches="tight")  # labels and titles never clipped
    plt.close(fig)
    return path


def _joint_grid(
    plt: Any,
    time_s: np.ndarray,
    command: np.ndarray,
    position: np.ndarray,
    title: str,
    path: Path,
) -> Path:
    joints = command.shape[1]
    cols = 2 if joints > 4 else 1
    rows = math.ceil(joints / cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(6.5 * cols, 1.5 * rows + 1), sharex=True, squeeze=False
    )
    for joint in range(joints):
        ax = axes[joint % rows][joint // rows]
        ax.plot(time_s, command[:, joint], lw=1.0, color="tab:orange", label="command")
        ax.plot(time_s, position[:, joint], lw=1.0, color="tab:blue", label="measured")
        ax.set_ylabel(f"joint {joint}\n[rad]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    for ax in axes.flat[joints:]:
        ax.set_visible(False)
    axes[0][0].legend(loc="upper right", fontsize=7, ncol=2)
    for col in range(cols):
        axes[rows - 1][col].set_xlabel("time [s]")
    fig.suptitle(f"{title}\ncommand vs measured, joint 0 = head", fontsize=9)
    # Fixed margins: tight_layout draws the whole figure once more to measure it.
    fig.subplots_adjust(
        left=0.09 / cols,
        right=0.98,
        bottom=0.6 / fig.get_figheight(),
        top=1 - 0.55 / fig.get_figheight(),
        hspace=0.25,
        wspace=0.18,
    )
    return _save(plt, fig, path)


def _per_joint(
    plt: Any,
    time_s: np.ndarray,
    values: np.ndarray,
    label: str,
    title: str,
    path: Path,
    *,
    rms: bool = False,
) -> Path:
    fig, ax = plt.subplots(figsize=(9, 4.5))
    colors = plt.get_cmap("viridis")(np.linspace(0, 0.9, values.shape[1]))
    for joint in range(values.shape[1]):
        ax.plot(time_s, values[:, joint], lw=0.8, color=colors[joint], label=f"joint {joint}")
    if rms:
        ax.plot(
            time_s,
            np.sqrt(np.mean(values**2, axis=1)),
            lw=2.0,
            color="black",
            label="RMS over joints",
        )
    ax.set_xlabel("time [s]")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=4, loc="upper right")
    ax.set_title(title, fontsize=9)
    fig.subplots_adjust(**_MARGINS)
    return _save(plt, fig, path)


def _com(plt: Any, com: np.ndarray, title: str, path: Path) -> Path:
    # Square and narrow: the title wraps, and the layout makes room for it and the tick labels.
    fig, ax = plt.subplots(figsize=(6, 6), layout="constrained")
    ax.plot(com[:, 0], com[:, 1], lw=1.5, color="tab:blue")
    ax.plot(*com[0, :2], "o", color="tab:green", label="start")
    ax.plot(*com[-1, :2], "s", color="tab:red", label="end")
    ax.set_aspect("equal", adjustable="datalim")
    ax.locator_params(nbins=5)  # a few metres' path leaves room for five tick labels, not ten
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    distance = float(np.hypot(*(com[-1, :2] - com[0, :2])))
    ax.set_title(
        f"{_wrap(title, 6)}\ncentre of mass from above: {distance:.3f} m start to end", fontsize=9
    )
    return _save(plt, fig, path)


def _timing(
    plt: Any, log: TelemetryLog, sidecar: dict[str, Any] | None, title: str, path: Path
) -> Path:
    time_s = log.column("time_s")
    periods_ms = np.diff(time_s) * 1e3
    period = nominal_period_s(log, sidecar)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    t = time_s[1:] - time_s[0]
    top.plot(t, periods_ms, lw=0.8, color="tab:blue", label="period between rows")
    late = np.zeros(periods_ms.shape, dtype=bool)
    if period:
        top.axhline(period * 1e3, color="black", lw=1, ls="--", label="control period")
        late = periods_ms > LATE_FACTOR * period * 1e3
        top.plot(t[late], periods_ms[late], "x", color="tab:red", label="late (> 1.5 periods)")
    top.set_ylabel("period [ms]")
    top.grid(alpha=0.3)
    top.legend(fontsize=7, loc="upper right")
    window = max(round(1.0 / period) if period else 10, 1)  # a one-second moving rate
    if len(t) >= window:
        rate = window / np.convolve(periods_ms / 1e3, np.ones(window), mode="valid")
        bottom.plot(t[window - 1 :], rate, lw=1.0, color="tab:green")
    bottom.set_ylabel("rate over 1 s [Hz]")
    bottom.set_xlabel("time [s]")
    bottom.grid(alpha=0.3)
    achieved = (len(time_s) - 1) / (time_s[-1] - time_s[0]) if len(time_s) > 1 else float("nan")
    top.set_title(f"{title}\nachieved {achieved:.1f} Hz, {int(late.sum())} late cycles", fontsize=9)
    fig.subplots_adjust(**_MARGINS)
    return _save(plt, fig, path)
