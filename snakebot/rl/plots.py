"""Learning-curve PNGs with matplotlib (headless Agg)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from snakebot.errors import OutputError
from snakebot.tuning.plots import pyplot


def curve_plot(curves: Mapping[str, Sequence[Any]], path: Path, *, title: str = "") -> Path:
    """Mean episode return and success rate against env steps, one line per curve label."""
    plt = pyplot()
    fig, (ax_return, ax_success) = plt.subplots(1, 2, figsize=(11, 4.2), dpi=110)
    for label, points in curves.items():
        steps = [p.steps for p in points]
        ax_return.plot(steps, [p.mean_return for p in points], "-", lw=1.6, label=label)
        rates = [
            100 * p.success_rate if not math.isnan(p.success_rate) else math.nan for p in points
        ]
        ax_success.plot(steps, rates, "-", lw=1.6, label=label)
    ax_return.set(xlabel="env steps", ylabel="mean episode return", title=title or "return")
    ax_success.set(xlabel="env steps", ylabel="success rate [%]", title="goals reached")
    for ax in (ax_return, ax_success):
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    try:
        fig.savefig(path)
    except OSError as exc:
        raise OutputError(path, f"cannot write the plot: {exc.strerror or exc}") from exc
    finally:
        plt.close(fig)
    return path
