"""PNG plots of tuning runs with matplotlib (headless Agg); optional: ``snakebot[tune]``."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from snakebot.errors import MissingDependencyError
from snakebot.tuning.trace import FloatArray
from snakebot.tuning.tuner import TuneResult

INSTALL = "pip install 'snakebot[tune]'"


def pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend; MissingDependencyError with the install command."""
    try:
        import matplotlib
    except ImportError as exc:
        raise MissingDependencyError(f"report plots need matplotlib: {INSTALL}") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def gait_plots(result: TuneResult, folder: Path) -> list[Path]:
    """convergence.png for every method, heatmap.png for a 1- or 2-parameter grid."""
    paths = [convergence_plot(result, folder / "convergence.png")]
    if result.grid is not None and len(result.grid.shape) <= 2:
        paths.append(heatmap_plot(result, folder / "heatmap.png"))
    return paths


def _label(result: TuneResult) -> str:
    unit = f" [{result.objective.unit}]" if result.objective.unit else ""
    return f"{result.objective.name}{unit}"


def convergence_plot(result: TuneResult, path: Path) -> Path:
    """Objective of every evaluation (crosses: not playable) and the best so far."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
    objective = result.objective
    xs = np.arange(1, len(result.history) + 1)
    values = np.array([e.value if e.feasible else math.nan for e in result.history])
    bad = np.array([not e.feasible for e in result.history])
    ax.plot(xs[~bad], values[~bad], ".", color="tab:blue", label="evaluation")
    best, running = [], math.nan
    for value in values:
        if objective.better(value, running):
            running = value
        best.append(running)
    ax.plot(xs, best, "-", color="tab:orange", lw=2, label="best so far")
    if bad.any():
        floor = np.nanmin(values) if np.isfinite(values).any() else 0.0
        ax.plot(xs[bad], np.full(bad.sum(), floor), "x", color="tab:red", label="not playable")
    base = result.baseline
    if base.feasible:
        ax.axhline(base.value, color="gray", ls="--", lw=1, label="baseline (start)")
    ax.set_xlabel("evaluation")
    ax.set_ylabel(_label(result))
    ax.set_title(
        f"{result.robot.name} / {result.space.gait}: {result.method}, "
        f"{len(result.history)} evaluations, {result.wall_s:.0f} s"
    )
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return _save(fig, path)


def heatmap_plot(result: TuneResult, path: Path) -> Path:
    """The grid's objective over its one or two parameters, values printed in the cells."""
    plt = pyplot()
    grid = result.grid
    assert grid is not None
    count = math.prod(grid.shape)
    rows = result.history[grid.first_index : grid.first_index + count]
    values = np.array([e.value if e.feasible else math.nan for e in rows]).reshape(grid.shape)
    names = result.space.names
    fig, ax = plt.subplots(figsize=(8, 6.4), dpi=110)
    if values.ndim == 1:
        ax.plot(grid.axes[0], values, "o-")
        ax.set_xlabel(names[0])
        ax.set_ylabel(_label(result))
    else:
        image = ax.imshow(values.T, origin="lower", aspect="auto", cmap="viridis")
        fig.colorbar(image, ax=ax, label=_label(result))
        _cell_text(ax, values)
        ax.set_xticks(range(len(grid.axes[0])), _ticks(grid.axes[0]), rotation=45)
        ax.set_yticks(range(len(grid.axes[1])), _ticks(grid.axes[1]))
        ax.set_xlabel(f"{names[0]} ({_unit(result, names[0])})")
        ax.set_ylabel(f"{names[1]} ({_unit(result, names[1])})")
    ax.set_title(
        f"{result.robot.name} / {result.space.gait}: {result.objective.name} over "
        f"{result.plan.duration_s:g} s runs (blank: not playable)"
    )
    return _save(fig, path)


def line_plots(
    path: Path,
    title: str,
    panels: Sequence[tuple[str, FloatArray, Mapping[str, FloatArray]]],
    xlabel: str = "time [s]",
) -> Path:
    """Stacked panels sharing x: each (y label, x values, {legend: y values})."""
    plt = pyplot()
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 2.6 * len(panels)), dpi=110, sharex=True)
    for ax, (ylabel, x, series) in zip(np.atleast_1d(axes), panels, strict=True):
        for label, y in series.items():
            ax.plot(x, y, label=label, lw=1.2)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    np.atleast_1d(axes)[-1].set_xlabel(xlabel)
    fig.suptitle(title)
    return _save(fig, path)


def _cell_text(ax: Any, values: FloatArray) -> None:
    finite = values[np.isfinite(values)]
    middle = float(np.mean([finite.min(), finite.max()])) if finite.size else 0.0
    for (i, j), value in np.ndenumerate(values):
        if np.isfinite(value):
            color = "black" if value > middle else "white"
            ax.text(i, j, f"{value:.2g}", ha="center", va="center", fontsize=7, color=color)


def _ticks(axis: FloatArray) -> list[str]:
    return [f"{v:.3g}" for v in axis]


def _unit(result: TuneResult, name: str) -> str:
    from snakebot.gaits import get_spec

    key = name.split("+")[0].split("[")[0]
    return get_spec(result.space.gait).param(key).unit or "-"


def _save(fig: Any, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path)
    fig.clf()
    pyplot().close(fig)
    return path


def gain_plots(search: Any, test: Any, folder: Path) -> list[Path]:
    """steps.png (each tested joint's step, current vs best gains) and chirp.png when measured."""
    now, best = search.current, search.best
    label_now = _gains_label("current", now.gains)
    label_best = _gains_label("best", best.gains)
    panels = []
    for joint, before, after in zip(test.joints, now.step_traces, best.step_traces, strict=True):
        t, command, position = before
        series = {"command": command, label_now: position, label_best: after[2]}
        panels.append((f"joint {joint} [rad]", t, series))
    paths = [line_plots(folder / "steps.png", "Step responses, one joint at a time", panels)]
    if search.chirp_before:
        panels = []
        for joint in test.joints:
            t, command, position = search.chirp_before[joint][1]
            after = search.chirp_after[joint][1][2]
            panels.append(
                (
                    f"joint {joint} [rad]",
                    t,
                    {"command": command, label_now: position, label_best: after},
                )
            )
        paths.append(
            line_plots(folder / "chirp.png", "Chirp 0.2-2 Hz, one joint at a time", panels)
        )
    return paths


def _gains_label(name: str, gains: Any) -> str:
    return f"{name} P{gains.position_p} I{gains.position_i} D{gains.position_d}"


def sysid_plots(result: Any, logs: Sequence[Any], folder: Path) -> list[Path]:
    """replay.png: per log, its most-moved joint as logged and as the twin replays it before
    and after the fit."""
    panels = []
    for log, before, after in zip(logs, result.replay_before, result.replay_after, strict=True):
        joint = int(np.argmax(np.ptp(log.command_rad, axis=0)))
        k = len(log.command_rad)
        t = np.arange(1, k + 1) * log.dt_s
        series = {
            "log": log.position_rad[:, joint],
            "twin before": before[:k, joint],
            "twin after": after[:k, joint],
        }
        panels.append((f"{log.path.name} joint {joint} [rad]", t, series))
    title = (
        f"Twin vs log: {result.rms_before_rad:.2e} rad RMS before, {result.rms_after_rad:.2e} after"
    )
    return [line_plots(folder / "replay.png", title, panels)]
