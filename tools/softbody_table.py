"""Reproduce the results table of docs/soft-bodies.md: Miller's (1988) soft bodies, measured.

Every row is a `snakebot run --json` (10 s gait, 100 Hz) whose command is printed beside it; the
damping rows use copies of the snake body file with other springs, and the standing-wave columns
come from the run's --log. The reference-integrator rows run the tests' numpy integrator.

    python tools/softbody_table.py [--rows all|worm|snake|damping|units|cliff|reference]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from snakebot.cli.main import main as snakebot
from snakebot.config.body_loader import load_body, resolve_body_path
from snakebot.telemetry import read_log

ROOT = Path(__file__).resolve().parents[1]


def run(*argv: str) -> dict[str, object]:
    """`snakebot run --json ARGV`, its summary."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = snakebot(["run", "--json", *argv])
    if code != 0:
        sys.exit(f"snakebot run {' '.join(argv)} failed with {code}")
    summary = json.loads(out.getvalue())
    assert isinstance(summary, dict)
    return summary


def snake_file(folder: Path, name: str, **springs: float) -> Path:
    """The snake body file with its [springs] table's values replaced by ``springs``."""
    lines = []
    for line in resolve_body_path("snake").read_text().splitlines():
        if line.startswith("preset ="):
            lines += [f"{key} = {value:g}" for key, value in springs.items()]
        elif not line.startswith("time_unit_s =") or "time_unit_s" not in springs:
            lines.append(line.replace('name = "snake"', f'name = "{name}"'))
    path = folder / f"{name}.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def standing_waves(
    log: Path, channels: int = 3, drive_hz: float = 1.0
) -> tuple[float, float, float]:
    """From a 10 s run's log (4 s to 10 s): the tail's yaw motion off the drive frequency (rad
    RMS, last three segments), the tail's yaw amplitude over the commanded one, and the reflection
    coefficient |B|/|F| of a least-squares fit A_i = F e^{-ik i} + B e^{ik i} of the yaw waves."""
    telemetry = read_log(log)
    time_s = telemetry.column("time_s")
    keep = (time_s >= 4.0) & (time_s <= 10.0)  # the gait's steady part, not the ramp-out
    t = time_s[keep]
    yaw = telemetry.joints("position_rad")[keep][:, 0::channels]
    command = telemetry.joints("command_rad")[keep][:, 0::channels]
    drive = np.exp(2j * math.pi * drive_hz * t)
    amplitude = 2 * (yaw * drive.conj()[:, None]).mean(axis=0)
    commanded = 2 * (command * drive.conj()[:, None]).mean(axis=0)
    free = yaw - (amplitude[None, :] * drive[:, None]).real
    segments = yaw.shape[1]
    k = 2 * math.pi * 1.4 / segments
    index = np.arange(segments)
    basis = np.stack((np.exp(-1j * k * index), np.exp(1j * k * index)), axis=1)
    (forward, backward), *_ = np.linalg.lstsq(basis, amplitude, rcond=None)
    tail = slice(segments - 3, segments)
    return (
        float(np.sqrt((free[:, tail] ** 2).mean())),
        float(np.abs(amplitude[tail]).mean() / np.abs(commanded[tail]).mean()),
        float(abs(backward) / abs(forward)),
    )


def row(label: str, command: str, summary: dict[str, object], *extra: str) -> None:
    def num(key: str, digits: int = 3) -> str:
        value = summary.get(key)
        return f"{value:.{digits}f}" if isinstance(value, float) else "-"

    cells = [
        label,
        f"`{command}`",
        num("distance_m"),
        num("body_lengths_per_cycle"),
        num("travel_angle_deg", 0),
        num("contact_fraction", 2),
        *extra,
    ]
    print("| " + " | ".join(cells) + " |", flush=True)


