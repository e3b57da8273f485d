"""CMU gait-library parity: conical sidewinding, the rolling helix and head-look.

- ``conical_sidewinding`` (Gong, Hatton & Choset, "Conical sidewinding", ICRA 2012; the
  extended gait equation, Gong et al. ICRA 2013): sidewinding whose amplitude changes linearly
  along the body, so the body's tracks lie on a cone rather than a cylinder and the snake turns
  as it sidewinds. As CMU's SEA code does it, every joint of the sidewinding gait equation is
  scaled by a factor linear in the joint index; here the factor is centred on the middle joint,
  ``1 + taper*((N-1)/2 - n)/N``, so the taper's sign picks the turn and taper 0 is exactly
  ``sidewinding``.
- ``rolling_helix`` (Zhen, Gong & Choset, "Modeling rolling gaits of a snake robot", ICRA
  2015; CMU's pole-climbing mode): the backbone is a helix of radius r and pitch p (rise per
  radian, m/rad) around a pole; its curvature k = r/(r^2+p^2) and torsion tau = p/(r^2+p^2)
  give the joint amplitude A = 2*k*sin(tau*m)/tau for joints m apart, with yaw joints
  A*cos(phi + tau*m*n) and pitch joints A*sin(phi + tau*m*n). Turning phi rolls the helix about
  its own backbone, which screws the coil along the pole.
- ``head_look``: the body plays a gait while the four joints behind the head (yaw, pitch,
  yaw, pitch; damped least squares) hold the head at a pan/tilt in the body's virtual chassis frame
  (Rollinson, Buchan & Choset 2012), level where the body lies flat.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from snakebot.errors import GaitError
from snakebot.gaits.base import (
    FloatArray,
    Gait,
    PhasedGait,
    check_finite,
    check_joint_count,
)
from snakebot.gaits.compound import SPECS as COMPOUND_SPECS
from snakebot.gaits.compound import CompoundGait
from snakebot.gaits.spec import GaitSpec, JointAxes, LiveRoles, ParamSpec, ParamValues

_PI = math.pi
_YAW_PITCH = JointAxes("yaw", "pitch", True, "the pitch wave lifts the body off its tracks")
_SIDEWINDING = next(spec for spec in COMPOUND_SPECS if spec.name == "sidewinding")


def taper_scale(joint_count: int, taper: float) -> FloatArray:
    """The conical factor (N,) per joint: 1 + taper*((N-1)/2 - n)/N, 1 on the middle joint.

    taper > 0 makes the head's waves larger than the tail's; taper 0 gives exactly 1.0.
    """
    n = np.arange(joint_count, dtype=np.float64)
    out: FloatArray = 1.0 + taper * ((joint_count - 1) / 2.0 - n) / joint_count
    return out


@dataclass(frozen=True)
class ConicalSidewindingGait(PhasedGait):
    """Sidewinding (a CompoundGait) with every joint scaled by ``taper_scale(N, taper)``.

    Angles in rad; ``taper`` is dimensionless (the amplitude changes by taper/N per joint, in
    units of the base amplitude). Two phases, as the compound gait's. Raises GaitError when the
    taper would turn a joint's wave over (a factor <= 0 on some joint).
    """

    sidewinding: CompoundGait
    taper: float = 0.0
    _scale: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_finite("conical_sidewinding", taper=self.taper)
        scale = taper_scale(self.sidewinding.joint_count, self.taper)
        if np.any(scale <= 0.0):
            raise GaitError(
                f"conical_sidewinding.taper: {self.taper:g} turns the waves over at one end "
                f"(the factor must stay > 0; |taper| < 2 always does)"
            )
        object.__setattr__(self, "_scale", scale)

    @property
    def joint_count(self) -> int:  # type: ignore[override]
        """N joints."""
        return self.sidewinding.joint_count

    @property
    def gait_label(self) -> str:
        """ "conical_sidewinding"."""
        return "conical_sidewinding"

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """The sidewinding waves' temporal frequencies (2,) in rad/s."""
        return self.sidewinding.phase_rates_rad_s

    @property
    def period_s(self) -> float | None:
        """The sidewinding period in s."""
        return self.sidewinding.period_s

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        out: FloatArray = self.sidewinding._at_phases(phases) * self._scale
        return out


