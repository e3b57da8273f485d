"""``snakebot rl compare``: the seed's figure, learning curves of several encodings side by side.

Each encoding trains with the same steps, seed and vectorisation into its own policy folder;
``compare.png`` draws the curves together and ``compare.json`` keeps the final numbers.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any, TextIO

from snakebot.errors import OutputError
from snakebot.rl.plots import curve_plot
from snakebot.rl.train import TrainResult, TrainSettings, dump_json, train


def compare(
    env_id: str,
    runs: dict[str, dict[str, Any]],
    steps: int,
    out: Path,
    *,
    seed: int,
    n_envs: int,
    vec: str,
    progress: TextIO | None = sys.stderr,
) -> dict[str, Any]:
    """Train every ``runs[encoding]`` (env kwargs) for ``steps``; returns the summary written to
    ``out/compare.json`` beside ``out/compare.png``."""
    results: dict[str, TrainResult] = {}
    for encoding, kwargs in runs.items():
        if progress is not None:
            progress.write(f"{encoding}:\n")
        settings = TrainSettings(env_id, kwargs, steps, n_envs, vec, seed=seed)
        results[encoding] = train(settings, out / encoding, progress=progress)
    curve_plot(
        {name: r.curve for name, r in results.items()},
        out / "compare.png",
        title=f"{env_id}: encodings",
    )
    summary = {
        "env_id": env_id,
        "steps": steps,
        "seed": seed,
        "runs": {name: dump_json(r) for name, r in results.items()},
    }
    path = out / "compare.json"
    try:
        path.write_text(json.dumps(summary, indent=2) + "\n")
    except OSError as exc:
        raise OutputError(path, f"cannot write the summary: {exc.strerror or exc}") from exc
    return summary
