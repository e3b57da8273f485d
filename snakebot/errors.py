"""One error hierarchy for snakebot; the CLI maps each class to an exit status in one place."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path


class SnakebotError(Exception):
    """Root of every error snakebot raises on purpose; its message says what to do."""


class ConfigError(SnakebotError, ValueError):
    """A robot, servo or gait file (or a command-line value) is invalid.

    ``source`` is the file, or the keyword argument the value came in (``budget``, ``terrain``:
    the command line names the flag instead), ``key`` the dotted key path in it
    (``joints[3].servo_id``) or the offending value.
    """

    def __init__(self, source: str | Path, key: str, message: str) -> None:
        self.source = str(source)
        self.key = key
        self.reason = message
        where = f"{self.source}: {key}" if key else self.source
        super().__init__(f"{where}: {message}")


class TerrainError(ConfigError):
    """A terrain that is not known, fails to load from its plugin, or cannot be registered
    (``snakebot.backends.terrains``); its source is the ``terrain`` option."""

    def __init__(self, message: str) -> None:
        super().__init__("terrain", "", message)


class GaitError(SnakebotError, ValueError):
    """A gait was asked for with an unknown name or invalid parameters."""


class GaitParamError(ConfigError, GaitError):
    """A gait parameter given as ``key=value`` text is invalid: a GaitError, and a ConfigError
    whose ``source`` is the keyword the text came in (``set``) and ``key`` the text itself."""


class GaitAxesWarning(UserWarning):
    """A gait runs on a robot whose joint axes are not the ones it was made for."""


class SafetyLimitError(SnakebotError):
    """A command or state left the envelope the safety layer guarantees."""


class BackendError(SnakebotError):
    """A backend was used wrongly (not connected, connected twice) or failed."""


class BackendStateError(BackendError):
    """A backend call came in the wrong lifecycle state (before connect, after close, twice)."""


class SimulationDivergedError(BackendError):
    """MuJoCo reported an unstable simulation (bad acceleration, NaN state)."""

    def __init__(self, time_s: float, detail: str) -> None:
        self.time_s = time_s
        self.detail = detail
        super().__init__(
            f"simulation diverged at t={time_s:.4f} s: {detail}. Lower the gains, the control "
            "rate or the timestep (twin.timestep_s), or add armature."
        )


class BusError(BackendError, ConnectionError):
    """A Dynamixel bus transaction failed; carries the port, servo IDs and the SDK's own text."""

    def __init__(self, port: str, servo_ids: Sequence[int], message: str) -> None:
        self.port = port
        self.servo_ids = tuple(servo_ids)
        ids = ",".join(str(i) for i in self.servo_ids) or "-"
        super().__init__(f"{port} [servo {ids}]: {message}")


class ServoFaultError(BackendError):
    """A servo latched a hardware error (overload, overheating, ...); only a reboot clears it."""

    def __init__(self, servo_id: int, flags: Sequence[str], message: str = "") -> None:
        self.servo_id = servo_id
        self.flags = tuple(flags)
        text = f"servo {servo_id} reports hardware error: {', '.join(self.flags) or 'unknown'}"
        if message:
            text += f". {message}"
        super().__init__(text)


class MissingDependencyError(SnakebotError, ImportError):
    """An optional dependency is not installed; the message carries the install command."""


class UsageError(SnakebotError):
    """The command line asks for something it may not (exit 2, like argparse's own errors).

    For rules argparse cannot express, e.g. a hardware backend without an explicit ``--robot``.
    """


class OutputError(SnakebotError):
    """An output file (telemetry log, video, report, exported model) cannot be written.

    ``path`` is the file, ``reason`` what the operating system said. Whatever was written before
    the failure stays on disk.
    """

    def __init__(self, path: str | Path, reason: str) -> None:
        self.path = str(path)
        self.reason = reason
        super().__init__(f"{self.path}: {reason}")


class OutputExistsError(OutputError):
    """An output file or folder already holds something the command would replace.

    Nothing is written: the user's recording, report or trained policy stays as it was. ``path``
    is what exists, ``reason`` says what would be replaced and how to go ahead.
    """


class BackendOptionError(UsageError, TypeError):
    """A backend was given an option it does not take (``port`` with the twin, say).

    ``backend`` is the backend's name, ``option`` the keyword refused and ``accepted`` the ones
    it takes. A usage error: the option does nothing there, so refusing it beats ignoring it.
    """

    def __init__(self, backend: str, option: str, accepted: Sequence[str]) -> None:
        self.backend = backend
        self.option = option
        self.accepted = tuple(accepted)
        takes = ", ".join(self.accepted) if self.accepted else "none"
        super().__init__(f"the {backend} backend takes no option {option!r} (its options: {takes})")


class PhysicsHealthError(BackendError):
    """The twin computed something no real snake could do: a hard physics-health limit was
    passed (docs/physics.md). ``time_s`` is when, ``check`` which limit, ``detail`` by how much."""

    def __init__(self, time_s: float, check: str, detail: str) -> None:
        self.time_s = time_s
        self.check = check
        self.detail = detail
        super().__init__(
            f"physics health: {check} at t={time_s:.4f} s: {detail}. The twin is not credible "
            "here: lower the gains or the timestep (twin.timestep_s), raise the armature, or "
            "see docs/physics.md"
        )

    def __reduce__(self) -> tuple[type[PhysicsHealthError], tuple[float, str, str]]:
        """Pickles with its fields, so it crosses a process pool (tuning workers)."""
        return (type(self), (self.time_s, self.check, self.detail))
