"""The one video writer (run --video, rl eval --video): a file that does not read back whole is
an error naming it. A full disk is made with RLIMIT_FSIZE in a child process (EFBIG past the
limit, as ENOSPC on a full disk: CPython ignores SIGXFSZ, ffmpeg is killed by it)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("imageio_ffmpeg")

from snakebot.backends.twin.video import VideoWriter

ENCODE_ON_A_FULL_DISK = """
import resource, sys
from pathlib import Path
import numpy as np
from snakebot.errors import OutputError
from snakebot.rl.evaluate import write_video
resource.setrlimit(resource.RLIMIT_FSIZE, (2000, 2000))
rng = np.random.default_rng(0)
frames = [rng.integers(0, 255, (96, 128, 3), dtype=np.uint8) for _ in range(20)]
try:
    write_video(Path(sys.argv[1]), frames, 25)
except OutputError as exc:
    print(exc)
    sys.exit(1)
"""


def _frames(count: int) -> list[np.ndarray]:
    return [np.full((96, 128, 3), 10 * i, np.uint8) for i in range(count)]


def test_a_finished_video_reads_back_with_every_frame(tmp_path: Path) -> None:
    path = tmp_path / "sub" / "ok.mp4"
    with VideoWriter(path, 25) as writer:
        for frame in _frames(12):
            writer.append(frame)
    assert writer.frames == 12 and path.stat().st_size > 0
    writer.close()  # a second close does nothing


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_FSIZE")
@pytest.mark.skipif(
    importlib.util.find_spec("gymnasium") is None, reason="rl eval's writer needs the rl extra"
)
def test_rl_evals_video_on_a_full_disk_is_an_output_error_naming_it(tmp_path: Path) -> None:
    path = tmp_path / "eval.mp4"
    done = subprocess.run(
        [sys.executable, "-c", ENCODE_ON_A_FULL_DISK, str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 1, done.stderr
    assert done.stdout.startswith(f"{path}: ") and "a full disk?" in done.stdout
