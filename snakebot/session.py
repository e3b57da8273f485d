"""The facade: ``load_robot``, ``connect`` and the ``Snake`` handle a script or the CLI drives.

::

    import snakebot
    robot = snakebot.load_robot("snake12")
    with snakebot.connect(robot, backend="twin") as snake:
        summary = snake.run("sidewinding", duration_s=10, params={"amplitude_odd": 0.5})
        print(summary.distance_m, summary.heading_deg)
        state = snake.read_state()

``connect`` reads the backend registry (snakebot.backends.registry): the same table as the CLI's
``--backend``, so a plugin's backend works here by its name. Leaving the ``with`` block (or
``close()``) leaves the joints as the robot file's stop policy says, whatever ended it.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from snakebot.backends.capabilities import ReportsTravel, SensesBody, SensesTorque
from snakebot.backends.registry import BackendSpec, get_backend_spec
from snakebot.config import RobotConfig
from snakebot.config.body import BodyConfig
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import CycleHook, RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import BackendStateError, ConfigError, GaitError
from snakebot.run_summary import RunSummary
from snakebot.types import BodyState, JointCommand, JointState, PDGains

if TYPE_CHECKING:
    from snakebot.backends.base import Backend
    from snakebot.control.cycle import CycleObserver, CycleSink, StopCheck
    from snakebot.drive.controller import DriveController
    from snakebot.drive.run import DriveObserver, DriveResult
    from snakebot.drive.sources import InputSource
    from snakebot.gaits import Gait
    from snakebot.gaits.live import LiveGait

__all__ = [
    "DEFAULT_BACKEND",
    "DEFAULT_DURATION_S",
    "DEFAULT_GAIT",
    "DEFAULT_RATE_HZ",
    "Robot",
    "RunSummary",
    "Snake",
    "connect",
    "load_robot",
    "resolve_gait",
    "robot_names",
    "watched",
]

Robot = RobotConfig | BodyConfig
"""What a snake is built from: a servo chain's robot file, or a mass-spring body file."""

DEFAULT_BACKEND = "twin"
DEFAULT_GAIT = "serpenoid"
DEFAULT_RATE_HZ = 100.0
DEFAULT_DURATION_S = 10.0
"""How long ``snakebot run`` plays a gait when not told (``Snake.run`` always asks)."""


def load_robot(robot: str | Path | Robot) -> Robot:
    """A robot by name (``"snake12"``, looked up on the config search path; a mass-spring body
    name such as ``"worm"`` too), by path to its ``.toml``, or a RobotConfig/BodyConfig as is.

    Raises ConfigError naming the file and key for a bad file, or the known names for an
    unknown one.
    """
    if isinstance(robot, RobotConfig | BodyConfig):
        return robot
    if not isinstance(robot, str | Path):
        raise ConfigError(
            "robot", "", f"expected a robot name, a path or a RobotConfig, got {robot!r}"
        )
    from snakebot.config.body_loader import load_robot_or_body

    return load_robot_or_body(robot)


def robot_names() -> list[str]:
    """Names ``load_robot`` finds on the config search path: robots and mass-spring bodies."""
    from snakebot.config.body_loader import body_names
    from snakebot.config.loader import robot_names as robots

    return sorted({*robots(), *body_names()})


def resolve_gait(
    robot: Robot,
    gait: str | Path | Gait | None = None,
    *,
    params: Mapping[str, object] | None = None,
    gait_file: str | Path | None = None,
) -> tuple[str, Gait]:
    """(name, Gait) for ``robot``'s joints and limits.

    ``gait`` is a registered gait name (default serpenoid), a gait file (``.toml`` path, as
    ``tune gait`` writes) or a Gait object (then ``params`` must be empty). ``gait_file`` names
    a gait file separately; with a ``gait`` name too, the two must agree. ``params`` override
    the defaults (or the file's values). Raises GaitError for an unknown gait or parameter or
    a preset that cannot work with the robot's joint axes (GaitAxesWarning where it merely
    fits badly), ConfigError for a bad gait file.
    """
    from snakebot.config import RobotConfig
    from snakebot.gaits import Gait, check_joint_axes, load_gait_file, make_gait

    if isinstance(gait, Gait):
        if params:
            raise GaitError("params apply to a gait by name or file, not to a Gait object")
        if gait.joint_count != robot.joint_count:
            raise GaitError(
                f"{type(gait).__name__} drives {gait.joint_count} joints; "
                f"{robot.name} has {robot.joint_count}"
            )
        return str(getattr(gait, "name", type(gait).__name__)), gait
    if gait is not None and _is_gait_file(gait):
        if gait_file is not None:
            raise GaitError(f"two gait files given: {gait} and {gait_file}")
        gait, gait_file = None, gait
    values: dict[str, object] = {}
    name = DEFAULT_GAIT if gait is None else str(gait)
    if gait_file is not None:
        file_name, values, _meta = load_gait_file(gait_file)
        if gait is not None and gait != file_name:
            raise ConfigError(
                gait_file,
                "gait",
                f"holds gait {file_name!r}, not {gait!r}: name the file's gait or none",
            )
        name = file_name
    values.update(params or {})
    if isinstance(robot, RobotConfig):  # a mass-spring body has muscles, not servo axes
        check_joint_axes(name, [joint.axis for joint in robot.joints], robot.name)
    built = make_gait(
        name, robot.joint_count, values, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
    )
    return name, built