def _build_conical(joint_count: int, p: ParamValues, lower: FloatArray, upper: FloatArray) -> Gait:
    values = dict(p.values)
    taper = values.pop("taper")
    assert isinstance(taper, float)
    base = _SIDEWINDING.factory(joint_count, ParamValues("sidewinding", values), lower, upper)
    assert isinstance(base, CompoundGait)
    return ConicalSidewindingGait(base, taper)


CONICAL_SPEC = GaitSpec(
    name="conical_sidewinding",
    summary=(
        "Steerable conical sidewinding (Gong, Hatton & Choset 2012): sidewinding whose "
        "amplitude changes linearly head to tail, so the body lies on a cone and turns; "
        "taper > 0 (bigger head waves) and < 0 turn opposite ways, taper 0 is sidewinding."
    ),
    params=(
        ParamSpec(
            "taper",
            "1",
            0.8,
            "amplitude change head to tail, in base amplitudes (factor 1 + taper*((N-1)/2-n)/N)",
            bounds=(-1.5, 1.5),
            tunable=True,
        ),
        *_SIDEWINDING.params,
    ),
    factory=_build_conical,
    ties=_SIDEWINDING.ties,
    live=LiveRoles(
        amplitude=_SIDEWINDING.live.amplitude,
        frequency=_SIDEWINDING.live.frequency,
        spatial_frequency=_SIDEWINDING.live.spatial_frequency,
        offset=("taper",),
    ),
    axes=_YAW_PITCH,
)


def helix_amplitude(radius_m: float, pitch_m_per_rad: float, spacing_m: float) -> float:
    """CMU's rolling-helix joint amplitude in rad: 2*k*sin(tau*m)/tau (Zhen et al. 2015).

    radius_m: the helix radius (pole axis to module axis), m; pitch_m_per_rad: rise per radian
    of turn (the pitch per turn / 2 pi), m/rad; spacing_m: joint to joint, m. GaitError for a
    non-positive radius or spacing.
    """
    if not (radius_m > 0 and spacing_m > 0):
        raise GaitError("rolling_helix: helix radius and joint spacing must be > 0 m")
    denominator = radius_m**2 + pitch_m_per_rad**2
    curvature = radius_m / denominator
    torsion = pitch_m_per_rad / denominator
    if torsion == 0.0:
        return 2.0 * curvature * spacing_m
    return 2.0 * curvature * math.sin(torsion * spacing_m) / torsion


@dataclass(frozen=True)
class RollingHelixGait(PhasedGait):
    """The rolling helix around a pole of ``pole_radius_m``: angles in rad, lengths in m.

    Yaw (even) joints ``side*A*cos(phi + tau*m*n)``, pitch (odd) joints ``A*sin(phi + tau*m*n)``
    with phi = omega*t, A = helix_amplitude(r, p, m), r = pole_radius_m + module_radius_m (the
    modules' axis rides one module radius off the pole), tau = p/(r^2+p^2), m = link_length_m.
    ``side`` (+1/-1) picks the coil's hand (CMU's PoleOnLeft); omega's sign the roll direction.
    Targets are clipped into [lower_rad, upper_rad] (N,). One phase.
    """

    joint_count: int
    pole_radius_m: float = 0.05
    module_radius_m: float = 0.022
    link_length_m: float = 0.065
    pitch_m_per_rad: float = 0.04
    omega: float = _PI / 2
    side: float = 1.0
    lower_rad: FloatArray | None = None
    upper_rad: FloatArray | None = None
    _rates: FloatArray = field(init=False, repr=False, compare=False)
    _amplitude: float = field(init=False, repr=False, compare=False)
    _lags: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_joint_count("rolling_helix", self.joint_count)
        check_finite(
            "rolling_helix",
            pole_radius_m=self.pole_radius_m,
            module_radius_m=self.module_radius_m,
            link_length_m=self.link_length_m,
            pitch_m_per_rad=self.pitch_m_per_rad,
            omega=self.omega,
        )
        if self.side not in (1.0, -1.0):
            raise GaitError(f"rolling_helix.side: expected 1 or -1, got {self.side:g}")
        if self.pole_radius_m < 0:
            raise GaitError("rolling_helix.pole_radius_m: expected >= 0 m")
        radius = self.pole_radius_m + self.module_radius_m
        amplitude = helix_amplitude(radius, self.pitch_m_per_rad, self.link_length_m)
        torsion = self.pitch_m_per_rad / (radius**2 + self.pitch_m_per_rad**2)
        lags = torsion * self.link_length_m * np.arange(self.joint_count, dtype=np.float64)
        object.__setattr__(self, "_rates", np.array([self.omega]))
        object.__setattr__(self, "_amplitude", amplitude)
        object.__setattr__(self, "_lags", lags)

    @property
    def amplitude_rad(self) -> float:
        """The joint amplitude A in rad before clipping."""
        return self._amplitude

    @property
    def gait_label(self) -> str:
        """ "rolling_helix"."""
        return "rolling_helix"

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """[omega] in rad/s."""
        return self._rates

    @property
    def period_s(self) -> float | None:
        """One roll, 2*pi/|omega| in s; None when omega is 0 (a still helix)."""
        return None if self.omega == 0.0 else 2.0 * _PI / abs(self.omega)

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        xi = phases[:, :1] + self._lags[None, :]
        yaw = np.arange(self.joint_count) % 2 == 0
        out: FloatArray = np.where(
            yaw, self.side * self._amplitude * np.cos(xi), self._amplitude * np.sin(xi)
        )
        if self.lower_rad is not None and self.upper_rad is not None:
            out = np.clip(out, self.lower_rad, self.upper_rad)
        return out


