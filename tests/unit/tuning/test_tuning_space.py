from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.errors import ConfigError
from snakebot.gaits import get_spec
from snakebot.gaits.keyframes import default_poses
from snakebot.tuning.feasibility import Violations
from snakebot.tuning.objectives import COT_CAP, Objective, objective_for
from snakebot.tuning.space import build_space, parse_bounds, tuning_base


def test_serpenoid_defaults_to_the_seeds_omega_by_phase_lag_search() -> None:
    space = build_space("serpenoid", tuning_base("serpenoid", 8, {}))
    assert space.names == ("omega", "phase_lag")
    assert space.lower.tolist() == [0.5, 0.1]
    assert space.start().tolist() == [math.pi, 0.7]
    params = space.params([2.0, 0.5])
    assert params["omega"] == 2.0 and params["phase_lag"] == 0.5 and params["amplitude"] == 0.4


def test_tied_parameters_move_together_and_bounds_accept_expressions() -> None:
    base = tuning_base("sidewinding", 12, {"amplitude_odd": 0.3})
    bounds = parse_bounds(["temporal_freq_even+temporal_freq_odd=1:2*pi", "phase_shift=0:pi/2"])
    space = build_space("sidewinding", base, bounds=bounds)
    assert "temporal_freq_even+temporal_freq_odd" in space.names
    x = space.start()
    x[space.names.index("temporal_freq_even+temporal_freq_odd")] = 5.0
    params = space.params(x)
    assert params["temporal_freq_even"] == params["temporal_freq_odd"] == 5.0
    assert params["amplitude_odd"] == 0.3  # --set values are the starting point
    assert space.upper[space.names.index("phase_shift")] == pytest.approx(math.pi / 2)


def test_keyframe_genome_is_half_a_mirrored_cycle_of_poses() -> None:
    base = tuning_base("keyframes", 4, {})
    assert base["mirror"] == 1.0 and len(base["poses"]) == 8  # type: ignore[arg-type]
    space = build_space("keyframes", base, joint_limit_rad=0.5)
    assert len(space.dims) == 8 and space.names[3] == "poses[3]"
    assert space.upper.max() == pytest.approx(0.5)  # the joint limits cap the pi/4 range
    genome = np.linspace(-0.4, 0.4, 8)
    assert space.params(genome)["poses"] == tuple(genome.tolist())
    assert space.start().tolist() == pytest.approx(list(default_poses(4)[:8]))


@pytest.mark.parametrize(
    ("params", "bounds", "key"),
    [
        (["nonsense"], [], "nonsense"),
        (["omega+omega"], [], "omega+omega"),
        (["omega"], ["phase_lag=0:1"], "phase_lag"),
        (["omega"], ["omega=2:1"], "omega=2:1"),
        (["omega"], ["omega=fast"], "omega=fast"),
    ],
)
def test_bad_params_or_bounds_name_the_option(
    params: list[str], bounds: list[str], key: str
) -> None:
    with pytest.raises(ConfigError) as info:
        build_space("serpenoid", tuning_base("serpenoid", 8, {}), params, parse_bounds(bounds))
    assert info.value.key == key


def test_gaits_without_defaults_ask_for_params() -> None:
    with pytest.raises(ConfigError, match=r"^params: "):
        build_space("dft", tuning_base("dft", 8, {}))


def test_heading_objective_projects_the_displacement() -> None:
    summary = {"displacement_m": [3.0, 4.0], "duration_s": 10.0, "speed_mps": 0.5}
    assert Objective("speed").value(summary) == 0.5
    assert Objective("speed_toward_heading", 90.0).value(summary) == pytest.approx(0.4)
    assert Objective("speed_toward_heading", 180.0).value(summary) == pytest.approx(-0.3)


def test_any_playable_gait_beats_any_unplayable_one() -> None:
    speed = objective_for("speed", 0.0, 0.5)
    bad = Violations(speed_excess=0.01)
    assert speed.loss(0.01, Violations()) < speed.loss(3.0, bad)
    assert speed.loss(3.0, bad) < speed.loss(3.0, Violations(speed_excess=0.5))
    cot = objective_for("cost_of_transport", 0.0, 0.5)
    assert cot.loss(0.1, Violations()) < cot.loss(0.2, Violations())
    assert cot.loss(math.nan, Violations()) == COT_CAP < cot.loss(0.1, bad)
    assert cot.better(0.1, 0.2) and speed.better(0.2, 0.1) and not speed.better(math.nan, 0.0)


_SIDEWINDING = (
    "amplitude_even",
    "amplitude_odd",
    "spatial_freq_even+spatial_freq_odd",
    "temporal_freq_even+temporal_freq_odd",
    "phase_shift",
)
# The tables tuning/space.py hard-coded before each gait declared its own search and bounds.
FORMER_SEARCH = {
    "serpenoid": ("omega", "phase_lag"),
    "compound": _SIDEWINDING,
    "sidewinding": _SIDEWINDING,
    "lateral_undulation": (
        "amplitude_even",
        "spatial_freq_even+spatial_freq_odd",
        "temporal_freq_even+temporal_freq_odd",
    ),
    "keyframes": ("poses",),
}
FORMER_BOUNDS = {
    "amplitude": (0.05, 1.2),
    "amplitude_even": (0.05, 1.2),
    "amplitude_odd": (0.05, 1.2),
    "omega": (0.5, 6 * math.pi),
    "temporal_freq_even": (0.5, 6 * math.pi),
    "temporal_freq_odd": (0.5, 6 * math.pi),
    "phase_lag": (0.1, math.pi / 2),
    "spatial_freq_even": (0.1, math.pi / 2),
    "spatial_freq_odd": (0.1, math.pi / 2),
    "phase_shift": (-math.pi, math.pi),
    "offset": (-0.3, 0.3),
    "offset_even": (-0.3, 0.3),
    "offset_odd": (-0.3, 0.3),
    "poses": (-math.pi / 4, math.pi / 4),
    "durations": (0.2, 1.5),
}


SHIPPED = (
    "serpenoid",
    "compound",
    "lateral_undulation",
    "sidewinding",
    "rolling",
    "linear_progression",
    "turn_in_place",
    "dft",
    "dft_shift",
    "simple",
    "keyframes",
)


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_gaits_declare_the_search_and_bounds_the_tuner_used_to_hard_code(
    name: str,
) -> None:
    spec = get_spec(name)
    assert spec.default_search == FORMER_SEARCH.get(name, ())
    assert {p.name: p.bounds for p in spec.params if p.bounds} == {
        p.name: FORMER_BOUNDS[p.name] for p in spec.params if p.name in FORMER_BOUNDS
    }
    assert spec.rolls_over == (name == "rolling")
    assert [p.name for p in spec.params if p.joint_poses] == (
        ["poses"] if name == "keyframes" else []
    )


def test_keyframe_tuning_starts_from_fixed_poses_as_a_full_cycle() -> None:
    base = tuning_base("keyframes", 4, {"poses": (0.1,) * 12})
    assert base["mirror"] == 0.0 and base["poses"] == (0.1,) * 12
    assert tuning_base("keyframes", 4, {"mirror": 0})["poses"] == default_poses(4)[:8]
