"""Miller's (1988) gaits for mass-spring bodies: rectilinear, undulation and sidewinding.

They drive a body's muscle channels (snakebot.backends.softbody): per segment, in the order of
the ``channels`` parameter (the body file's ``[muscles] channels``), a yaw angle (rad), a pitch
angle (rad) and an axial strain (0.3 = 30 % shorter). Segment i of S (head = 0) plays

    wave(omega * t - 2 pi * waves * i / S)

so a positive omega sends the wave from head to tail and ``waves`` counts wavelengths along the
body (Miller's snake: wavelength L / 1.4, waves = 1.4). ``shape`` "square" plays sign(sin).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait, PhasedGait, check_finite, check_joint_count
from snakebot.gaits.spec import GaitSpec, LiveRoles, ParamSpec, ParamValues

AXES = ("yaw", "pitch", "axial")
SHAPES = ("sine", "square")
# Every ordered choice of distinct channels a body file may declare, e.g. "yaw,pitch,axial".
CHANNEL_CHOICES = tuple(
    ",".join(combo)
    for size in range(1, len(AXES) + 1)
    for combo in itertools.permutations(AXES, size)
)
DEFAULT_CHANNELS = "yaw,pitch,axial"


@dataclass(frozen=True)
class MillerGait(PhasedGait):
    """Travelling waves on the yaw, pitch and axial channels of every segment.

    Amplitudes in rad (yaw, pitch) and strain (axial); ``omega`` in rad/s; ``waves`` per body
    length; ``pitch_shift`` in rad is the pitch wave's lead over the yaw and axial waves. One
    phase, phi = omega*t: ``targets_at_phase([phi])``.
    """

    joint_count: int
    channels: tuple[str, ...] = AXES
    yaw_amplitude: float = 0.0
    pitch_amplitude: float = 0.0
    axial_amplitude: float = 0.0
    omega: float = 2 * math.pi
    waves: float = 1.0
    pitch_shift: float = math.pi / 2
    shape: str = "sine"
    name: str = "miller"
    _rates: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = check_joint_count(self.name, self.joint_count)
        check_finite(
            self.name,
            yaw_amplitude=self.yaw_amplitude,
            pitch_amplitude=self.pitch_amplitude,
            axial_amplitude=self.axial_amplitude,
            omega=self.omega,
            waves=self.waves,
            pitch_shift=self.pitch_shift,
        )
        if n % len(self.channels):
            raise GaitError(
                f"{self.name}: {n} joints are not whole segments of {len(self.channels)} channels "
                f"({','.join(self.channels)}); set channels= to the body's [muscles] channels"
            )
        for axis, amplitude in zip(
            AXES, (self.yaw_amplitude, self.pitch_amplitude, self.axial_amplitude), strict=True
        ):
            if amplitude != 0.0 and axis not in self.channels:
                raise GaitError(
                    f"{self.name} drives the {axis} channel, but channels="
                    f"{','.join(self.channels)} has none; use a body with {axis} muscles"
                )
        object.__setattr__(self, "_rates", np.array([self.omega]))

    @property
    def gait_label(self) -> str:
        """The gait's registered name."""
        return self.name

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """[omega] in rad/s."""
        return self._rates

    @property
    def segments(self) -> int:
        """S = N / channels per segment."""
        return self.joint_count // len(self.channels)

    @property
    def period_s(self) -> float | None:
        """2*pi/|omega| in s; None when omega is 0."""
        return None if self.omega == 0.0 else 2.0 * math.pi / abs(self.omega)

    def _wave(self, phase: FloatArray) -> FloatArray:
        wave: FloatArray = np.sin(phase)
        return np.sign(wave) if self.shape == "square" else wave

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        segment = np.arange(self.segments, dtype=np.float64)
        phase = phases[:, :1] - 2.0 * math.pi * self.waves * segment / self.segments
        by_axis = {
            "yaw": self.yaw_amplitude * self._wave(phase),
            "pitch": self.pitch_amplitude * self._wave(phase + self.pitch_shift),
            "axial": self.axial_amplitude * self._wave(phase),
        }
        table = np.stack([by_axis[c] for c in self.channels], axis=2)
        out: FloatArray = table.reshape(phases.shape[0], self.joint_count)
        return out


def _channels_param() -> ParamSpec:
    return ParamSpec(
        "channels",
        "",
        DEFAULT_CHANNELS,
        "the body's channels per segment, as in its [muscles] channels",
        CHANNEL_CHOICES,
    )


