"""Build the twin's MuJoCo model from a robot config with ``mujoco.MjSpec``.

Modules are capsules laid head (at the origin, facing +x) to tail (towards -x). Capsules are the
one MuJoCo shape whose floor contact frame follows the body, so a capsule-floor ``pair`` with
friction (axial, lateral) gives friction along and across each module (locomotion.md §4).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from snakebot.backends.twin.friction.layout import NUMERIC_NAME
from snakebot.backends.twin.friction.scale import (
    FRICTION_MODELS,
    FrictionModel,
    ScaleFriction,
    add_scale_friction,
    bind_scale_friction,
    python_callback_paused,
)
from snakebot.backends.twin.terrain import BodyShape, Terrain, as_terrain
from snakebot.config.paths import scene_path
from snakebot.config.schema import RobotConfig
from snakebot.errors import ConfigError
from snakebot.servo.dynamics import ServoDynamics, history_samples, servo_dynamics

SCENE_PATH = scene_path()
"""The twin's scene (floor, light, tracking camera), shipped as package data."""
# Links collide with each other (bit 2) but reach the floor only through explicit pairs: a second,
# isotropic floor contact would cancel the anisotropy (locomotion.md §4.4, gotcha 3). With the
# scale model they touch the ground (bit 1) too, normal force only (condim 1, their priority
# wins over the terrain's), and friction comes from friction/scale.py.
_LINK_CONTYPE = 2
_SCALE_LINK_CONTYPE = 1 | 2
_SCALE_LINK_PRIORITY = 2
_SPIN_ROLL_FRICTION = (0.005, 0.0001, 0.0001)
_AXIS_VECTORS = {"yaw": (0.0, 0.0, 1.0), "pitch": (0.0, 1.0, 0.0)}
# Actuator history interpolation: 0 holds the last sample, so the delay acts in whole timesteps;
# 1 (linear) makes the delayed command continuous in the delay, which sysid needs to fit it.
_LINEAR_INTERP = 1


@dataclass(frozen=True)
class GroundFriction:
    """Coulomb friction of every module on the floor, along and across the module.

    ``backward`` (the scale model only; None = ``axial``) is for sliding tail-first.
    """

    axial: float
    lateral: float
    backward: float | None = None

    @property
    def roll_resistant(self) -> bool:
        """Directional friction stands for wheels (or scales), which keep a module upright."""
        return self.axial < self.lateral

    def pair_friction(self, radius_m: float) -> list[float]:
        """MuJoCo pair friction: axial, lateral, spin, then rolling about the two tangents.

        A capsule pushed sideways rolls about its own axis (locomotion.md §4.2). Wheels on a rigid
        axle cannot, so a roll-resistant ground adds rolling friction (condim 6) well above the
        lateral friction force's moment, lateral * radius; well above, because the elliptic cone
        shares one budget between sliding and rolling.
        """
        roll = 4.0 * self.lateral * radius_m if self.roll_resistant else _SPIN_ROLL_FRICTION[1]
        return [self.axial, self.lateral, _SPIN_ROLL_FRICTION[0], roll, roll]

    def scale(self, source: str = "friction") -> ScaleFriction:
        """The scale model's coefficients: forward = axial, backward, lateral."""
        backward = self.axial if self.backward is None else self.backward
        return ScaleFriction(self.axial, backward, self.lateral, source=source)

    @classmethod
    def parse(cls, text: str, option: str = "friction") -> GroundFriction:
        """Parse ``AXIAL,LATERAL`` or ``FORWARD,BACKWARD,LATERAL`` (non-negative numbers)."""
        parts = text.split(",")
        try:
            values = [float(p) for p in parts]
        except ValueError:
            values = []
        if len(values) not in (2, 3):
            raise ConfigError(
                option,
                "",
                "expected AXIAL,LATERAL or FORWARD,BACKWARD,LATERAL (numbers, e.g. 0.02,1.0), "
                f"got {text!r}",
            )
        if not all(v >= 0 and math.isfinite(v) for v in values):
            raise ConfigError(option, "", f"friction coefficients must be >= 0, got {text!r}")
        if len(values) == 3:
            forward, backward, lateral = values
            ScaleFriction(forward, backward, lateral, source=option)  # backward >= forward
            return cls(forward, lateral, backward)
        return cls(values[0], values[1])


