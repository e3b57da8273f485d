"""Scale friction: body-aligned directional friction on any ground, in C or numpy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.backends.twin.friction import scale_c
from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.gaits import make_gait
from snakebot.tuning.commands import GaitCommands
from snakebot.tuning.engine import TwinBatch
from snakebot.tuning.trace import summarise
from tests.integration.twin.terrain_runs import play

FLAT_FIELD = "rough:roughness_m=0"


def distance(robot_name: str, gait: str, duration_s: float, **twin: object) -> float:
    robot = load_robot(robot_name)
    with TwinBackend(robot, **twin) as backend:  # type: ignore[arg-type]
        return float(play(backend, robot, gait, duration_s).summary["distance_m"])


@pytest.mark.slow
def test_lateral_undulation_keeps_its_plane_speed_on_a_flat_height_field() -> None:
    plane_pairs = distance("snake8", "serpenoid", 6.0)
    plane_scale = distance("snake8", "serpenoid", 6.0, friction_model="scale")
    field_scale = distance("snake8", "serpenoid", 6.0, terrain=FLAT_FIELD)
    field_pairs = distance("snake8", "serpenoid", 6.0, terrain=FLAT_FIELD, friction_model="pairs")
    assert plane_pairs > 0.8
    # The defect: pairs on a height field are world-aligned and the snake stops.
    assert field_pairs < 0.1 * plane_pairs
    assert field_scale >= 0.9 * plane_pairs
    assert field_scale >= 0.9 * plane_scale


def test_auto_picks_pairs_on_the_plane_and_scale_on_a_height_field() -> None:
    robot = load_robot("snake8")
    with TwinBackend(robot) as plane, TwinBackend(robot, terrain=FLAT_FIELD) as field:
        assert plane.model.npair == robot.link_count
        assert field.model.npair == 0
        assert field.model.sensor("snakebot_contact_load").dim[0] == robot.link_count


@pytest.mark.slow
def test_rolling_rolls_on_a_height_field() -> None:
    # Rolling needs friction where the module touches: at the COM it would not turn the body.
    plane = distance("snake12", "rolling", 10.0)
    field = distance("snake12", "rolling", 10.0, terrain=FLAT_FIELD)
    assert plane > 0.3
    assert field >= 0.8 * plane


def backslide_m(backward: float) -> float:
    """How far a straight snake holding still slides down a 20 degree slope in 3 s."""
    robot = load_robot("snake8")
    friction = GroundFriction(0.05, 1.0, backward)
    with TwinBackend(
        robot, terrain="slope:angle_deg=20", friction=friction, friction_model="scale"
    ) as twin:
        start = twin.body_state().com_m
        twin.advance(3.0)
        return float(start[0] - twin.body_state().com_m[0])


def test_scales_resist_sliding_tail_first() -> None:
    smooth, scaled = backslide_m(0.05), backslide_m(1.0)
    assert smooth > 1.0  # axial friction 0.05 cannot hold 20 degrees (tan = 0.36)
    assert scaled < 0.1 * smooth


def com_track(implementation: str, robot_name: str, monkeypatch: pytest.MonkeyPatch) -> np.ndarray:
    monkeypatch.setenv("SNAKEBOT_SCALE_FRICTION", implementation)
    robot = load_robot(robot_name)
    track = []
    with TwinBackend(robot, terrain="rough:roughness_m=0.005") as twin:
        for step in range(50):
            twin.send_command_unchecked(
                0.5 * np.sin(0.7 * np.arange(robot.joint_count) - 6 * step * 0.01)
            )
            twin.advance(0.01)
            track.append(twin.body_state().com_m)
    return np.array(track)


# snake8's wheels feel friction at the module's COM, snake12's bare modules where they touch.
@pytest.mark.parametrize("robot_name", ["snake8", "snake12"])
def test_c_and_numpy_compute_the_same_friction(
    robot_name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    c_track = com_track("c", robot_name, monkeypatch)
    numpy_track = com_track("numpy", robot_name, monkeypatch)
    assert np.abs(c_track[-1] - c_track[0]).max() > 0.005  # it moved
    np.testing.assert_allclose(numpy_track, c_track, atol=1e-6)


def test_the_compiled_object_is_cached_and_reused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("SNAKEBOT_CACHE", str(tmp_path))
    monkeypatch.setattr(scale_c, "_LIBRARY", None)
    with TwinBackend(load_robot("snake8"), terrain=FLAT_FIELD) as twin:
        twin.advance(0.1)
    built = list(tmp_path.glob("scale_friction_*.so"))
    assert len(built) == 1
    stamp = built[0].stat().st_mtime_ns
    monkeypatch.setattr(scale_c, "_LIBRARY", None)
    with TwinBackend(load_robot("snake8"), terrain=FLAT_FIELD) as twin:
        twin.advance(0.1)
    assert built[0].stat().st_mtime_ns == stamp


def test_without_a_compiler_numpy_takes_over_with_a_warning(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("SNAKEBOT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("PATH", str(tmp_path))  # no cc, gcc or clang
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setattr(scale_c, "_LIBRARY", None)
    robot = load_robot("snake8")
    twin = TwinBackend(robot, terrain=FLAT_FIELD)
    with pytest.warns(RuntimeWarning, match="numpy.*no C compiler"):
        twin.connect()
    try:
        moved = float(play(twin, robot, "serpenoid", 3.0).summary["distance_m"])
    finally:
        twin.close()
    assert moved > 0.3  # friction still acts: lateral undulation works
    assert not (tmp_path / "cache").exists() or not any((tmp_path / "cache").iterdir())


def test_a_batch_runs_after_a_numpy_twin_in_the_same_process(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A twin on numpy scale friction leaves its Python callback installed process-wide, which
    ``mujoco.batch`` refuses; a tuning batch made after it swaps in the C callback (the same
    forces) and runs, here on the plane (a model with no scale friction of its own), and the
    numpy twin still feels its friction."""
    robot = load_robot("snake8")
    monkeypatch.setenv("SNAKEBOT_SCALE_FRICTION", "numpy")
    numpy_twin = TwinBackend(robot, terrain=FLAT_FIELD)
    numpy_twin.connect()
    try:
        monkeypatch.delenv("SNAKEBOT_SCALE_FRICTION")
        batch = TwinBatch(robot)
        gait = make_gait("serpenoid", robot.joint_count, {})
        (trace,) = batch.run(GaitCommands([gait], robot), 2.0, 100.0)
        assert float(summarise(trace, robot, gait.period_s)["distance_m"]) > 0.1
        moved = float(play(numpy_twin, robot, "serpenoid", 2.0).summary["distance_m"])
        assert moved > 0.1  # friction still acts on the first twin's model
    finally:
        numpy_twin.close()


def test_a_batch_refuses_numpy_scale_friction_by_name(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SNAKEBOT_SCALE_FRICTION", "numpy")
    with pytest.raises(ConfigError, match="SNAKEBOT_SCALE_FRICTION") as caught:
        TwinBatch(load_robot("snake8"), terrain=FLAT_FIELD)
    assert "C" in str(caught.value)
