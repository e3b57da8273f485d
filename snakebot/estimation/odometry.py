"""Odometry from the servos alone: the world motion of the virtual chassis, cycle by cycle.

Method (docs/estimation.md). Each control cycle, forward kinematics of the measured joint
angles places the modules in the virtual chassis (snakebot.estimation.chassis); the chassis is
levelled (its x axis laid into the ground plane, z up) with "up" from the body's shape: the
head's z for a chain that bends in yaw only, else the chassis axis of clearly least extent
(sidewinding's body lies in the plane of its two largest extents), on the side of the last up and
of the IMU's gravity where there is one (``level_by="gravity"`` takes the IMU's up instead).
Modules that touch the ground hardly slip, so the levelled chassis moved by the planar rigid
motion that keeps them where they were since the last cycle:

- Turn: the weighted least-squares rigid motion of every module, each weighed by a Gaussian of
  its height above the lowest (``turn_height_m``): a 2-D Kabsch in closed form for static
  contacts, two Gauss-Newton steps with no_lateral_slip's per-module metric.
- IMU: the change of the head's heading by the gyro (``heading_rate``), less the head's turn in
  the chassis that FK gives, is a second measurement of the turn; the two are fused by their
  variances (the one-step Kalman combination: the fit's residual variance, the gyro's noise).
- Shift: with the turn fixed, the translation that keeps the modules touching the ground in both
  cycles where they were: the ``contact_modules`` lowest (sidewinding's carrying modules), all of
  them for a body lying flat.
- Slip: ``static`` contacts keep still both ways (sidewinding); with ``no_lateral_slip`` (a
  planar snake on wheels or scales, lateral undulation) a module slides freely along its own axis
  and only its sideways motion counts (``axial_weight`` of the along-axis residual); ``auto``
  picks no_lateral_slip for a chain that bends in yaw only.

The estimate never reads a pose from the backend: of the body record it takes the gyro and the
gravity direction in the head (the IMU's tilt) only.

``ChassisOdometry`` is a cycle observer (give it to ``run_gait``'s observers) and a
``PoseSource`` (``body_state()``), so a goal policy, ``run --to`` or a heading controller can
run on the servo bus with no motion capture.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
import numpy.typing as npt

from snakebot.estimation.chassis import ChassisFrame, VirtualChassis
from snakebot.estimation.kinematics import ChainGeometry, cross3
from snakebot.types import BodyState, JointState

if TYPE_CHECKING:
    from snakebot.control.cycle import CycleRecord

FloatArray = npt.NDArray[np.float64]
SlipModel = Literal["auto", "static", "no_lateral_slip"]
SLIP_MODELS: tuple[str, ...] = ("auto", "static", "no_lateral_slip")
LevelBy = Literal["shape", "gravity"]
CLEAR_RATIO = 0.6
"""The smaller cross extent of the chassis must be under this fraction of the larger for its
axis to be taken as the ground's normal; closer than that the last normal is kept."""


@dataclass(frozen=True)
class OdometryConfig:
    """How the odometry weighs what it sees (see the module doc).

    ``slip``: auto, static or no_lateral_slip. ``contact_modules``: the modules that count as
    touching the ground are the ``contact_modules`` lowest and any within ``contact_height_m``
    of the highest of those (all of them, for a body lying flat); they give the translation.
    The turn is fitted on a wider base: every module weighed by a Gaussian of its height above
    the lowest (``turn_height_m``). ``level_by``: the ground's
    normal from the body's shape (the chassis axis of least extent; the head's z for a chain
    that bends in yaw only), or from the IMU's gravity where there is one. ``axial_weight``:
    with no_lateral_slip, the weight of a module's along-axis motion against its sideways motion
    (0 < w <= 1). ``use_imu``: read the head IMU when the cycle record has one.
    ``gyro_noise_rad_s``: the gyro's noise (standard deviation per reading) the fusion assumes.
    ``radius_m``: module radius, for the centre's height above the ground. ValueError for a
    value out of range.
    """

    slip: SlipModel = "auto"
    contact_modules: int = 3
    contact_height_m: float = 0.001
    turn_height_m: float = 0.008
    level_by: LevelBy = "shape"
    axial_weight: float = 0.02
    use_imu: bool = True
    gyro_noise_rad_s: float = 0.005
    radius_m: float = 0.0

    def __post_init__(self) -> None:
        if self.slip not in SLIP_MODELS:
            raise ValueError(f"slip must be one of {', '.join(SLIP_MODELS)}, got {self.slip!r}")
        if not (self.contact_height_m >= 0 and math.isfinite(self.contact_height_m)):
            raise ValueError(f"contact_height_m must be >= 0, got {self.contact_height_m}")
        if not (self.turn_height_m > 0 and math.isfinite(self.turn_height_m)):
            raise ValueError(f"turn_height_m must be > 0, got {self.turn_height_m}")
        if self.contact_modules < 2:
            raise ValueError(f"contact_modules must be >= 2, got {self.contact_modules}")
        if self.level_by not in ("shape", "gravity"):
            raise ValueError(f"level_by must be shape or gravity, got {self.level_by!r}")
        if not (0 < self.axial_weight <= 1):
            raise ValueError(f"axial_weight must be in (0, 1], got {self.axial_weight}")
        if not (self.gyro_noise_rad_s > 0 and math.isfinite(self.gyro_noise_rad_s)):
            raise ValueError(f"gyro_noise_rad_s must be > 0, got {self.gyro_noise_rad_s}")
        if not (self.radius_m >= 0 and math.isfinite(self.radius_m)):
            raise ValueError(f"radius_m must be >= 0, got {self.radius_m}")


