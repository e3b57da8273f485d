"""`snakebot run`'s outputs: one that cannot be written is exit 1 naming it, before the run."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from snakebot.cli.main import main


@pytest.fixture
def blocker(tmp_path: Path) -> Path:
    """A regular file where a folder should be."""
    path = tmp_path / "blocker"
    path.write_text("")
    return path


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(["run", "--duration", "0.3", *argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_log_on_a_full_device(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "--log", "/dev/full")
    assert code == 1 and out == ""
    assert err == "snakebot: error: /dev/full: cannot write log file: No space left on device\n"


def test_a_log_under_a_file(capsys: pytest.CaptureFixture[str], blocker: Path) -> None:
    code, _, err = run(capsys, "--log", str(blocker / "run.csv"))
    assert code == 1
    assert err == (
        f"snakebot: error: {blocker}/run.csv: cannot write the log: Not a directory ({blocker})\n"
    )


@pytest.mark.parametrize(
    ("video", "message"),
    [
        ("{blocker}/run.mp4", "{blocker}/run.mp4: cannot write the video: Not a directory"),
        ("{tmp}/folder.mp4", "{tmp}/folder.mp4: cannot write the video: Is a directory"),
        ("{tmp}/run.txt", "--video: {tmp}/run.txt: expected a video file name ending in .mp4"),
        ("/dev/full", "--video: /dev/full: expected a video file name ending in .mp4"),
    ],
)
def test_an_unwritable_video_stops_the_run_before_it_starts(
    video: str, message: str, capsys: pytest.CaptureFixture[str], blocker: Path, tmp_path: Path
) -> None:
    paths = {"blocker": blocker, "tmp": tmp_path}
    (tmp_path / "folder.mp4").mkdir()
    log = tmp_path / "run.csv"
    code, out, err = run(capsys, "--video", video.format(**paths), "--log", str(log))
    assert code == (2 if message.startswith("--video") else 1) and out == ""  # 2: bad usage
    assert err.startswith(f"snakebot: error: {message.format(**paths)}")
    assert not log.exists()  # refused before the run: no log either


def test_video_renders_offscreen_without_a_display_or_mujoco_gl(tmp_path: Path) -> None:
    video = tmp_path / "run.mp4"
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")
    }
    done = subprocess.run(
        [sys.executable, "-m", "snakebot", "run", "--duration", "0.3", "--video", str(video)],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        cwd=tmp_path,
    )
    if sys.platform.startswith("linux"):
        assert done.returncode == 0, done.stderr
        assert video.stat().st_size > 1000
    else:  # elsewhere MuJoCo's default platform renders, or it is a clear error
        assert done.returncode in (0, 1), done.stderr


HEADLESS_VIDEO_IN_PROCESS = """
import sys
from snakebot.cli.main import main
sys.exit(main(["run", "--duration", "0.3", "--video", sys.argv[1]]))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="headless Linux rendering")
def test_video_renders_headless_when_main_is_called_in_process(tmp_path: Path) -> None:
    """main() from a script (not the console script) with nothing set: this was exit 1 ("no
    offscreen rendering") because mujoco was imported before MUJOCO_GL was chosen."""
    video = tmp_path / "run.mp4"
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")
    }
    done = subprocess.run(
        [sys.executable, "-c", HEADLESS_VIDEO_IN_PROCESS, str(video)],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    assert video.stat().st_size > 1000
    assert f"rendering {video} offscreen" in done.stderr


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a display-less Linux session")
def test_viewer_without_a_display_leaves_an_existing_log_untouched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    log = tmp_path / "yesterday.csv"
    log.write_text("time_s,joint\n0.0,0.1\n")
    code, out, err = run(capsys, "--viewer", "--log", str(log), "--force")
    assert code == 1 and out == ""
    assert "the live viewer needs a display" in err
    assert log.read_text() == "time_s,joint\n0.0,0.1\n"


def test_video_without_imageio_leaves_an_existing_log_untouched(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # The `video` extra not installed: importing imageio fails as it would without it.
    monkeypatch.setitem(sys.modules, "imageio", None)
    monkeypatch.setitem(sys.modules, "imageio.v2", None)
    log = tmp_path / "yesterday.csv"
    log.write_text("time_s,joint\n0.0,0.1\n")
    code, out, err = run(capsys, "--video", str(tmp_path / "run.mp4"), "--log", str(log), "--force")
    assert code == 1 and out == ""
    assert "pip install 'snakebot[video]'" in err
    assert log.read_text() == "time_s,joint\n0.0,0.1\n"
    assert not (tmp_path / "run.mp4").exists()


def _file_size_limit(limit: int) -> Callable[[], None]:
    def apply() -> None:  # in the child: a disk that is full after ``limit`` bytes of a file
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return apply


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_FSIZE, EGL")
def test_a_video_the_disk_cannot_finish_is_exit_1_not_wrote_n_frames(tmp_path: Path) -> None:
    # The campaign's full disk: ffmpeg says "Error writing trailer", the file is unreadable.
    # RLIMIT_FSIZE makes the same failure honestly: writes past 4 kB fail (EFBIG), as ENOSPC.
    video = tmp_path / "run.mp4"
    done = subprocess.run(
        [sys.executable, "-m", "snakebot", "run", "--duration", "1", "--video", str(video)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
        preexec_fn=_file_size_limit(4096),
    )
    assert done.returncode == 1, done.stderr
    assert f"snakebot: error: {video}: " in done.stderr
    assert "wrote" not in done.stderr and "internal error" not in done.stderr
