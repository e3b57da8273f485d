"""What a backend can do beyond the contract every backend keeps (``base.Backend``).

Each optional ability is a runtime-checkable Protocol: a caller asks ``isinstance(backend,
SensesBody)`` and then uses it, and a backend has the ability by having its methods — no flag,
no registration, no probe by name. ``snakebot.testing.contract`` tests each ability a backend
has (``claimed``), so claiming one is a promise the conformance suite holds it to.

An ability that depends on the hardware (current sensing: only servo models with a Present
Current register report it) is given per instance: the backend makes the method an attribute of
the instance in its ``__init__`` where the ability is there, so ``isinstance`` answers for that
chain. Everything is SI, head to tail, shape (N,) per joint.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from snakebot.types import BodyState, JointState

if TYPE_CHECKING:
    import mujoco

__all__ = [
    "CAPABILITIES",
    "BusReport",
    "ChecksPhysics",
    "LimitsTorque",
    "OnBus",
    "ReportsHealth",
    "ReportsTravel",
    "Resettable",
    "SensesBody",
    "SensesCurrent",
    "SensesImu",
    "SensesTorque",
    "Simulated",
    "claimed",
    "torque_caps",
]

FloatArray = npt.NDArray[np.float64]


@runtime_checkable
class SensesBody(Protocol):
    """Measures the whole body: centre of mass (3,) m in the world frame and the head link's
    orientation (w, x, y, z), as of the last ``advance`` (the twin, the soft body; a motion
    capture rig could). Needs a connected backend."""

    def body_state(self) -> BodyState:
        """The body now."""
        ...


@runtime_checkable
class SensesImu(SensesBody, Protocol):
    """Has a head IMU: ``body_state().head_gyro_rad_s`` (3,) is what a gyro in the head reads,
    in its own frame, and ``head_quat`` is the IMU's orientation. The IMU's reading stays inside
    ``BodyState`` (one record of the body per cycle); this ability promises it is there (never
    None) and gives the gyro alone where that is all a caller needs."""

    def head_gyro_rad_s(self) -> FloatArray:
        """The head gyro's angular velocity (3,) rad/s in the head's frame now."""
        ...


@runtime_checkable
class ReportsHealth(Protocol):
    """Slow readings about the hardware's condition (the servo chain: ``temperature_c`` (N,),
    ``input_voltage_v`` (N,)), by name with the unit in the name, as of the backend's last slow
    read; cheap (no bus traffic), so a display may ask every cycle. Empty before the first."""

    def health(self) -> Mapping[str, np.ndarray]:
        """The latest slow readings by name."""
        ...


@runtime_checkable
class ChecksPhysics(Protocol):
    """Judges whether its physics stayed credible (the rigid twin: docs/physics.md)."""

    def physics_health(self) -> dict[str, object] | None:
        """The run's physics health so far; None with the checks switched off."""
        ...

    def reset_physics_health(self) -> None:
        """Start the account afresh (a new episode is judged on its own)."""
        ...


@runtime_checkable
class SensesCurrent(Protocol):
    """Measures each servo's current draw (signed, in the joint's sense, A) with every
    ``read_state``: a servo model with a Present Current register, or a twin whose servo file
    models the current."""

    def present_current_a(self) -> FloatArray:
        """Current per joint (N,) A as of the last ``read_state``."""
        ...


@runtime_checkable
class SensesTorque(Protocol):
    """Measures each joint's output torque with every ``read_state``: its
    ``JointState.effort_nm`` is a measurement, not an estimate. A servo model with a Present
    Current register (torque = kt * current, the torque constant from the servo file), or the
    rigid twin (its servo model's output torque, what that register would read). What
    gait-based compliance yields to (snakebot.control.compliance)."""

    def measured_torque_nm(self) -> FloatArray:
        """Output torque per joint (N,) N*m as of the last ``read_state`` (its ``effort_nm``)."""
        ...


