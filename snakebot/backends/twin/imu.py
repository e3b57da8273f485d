"""Sensors of the twin: an IMU in the head and the servos' encoders, as a real robot reads them.

The IMU gives the head's orientation (w, x, y, z) and a gyro's angular rate in the head's own
frame, with optional Gaussian noise; the encoders round positions to whole ticks and add
optional Gaussian noise. Noise comes from one generator seeded per twin, so runs repeat.
Reading them never changes the physics.
"""

from __future__ import annotations

import mujoco
import numpy as np

from snakebot.config.servos.extras import ServoExtras


class TwinSensors:
    """The head IMU and the encoders of one twin (``head_id`` the head body)."""

    def __init__(
        self,
        model: mujoco.MjModel,
        head_id: int,
        extras: ServoExtras,
        rad_per_tick: float,
        seed: int = 0,
    ) -> None:
        self._model = model
        self._head = head_id
        self._gyro_noise = extras.imu_gyro_noise_rad_s or 0.0
        self._position_noise = extras.encoder_noise_rad or 0.0
        self._tick_rad = rad_per_tick if extras.quantise_encoder else 0.0
        self._rng = np.random.default_rng(seed)
        self._velocity = np.zeros(6)
        self._angular = self._velocity[:3]
        self._data: mujoco.MjData | None = None
        self._head_frame = np.zeros((3, 3))

    @property
    def alters_positions(self) -> bool:
        """Whether read positions differ from the simulated ones."""
        return bool(self._tick_rad or self._position_noise)

    def gyro_rad_s(self, data: mujoco.MjData) -> np.ndarray:
        """The head's angular velocity (3,) in its own frame, rad/s, plus gyro noise.

        Taken in the world frame and turned into the head body's frame (``xmat``): MuJoCo's
        local frame for a body is its inertial frame, whose axes a capsule's principal axes
        order differently (the head's yaw came out on the inertial x axis)."""
        if data is not self._data:  # the head's frame as a view into this data, made once
            self._data, self._head_frame = data, data.xmat[self._head].reshape(3, 3)
        mujoco.mj_objectVelocity(
            self._model, data, mujoco.mjtObj.mjOBJ_BODY, self._head, self._velocity, 0
        )
        return self.gyro_of(self._angular, data)

    def gyro_of(self, angular_rad_s: np.ndarray, data: mujoco.MjData) -> np.ndarray:
        """What the gyro reads (3,) rad/s for the head's angular velocity ``angular_rad_s``
        (3,) in the world frame (``mj_objectVelocity``'s, of ``data`` now): turned into the
        head's frame, plus gyro noise."""
        if data is not self._data:
            self._data, self._head_frame = data, data.xmat[self._head].reshape(3, 3)
        rate: np.ndarray = angular_rad_s @ self._head_frame
        if self._gyro_noise:
            rate += self._rng.normal(0.0, self._gyro_noise, 3)
        return rate

    def encoder_rad(self, position_rad: np.ndarray) -> np.ndarray:
        """``position_rad`` (N,) as the encoders report it: in whole ticks, plus noise."""
        out = position_rad
        if self._tick_rad:
            out = np.round(out / self._tick_rad) * self._tick_rad
        if self._position_noise:
            out = out + self._rng.normal(0.0, self._position_noise, out.shape)
        return out
