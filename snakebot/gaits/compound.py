"""CMU compound serpenoid (gait equation) and its presets for yaw (even) / pitch (odd) snakes."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from snakebot.gaits.base import FloatArray, Gait, PhasedGait, check_finite, check_joint_count
from snakebot.gaits.spec import (
    FLAG_UNIT,
    GaitSpec,
    JointAxes,
    LiveRoles,
    ParamSpec,
    ParamValues,
)


@dataclass(frozen=True)
class CompoundGait(PhasedGait):
    """Tesch et al. (2009) gait equation with angles in rad, rad/joint, rad/s.

    Even joints n: offset_even + amplitude_even*sin(spatial_freq_even*n - temporal_freq_even*t);
    odd joints: offset_odd + amplitude_odd*sin(spatial_freq_odd*n - temporal_freq_odd*t + shift).
    The rear half is n >= N//2: half_flip negates phase_shift there, offset_split the offsets.
    No (-1)^floor(n/2) hardware flip: joint directions belong to the robot config.
    Two phases, (temporal_freq_even*t, temporal_freq_odd*t): ``targets_at_phase([pe, po])``.
    """

    joint_count: int
    amplitude_even: float = 0.6
    amplitude_odd: float = 0.6
    offset_even: float = 0.0
    offset_odd: float = 0.0
    spatial_freq_even: float = 0.5
    spatial_freq_odd: float = 0.5
    temporal_freq_even: float = math.pi
    temporal_freq_odd: float = math.pi
    phase_shift: float = math.pi / 4
    half_flip: bool = False
    offset_split: bool = False
    name: str = "compound"
    _rates: FloatArray = field(init=False, repr=False, compare=False)
    _even: FloatArray = field(init=False, repr=False, compare=False)
    _odd: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_joint_count(self.name, self.joint_count)
        check_finite(
            self.name,
            amplitude_even=self.amplitude_even,
            amplitude_odd=self.amplitude_odd,
            offset_even=self.offset_even,
            offset_odd=self.offset_odd,
            spatial_freq_even=self.spatial_freq_even,
            spatial_freq_odd=self.spatial_freq_odd,
            temporal_freq_even=self.temporal_freq_even,
            temporal_freq_odd=self.temporal_freq_odd,
            phase_shift=self.phase_shift,
        )
        n = np.arange(self.joint_count, dtype=np.float64)
        rear = n >= self.joint_count // 2
        shift = np.where(self.half_flip & rear, -self.phase_shift, self.phase_shift)
        rates = np.array([self.temporal_freq_even, self.temporal_freq_odd])
        object.__setattr__(self, "_rates", rates)
        object.__setattr__(self, "_even", self.spatial_freq_even * n)
        object.__setattr__(self, "_odd", self.spatial_freq_odd * n + shift)

    @property
    def gait_label(self) -> str:
        """The preset's name."""
        return self.name

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """[temporal_freq_even, temporal_freq_odd] in rad/s."""
        return self._rates

    @property
    def period_s(self) -> float | None:
        """2*pi/|temporal_freq_even| in s, else from the odd frequency, None if both are 0."""
        for omega in (self.temporal_freq_even, self.temporal_freq_odd):
            if omega != 0.0:
                return 2.0 * math.pi / abs(omega)
        return None

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        n = np.arange(self.joint_count)
        side = np.where(self.offset_split & (n >= self.joint_count // 2), -1.0, 1.0)
        even = side * self.offset_even + self.amplitude_even * np.sin(self._even - phases[:, :1])
        odd = side * self.offset_odd + self.amplitude_odd * np.sin(self._odd - phases[:, 1:2])
        out: FloatArray = np.where(n % 2 == 0, even, odd)
        return out


_PI = math.pi
# Tuning bounds as serpenoid's: frequencies reach 3 Hz so the servo envelope, not the box, decides.
_AMPLITUDE, _OFFSET, _SPATIAL, _TEMPORAL = (0.05, 1.2), (-0.3, 0.3), (0.1, _PI / 2), (0.5, 6 * _PI)
_FIELDS: tuple[tuple[str, str, str, tuple[float, float] | None], ...] = (
    ("amplitude_even", "rad", "amplitude of the even (yaw) wave", _AMPLITUDE),
    ("amplitude_odd", "rad", "amplitude of the odd (pitch) wave", _AMPLITUDE),
    ("offset_even", "rad", "constant bias of the even joints (turning)", _OFFSET),
    ("offset_odd", "rad", "constant bias of the odd joints", _OFFSET),
    ("spatial_freq_even", "rad/joint", "phase step per joint index, even wave", _SPATIAL),
    ("spatial_freq_odd", "rad/joint", "phase step per joint index, odd wave", _SPATIAL),
    ("temporal_freq_even", "rad/s", "even wave frequency; > 0 sends it head -> tail", _TEMPORAL),
    ("temporal_freq_odd", "rad/s", "odd wave frequency; > 0 sends it head -> tail", _TEMPORAL),
    (
        "phase_shift",
        "rad",
        "odd wave lead over the even wave; its sign sets the direction",
        (-_PI, _PI),
    ),
    ("half_flip", FLAG_UNIT, "1: negate phase_shift for joints n >= N//2 (turn in place)", None),
    ("offset_split", FLAG_UNIT, "1: negate the offsets for joints n >= N//2", None),
)
# Both waves' spatial and temporal frequencies move together in a default search.
_TIES = (
    ("spatial_freq_even", "spatial_freq_odd"),
    ("temporal_freq_even", "temporal_freq_odd"),
)
# Driving: both waves scale together; turning biases the even (yaw) joints.
_LIVE = LiveRoles(
    amplitude=("amplitude_even", "amplitude_odd"),
    frequency=_TIES[1],
    spatial_frequency=_TIES[0],
    offset=("offset_even",),
)
_SIDEWINDING_SEARCH = frozenset(
    (
        "amplitude_even",
        "amplitude_odd",
        "spatial_freq_even",
        "spatial_freq_odd",
        "temporal_freq_even",
        "temporal_freq_odd",
        "phase_shift",
    )
)
_SIDEWINDING = {
    "amplitude_even": 0.6,
    "amplitude_odd": 0.6,
    "spatial_freq_even": 0.5,
    "spatial_freq_odd": 0.5,
    "temporal_freq_even": _PI,
    "temporal_freq_odd": _PI,
    "phase_shift": _PI / 4,
}
_BASE = {name: 0.0 for name, _, _, _ in _FIELDS} | _SIDEWINDING

PRESETS: dict[str, tuple[str, dict[str, float]]] = {
    "compound": (
        "CMU gait equation (Tesch et al. 2009) on even (yaw) / odd (pitch) joints; defaults "
        "are the sidewinding set.",
        {},
    ),
    "sidewinding": (
        "Sidewinding: yaw and pitch waves pi/4 apart, moves sideways without anisotropic "
        "friction. A 0.6, spatial 0.5 rad/joint, phase_shift pi/4 as CMU's reusnake set, at "
        "0.5 Hz; locomotion.md measured 0.45 BL/cycle with this gait on a 16-module MuJoCo "
        "snake on isotropic ground. -pi/4 goes the other way.",
        {},
    ),
    "lateral_undulation": (
        "Lateral undulation: yaw wave only, pitch joints still. A 0.6 rad, 0.7 rad/joint "
        "(1.4 rad between yaw neighbours, about 1.3 waves on 12 joints, near Miller's 1.4; "
        "CMU's 4 rad/module with their axis flip also gives 1.4 rad), 0.5 Hz. Needs wheels or "
        "anisotropic friction.",
        {
            "amplitude_odd": 0.0,
            "spatial_freq_even": 0.7,
            "spatial_freq_odd": 0.7,
            "phase_shift": 0.0,
        },
    ),
    "rolling": (
        "Rolling: an arc (spatial 0) turned about the body axis by yaw and pitch waves pi/2 "
        "apart (snakelib rolling); A 0.3 at 0.5 Hz rolled 0.08 BL/cycle sideways in MuJoCo "
        "(locomotion.md).",
        {
            "amplitude_even": 0.3,
            "amplitude_odd": 0.3,
            "spatial_freq_even": 0.0,
            "spatial_freq_odd": 0.0,
            "phase_shift": _PI / 2,
        },
    ),
    "linear_progression": (
        "Linear progression: pitch (odd) wave only, A 0.5, pi/4 rad/joint, 0.5 Hz (CMU ReU/SEA "
        "set). Temporal freq is negative as in snakelib: the wave runs tail -> head and the "
        "body inches head first. Yaw offset 0.3 split front/rear (snakelib beta) bends the body "
        "into a shallow S for stability.",
        {
            "amplitude_even": 0.0,
            "amplitude_odd": 0.5,
            "offset_even": 0.3,
            "spatial_freq_even": _PI / 4,
            "spatial_freq_odd": _PI / 4,
            "temporal_freq_even": -_PI,
            "temporal_freq_odd": -_PI,
            "phase_shift": 0.0,
            "offset_split": 1.0,
        },
    ),
    "turn_in_place": (
        "Turn in place: sidewinding whose phase_shift flips sign on the rear half, so the halves "
        "sidewind in opposite directions; CMU ReU set (A 0.4, 0.5 rad/joint, 3.5 rad/s = 0.56 Hz).",
        {
            "amplitude_even": 0.4,
            "amplitude_odd": 0.4,
            "temporal_freq_even": 3.5,
            "temporal_freq_odd": 3.5,
            "half_flip": 1.0,
        },
    ),
}


# The joint axes each preset needs: the gait equation puts its two waves on even (yaw) and odd
# (pitch) joints. Without the pitch wave nothing lifts, so sidewinding, rolling and turning in
# place cannot happen; on an all-yaw snake they make planar waves that go somewhere else (the
# audit: "turn_in_place" went straight 7.2 m on snake8 and "rolling" did not roll).
_ALTERNATING = JointAxes("yaw", "pitch")
AXES: dict[str, JointAxes] = {
    "compound": _ALTERNATING,
    "sidewinding": JointAxes("yaw", "pitch", True, "the pitch wave lifts the body off its tracks"),
    "rolling": JointAxes("yaw", "pitch", True, "the body rolls about its axis only with both"),
    "turn_in_place": JointAxes("yaw", "pitch", True, "each half sidewinds, which needs both"),
    "linear_progression": JointAxes(
        None, "pitch", True, "the body inches forward on a vertical wave"
    ),
    "lateral_undulation": JointAxes("yaw", None, False, "its wave bends the body sideways"),
}

# What `tune gait` searches by default per preset (the others have no default search).
_SEARCH: dict[str, frozenset[str]] = {
    "compound": _SIDEWINDING_SEARCH,
    "sidewinding": _SIDEWINDING_SEARCH,
    "lateral_undulation": _SIDEWINDING_SEARCH - {"amplitude_odd", "phase_shift"},
}


def _factory(name: str) -> GaitSpec:
    summary, overrides = PRESETS[name]
    defaults = _BASE | overrides
    searched = _SEARCH.get(name, frozenset())
    params = tuple(
        ParamSpec(key, unit, defaults[key], doc, bounds=bounds, tunable=key in searched)
        for key, unit, doc, bounds in _FIELDS
    )

    def build(joint_count: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
        numbers = {key: p.number(key) for key, unit, _, _ in _FIELDS if unit != FLAG_UNIT}
        return CompoundGait(
            joint_count,
            half_flip=p.flag("half_flip"),
            offset_split=p.flag("offset_split"),
            name=name,
            **numbers,
        )

    return GaitSpec(
        name=name,
        summary=summary,
        params=params,
        factory=build,
        ties=_TIES,
        rolls_over=name == "rolling",
        live=_LIVE,
        axes=AXES[name],
    )


SPECS = tuple(_factory(name) for name in PRESETS)