def ground_friction(robot: RobotConfig, override: GroundFriction | None = None) -> GroundFriction:
    """The robot's own ground model, unless ``override`` (the ``friction`` option) replaces it."""
    if override is not None:
        return override
    twin = robot.twin
    if twin.ground == "isotropic":
        return GroundFriction(twin.lateral_friction, twin.lateral_friction)
    return GroundFriction(twin.axial_friction, twin.lateral_friction, twin.backward_friction)


def resolve_friction_model(
    robot: RobotConfig, terrain: Terrain, model: FrictionModel | None = None
) -> FrictionModel:
    """The friction model that applies, "pairs" or "scale": ``model`` (``--friction-model``),
    else the robot file's ``twin.friction_model``; "auto" means pairs where the snake lies on the
    floor plane, scale elsewhere."""
    chosen = model or robot.twin.friction_model
    if chosen not in FRICTION_MODELS:
        raise ConfigError(
            "friction_model", "", f"expected one of {FRICTION_MODELS}, got {chosen!r}"
        )
    if chosen == "auto":
        return "pairs" if terrain.plane_ground else "scale"
    return chosen


def body_shape(robot: RobotConfig) -> BodyShape:
    """The chain's dimensions, as terrains lay themselves out around it."""
    return BodyShape(robot.link_count, robot.link.length_m, robot.link.radius_m)


def link_name(index: int) -> str:
    """Name of module ``index`` (0 = head)."""
    return f"link{index}"


def joint_name(index: int) -> str:
    """Name of joint ``index`` (0 = between head and the next module)."""
    return f"joint{index}"


def build_spec(
    robot: RobotConfig,
    *,
    friction: GroundFriction | None = None,
    timestep_s: float | None = None,
    scene_path: Path = SCENE_PATH,
    terrain: Terrain | str | None = None,
    friction_model: FrictionModel | None = None,
) -> mujoco.MjSpec:
    """An ``MjSpec`` of ``robot`` in the scene on ``terrain`` (a Terrain, ``--terrain``
    text, or None for flat), with the ground friction of ``friction_model`` (None: the robot
    file's); compile it with :func:`build_model`, or ``to_xml()`` it for a viewer.

    ConfigError naming the ``--terrain`` key if the terrain cannot host this robot.
    """
    ground_terrain = as_terrain(terrain)
    shape = body_shape(robot)
    ground_terrain.check(shape)
    model_name = resolve_friction_model(robot, ground_terrain, friction_model)
    spec = mujoco.MjSpec.from_file(str(scene_path))
    spec.modelname = robot.name
    spec.compiler.degree = False
    spec.option.timestep = timestep_s if timestep_s is not None else robot.twin.timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    dynamics = servo_dynamics(robot.servo.physics, robot.gains)
    length, radius = robot.link.length_m, robot.link.radius_m
    ground = ground_friction(robot, friction)

    parent = spec.worldbody
    for index in range(robot.link_count):
        body = parent.add_body(name=link_name(index))
        if index == 0:
            start = ground_terrain.start_pose(shape)
            body.pos = list(start.pos)
            body.quat = list(start.quat)
            body.add_freejoint(name="root")
        else:
            body.pos = [-length, 0.0, 0.0]
            _add_joint(body, robot, index - 1, dynamics)
        geom = body.add_geom(
            name=f"{link_name(index)}_geom",
            type=mujoco.mjtGeom.mjGEOM_CAPSULE,
            fromto=[-radius, 0, 0, -(length - radius), 0, 0],
            size=[radius, 0, 0],
            mass=robot.link.mass_kg,
            contype=_LINK_CONTYPE,
            conaffinity=_LINK_CONTYPE,
            rgba=[0.85, 0.45, 0.1, 1] if index == 0 else [0.15, 0.15, 0.17, 1],
        )
        if model_name == "scale":
            geom.contype = geom.conaffinity = _SCALE_LINK_CONTYPE
            geom.condim = 1
            geom.priority = _SCALE_LINK_PRIORITY
        else:
            spec.add_pair(
                name=f"floor_{link_name(index)}",
                geomname1=ground_terrain.pair_geom,
                geomname2=f"{link_name(index)}_geom",
                condim=6 if ground.roll_resistant else 3,
                friction=ground.pair_friction(radius),
            )
        parent = body
    ground_terrain.add_to(spec, shape)
    if model_name == "scale":
        add_scale_friction(spec, robot.link_count, ground.scale(str(robot.source)))
    head = spec.body(link_name(0))
    head.add_camera(
        name="track",
        mode=mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM,
        pos=[-robot.body_length_m / 2, -1.6 * robot.body_length_m, 1.1 * robot.body_length_m],
        xyaxes=[1, 0, 0, 0, 0.57, 0.82],
    )
    return spec


