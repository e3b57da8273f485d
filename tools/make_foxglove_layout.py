"""Write docs/foxglove/snakebot-layout.json with the Foxglove SDK's layout types.

The layout: the 3-D view of the snake (following the head) beside tabs of plots: one panel per
joint (command vs measured), tracking error and effort of every joint, the run's rate and
tracking, servo temperatures and voltages, the drive's controls, and the servo errors.

    .venv/bin/python tools/make_foxglove_layout.py [--joints 12] [--out FILE]

The shipped file is for up to 12 joints; a snake with fewer leaves the last joint panels empty.
tests/unit/telemetry/test_layout.py checks the shipped file is this tool's output and that every
path it plots is a field of a channel snakebot sends.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import foxglove.layouts as fl

OUT = Path(__file__).resolve().parents[1] / "docs" / "foxglove" / "snakebot-layout.json"
COMMAND, MEASURED = "#f28e2b", "#4e79a7"


def _grid(panels: list[Any], columns: int) -> Any:
    rows = [panels[i : i + columns] for i in range(0, len(panels), columns)]
    return fl.SplitContainer(
        direction="column",
        items=[
            fl.SplitItem(
                proportion=1,
                content=fl.SplitContainer(
                    direction="row", items=[fl.SplitItem(proportion=1, content=p) for p in row]
                ),
            )
            for row in rows
        ],
    )


def _plot(title: str, series: list[Any], **config: Any) -> Any:
    return fl.PlotPanel(title=title, config=fl.PlotConfig(paths=series, show_legend=True, **config))


def joint_panel(joint: int) -> Any:
    """Command vs measured of one joint."""
    return _plot(
        f"joint {joint} [rad]",
        [
            fl.PlotSeries(value=f"/joints.command_rad[{joint}]", label="command", color=COMMAND),
            fl.PlotSeries(value=f"/joints.position_rad[{joint}]", label="measured", color=MEASURED),
        ],
        legend_display="floating",
    )


def all_joints(title: str, path: str) -> Any:
    """Every joint of an array field, one series per index."""
    return _plot(
        title, [fl.PlotSeries(value=f"{path}[:]", array_expansion="byIndex", label="joint")]
    )


def layout(joints: int) -> Any:
    """The whole layout for up to ``joints`` joints."""
    columns = 3 if joints > 6 else 2
    scene = fl.ThreeDeePanel(
        title="snake (world; follows the head)",
        config=fl.ThreeDeeConfig(
            follow_tf="link0",
            fixed_frame="world",
            follow_mode="follow-position",
            camera_state=fl.ThreeDeeCameraState(
                distance=1.5, phi=55.0, theta_offset=-60.0, perspective=True
            ),
            topics={"/scene": fl.BaseRendererSceneUpdateTopicSettings(visible=True)},
            layers={"grid": fl.BaseRendererGridLayerSettings()},
        ),
    )
    status = fl.RawMessagesPanel(
        title="run metrics", config=fl.RawMessagesConfig(topic_path="/run_metrics")
    )
    errors = fl.RawMessagesPanel(
        title="servo errors", config=fl.RawMessagesConfig(topic_path="/servo_errors.errors")
    )
    left = fl.SplitContainer(
        direction="column",
        items=[
            fl.SplitItem(proportion=3, content=scene),
            fl.SplitItem(proportion=1, content=status),
            fl.SplitItem(proportion=1, content=errors),
        ],
    )
    tabs = fl.TabContainer(
        selected_tab_index=0,
        tabs=[
            fl.TabItem(
                title="joints", content=_grid([joint_panel(j) for j in range(joints)], columns)
            ),
            fl.TabItem(
                title="tracking & effort",
                content=_grid(
                    [
                        all_joints(
                            "tracking error, command - measured [rad]", "/joints.tracking_error_rad"
                        ),
                        all_joints("effort [N m]", "/joints.effort_nm"),
                        all_joints("velocity [rad/s]", "/joints.velocity_rad_s"),
                    ],
                    1,
                ),
            ),
            fl.TabItem(
                title="rate & health",
                content=_grid(
                    [
                        _plot(
                            "control rate [Hz]",
                            [
                                fl.PlotSeries(
                                    value="/run_metrics.achieved_rate_hz", label="achieved"
                                ),
                                fl.PlotSeries(
                                    value="/run_metrics.rate_hz", label="asked", line_style="dashed"
                                ),
                            ],
                        ),
                        _plot(
                            "overruns, tracking",
                            [
                                fl.PlotSeries(value="/run_metrics.overruns", label="overruns"),
                                fl.PlotSeries(
                                    value="/run_metrics.tracking_rms_rad",
                                    label="tracking RMS [rad]",
                                    use_right_y_axis=True,
                                ),
                            ],
                        ),
                        all_joints(
                            "servo temperature [degC] (hardware)", "/servo_health.temperature_c"
                        ),
                        all_joints(
                            "servo input voltage [V] (hardware)", "/servo_health.input_voltage_v"
                        ),
                    ],
                    2,
                ),
            ),
            fl.TabItem(
                title="drive",
                content=_grid(
                    [
                        _plot(
                            "speed, turn",
                            [
                                fl.PlotSeries(value="/drive.speed", label="speed"),
                                fl.PlotSeries(value="/drive.turn", label="turn"),
                            ],
                        ),
                        _plot(
                            "amplitude, wavelength",
                            [
                                fl.PlotSeries(value="/drive.amplitude", label="amplitude"),
                                fl.PlotSeries(value="/drive.wavelength", label="wavelength"),
                            ],
                        ),
                        fl.RawMessagesPanel(
                            title="drive status", config=fl.RawMessagesConfig(topic_path="/drive")
                        ),
                    ],
                    1,
                ),
            ),
        ],
    )
    return fl.Layout(
        content=fl.SplitContainer(
            direction="row",
            items=[
                fl.SplitItem(proportion=2, content=left),
                fl.SplitItem(proportion=3, content=tabs),
            ],
        )
    )


def render(joints: int) -> str:
    """The layout as the JSON file ships it (indented, one newline at the end)."""
    return json.dumps(json.loads(layout(joints).to_json()), indent=1) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--joints", type=int, default=12)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    if not 1 <= args.joints <= 64 or not math.isfinite(args.joints):
        parser.error("--joints: 1 to 64")
    args.out.write_text(render(args.joints))
    print(f"{args.out}: {args.joints} joint panels")


if __name__ == "__main__":
    main()
