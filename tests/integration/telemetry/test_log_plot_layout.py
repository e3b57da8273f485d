"""Every PNG of `snakebot log plot` shows all it draws: no title, tick label or axis label runs
off the picture (a snake12 drive's five gait names once clipped com_path.png's title)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from snakebot.cli.main import main


def test_nothing_drawn_runs_off_the_edge_of_a_plot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import matplotlib.image

    script = tmp_path / "keys.txt"
    script.write_text("0.0 w\n0.5 q\n")
    log = tmp_path / "drive.csv"
    assert main(["drive", "--robot", "snake12", "--script", str(script), "--log", str(log)]) == 0
    assert main(["log", "plot", str(log), "--out", str(tmp_path / "plots")]) == 0, (
        capsys.readouterr().err
    )
    pictures = sorted((tmp_path / "plots").glob("*.png"))
    assert "com_path.png" in [p.name for p in pictures]
    for picture in pictures:
        rgb = matplotlib.image.imread(picture)[..., :3]
        border = np.concatenate(
            [
                rgb[:3].reshape(-1, 3),
                rgb[-3:].reshape(-1, 3),
                rgb[:, :3].reshape(-1, 3),
                rgb[:, -3:].reshape(-1, 3),
            ]
        )
        ink = int((border.min(axis=1) < 0.9).sum())
        assert ink == 0, f"{picture.name}: {ink} drawn pixels on the picture's edge"