@dataclass(frozen=True)
class PlanarPose:
    """The levelled chassis in the estimate's world: ``x_m``, ``y_m`` (its origin, the module
    centroid), ``yaw_rad`` (its x axis), at robot time ``time_s``; ``distance_m`` the path
    length its origin travelled since the start."""

    time_s: float
    x_m: float
    y_m: float
    yaw_rad: float
    distance_m: float


@dataclass(frozen=True)
class _Levelled:
    """One cycle in the levelled chassis: modules (M, 2) in the ground plane, heights (M,),
    module axes (M, 2) in the plane, the head's heading in it, and the levelled frame (3, 3)
    in the head's frame."""

    planar_m: FloatArray
    height_m: FloatArray
    tangent: FloatArray
    head_heading_rad: float
    head_to_level: FloatArray
    up_head: FloatArray
    """Up (3,) in the head's frame as the gyro's heading rate takes it (the IMU's gravity
    where there is one, else the ground normal of the levelling)."""


class ChassisOdometry:
    """World pose of the virtual chassis from the measured joints (and the head IMU).

    ``geometry``: the chain (``ChainGeometry.of_robot``); ``config``: OdometryConfig. Feed it
    every cycle's record (it is a ``CycleObserver``) or call ``update`` with the joint angles;
    the first update fixes the estimate's world: the head at the origin facing +x (the twin's
    start pose on flat ground). ``body_state()`` (a ``PoseSource``) is None before the first.
    """

    def __init__(self, geometry: ChainGeometry, config: OdometryConfig | None = None) -> None:
        self.geometry = geometry
        self.config = config if config is not None else OdometryConfig()
        slip = self.config.slip
        if slip == "auto":
            slip = "no_lateral_slip" if geometry.planar else "static"
        self.slip: SlipModel = slip
        self.chassis = VirtualChassis()
        self._last: _Levelled | None = None
        self._pose: PlanarPose | None = None
        self._body: BodyState | None = None
        self._last_rate: float | None = None
        self._up_head = np.array([0.0, 0.0, 1.0])
        self.cycles = 0

    def reset(self) -> None:
        """Forget everything: the next update starts the estimate afresh."""
        self.chassis.reset()
        self._last = None
        self._pose = None
        self._body = None
        self._last_rate = None
        self._up_head = np.array([0.0, 0.0, 1.0])
        self.cycles = 0

    @property
    def pose(self) -> PlanarPose | None:
        """The latest planar pose, or None before the first update."""
        return self._pose

    def start(self, state: JointState) -> PlanarPose:
        """Start the estimate at a joint state read before the first cycle (so a pose exists
        when the first cycle's gait asks for it); no IMU."""
        return self.update(state.time_s, state.position_rad)

    def __call__(self, record: CycleRecord) -> None:
        """Observe one cycle: its measured joints, and of ``record.body`` the head IMU only."""
        gyro = up = None
        body = record.body
        if self.config.use_imu and body is not None and body.head_gyro_rad_s is not None:
            gyro = body.head_gyro_rad_s
            up = gravity_up_in_head(body.head_quat)
        self.update(record.time_s, record.state.position_rad, gyro_rad_s=gyro, up_in_head=up)

    def update(
        self,
        time_s: float,
        position_rad: npt.ArrayLike,
        *,
        gyro_rad_s: npt.ArrayLike | None = None,
        up_in_head: npt.ArrayLike | None = None,
    ) -> PlanarPose:
        """Advance the estimate to robot time ``time_s`` s with joint angles (N,) rad; the head
        IMU's angular rate (3,) rad/s and the world's up direction (3,) in the head's frame where
        there is one. Returns the new pose. ValueError for a wrong shape."""
        frames = self.geometry.frames(position_rad)
        centres = frames[0] - 0.5 * self.geometry.length_m * frames[1][:, :, 0]
        frame = self.chassis.update(centres)
        level = self._level(frame, frames[1][:, :, 0], up_in_head)
        pose = self._pose
        if pose is None or self._last is None:
            # The estimate's world: the head at the origin facing +x. The chassis origin lies
            # where FK puts it from the head, turned by the head's heading in the plane.
            yaw = -level.head_heading_rad
            head_in_level = -(level.head_to_level.T @ frame.origin_m)[:2]
            c, s = math.cos(yaw), math.sin(yaw)
            x = -(c * head_in_level[0] - s * head_in_level[1])
            y = -(s * head_in_level[0] + c * head_in_level[1])
            pose = PlanarPose(float(time_s), x, y, yaw, 0.0)
        else:
            dyaw, variance = self._turn(self._last, level)
            gyro_step = self._gyro_yaw_step(level, gyro_rad_s, float(time_s) - pose.time_s)
            if gyro_step is not None:
                gyro_variance = (self.config.gyro_noise_rad_s * (float(time_s) - pose.time_s)) ** 2
                gyro_weight = variance / (variance + gyro_variance)
                dyaw = gyro_weight * gyro_step + (1.0 - gyro_weight) * dyaw
            dx, dy = self._translation(self._last, level, dyaw)
            c, s = math.cos(pose.yaw_rad), math.sin(pose.yaw_rad)
            step_x, step_y = c * dx - s * dy, s * dx + c * dy
            pose = PlanarPose(
                float(time_s),
                pose.x_m + step_x,
                pose.y_m + step_y,
                pose.yaw_rad + dyaw,
                pose.distance_m + math.hypot(step_x, step_y),
            )
        if gyro_rad_s is not None:
            self._last_rate = heading_rate(np.asarray(gyro_rad_s, dtype=float), level.up_head)
        self._last, self._pose = level, pose
        self._body = self._body_state(frame, level, pose)
        self.cycles += 1
        return pose

    def body_state(self) -> BodyState | None:
        """The estimated body (PoseSource): the module centroid (3,) m in the estimate's world
        and the head's orientation (w, x, y, z); no gyro. None before the first update."""
        return self._body

    # -- one cycle's pieces ---------------------------------------------------------------
    def _level(
        self, frame: ChassisFrame, module_x: FloatArray, up_in_head: npt.ArrayLike | None
    ) -> _Levelled:
        """The chassis laid into the ground plane: where "up" is, then the modules in it."""
        rotation = frame.rotation
        gravity = None if up_in_head is None else np.asarray(up_in_head, dtype=float)
        if gravity is not None and self.config.level_by == "gravity":
            up_head = gravity / math.sqrt(float(gravity @ gravity))
        else:
            up_head = self._shape_up(frame)
            if gravity is not None and up_head @ gravity < 0:  # the IMU knows which side is up
                up_head = -up_head
        self._up_head = up_head
        gyro_up = up_head if gravity is None else gravity
        forward = rotation[:, 0] - (rotation[:, 0] @ up_head) * up_head
        norm = math.sqrt(float(forward @ forward))
        if norm < 1e-6:  # the body stands on end: keep the chassis's y in the plane instead
            side = rotation[:, 1] - (rotation[:, 1] @ up_head) * up_head
            forward = cross3(side / np.linalg.norm(side), up_head)
            norm = 1.0
        forward = forward / norm
        head_to_level = np.column_stack([forward, cross3(up_head, forward), up_head])
        local = (self.chassis_points(frame)) @ head_to_level
        tangent = module_x @ head_to_level[:, :2]
        lengths = np.linalg.norm(tangent, axis=1, keepdims=True)
        tangent = np.divide(tangent, lengths, out=np.zeros_like(tangent), where=lengths > 1e-9)
        head_x = head_to_level[0, :2]  # the head's x axis (head frame e_x) in the plane
        return _Levelled(
            planar_m=local[:, :2],
            height_m=local[:, 2],
            tangent=tangent,
            head_heading_rad=math.atan2(float(head_x[1]), float(head_x[0])),
            head_to_level=head_to_level,
            up_head=gyro_up / math.sqrt(float(gyro_up @ gyro_up)),
        )

    def _shape_up(self, frame: ChassisFrame) -> FloatArray:
        """The ground's normal (3,) in the head's frame from the body's shape: the head's z for
        a chain that bends in yaw only; else the chassis axis of clearly least extent (y or z),
        on the side of the last normal. A body with no clear least extent (straight, or round
        in section) keeps the last normal (the head's z at the start)."""
        last = self._up_head
        if self.geometry.planar:
            return np.array([0.0, 0.0, 1.0])
        extent, rotation = frame.extent_m, frame.rotation
        small, large = sorted((float(extent[1]), float(extent[2])))
        if large <= self.chassis.min_extent_m or small >= CLEAR_RATIO * large:
            return last
        axis = rotation[:, 1] if extent[1] < extent[2] else rotation[:, 2]
        up: FloatArray = axis if axis @ last >= 0 else -axis
        return up

    @staticmethod
    def chassis_points(frame: ChassisFrame) -> FloatArray:
        """The modules (M, 3) about the chassis origin, in the head's axes."""
        points: FloatArray = frame.positions_m @ frame.rotation.T
        return points

    def _weights(self, level: _Levelled) -> FloatArray:
        """1 for the modules taken to touch the ground, 0 for the others."""
        height = level.height_m
        count = min(self.config.contact_modules, height.size)
        reference = np.partition(height, count - 1)[count - 1]
        weights: FloatArray = (height <= reference + self.config.contact_height_m).astype(float)
        return weights

    def _metric(self, level: _Levelled, weights: FloatArray) -> FloatArray:
        """Per module the weighted 2x2 metric of its planar residual (M, 2, 2): isotropic for
        static contacts; along its axis ``axial_weight`` of across it with no lateral slip."""
        tangent = level.tangent
        if self.slip == "no_lateral_slip":
            normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
            metric = self.config.axial_weight * tangent[:, :, None] * tangent[:, None, :]
            metric = metric + normal[:, :, None] * normal[:, None, :]
        else:
            metric = np.broadcast_to(np.eye(2), (tangent.shape[0], 2, 2))
        out: FloatArray = metric * weights[:, None, None]
        return out

    def _turn(self, last: _Levelled, now: _Levelled) -> tuple[float, float]:
        """The levelled chassis's yaw change since ``last`` (rad) and its variance (rad²): the
        rigid planar motion that best keeps the low modules where they were (weights: a
        Gaussian of the height above the lowest): closed form for static contacts, else by
        Gauss-Newton from no motion, twice."""
        scale = self.config.turn_height_m
        weights = np.exp(-0.5 * ((last.height_m - last.height_m.min()) / scale) ** 2)
        weights *= np.exp(-0.5 * ((now.height_m - now.height_m.min()) / scale) ** 2)
        weights = np.sqrt(weights)
        points, target = now.planar_m, last.planar_m
        if self.slip == "static":
            return _planar_kabsch_turn(points, target, weights)
        metric = self._metric(now, weights)
        motion = np.zeros(3)  # dx, dy, dyaw
        normal_matrix = np.eye(3)
        residual = np.zeros_like(points)
        for _ in range(2):
            turned = points @ _rotation_2d(float(motion[2])).T
            residual = turned + motion[:2] - target  # (M, 2)
            # d residual / d(dx, dy, dyaw): [I, J p] with J p = (-p_y, p_x)
            jac = np.zeros((points.shape[0], 2, 3))
            jac[:, 0, 0] = jac[:, 1, 1] = 1.0
            jac[:, 0, 2], jac[:, 1, 2] = -turned[:, 1], turned[:, 0]
            weighted_jac = metric @ jac  # (M, 2, 3)
            normal_matrix = np.einsum("mij,mik->jk", jac, weighted_jac) + 1e-9 * np.eye(3)
            gradient = np.einsum("mij,mi->j", weighted_jac, residual)
            motion = motion + np.linalg.solve(normal_matrix, -gradient)
        cost = float(np.einsum("mi,mij,mj->", residual, metric, residual))
        dof = max(float(np.sqrt(weights).sum()) * 2.0 - 3.0, 1.0)
        variance = cost / dof * float(np.linalg.inv(normal_matrix)[2, 2])
        return float(motion[2]), max(variance, 1e-12)

    def _translation(self, last: _Levelled, now: _Levelled, dyaw: float) -> tuple[float, float]:
        """The shift (dx, dy) m that, after turning by ``dyaw``, best keeps the modules that
        touch the ground in both cycles where they were (weighted least squares)."""
        weights = self._weights(last) * self._weights(now)
        if not weights.any():
            weights = self._weights(now)
        metric = self._metric(now, weights)
        gap = last.planar_m - now.planar_m @ _rotation_2d(dyaw).T  # (M, 2)
        total = metric.sum(axis=0) + 1e-12 * np.eye(2)
        shift = np.linalg.solve(total, np.einsum("mij,mj->i", metric, gap))
        return float(shift[0]), float(shift[1])

    def _gyro_yaw_step(
        self, now: _Levelled, gyro_rad_s: npt.ArrayLike | None, dt_s: float
    ) -> float | None:
        """The chassis's yaw change over ``dt_s`` by the gyro: the change of the head's heading
        in the world (its rate, trapezoid) less its change in the chassis; None without a
        gyro."""
        last = self._last
        if gyro_rad_s is None or last is None or self._last_rate is None or dt_s <= 0:
            return None
        rate = heading_rate(np.asarray(gyro_rad_s, dtype=float), now.up_head)
        head_turn = 0.5 * (rate + self._last_rate) * dt_s
        relative = math.remainder(now.head_heading_rad - last.head_heading_rad, 2 * math.pi)
        return head_turn - relative

    def _body_state(self, frame: ChassisFrame, level: _Levelled, pose: PlanarPose) -> BodyState:
        c, s = math.cos(pose.yaw_rad), math.sin(pose.yaw_rad)
        world_from_level = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        head_rotation = world_from_level @ level.head_to_level.T
        height = float(-level.height_m.min()) + self.config.radius_m
        com = np.array([pose.x_m, pose.y_m, height])
        return BodyState(com_m=com, head_quat=rotation_to_quat(head_rotation))


