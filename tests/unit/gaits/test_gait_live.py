"""Live gaits: controls and gait changes mid-run never jump a target (issue 13, point 1)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import numpy as np
import numpy.typing as npt
import pytest

from snakebot.config import load_robot
from snakebot.control.safety import SafetyLayer
from snakebot.errors import GaitError
from snakebot.gaits import GaitSpec, make_gait, register_gait
from snakebot.gaits.base import FloatArray, Gait, PhasedGait, as_times, shaped
from snakebot.gaits.live import LiveGait
from snakebot.gaits.live_track import LiveControls
from snakebot.gaits.registry import GAITS

ROBOT = load_robot("snake12")
RATE_HZ = 100.0
DT = 1.0 / RATE_HZ
SLEW = ROBOT.max_speed_rad_s * DT  # what the safety layer would let through per cycle
SHIPPED = sorted(name for name in GAITS.names() if GAITS.origin(name).kind == "built-in")


def live(**options: float) -> LiveGait:
    gait = LiveGait(
        ROBOT.joint_count,
        lower_rad=ROBOT.lower_rad,
        upper_rad=ROBOT.upper_rad,
        max_speed_rad_s=ROBOT.max_speed_rad_s,
        period_s=DT,
        **options,
    )
    gait.start(np.zeros(ROBOT.joint_count))
    return gait


Script = dict[int, Callable[[LiveGait], object]]


def play(gait: LiveGait, cycles: int, script: Script | None = None, t0: int = 0) -> np.ndarray:
    """Targets (cycles, N), with script[k](gait) run before cycle k."""
    out = []
    for k in range(t0, t0 + cycles):
        if script and k in script:
            script[k](gait)
        out.append(gait.command(k * DT))
    return np.array(out)


def steps(targets: np.ndarray) -> np.ndarray:
    return np.abs(np.diff(targets, axis=0)).max(axis=1)


def test_a_frequency_change_turns_the_phase_faster_instead_of_jumping() -> None:
    gait = live(transition_s=0.5)
    gait.select("serpenoid")
    gait.set_controls(LiveControls(speed=1.0))
    before = play(gait, 730)
    after = play(gait, 300, {730: lambda g: g.set_controls(LiveControls(speed=2.5))}, t0=730)
    targets = np.vstack([before, after])
    assert steps(targets).max() <= SLEW
    # Recomputing omega * t instead would have jumped at the change:
    slow, fast = make_gait("serpenoid", 12), make_gait("serpenoid", 12, {"omega": 2.5 * math.pi})
    assert np.abs(fast.targets(7.3) - slow.targets(7.3)).max() > 5 * SLEW


def test_at_a_steady_speed_the_live_gait_is_the_gait_itself() -> None:
    gait = live(smoothing_s=0.2)
    gait.select("sidewinding")
    gait.set_controls(LiveControls(speed=1.5))
    play(gait, 300)  # blend and speed ramp are over
    phase = np.array(gait.status().phase_rad)
    reference = make_gait("sidewinding", 12)
    assert isinstance(reference, PhasedGait)
    later = play(gait, 50, t0=300)
    for k, row in enumerate(later, start=1):
        expected = reference.targets_at_phase(phase + 1.5 * reference.phase_rates_rad_s * k * DT)
        np.testing.assert_allclose(row, expected, atol=1e-9)


def test_reversing_ramps_the_phase_rate_through_zero() -> None:
    gait = live(smoothing_s=0.5)
    gait.select("serpenoid")
    gait.set_controls(LiveControls(speed=1.0))
    play(gait, 200)
    phases = []
    for k in range(200, 400):
        if k == 220:
            gait.set_controls(LiveControls(speed=-1.0))
        gait.command(k * DT)
        phases.append(gait.status().phase_rad[0])
    rate = np.diff(phases) / DT
    assert rate[0] == pytest.approx(math.pi) and rate[-1] == pytest.approx(-math.pi)
    # one unit per smoothing_s: -1..1 takes 1 s, so the rate moves by 2*pi/s**2 * DT per cycle
    assert np.abs(np.diff(rate)).max() <= 2 * math.pi * DT + 1e-9
    assert 0.9 <= np.sum(np.abs(np.diff(np.sign(rate))) > 0) <= 2  # crossed zero once


@pytest.mark.parametrize(
    ("change", "param", "value"),
    [
        (LiveControls(speed=1.0, amplitude=1.5), "amplitude", 0.6),
        (LiveControls(speed=1.0, wavelength=2.0), "phase_lag", 0.35),
        (LiveControls(speed=1.0, turn=1.0), "offset", -0.3),  # left: negative yaw bias
        (LiveControls(speed=1.0, turn=-0.5), "offset", 0.15),
    ],
)
def test_shape_controls_are_smoothed_into_the_gait_parameters(
    change: LiveControls, param: str, value: float
) -> None:
    gait = live(smoothing_s=0.4)
    gait.select("serpenoid")
    gait.set_controls(LiveControls(speed=1.0))
    targets = play(gait, 400, {150: lambda g: g.set_controls(change)})
    assert steps(targets).max() <= SLEW
    settled = (change.amplitude - 1) + (change.wavelength - 1) + abs(change.turn)
    assert gait.status().controls == change  # reached after `settled` * 0.4 s
    assert 150 + settled * 0.4 / DT < 400
    phase = np.array(gait.status().phase_rad)
    reference = make_gait("serpenoid", 12, {param: value})
    assert isinstance(reference, PhasedGait)
    np.testing.assert_allclose(targets[-1], reference.targets_at_phase(phase), atol=1e-9)


@pytest.mark.parametrize(("first", "second"), list(itertools.permutations(SHIPPED, 2)))
def test_every_transition_between_shipped_gaits_stays_under_the_slew_limit(
    first: str, second: str
) -> None:
    """The safety layer passes every target unchanged: its slew limit never catches a step."""
    gait = live(transition_s=0.5)
    safety = SafetyLayer.for_robot(ROBOT)
    safety.reset(np.zeros(ROBOT.joint_count))
    script: Script = {
        0: lambda g: g.select(first),
        1: lambda g: g.set_controls(LiveControls(speed=4.0, amplitude=2.0)),  # clipped to fit
        150: lambda g: g.select(second),
        220: lambda g: g.select(first),  # back before that blend ends: a blend of blends
        400: lambda g: g.pause(),
        500: lambda g: g.resume(),
        650: lambda g: g.stop(),
    }
    targets = play(gait, 1200, script)
    commands = np.array([safety.filter(t, DT) for t in targets])
    np.testing.assert_allclose(commands, targets, rtol=0, atol=1e-12)  # float rounding only
    assert steps(targets).max() <= SLEW
    assert gait.finished
    np.testing.assert_array_equal(targets[-1], np.zeros(ROBOT.joint_count))


def test_a_blend_too_short_for_the_servos_is_lengthened_from_the_speed_budget() -> None:
    gait = live(transition_s=0.0)
    gait.select("rolling")
    gait.set_controls(LiveControls(speed=1.0))
    play(gait, 200)
    targets = play(gait, 300, {200: lambda g: g.select("sidewinding")}, t0=200)
    assert steps(targets).max() <= 0.8 * ROBOT.max_speed_rad_s * DT + 1e-12
    assert gait.governed_cycles == 0  # the blend time, not the governor, kept it in


def test_the_governor_slows_time_rather_than_step_past_the_budget() -> None:
    gait = live(smoothing_s=0.0, margin=0.5)
    gait.select("serpenoid", {"amplitude": 1.2})
    gait.set_controls(LiveControls(speed=4.0))
    targets = play(gait, 300)
    assert steps(targets).max() <= 0.5 * ROBOT.max_speed_rad_s * DT + 1e-12
    assert gait.status().speed_limit < 4.0  # the servo envelope, not the box, sets the speed


def test_pause_rests_resume_plays_and_stop_finishes_on_the_rest_pose() -> None:
    gait = live()
    gait.select("lateral_undulation")
    gait.set_controls(LiveControls(speed=1.0))
    play(gait, 200, {100: lambda g: g.pause()})
    assert gait.status().mode == "paused"
    np.testing.assert_array_equal(gait.command(2.0), np.zeros(12))
    gait.resume()
    moving = play(gait, 200, t0=201)
    assert np.abs(moving[-1]).max() > 0.3 and gait.status().mode == "driving"
    gait.stop()
    gait.select("rolling")  # ignored once stopping
    play(gait, 300, t0=401)
    assert gait.finished and gait.status().gait == "lateral_undulation"


def test_a_gait_that_reads_the_measured_pose_cannot_be_driven_and_the_motion_goes_on() -> None:
    gait = live()
    gait.select("serpenoid")
    with pytest.raises(GaitError, match=r"keyframes: cannot be driven live.*advance=time"):
        gait.select("keyframes", {"advance": "error"})
    assert gait.status().gait == "serpenoid"
    with pytest.raises(GaitError, match="unknown gait"):
        gait.select("slither")


def test_targets_of_time_are_refused() -> None:
    with pytest.raises(GaitError, match="cycle by cycle"):
        live().targets(1.0)


@pytest.mark.parametrize(
    ("option", "value"),
    [("max_speed_rad_s", 0.0), ("period_s", math.inf), ("margin", 1.5), ("smoothing_s", -1.0)],
)
def test_bad_options_are_named(option: str, value: float) -> None:
    kwargs = {
        "lower_rad": ROBOT.lower_rad,
        "upper_rad": ROBOT.upper_rad,
        "max_speed_rad_s": 5.0,
        "period_s": 0.01,
        option: value,
    }
    with pytest.raises(GaitError, match="live gait"):
        LiveGait(12, **kwargs)  # type: ignore[arg-type]


def test_the_first_command_starts_from_the_measured_pose() -> None:
    gait = LiveGait(3, lower_rad=-1.0, upper_rad=1.0, max_speed_rad_s=5.0, period_s=DT)
    gait.select("serpenoid")
    first = gait.command(12.0, np.array([0.5, 2.0, -0.2]))
    np.testing.assert_array_equal(first, [0.5, 1.0, -0.2])  # clipped into the limits


class _Rocking(Gait):
    """A gait of time alone, as plugins wrote them before phases: every joint sin(2 t)."""

    def __init__(self, joint_count: int) -> None:
        self.joint_count = joint_count

    @property
    def period_s(self) -> float:
        return math.pi

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        t, scalar = as_times("rocking", time_s)
        return shaped(np.repeat(0.3 * np.sin(2 * t)[:, None], self.joint_count, axis=1), scalar)


def test_a_gait_of_time_alone_drives_live_with_speed_warping_its_time() -> None:
    spec = GaitSpec("rocking", "test", (), lambda n, p, lo, hi: _Rocking(n))
    register_gait(spec)
    try:
        gait = live(smoothing_s=0.0)
        gait.select("rocking")
        gait.set_controls(LiveControls(speed=2.0))
        targets = play(gait, 300)
        assert steps(targets).max() <= SLEW
        phase = gait.status().phase_rad[0]  # 2 rad/s of phase per s at speed 1: t = phase / 2
        np.testing.assert_allclose(targets[-1], _Rocking(12).targets(phase / 2.0), atol=1e-9)
        later = play(gait, 10, t0=300)
        assert gait.status().phase_rad[0] == pytest.approx(phase + 10 * DT * 2.0 * 2.0)
        assert later.shape == (10, 12)
    finally:
        GAITS.unregister("rocking")