@runtime_checkable
class LimitsTorque(Protocol):
    """Caps each servo's output torque while it still follows its position goals: a servo
    model with current-based position control (Dynamixel Operating Mode 5: Goal Current, the
    cap over the torque constant from the servo file, bounds the drive current), or the rigid
    twin (its actuators' force range). A joint held away from its goal pushes with no more than
    its cap and gives way beyond it, so the snake's shape yields to what holds it."""

    def limit_torque(self, torque_nm: npt.ArrayLike) -> None:
        """Cap each joint's torque at ``torque_nm`` (a scalar or (N,) N*m, > 0; values above
        the servo's stall torque mean no cap). Before connect it takes effect when the backend
        connects, before any torque comes on; after connect at once. ValueError for a wrong
        shape or a value that is not > 0; a chain raises ServoSettingsError (naming the servo
        IDs) at connect where a servo is not in current-based position mode."""
        ...


@runtime_checkable
class ReportsTravel(Protocol):
    """Measures how the body travelled over the run beyond what the runner measures (the soft
    body: its mean axis, the travel angle against it, the ground contact), for the summary."""

    def travel(self) -> Mapping[str, float]:
        """Figures since connect, by name with the unit in the name (``travel_angle_deg``)."""
        ...


@runtime_checkable
class Resettable(Protocol):
    """Can be put back to a start pose at once (a simulation: a learning environment's new
    episode). After ``reset`` the body rests at the origin facing +x, straight or in
    ``position_rad`` (N,) rad, every joint's goal is that pose, time is 0 and the physics-health
    account (where there is one) starts afresh."""

    def reset(self, position_rad: FloatArray | None = None) -> JointState:
        """Reset; returns the joint state read at the start pose."""
        ...


@runtime_checkable
class Simulated(Protocol):
    """Has a MuJoCo model and data to render or view (the twin, the soft body); built at
    connect, so a backend has this ability once connected."""

    model: mujoco.MjModel
    data: mujoco.MjData


class StatusNames(Protocol):
    """Names a status packet's condition bits (``snakebot.families.ServoFamily``)."""

    def status_errors(self, error: int) -> tuple[str, ...]:
        """The names of the condition bits set in ``error``."""
        ...


class BusReport(Protocol):
    """What a servo bus counts that a display shows (``backends.dynamixel.bus.ServoBus``)."""

    @property
    def retry_counts(self) -> Mapping[int, int]:
        """Retries so far per servo ID."""
        ...

    @property
    def group_retries(self) -> int:
        """Retries of group transactions so far."""
        ...

    @property
    def alerts(self) -> set[int]:
        """IDs whose last status packet raised the alert bit or an alarm."""
        ...

    @property
    def conditions(self) -> Mapping[int, int]:
        """The status error bits of the servos in ``alerts``, by ID."""
        ...

    @property
    def family(self) -> StatusNames:
        """The servo family, which names the status bits."""
        ...


@runtime_checkable
class OnBus(Protocol):
    """Drives servos on a serial port (or an emulator URL) through ``bus``."""

    @property
    def port(self) -> str:
        """The serial port (or emulator URL)."""
        ...

    @property
    def bus(self) -> BusReport:
        """The bus the servos are on."""
        ...


CAPABILITIES: tuple[type, ...] = (
    SensesBody,
    SensesImu,
    ReportsHealth,
    ChecksPhysics,
    SensesCurrent,
    SensesTorque,
    LimitsTorque,
    ReportsTravel,
    Resettable,
    Simulated,
    OnBus,
)
"""Every optional ability, in the order ``claimed`` lists them."""


def torque_caps(torque_nm: npt.ArrayLike, joint_count: int) -> FloatArray:
    """``LimitsTorque.limit_torque``'s argument checked: a scalar (every joint) or (N,) N*m,
    each finite and > 0, as a (N,) float array. ValueError naming what is wrong."""
    caps = np.broadcast_to(np.asarray(torque_nm, dtype=float), (joint_count,)).copy()
    if not (np.isfinite(caps).all() and (caps > 0).all()):
        raise ValueError(f"torque limits must be finite and > 0 N*m, got {caps.tolist()}")
    return caps


def claimed(backend: object) -> tuple[str, ...]:
    """The names of the abilities ``backend`` has (e.g. ``("SensesBody", "Resettable")``)."""
    return tuple(cap.__name__ for cap in CAPABILITIES if isinstance(backend, cap))
