"""Physics health of mass-spring bodies (issue 23): the four checks, the summary, the typed error.

A healthy crawl reports its figures with no warning; a body the loader accepts but MuJoCo cannot
integrate (springs damped 30x Miller's worm: explicit damping past its stability limit) stops
with PhysicsHealthError and exit 1; each check is driven past its limit by putting the lattice
into a state that breaks exactly that check.
"""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

from snakebot.backends.softbody import SoftBodyBackend
from snakebot.backends.softbody.health import BodyHealthLimits, BodyHealthMonitor
from snakebot.cli.main import main
from snakebot.config.body_loader import load_body
from snakebot.errors import PhysicsHealthError
from tests.conftest import CONFIGS

WORM = load_body("worm")


def test_a_worm_crawling_reports_its_physics_health(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["run", "--robot", "worm", "--gait", "rectilinear", "--duration", "3", "--json"]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    physics = summary["physics"]
    assert physics["warnings"] == []
    assert physics["airborne_fraction"] == 0.0
    assert 0.0 <= physics["max_floor_penetration_mm"] < 0.5 * physics["point_radius_mm"]
    assert 0.0 < physics["max_spring_strain"] < 0.1
    assert 0.0 < physics["max_energy_ratio"] < 1.0
    # The health check counts the ramp-out too; the run's work only the gait's scored cycles.
    assert physics["energy_injected_j"] >= summary["positive_work_j"] > 0.0


def test_a_body_integrated_past_its_stability_ends_in_the_typed_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (CONFIGS / "bodies" / "worm.toml").read_text()
    broken = tmp_path / "overdamped_worm.toml"
    broken.write_text(
        text.replace('preset = "worm"', "k = 1.5\ndamping = 27.0").replace(
            'name = "worm"', 'name = "overdamped_worm"'
        )
    )
    argv = ["run", "--robot", str(broken), "--gait", "rectilinear", "--duration", "2", "--json"]
    assert main(argv) == 1
    error = json.loads(capsys.readouterr().err)["error"]
    assert "physics health: energy at t=" in error


def monitor_of(soft: SoftBodyBackend, **limits: object) -> BodyHealthMonitor:
    assert soft._point_geoms is not None
    return BodyHealthMonitor(
        soft.model,
        soft.data,
        soft._point_geoms,
        soft._point_bodies,
        WORM.lattice.point_radius_m,
        BodyHealthLimits(**limits),  # type: ignore[arg-type]
    )


def test_each_check_raises_past_its_hard_limit_and_warns_below_it() -> None:
    with SoftBodyBackend(WORM) as soft:
        model, data = soft.model, soft.data
        radius = WORM.lattice.point_radius_m
        calm = monitor_of(soft)
        calm.sample(data, 0.0)  # at rest on the floor
        assert calm.summary(0.0, 0.0)["warnings"] == []

        bottom = 3 * 2 + 2  # point 2 (a bottom corner of the head ring): its z slide
        data.qpos[bottom] = -3.5 * radius  # sunk 3.5 radii: through the floor
        mujoco.mj_forward(model, data)
        with pytest.raises(PhysicsHealthError, match="point penetration"):
            monitor_of(soft).sample(data, 0.0)
        data.qpos[bottom] = 0.0

        data.qpos[0] = 0.03  # point 0 pulled 3 cm ahead: its springs 150 % long or more
        mujoco.mj_forward(model, data)
        with pytest.raises(PhysicsHealthError, match="spring strain"):
            monitor_of(soft).sample(data, 0.0)
        soft_limits = monitor_of(soft, hard=False)
        soft_limits.sample(data, 0.0)
        assert any("rest length" in w for w in soft_limits.summary(0.0, 0.0)["warnings"])  # type: ignore[attr-defined]
        data.qpos[0] = 0.0

        data.qvel.reshape(-1, 3)[:, 0] = 1.0  # 1 m/s with no work done: energy from nowhere
        mujoco.mj_forward(model, data)
        with pytest.raises(PhysicsHealthError, match="energy"):
            monitor_of(soft).sample(data, 0.0)
        data.qvel[:] = 0.0

        data.qpos.reshape(-1, 3)[:, 2] = 0.05  # the whole body 5 cm up
        mujoco.mj_forward(model, data)
        flying = monitor_of(soft)
        flying.sample(data, 0.0)
        health = flying.summary(0.0, 0.0)
        assert health["airborne_fraction"] == 1.0
        assert any("no point touched" in w for w in health["warnings"])  # type: ignore[attr-defined]


def test_the_account_starts_afresh_and_can_be_switched_off() -> None:
    with SoftBodyBackend(WORM, health=None) as off:
        off.advance(0.01)
        assert off.physics_health() is None
    with SoftBodyBackend(WORM) as soft:
        fresh = soft.physics_health()
        for _ in range(20):
            soft.advance(0.01)
        assert soft.physics_health() != fresh
        soft.reset_physics_health()
        assert soft.physics_health() == fresh
        assert np.isfinite(soft.data.qpos).all()
