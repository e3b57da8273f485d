"""A new X-series model is one data file plus its servo file: no code.

The XW540-T260 ships with no snakebot data. A user writes its control-table facts (addresses come
from the SDK's own xw540_t260.model), a servo file and a robot file into their own folders, points
SNAKEBOT_SERVO_DATA at the data, and the robot runs: on the twin, and over the real dynamixel_sdk
against the emulator serving that model, every Goal Position inside the joint limits.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.gaits import make_gait
from snakebot.servo_tables import supported_models, table_for_model

MODEL = "XW540-T260"
IDS = range(1, 7)

# e-Manual _data/dxl_x_info.yml xw540-t260: 9.5 N·m at 12 V and 4.9 A, 40 rpm; the X map of the
# SDK's xw540_t260.model (no LED, no External Ports); ranges as the XM540-W270's.
DATA = f"""
[model]
base = "_x_series"
name = "{MODEL}"
model_number = 1170
model_file = "xw540_t260.model"
operating_modes = [0, 1, 3, 4, 5, 16]
nominal_voltage_v = 12.0
no_load_speed_rad_s = {40 * 2 * math.pi / 60}
stall_torque_nm = 9.5
stall_current_a = 4.9

[registers]
model_number = {{ default = 1170 }}
max_voltage_limit = {{ minimum = 95, maximum = 160, default = 160 }}
min_voltage_limit = {{ minimum = 95, maximum = 160, default = 95 }}
current_limit = {{ minimum = 0, maximum = 2047, default = 2047, unit = "A", scale = 0.00269 }}
velocity_limit = {{ default = 128 }}
goal_current = {{ minimum = -2047, maximum = 2047, unit = "A", scale = 0.00269, signed = true }}
present_current = {{ access = "R", unit = "A", scale = 0.00269, signed = true }}
led = {{ absent = true }}
"""

SERVO = f"""
model = "{MODEL}"

[physics]
supply_voltage_v = 12.0
armature_kgm2 = 0.004
friction_loss_nm = 0.06
viscous_damping_nms = 0.02
pwm_limit = 885
d_gain_loop_period_s = 0.001
p_gain_divisor = 256
d_gain_divisor = 32

[settings]
return_delay_time_us = 0
operating_mode = 3
drive_mode = 0
min_position_limit_deg = -110
max_position_limit_deg = 110
"""

ROBOT = f"""
name = "xw6"
servo = "{MODEL}"

[bus]
baud = 1000000

[link]
length_m = 0.1
radius_m = 0.03
mass_kg = 0.26

[joint_defaults]
lower_rad = -1.2
upper_rad = 1.2
""" + "".join(f'\n[[joints]]\nservo_id = {i}\naxis = "yaw"\n' for i in IDS)


@pytest.fixture
def robot_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    models = tmp_path / "models"
    models.mkdir()
    (models / "xw540_t260.toml").write_text(DATA)
    monkeypatch.setenv("SNAKEBOT_SERVO_DATA", str(models))
    for folder, name, text in (("servos", "xw540-t260", SERVO), ("robots", "xw6", ROBOT)):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / f"{name}.toml").write_text(text)
    return tmp_path / "robots" / "xw6.toml"


def test_the_new_model_runs_on_the_twin_and_over_the_emulator_from_data_alone(
    robot_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert MODEL in supported_models()
    robot = load_robot(robot_path)
    assert robot.servo.model_number == table_for_model(MODEL).model_number == 1170
    argv = ["run", "--robot", str(robot_path), "--gait", "serpenoid", "--duration", "2", "--json"]
    assert main(argv) == 0, capsys.readouterr().err
    assert json.loads(capsys.readouterr().out)["max_abs_command_rad"] <= 1.2

    chain = make_chain_for_ids(MODEL, IDS, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain, time="wall") as url:
        code = main([*argv, "--backend", "dynamixel", "--port", url])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0 and summary["backend"] == "dynamixel"
    assert summary["max_abs_command_rad"] <= 1.2


def test_every_goal_the_new_model_receives_is_inside_the_joint_limits(robot_path: Path) -> None:
    robot = load_robot(robot_path)
    chain = make_chain_for_ids(MODEL, IDS, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    goals: list[list[int]] = []
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with backend:
            run_gait(
                backend,
                make_gait("serpenoid", len(IDS)),
                SafetyLayer.for_robot(robot),
                RunPlan(duration_s=2.0),
                RunMetrics(len(IDS), robot.body_length_m, robot.total_mass_kg),
                on_cycle=lambda cycle, t: goals.append(
                    [s.peek("goal_position") for s in chain.servos]
                ),
            )
    ticks = table_for_model(MODEL).specs.ticks
    angles = (np.array(goals) - ticks.centre) / ticks.ticks_per_rad
    assert len(goals) >= 150  # 2 s at 100 Hz, less the cycles of the ramp-out
    assert np.abs(angles).max() > 0.3  # the gait reached the servos
    assert np.all(np.abs(angles) <= 1.2 + 1 / ticks.ticks_per_rad)