def _omega(default: float) -> ParamSpec:
    return ParamSpec(
        "omega",
        "rad/s",
        default,
        "temporal frequency (2*pi rad/s = 1 Hz); > 0 sends the wave head -> tail",
        bounds=(0.5 * math.pi, 4.0 * math.pi),
        tunable=True,
    )


def _waves(default: float, doc: str) -> ParamSpec:
    return ParamSpec("waves", "1", default, doc, bounds=(0.25, 2.5), tunable=True)


def _rectilinear(n: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return MillerGait(
        n,
        channels=tuple(p.text("channels").split(",")),
        axial_amplitude=p.number("amplitude"),
        omega=p.number("omega"),
        waves=p.number("waves"),
        shape=p.text("shape"),
        name="rectilinear",
    )


def _undulation(n: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return MillerGait(
        n,
        channels=tuple(p.text("channels").split(",")),
        yaw_amplitude=p.number("amplitude"),
        omega=p.number("omega"),
        waves=p.number("waves"),
        shape=p.text("shape"),
        name="undulation",
    )


def _sidewinding(n: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return MillerGait(
        n,
        channels=tuple(p.text("channels").split(",")),
        yaw_amplitude=p.number("amplitude"),
        pitch_amplitude=p.number("amplitude_pitch"),
        omega=p.number("omega"),
        waves=p.number("waves"),
        pitch_shift=p.number("phase_shift"),
        name="miller_sidewinding",
    )


_SHAPE = ParamSpec("shape", "", "sine", "wave shape: sine, or square (sign of the sine)", SHAPES)

SPECS = (
    GaitSpec(
        name="rectilinear",
        summary=(
            "Miller's worm (mass-spring bodies): a compression wave head -> tail on the axial "
            "channels; needs directional friction to crawl. Half a wave over the body at 1 Hz, "
            "30 % strain."
        ),
        params=(
            ParamSpec(
                "amplitude",
                "1",
                0.3,
                "axial strain amplitude (0.3 = segments 30 % shorter and longer)",
                bounds=(0.05, 0.4),
                tunable=True,
            ),
            _omega(2 * math.pi),
            _waves(0.5, "compression waves along the body"),
            _SHAPE,
            _channels_param(),
        ),
        factory=_rectilinear,
        live=LiveRoles(
            amplitude=("amplitude",), frequency=("omega",), spatial_frequency=("waves",)
        ),
    ),
    GaitSpec(
        name="undulation",
        summary=(
            "Miller's lateral undulation (mass-spring bodies): left and right muscles 180 deg "
            "out of phase, i.e. a yaw wave head -> tail, L/1.4 long, 0.4 rad per segment, 1 Hz."
        ),
        params=(
            ParamSpec(
                "amplitude",
                "rad",
                0.4,
                "yaw bend amplitude per segment",
                bounds=(0.05, 0.6),
                tunable=True,
            ),
            _omega(2 * math.pi),
            _waves(1.4, "waves along the body (Miller: wavelength L / 1.4)"),
            _SHAPE,
            _channels_param(),
        ),
        factory=_undulation,
        live=LiveRoles(
            amplitude=("amplitude",), frequency=("omega",), spatial_frequency=("waves",)
        ),
    ),
    GaitSpec(
        name="miller_sidewinding",
        summary=(
            "Miller's sidewinding (mass-spring bodies): undulation plus a vertical wave 90 deg "
            "out of phase that lifts most of the body; wavelength L / 1.4, 1 Hz."
        ),
        params=(
            ParamSpec(
                "amplitude",
                "rad",
                0.4,
                "yaw bend amplitude per segment",
                bounds=(0.05, 0.6),
                tunable=True,
            ),
            ParamSpec(
                "amplitude_pitch",
                "rad",
                0.4,
                "pitch bend amplitude per segment",
                bounds=(0.05, 0.6),
                tunable=True,
            ),
            _omega(2 * math.pi),
            _waves(1.4, "waves along the body (Miller: wavelength L / 1.4)"),
            ParamSpec(
                "phase_shift",
                "rad",
                math.pi / 2,
                "pitch wave lead over the yaw wave; its sign sets the sideways direction",
                bounds=(-math.pi, math.pi),
            ),
            _channels_param(),
        ),
        factory=_sidewinding,
        live=LiveRoles(
            amplitude=("amplitude", "amplitude_pitch"),
            frequency=("omega",),
            spatial_frequency=("waves",),
        ),
    ),
)
