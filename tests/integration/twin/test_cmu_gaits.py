"""The CMU parity gaits on the twin: conical sidewinding steers by its taper's sign, head-look
holds the head nearer level than the same gait without it, the rolling helix coils by the pole.

Measured on snake12 (docs/twin.md, "CMU gait-library parity", has the figures): over 6 s,
taper +0.8 turns the body +49 deg (anticlockwise seen from above), -0.8 turns it -44 deg, plain
sidewinding 2 deg.
"""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.backends.twin.pole_wrap import wrap_on_pole
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait
from snakebot.types import JointCommand
from tests.integration.twin.terrain_runs import play

ROBOT = "snake12"


def heading_rad(twin: TwinBackend) -> float:
    """The body's heading: its principal axis in the ground plane, pointing to the head."""
    ids = [twin.model.body(link_name(i)).id for i in range(twin.robot.link_count)]
    xy = np.asarray(twin.data.xipos[ids])[:, :2]
    _, _, vt = np.linalg.svd(xy - xy.mean(axis=0))
    axis = vt[0] if np.dot(xy[0] - xy[-1], vt[0]) > 0 else -vt[0]
    return float(np.arctan2(axis[1], axis[0]))


def turn_deg(taper: float, duration_s: float = 6.0) -> float:
    robot = load_robot(ROBOT)
    with TwinBackend(robot) as twin:
        start = heading_rad(twin)
        play(twin, robot, "conical_sidewinding", duration_s, {"taper": taper})
        end = heading_rad(twin)
    return float(np.degrees(np.angle(np.exp(1j * (end - start)))))


def test_conical_sidewinding_turns_the_way_its_taper_says() -> None:
    straight, left, right = turn_deg(0.0), turn_deg(0.8), turn_deg(-0.8)
    assert abs(straight) < 15.0
    assert left > straight + 25.0
    assert right < straight - 25.0


def head_tilt_deg(gait: str, params: dict[str, object], duration_s: float = 6.0) -> np.ndarray:
    """The angle (deg) between the head's up axis and the world's, each cycle after the first
    second (pitch and roll together)."""
    robot = load_robot(ROBOT)
    made = make_gait(
        gait, robot.joint_count, params, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
    )
    tilts: list[float] = []
    with TwinBackend(robot) as twin:

        def sample(_cycle: int, time_s: float) -> None:
            if time_s > 1.0:
                _, x, y, _ = twin.body_state().head_quat
                tilts.append(float(np.degrees(np.arccos(np.clip(1 - 2 * (x * x + y * y), -1, 1)))))

        run_gait(
            twin,
            made,
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s, ramp_out=False),
            RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            on_cycle=sample,
        )
    return np.array(tilts)


@pytest.mark.parametrize("base", ["sidewinding", "conical_sidewinding"])
def test_head_look_holds_the_head_nearer_level_than_the_gait_alone(base: str) -> None:
    alone = head_tilt_deg(base, {})
    looking = head_tilt_deg("head_look", {"base": base})
    # Measured: sidewinding 49 deg mean tilt alone, 36 with head-look; conical 48 -> 36.
    assert looking.mean() < alone.mean() - 8.0
    assert looking.mean() < 42.0


def test_head_look_keeps_a_flat_gait_level() -> None:
    looking = head_tilt_deg("head_look", {"base": "lateral_undulation", "pan_rad": 0.3})
    assert looking.max() < 2.0


def test_the_rolling_helix_of_the_poles_radius_lifts_the_body_beside_the_pole() -> None:
    robot = load_robot(ROBOT)
    heights: list[float] = []
    with TwinBackend(robot, terrain="pole:diameter_m=0.1") as twin:
        lying = float(twin.body_state().com_m[2])
        made = make_gait(
            "rolling_helix",
            robot.joint_count,
            {"pole_radius_m": 0.05},
            lower_rad=robot.lower_rad,
            upper_rad=robot.upper_rad,
        )

        def sample(cycle: int, _time_s: float) -> None:
            if cycle % 50 == 0:
                heights.append(float(twin.body_state().com_m[2]))

        run_gait(
            twin,
            made,
            SafetyLayer.for_robot(robot),
            RunPlan(5.0, ramp_out=False),
            RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            on_cycle=sample,
        )
    # Measured: 0.04 m lying, 0.08-0.095 m coiled (the helix stands on its turns); it does not
    # climb: the coil forms with its axis along the ground, beside the pole, not around it.
    assert min(heights[2:]) > 1.7 * lying


def climb_m(omega: float, duration_s: float = 6.0) -> list[float]:
    """Centre-of-mass heights (m) every 0.5 s of the rolling helix wrapped on the 0.1 m pole."""
    robot = load_robot(ROBOT)
    # 0.055 m: the coil of the 0.05 m pole's own radius comes out a few mm tight on 12 joints.
    params = {"pole_radius_m": 0.055, "omega": omega}
    made = make_gait(
        "rolling_helix",
        robot.joint_count,
        params,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
    )
    heights = []
    with TwinBackend(robot, terrain="pole:diameter_m=0.1,height_m=1.5") as twin:
        wrap_on_pole(twin, made.targets(0.0))
        for cycle in range(round(duration_s * 100)):
            if cycle % 50 == 0:
                heights.append(float(twin.body_state().com_m[2]))
            twin.send_command(JointCommand(made.targets(cycle * 0.01)))
            twin.advance(0.01)
        heights.append(float(twin.body_state().com_m[2]))
    return heights


def test_the_rolling_helix_wrapped_on_the_pole_climbs_it_and_reversed_comes_down() -> None:
    # Head end up, left=1: omega < 0 screws the coil up the pole, omega > 0 down it.
    up, down = np.array(climb_m(-np.pi / 2)), np.array(climb_m(np.pi / 2))
    # Measured: 0.20 -> 0.39 m in 6 s (0.03 m/s, steady); the other way 0.20 -> 0.07 m.
    assert up[-1] - up[0] > 0.12
    assert np.all(up[7:] > up[:6].max())  # still rising: the second half higher than the first
    assert down[-1] < down[0] - 0.08
