"""Pole climbing on the twin: the rolling helix started wrapped on the pole (docs/twin.md).

Puts snake12 coiled around the pole terrain's pole in the gait's t = 0 shape, head end up
(``snakebot.backends.twin.pole_wrap``, as CMU's robots are wrapped by hand), runs the rolling
helix through the runner and its safety layer (no start ramp: the ramp would uncoil it) and
prints the centre of mass height every second, the climb in m and in body lengths, and the
wall time.

    python tools/bench_pole_climb.py                       # the table of docs/twin.md
    python tools/bench_pole_climb.py --omega -1.5708 --pitch 0.04 --pole-radius 0.055
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.pole_wrap import wrap_on_pole
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait


def climb_heights(
    robot_name: str, terrain: str, params: dict[str, float], duration_s: float, every_s: float
) -> tuple[list[float], float]:
    """Centre-of-mass heights (m) every ``every_s`` s from t = 0 to ``duration_s``, and the
    robot's body length (m)."""
    robot = load_robot(robot_name)
    gait = make_gait(
        "rolling_helix",
        robot.joint_count,
        params,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
    )
    heights: list[float] = []
    every = max(1, round(every_s * 100))
    with TwinBackend(robot, terrain=terrain) as twin:
        wrap_on_pole(twin, gait.targets(0.0))
        heights.append(float(twin.body_state().com_m[2]))
        safety = SafetyLayer(robot.lower_rad, robot.upper_rad, robot.max_speed_rad_s, 0.0)

        def sample(cycle: int, _time_s: float) -> None:
            if (cycle + 1) % every == 0:
                heights.append(float(twin.body_state().com_m[2]))

        run_gait(
            twin,
            gait,
            safety,
            RunPlan(duration_s, ramp_out=False),
            RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            on_cycle=sample,
        )
    return heights, robot.body_length_m


def main(argv: list[str] | None = None) -> int:
    """Run the climb and print the heights; 0."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robot", default="snake12")
    parser.add_argument("--terrain", default="pole:diameter_m=0.1,height_m=1.5")
    parser.add_argument("--omega", type=float, default=-2.2, help="rad/s (< 0 climbs)")
    parser.add_argument("--pitch", type=float, default=0.03, help="pitch_m_per_rad, m/rad")
    parser.add_argument("--pole-radius", type=float, default=0.052, help="pole_radius_m, m")
    parser.add_argument("--duration", type=float, default=15.0, help="s of robot time")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    params = {
        "omega": args.omega,
        "pitch_m_per_rad": args.pitch,
        "pole_radius_m": args.pole_radius,
    }
    start = time.perf_counter()
    heights, body_length = climb_heights(args.robot, args.terrain, params, args.duration, 1.0)
    wall = time.perf_counter() - start
    climb = heights[-1] - heights[0]
    result = {
        "params": params,
        "heights_m": [round(h, 3) for h in heights],
        "climb_m": round(climb, 3),
        "body_lengths": round(climb / body_length, 2),
        "rate_m_s": round(float(np.polyfit(np.arange(len(heights)), heights, 1)[0]), 4),
        "wall_s": round(wall, 1),
    }
    if args.json:
        print(json.dumps(result))
        return 0
    print(f"{args.robot} on {args.terrain}, rolling_helix {params}")
    print("| t (s) | " + " | ".join(str(t) for t in range(len(heights))) + " |")
    print("| COM height (m) | " + " | ".join(f"{h:.3f}" for h in heights) + " |")
    print(
        f"climb {climb:.3f} m = {climb / body_length:.2f} body lengths in {args.duration:g} s "
        f"({result['rate_m_s']} m/s), wall {wall:.1f} s"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