def header(*extra: str) -> None:
    columns = ["run", "command", "distance m", "BL/cycle", "travel vs axis deg", "touching", *extra]
    print("\n| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))


def worm_rows() -> None:
    header()
    for body, gait in (("worm", "rectilinear"), ("caterpillar", "rectilinear")):
        for directional in ("on", "off"):
            argv = ["--robot", body, "--gait", gait, "--directional", directional]
            row(f"{body}, scales {directional}", "snakebot run " + " ".join(argv), run(*argv))


def snake_rows() -> None:
    header()
    for body, gait in (
        ("snake", "undulation"),
        ("snake", "miller_sidewinding"),
        ("snake_yawpitch", "lateral_undulation"),
        ("snake_yawpitch", "sidewinding"),
    ):
        for directional in ("on", "off"):
            argv = ["--robot", body, "--gait", gait, "--directional", directional]
            row(
                f"{body} {gait}, scales {directional}", "snakebot run " + " ".join(argv), run(*argv)
            )


def damping_rows(folder: Path) -> None:
    header("tail off-drive rad", "tail amplitude / command", "reflected / forward wave")
    for time_unit in (0.005, 0.01):
        for damping in (3.5, 0.52, 0.2):
            ratio = damping / (2 * math.sqrt(0.5))
            name = f"snake_T{time_unit:g}_D{damping:g}"
            path = snake_file(folder, name, k=0.5, damping=damping, time_unit_s=time_unit)
            log = folder / f"{name}.csv"
            argv = ["--robot", str(path), "--gait", "undulation", "--log", str(log)]
            summary = run(*argv)
            free, tail, reflection = standing_waves(log)
            label = f"snake undulation, T {time_unit:g} s, D {damping:g} (ratio {ratio:.2f})"
            shown = f"snakebot run --robot {name}.toml --gait undulation --log {name}.csv"
            row(label, shown, summary, f"{free:.4f}", f"{tail:.2f}", f"{reflection:.2f}")


def units_rows(folder: Path) -> None:
    header()
    for time_unit in (0.005, 0.01):
        name = f"snake_T{time_unit:g}"
        path = snake_file(folder, name, k=0.5, damping=3.5, time_unit_s=time_unit)
        argv = ["--robot", str(path), "--gait", "miller_sidewinding"]
        shown = f"snakebot run --robot {name}.toml --gait miller_sidewinding"
        row(f"snake sidewinding, T {time_unit:g} s", shown, run(*argv))


def cliff_rows(folder: Path) -> None:
    header("COM height start -> end m")
    log = folder / "cliff.csv"
    argv = ["--robot", "worm", "--gait", "rectilinear", "--terrain", "cliff", "--log", str(log)]
    summary = run(*argv)
    z = read_log(log).column("com_z_m")
    shown = "snakebot run --robot worm --gait rectilinear --terrain cliff --log cliff.csv"
    row("worm over the cliff", shown, summary, f"{z[0]:.3f} -> {z[-1]:.3f}")


def reference_rows(folder: Path) -> None:
    sys.path.insert(0, str(ROOT))
    from snakebot.gaits import make_gait
    from tests.integration.softbody.reference_integrator import run_reference

    worm = load_body("worm")
    print(
        "\n| worm rectilinear, 10 s | MuJoCo: scales on / off, m | ratio "
        "| numpy reference: on / off, m | ratio |"
    )
    print("|---|---|---|---|---|")
    for volume in (False, True):
        body = replace(worm, muscles=replace(worm.muscles, volume_preservation=volume))
        path = folder / f"worm_volume_{volume}.toml"
        text = resolve_body_path("worm").read_text()
        path.write_text(
            text.replace(
                "volume_preservation = true", f"volume_preservation = {str(volume).lower()}"
            )
        )
        runs = [
            run("--robot", str(path), "--gait", "rectilinear", "--directional", d)
            for d in ("on", "off")
        ]
        mujoco = [float(summary["displacement_m"][0]) for summary in runs]
        gait = make_gait("rectilinear", body.joint_count)
        reference = [
            float(run_reference(body, gait, duration_s=10.0, directional=d).displacement[0])
            for d in (True, False)
        ]
        cells = [
            f"{pair[0]:.3f} / {pair[1]:.3f} | {pair[0] / max(abs(pair[1]), 1e-9):.0f}"
            for pair in (mujoco, reference)
        ]
        label = "volume preservation " + ("on" if volume else "off")
        print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--rows",
        default="all",
        choices=("all", "worm", "snake", "damping", "units", "cliff", "reference"),
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if args.rows in ("all", "worm"):
            worm_rows()
        if args.rows in ("all", "snake"):
            snake_rows()
        if args.rows in ("all", "damping"):
            damping_rows(folder)
        if args.rows in ("all", "units"):
            units_rows(folder)
        if args.rows in ("all", "cliff"):
            cliff_rows(folder)
        if args.rows in ("all", "reference"):
            reference_rows(folder)


if __name__ == "__main__":
    main()