def _add_joint(body: mujoco.MjsBody, robot: RobotConfig, index: int, servo: ServoDynamics) -> None:
    joint_cfg = robot.joints[index]
    body.add_joint(
        name=joint_name(index),
        type=mujoco.mjtJoint.mjJNT_HINGE,
        axis=list(_AXIS_VECTORS[joint_cfg.axis]),
        range=[joint_cfg.lower_rad, joint_cfg.upper_rad],
        limited=mujoco.mjtLimited.mjLIMITED_TRUE,
        damping=servo.joint_damping_nms,
        armature=servo.armature_kgm2,
        frictionloss=servo.friction_loss_nm,
    )


def add_actuators(spec: mujoco.MjSpec, robot: RobotConfig) -> None:
    """One position servo per joint: kp and kv from the gains, force clipped at stall torque.

    With an actuator delay each servo acts on its command of ``delay_s`` ago, read from a
    history of ``history_samples`` commands (part of the ``mjSTATE_INTEGRATION`` state).
    """
    servo = servo_dynamics(robot.servo.physics, robot.gains)
    kv = servo.actuator_kv(spec.option.timestep)
    samples = history_samples(spec.option.timestep)
    for index, joint_cfg in enumerate(robot.joints):
        actuator = spec.add_actuator(name=f"servo{joint_cfg.servo_id}", target=joint_name(index))
        actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
        actuator.set_to_position(kp=servo.stiffness_nm_per_rad, kv=kv)
        actuator.ctrlrange = [joint_cfg.lower_rad, joint_cfg.upper_rad]
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.forcerange = [-servo.torque_limit_nm, servo.torque_limit_nm]
        actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        if servo.delay_s is not None:
            actuator.delay = servo.delay_s
            actuator.nsample = samples
            actuator.interp = _LINEAR_INTERP


def hold_ctrl_history(model: mujoco.MjModel, data: mujoco.MjData, command_rad: np.ndarray) -> None:
    """Make ``command_rad`` (N,) every past command of the delayed actuators, as if the servos
    had held it; MjData starts the history at 0, a straight-snake command. No-op without delay.
    """
    for actuator in np.flatnonzero(model.actuator_history[:, 0] > 0):
        samples = int(model.actuator_history[actuator, 0])
        values = np.full((samples, 1), float(command_rad[actuator]))
        mujoco.mj_initCtrlHistory(model, data, int(actuator), None, values)


def build_model(
    robot: RobotConfig,
    *,
    friction: GroundFriction | None = None,
    timestep_s: float | None = None,
    terrain: Terrain | str | None = None,
    friction_model: FrictionModel | None = None,
) -> tuple[mujoco.MjModel, mujoco.MjSpec]:
    """Compile the twin of ``robot``; returns the model and the spec it came from.

    With the scale friction model this installs its callback (friction/scale.py).
    ConfigError naming the robot file if MuJoCo refuses the model (see :func:`compile_spec`).
    """
    spec = build_spec(
        robot,
        friction=friction,
        timestep_s=timestep_s,
        terrain=terrain,
        friction_model=friction_model,
    )
    add_actuators(spec, robot)
    model = compile_spec(spec, robot)
    if uses_scale_friction(model):
        bind_scale_friction(model, model.body(link_name(0)).id)
    return model, spec


def uses_scale_friction(model: mujoco.MjModel) -> bool:
    """True if ``model`` was built with the scale friction model."""
    return bool(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, NUMERIC_NAME) >= 0)


# Which robot-file table a MuJoCo element named in a compile error comes from.
_ELEMENT_KEYS = {"link": "link", "joint": "joints", "servo": "gains", "floor": "twin"}


def compile_spec(spec: mujoco.MjSpec, robot: RobotConfig) -> mujoco.MjModel:
    """``spec.compile()``, with MuJoCo's refusal (a mass or size it cannot use, say) raised as a
    ConfigError naming the robot file and the table the offending element comes from."""
    try:
        with python_callback_paused():
            return spec.compile()
    except ValueError as exc:
        text = " ".join(str(exc).replace("Error:", "").split())
        element = re.search(r"Element name '([A-Za-z_]+?)\d*'", text)
        key = _ELEMENT_KEYS.get(element.group(1), "") if element else ""
        raise ConfigError(robot.source, key, f"MuJoCo cannot compile the twin: {text}") from None