_CLIP_MARGIN_RAD = 0.02


def _build_helix(joint_count: int, p: ParamValues, lower: FloatArray, upper: FloatArray) -> Gait:
    return RollingHelixGait(
        joint_count,
        pole_radius_m=p.number("pole_radius_m"),
        module_radius_m=p.number("module_radius_m"),
        link_length_m=p.number("link_length_m"),
        pitch_m_per_rad=p.number("pitch_m_per_rad"),
        omega=p.number("omega"),
        side=1.0 if p.flag("left") else -1.0,
        lower_rad=np.minimum(lower + _CLIP_MARGIN_RAD, 0.0),
        upper_rad=np.maximum(upper - _CLIP_MARGIN_RAD, 0.0),
    )


HELIX_SPEC = GaitSpec(
    name="rolling_helix",
    summary=(
        "CMU rolling helix for pole climbing (Zhen, Gong & Choset 2015): the body coils into a "
        "helix of the pole's radius and rolls about its backbone, screwing up the pole; set "
        "pole_radius_m to the pole's (the pole terrain's diameter_m / 2; on 12 joints 5 mm more "
        "keeps the coil off the pole) and the module size. Wrapped head end up, omega < 0 "
        "climbs (docs/twin.md)."
    ),
    params=(
        ParamSpec("pole_radius_m", "m", 0.05, "radius of the pole to wrap", bounds=(0.0, 0.3)),
        ParamSpec(
            "module_radius_m",
            "m",
            0.022,
            "module radius (pole surface to module axis)",
            bounds=(0.005, 0.1),
        ),
        ParamSpec("link_length_m", "m", 0.065, "joint to joint distance", bounds=(0.02, 0.2)),
        ParamSpec(
            "pitch_m_per_rad",
            "m/rad",
            0.04,
            "helix rise per radian of turn (pitch per turn / 2 pi); larger: looser coil",
            bounds=(0.01, 0.2),
            tunable=True,
        ),
        ParamSpec(
            "omega",
            "rad/s",
            _PI / 2,
            "rolling rate; its sign sets the direction (up or down the pole)",
            bounds=(-2 * _PI, 2 * _PI),
            tunable=True,
        ),
        ParamSpec("left", "0/1", 1.0, "1: coil one hand (CMU PoleOnLeft), 0: the other"),
    ),
    factory=_build_helix,
    rolls_over=True,
    live=LiveRoles(frequency=("omega",)),
    axes=JointAxes("yaw", "pitch", True, "the helix needs both bending axes"),
)


HEAD_JOINTS = 4