def _planar_kabsch_turn(
    points: FloatArray, target: FloatArray, weights: FloatArray
) -> tuple[float, float]:
    """The turn (rad) of the weighted least-squares rigid motion taking ``points`` (M, 2) onto
    ``target`` (M, 2) (2-D Kabsch, in closed form), and its variance (rad²)."""
    total = float(weights.sum())
    p = points - weights @ points / total
    q = target - weights @ target / total
    cross = float(weights @ (p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]))
    dot = float(weights @ (p[:, 0] * q[:, 0] + p[:, 1] * q[:, 1]))
    turn = math.atan2(cross, dot)
    c, s = math.cos(turn), math.sin(turn)
    residual = q - p @ np.array([[c, s], [-s, c]])
    cost = float(weights @ (residual * residual).sum(axis=1))
    spread = float(weights @ (p * p).sum(axis=1))
    dof = max(total * 2.0 - 3.0, 1.0)
    return turn, max(cost / dof / max(spread, 1e-12), 1e-12)


def _rotation_2d(angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s], [s, c]])


def heading_rate(gyro_rad_s: FloatArray, up_in_head: FloatArray) -> float:
    """How fast the head's heading (its x axis laid into the ground plane) turns, rad/s, for
    the gyro's angular rate (3,) and the world's up (3,), both in the head's frame. Not the rate
    about up alone: a pitched head turning about its own axes moves its heading too
    (d heading/dt = w.u - (x.u)(w.x - (w.u)(x.u)) / (1 - (x.u)^2), x the head's axis)."""
    about_up = float(gyro_rad_s @ up_in_head)
    x_up = float(up_in_head[0])
    level = 1.0 - x_up * x_up
    if level < 1e-6:  # the head points straight up or down: its heading is undefined
        return about_up
    return about_up - x_up * (float(gyro_rad_s[0]) - about_up * x_up) / level


def gravity_up_in_head(head_quat: npt.ArrayLike) -> FloatArray:
    """The world's up (3,) in the head's frame from the head IMU's orientation (w, x, y, z): its
    tilt only (what an accelerometer measures at rest), never its heading."""
    w, x, y, z = (float(v) for v in np.asarray(head_quat, dtype=float))
    # Third row of the head's rotation matrix: world z in head coordinates.
    return np.array([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)])


def rotation_to_quat(rotation: FloatArray) -> FloatArray:
    """A rotation matrix (3, 3) as a unit quaternion (w, x, y, z), w >= 0."""
    m = rotation
    trace = float(m[0, 0] + m[1, 1] + m[2, 2])
    if trace > 0:
        s = 2.0 * math.sqrt(trace + 1.0)
        quat = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        quat = [(m[2, 1] - m[1, 2]) / s, 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        quat = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        quat = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s]
    out = np.array(quat, dtype=float)
    out /= np.linalg.norm(out)
    return out if out[0] >= 0 else -out