def _is_gait_file(gait: str | Path) -> bool:
    if isinstance(gait, Path):
        return True
    from snakebot.gaits import gait_names

    return gait not in gait_names() and (gait.endswith(".toml") or Path(gait).is_file())


def watched(spec: BackendSpec, options: Mapping[str, object]) -> dict[str, object]:
    """``options`` with ``realtime`` on where ``spec``'s backend takes it (a simulation): a
    person watching a viewer or driving live needs the wall clock, not a twin racing ahead.
    Unchanged for a backend without the option (hardware runs in real time anyway)."""
    paced = dict(options)
    if "realtime" in spec.option_names:
        paced["realtime"] = True
    return paced


class Snake:
    """A robot on a backend: run gaits, read and command the joints; close leaves it safe.

    Made by :func:`connect` (connected) or :meth:`prepare` (not yet: connect when entering the
    ``with`` block, after any other setup that may still fail). Every method is in SI units
    (rad, s, N·m) and raises what the backend raises (BackendError and subclasses).
    """

    def __init__(self, robot: Robot, backend: Backend, backend_name: str) -> None:
        self.robot = robot
        self.backend = backend
        """The Backend underneath (snakebot.backends.base): for what the facade does not wrap."""
        self.backend_name = backend_name

    @classmethod
    def prepare(
        cls,
        robot: str | Path | Robot,
        backend: str | BackendSpec = DEFAULT_BACKEND,
        **options: object,
    ) -> Snake:
        """A Snake whose backend is made (options checked) but not connected: no port is opened
        and no model built until :meth:`connect` or ``with``. Raises what :func:`connect`
        raises before connecting."""
        config = load_robot(robot)
        spec = backend if isinstance(backend, BackendSpec) else get_backend_spec(backend)
        return cls(config, spec.make(config, **options), spec.name)

    # -- lifecycle ---------------------------------------------------------------------------
    def connect(self) -> Snake:
        """Connect the backend (build the twin / open the port, torque on); returns self."""
        self.backend.connect()
        return self

    @property
    def connected(self) -> bool:
        """True between connecting and closing."""
        return self.backend.connected

    def close(self) -> None:
        """Leave the joints as the stop policy says (ramp to rest, then hold or limp) and
        release the backend; idempotent. Raises what kept the servos from being left safe."""
        self.backend.close()

    def __enter__(self) -> Snake:
        if not self.backend.connected:
            self.connect()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.backend.__exit__(exc_type, exc, tb)

    def __repr__(self) -> str:
        state = "connected" if self.connected else "not connected"
        return f"<Snake {self.robot.name} on {self.backend_name}, {state}>"

    # -- running gaits -----------------------------------------------------------------------
    def run(
        self,
        gait: str | Path | Gait = DEFAULT_GAIT,
        *,
        duration_s: float,
        params: Mapping[str, object] | None = None,
        rate_hz: float = DEFAULT_RATE_HZ,
        log: str | Path | CycleSink | None = None,
        on_cycle: CycleHook | None = None,
        ramp_out: bool = True,
        observers: Sequence[CycleObserver] = (),
        stop: StopCheck | None = None,
    ) -> RunSummary:
        """Play ``gait`` for ``duration_s`` seconds at ``rate_hz``, then ramp out to rest.

        ``gait``: a gait name, a gait file path or a Gait; ``params`` override its parameters.
        ``log``: a CSV path (or an open sink: CsvTelemetryWriter, or any
        snakebot.control.cycle.CycleSink, which sees each cycle's record) for per-cycle
        telemetry; rows
        written stay on disk whatever ends the run. ``on_cycle(cycle, gait_time_s)`` runs after
        every cycle. Each of ``observers`` sees every cycle's record after ``log`` (an
        estimator: snakebot.estimation); ``stop()``, asked before every gait cycle, ends the gait
        with a reason (``summary.extra["stopped_by"]``). Ctrl-C ends the gait early and ramps
        out (``summary.interrupted``).
        Raises GaitError/ConfigError for a bad gait (before anything moves), ValueError for a
        non-positive duration or rate, OutputError for a log that cannot be written,
        BackendError for what the backend reports.
        """
        self._require_connected()
        name, built = resolve_gait(self.robot, gait, params=params)
        plan = RunPlan(duration_s=duration_s, rate_hz=rate_hz, ramp_out=ramp_out)
        robot = self.robot
        metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
        safety = SafetyLayer.for_robot(robot)
        # Where the servos measure their torque, every run reports how long they stalled.
        stall = None
        if isinstance(self.backend, SensesTorque) and isinstance(robot, RobotConfig):
            from snakebot.control.compliance import StallMeter

            physics = robot.servo.physics
            stall = StallMeter(physics.stall_torque_nm, physics.no_load_speed_rad_s)
            observers = [*observers, stall]
        with self._open_log(log) as writer:
            result = run_gait(
                self.backend,
                built,
                safety,
                plan,
                metrics,
                log=writer,
                on_cycle=on_cycle,
                observers=observers,
                stop=stop,
            )
        # A backend that measures more than the runner (the soft body's travel angle) says so.
        backend = self.backend
        extra: dict[str, object] = (
            dict(backend.travel()) if isinstance(backend, ReportsTravel) else {}
        )
        if result.stopped_by:
            extra["stopped_by"] = result.stopped_by
        if stall is not None:
            extra.update(stall.summary())
        return RunSummary.from_run(
            robot=robot.name,
            gait=name,
            backend=self.backend_name,
            metrics=result.summary,
            extra=extra,
            log=_path_of(writer),
            log_rows=result.log_rows,
        )

    def drive(
        self,
        live: LiveGait,
        controller: DriveController,
        source: InputSource,
        *,
        rate_hz: float = DEFAULT_RATE_HZ,
        observers: Sequence[DriveObserver] = (),
        stop_check: Callable[[], str | None] | None = None,
    ) -> DriveResult:
        """Drive live until a stop: ``source``'s keys go through ``controller`` to the ``live``
        gait (snakebot.drive.setup.live_gait makes one for this robot), then through the safety
        layer to the joints at ``rate_hz``. Each ``observers`` entry sees every cycle;
        ``stop_check()`` returning a reason stops the drive (a signal, say). Ends at the rest
        pose; leaving the ``with`` block then applies the stop policy. See
        snakebot.drive.run.run_drive for what is raised.
        """
        from snakebot.drive.run import run_drive

        self._require_connected()
        robot = self.robot
        return run_drive(
            self.backend,
            live,
            SafetyLayer.for_robot(robot),
            controller,
            source,
            rate_hz=rate_hz,
            metrics=RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            observers=list(observers),
            stop_check=stop_check,
        )

    @contextlib.contextmanager
    def _open_log(self, log: str | Path | CycleSink | None) -> Iterator[CycleSink | None]:
        from snakebot.telemetry import CsvTelemetryWriter

        if log is None or not isinstance(log, str | Path):
            yield log
            return
        with CsvTelemetryWriter(log, self.robot.joint_count) as writer:
            yield writer

    # -- the joints directly -----------------------------------------------------------------
    def read_state(self) -> JointState:
        """Joint positions (rad), velocities (rad/s) and efforts (N·m) now, shape (N,) each."""
        return self.backend.read_state()

    def send_command(self, position_rad: JointCommand | npt.ArrayLike) -> None:
        """Goal positions in rad, shape (N,), head to tail; they take effect as time advances.
        Not filtered by the safety layer: :meth:`run` is the safe way to move. ValueError for
        a wrong shape."""
        if not isinstance(position_rad, JointCommand):
            position_rad = JointCommand(np.asarray(position_rad, dtype=float))
        self.backend.send_command(position_rad)

    def advance(self, dt_s: float) -> None:
        """Let ``dt_s`` seconds pass (the twin steps physics; hardware sleeps)."""
        self.backend.advance(dt_s)

    def body_state(self) -> BodyState | None:
        """Centre of mass (m, (3,)) and head orientation on a twin; None on hardware."""
        backend = self.backend
        return backend.body_state() if isinstance(backend, SensesBody) else None

    def set_torque(self, enabled: bool) -> None:
        """Torque on (joints hold) or off (limp) on every joint."""
        self.backend.set_torque(enabled)

    def set_gains(self, gains: PDGains) -> None:
        """Position-loop gains for every joint in SI (PDGains: N·m/rad, N·m·s/rad)."""
        self.backend.set_gains(gains)

    def _require_connected(self) -> None:
        if not self.backend.connected:
            raise BackendStateError(
                f"{self!r}: connect first (snakebot.connect(...) or `with snake:`)"
            )


def connect(
    robot: str | Path | Robot, backend: str | BackendSpec = DEFAULT_BACKEND, **options: Any
) -> Snake:
    """``robot`` (a name, a path or a config; see :func:`load_robot`) on ``backend``, connected.

    ``backend`` is a registered name (``"twin"``/``"sim"``, ``"dynamixel"``, ``"softbody"`` or a
    plugin's; see ``snakebot.backend_names()``) or a BackendSpec. ``options`` go to its
    factory: the twin takes ``friction``, ``terrain``, ``realtime``; the Dynamixel chain
    ``port``, ``baud``, ``allow_extra_servos``. Use the Snake as a context manager so the stop
    policy applies however the block ends.

    Raises BackendOptionError for an option the backend does not take, ConfigError for a bad
    robot file or option value, BackendError for an unknown backend or a failed connection.
    """
    return Snake.prepare(robot, backend, **options).connect()


def _path_of(log: object) -> str | None:
    """The file a log sink writes (a CSV writer's ``path``); None for other sinks or none."""
    path = getattr(log, "path", None)
    return None if path is None else str(path)
