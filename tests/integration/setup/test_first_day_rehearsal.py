"""docs/first-day.md's emulated first day, run as written against `emulate --pty --fresh 12`.

The commands come from the guide's rehearsal block itself, so the guide and this test cannot
drift: factory-fresh servos -> IDs -> settings -> calibration -> direction check -> a gait that
suits snake12. Every step must exit 0 (issue 19: calibrate was refused on day one, and the
rehearsal ran `serpenoid`, which snakebot warns will not move snake12 as its name says).
"""

from __future__ import annotations

import math
import os
import re
import shlex
from collections.abc import Iterator
from pathlib import Path

import pytest

from snakebot.config import load_robot
from tests.conftest import REPO
from tests.integration.setup.conftest import Cli
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

GUIDE = REPO / "docs" / "first-day.md"
MARKER = "<!-- rehearsal:"
EMULATOR = "snakebot emulate --robot snake12 --pty --fresh 12 --state-file servos.json"


def rehearsal_block() -> list[str]:
    text = GUIDE.read_text(encoding="utf-8")
    assert text.count(MARKER) == 1, f"{GUIDE}: expected one {MARKER} block"
    after = text[text.index(MARKER) :]
    assert EMULATOR in " ".join(text[: text.index(MARKER)].split()[-40:]), "emulator line moved"
    return after.split("```sh\n", 1)[1].split("\n```", 1)[0].splitlines()


def steps(lines: list[str], env: dict[str, str]) -> Iterator[list[str]]:
    """The block's steps: ["plug"] where the guide waits for a servo, else a snakebot argv.

    Understands what the block uses (VAR=value, for VAR in ...; do ... done, read -p, snakebot)
    and fails on anything else, so a new kind of line is run here or noticed.
    """
    index = 0
    while index < len(lines):
        line = lines[index]
        index += 1
        words = shlex.split(line, comments=True)
        if not words:
            continue
        loop = re.fullmatch(r"\s*for (\w+) in ([^;]+); do\s*", line)
        if loop:
            depth, body = 1, []
            while depth:
                inner = lines[index]
                index += 1
                depth += inner.strip().startswith("for ") - (inner.strip() == "done")
                if depth:
                    body.append(inner)
            for value in loop.group(2).split():
                yield from steps(body, {**env, loop.group(1): value})
        elif re.fullmatch(r"[A-Z]+=\S+", words[0]) and len(words) == 1:
            name = words[0].split("=")[0]
            assert name in env, f"the test supplies {name} itself (it is the emulator's port)"
        elif words[0] == "read":
            yield ["plug"]
        elif words[0] == "snakebot":
            expanded = re.sub(r"\$(\w+)", lambda m: env[m.group(1)], line)
            yield shlex.split(expanded, comments=True)[1:]
        else:
            pytest.fail(f"{GUIDE}: the rehearsal has a line this test cannot run: {line!r}")


def test_the_first_day_guide_runs_as_written_to_a_walking_snake(
    tmp_path: Path, cli: Cli, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # "in an empty folder": servos.json and snake12.toml land here
    lines = rehearsal_block()
    with emulator("--robot", "snake12", "--fresh", "12", "--state-file", "servos.json") as emu:
        outputs: dict[str, list[str]] = {}
        for argv in steps(lines, {"PORT": emu.port}):
            if argv == ["plug"]:
                assert emu.command("plug")["event"] == "plugged"
                continue
            code, out, err = cli(*argv)
            assert code == 0, f"`snakebot {shlex.join(argv)}` exited {code}:\n{out}\n{err}"
            assert "will not move as" not in err, err
            outputs.setdefault(" ".join(argv[:2]), []).append(out)
    assert len(outputs["config assign-id"]) == 12
    assert "12 servo(s)" in outputs["scan --port"][0]
    robot = load_robot(tmp_path / "snake12.toml")
    offsets = [j.zero_offset_rad for j in robot.joints]
    assert all(abs(o) < math.radians(20) for o in offsets) and max(map(abs, offsets)) > 0.2
    jogs = outputs["servo jog"]
    assert len(jogs) == 24
    for out in jogs[0::2]:
        assert re.search(r"-> \+1[45]\.\d deg", out), out
    (run,) = outputs["run --robot"]
    cycles = int(re.search(r"(\d+) control cycles", run).group(1))  # type: ignore[union-attr]
    assert cycles > 100, run