def _turn(axis: str, angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    if axis == "yaw":
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _chain_rotation(axes: tuple[str, ...], q: FloatArray) -> FloatArray:
    """Rz/Ry product turns(q0) @ turns(q1) @ ...: module len(q) seen from the head."""
    out = np.eye(3)
    for axis, angle in zip(axes, q, strict=True):
        out = out @ _turn(axis, float(angle))
    return out


def _orientation_error(current: FloatArray, want: FloatArray) -> FloatArray:
    """The rotation vector (3,) in rad, in ``current``'s frame, that takes current to want
    (small-angle: the skew part of current^T want)."""
    d = current.T @ want
    return 0.5 * np.array([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]])


def solve_head(
    axes: tuple[str, ...],
    want: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    iterations: int = 12,
    damping: float = 0.15,
) -> FloatArray:
    """Joint angles (H,) in rad, inside [lower, upper] (H,), for the H head joints of ``axes``
    whose chain rotation (module H seen from the head) comes closest to ``want`` (3, 3): damped
    least squares from the straight pose. Yaw and pitch joints alone reach roll only at second
    order, so a roll error is corrected only as far as small joint angles allow.
    """
    q = np.zeros(len(axes))
    step = 1e-6
    for _ in range(iterations):
        current = _chain_rotation(axes, q)
        error = _orientation_error(current, want)
        if float(np.linalg.norm(error)) < 1e-6:
            break
        jacobian = np.empty((3, len(axes)))
        for j in range(len(axes)):
            moved = q.copy()
            moved[j] += step
            jacobian[:, j] = _orientation_error(current, _chain_rotation(axes, moved)) / step
        gram = jacobian @ jacobian.T + damping**2 * np.eye(3)
        q = np.clip(q + jacobian.T @ np.linalg.solve(gram, error), lower, upper)
    return q


def _unit_chain(axes: tuple[str, ...], q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Module centres (M, 3) and rotations (M, 3, 3) of a unit-length chain, in the head frame."""
    rotations = np.empty((len(axes) + 1, 3, 3))
    rotations[0] = np.eye(3)
    for i, axis in enumerate(axes):
        rotations[i + 1] = rotations[i] @ _turn(axis, float(q[i]))
    origins = np.zeros((len(axes) + 1, 3))
    origins[1:] = np.cumsum(-rotations[:-1, :, 0], axis=0)
    return origins - 0.5 * rotations[:, :, 0], rotations


def body_chassis(axes: tuple[str, ...], q: npt.ArrayLike, head_joints: int) -> FloatArray:
    """The virtual chassis (3, 3) of the modules behind the head joints, in the frame of module
    ``head_joints`` (the first body module), for joint angles q (N,) in rad.

    Columns: x the body's principal axis pointing towards the head, z the cross axis of least
    extent pointing the way the modules' own z axes (up on a snake that started upright) do on
    average, y = z × x. Uniform modules: the frame does not depend on the module length.
    """
    centres, rotations = _unit_chain(axes, np.asarray(q, dtype=np.float64))
    body = centres[head_joints:]
    centred = body - body.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=True)
    x, z = vt[0], vt[2]
    if np.dot(body[0] - body[-1], x) < 0:
        x = -x
    if np.dot(rotations[head_joints:, :, 2].sum(axis=0), z) < 0:
        z = -z
    y = np.cross(z, x)
    chassis = np.column_stack([x, y, z])
    out: FloatArray = rotations[head_joints].T @ chassis
    return out


@dataclass(frozen=True)
class HeadLookGait(PhasedGait):
    """``base``'s joint targets with joints 0..3 (yaw, pitch, yaw, pitch) replaced so
    the head points ``pan_rad`` left (about the chassis z) and ``tilt_rad`` up (about its y) in
    the virtual chassis frame of the rest of the body, with the head's own z along the
    chassis's: level where the body lies flat. Computed from the commanded shape (a function of
    time, as the base gait), so it needs no sensor. The head joints stay inside
    [lower_rad, upper_rad] (default +-1.5 rad). GaitError when N < 6 (four head joints and a
    body of two modules to take the chassis from).
    """

    base: PhasedGait
    pan_rad: float = 0.0
    tilt_rad: float = 0.0
    lower_rad: FloatArray | None = None
    upper_rad: FloatArray | None = None
    _axes: tuple[str, ...] = field(init=False, repr=False, compare=False)
    _aim: FloatArray = field(init=False, repr=False, compare=False)
    _lower: FloatArray = field(init=False, repr=False, compare=False)
    _upper: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_finite("head_look", pan_rad=self.pan_rad, tilt_rad=self.tilt_rad)
        n = self.base.joint_count
        if n < HEAD_JOINTS + 2:
            raise GaitError(
                f"head_look: needs at least {HEAD_JOINTS + 2} joints ({HEAD_JOINTS} for the head, "
                f"the rest "
                f"for the body it looks from), got {n}"
            )
        object.__setattr__(self, "_axes", tuple("yaw" if i % 2 == 0 else "pitch" for i in range(n)))
        aim = _turn("yaw", self.pan_rad) @ _turn("pitch", -self.tilt_rad)
        object.__setattr__(self, "_aim", aim)
        low = np.full(HEAD_JOINTS, -1.5) if self.lower_rad is None else self.lower_rad
        high = np.full(HEAD_JOINTS, 1.5) if self.upper_rad is None else self.upper_rad
        object.__setattr__(self, "_lower", np.asarray(low, dtype=np.float64)[:HEAD_JOINTS])
        object.__setattr__(self, "_upper", np.asarray(high, dtype=np.float64)[:HEAD_JOINTS])

    @property
    def joint_count(self) -> int:  # type: ignore[override]
        """N joints, as the base gait."""
        return self.base.joint_count

    @property
    def period_s(self) -> float | None:
        """The base gait's period in s."""
        return self.base.period_s

    def head_joints_for(self, body_rad: npt.ArrayLike) -> FloatArray:
        """The four head joint angles (4,) in rad that aim the head for the body shape
        ``body_rad`` (N,) (only joints 4.. are read), inside the head joints' limits."""
        chassis = body_chassis(self._axes, body_rad, HEAD_JOINTS)
        want = chassis @ self._aim  # the head's frame seen from the first body module
        return solve_head(self._axes[:HEAD_JOINTS], want.T, self._lower, self._upper)

    @property
    def gait_label(self) -> str:
        """ "head_look"."""
        return "head_look"

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """The base gait's phase rates in rad/s."""
        return self.base.phase_rates_rad_s

    @property
    def phase0_rad(self) -> FloatArray:
        """The base gait's phases at t = 0 in rad."""
        return self.base.phase0_rad

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        rows = self.base._at_phases(phases)
        out: FloatArray = rows.copy()
        for k in range(rows.shape[0]):
            out[k, :HEAD_JOINTS] = self.head_joints_for(rows[k])
        return out

    def reset(self) -> None:
        """Reset the base gait."""
        self.base.reset()


_LOOK_BASES = ("sidewinding", "lateral_undulation", "conical_sidewinding")


def _build_look(joint_count: int, p: ParamValues, lower: FloatArray, upper: FloatArray) -> Gait:
    name = p.text("base")
    spec = (
        CONICAL_SPEC
        if name == "conical_sidewinding"
        else next(s for s in COMPOUND_SPECS if s.name == name)
    )
    values = {q.name: q.default for q in spec.params}
    base = spec.factory(joint_count, ParamValues(name, values), lower, upper)
    assert isinstance(base, PhasedGait)
    return HeadLookGait(
        base, p.number("pan_rad"), p.number("tilt_rad"), lower_rad=lower, upper_rad=upper
    )


LOOK_SPEC = GaitSpec(
    name="head_look",
    summary=(
        "Head-look: a body gait (base, at its defaults) with the four joints behind the head "
        "holding it level and pointed (pan/tilt in the body's virtual chassis frame); for a "
        "camera. HeadLookGait wraps any phased gait from Python."
    ),
    params=(
        ParamSpec("base", "", "sidewinding", "the body's gait", _LOOK_BASES),
        ParamSpec(
            "pan_rad", "rad", 0.0, "look left (+) / right (-) of the body axis", bounds=(-1.0, 1.0)
        ),
        ParamSpec("tilt_rad", "rad", 0.0, "look up (+) / down (-)", bounds=(-0.8, 0.8)),
    ),
    factory=_build_look,
    axes=JointAxes("yaw", "pitch", True, "four alternating head joints aim the head"),
)

SPECS = (CONICAL_SPEC, HELIX_SPEC, LOOK_SPEC)
