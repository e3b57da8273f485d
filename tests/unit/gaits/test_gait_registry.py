import math

import numpy as np
import pytest

from snakebot.errors import ConfigError, GaitError
from snakebot.gaits import (
    Gait,
    gait_names,
    gait_origin,
    get_spec,
    make_gait,
    parse_number,
    parse_set_options,
    resolve_params,
)
from snakebot.gaits.spec import coerce_value

EXPECTED = {
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
    "conical_sidewinding",
    "rolling_helix",
}
# Miller's gaits drive mass-spring bodies; tests/unit/gaits/test_gait_miller.py covers them.
MILLER = {"rectilinear", "undulation", "miller_sidewinding"}
# head_look needs 6 joints (4 aim the head); tests/unit/gaits/test_gait_cmu.py covers it.
HEAD_LOOK = {"head_look"}


def test_all_gaits_are_registered() -> None:
    # Gaits from installed plugins are listed too (tests/plugins checks this suite with one).
    built_in = {name for name in gait_names() if gait_origin(name).kind == "built-in"}
    assert built_in == EXPECTED | MILLER | HEAD_LOOK
    assert gait_names() == sorted(gait_names())


@pytest.mark.parametrize("n", [2, 8, 12, 33])
@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_every_gait_builds_and_returns_finite_targets(name: str, n: int) -> None:
    gait = make_gait(name, n)
    assert isinstance(gait, Gait) and gait.joint_count == n
    times = np.linspace(-0.5, 3.0, 8)
    single, batch = gait.targets(0.37), gait.targets(times)
    assert single.shape == (n,) and batch.shape == (8, n)
    assert np.all(np.isfinite(single)) and np.all(np.isfinite(batch))
    np.testing.assert_allclose(batch, np.stack([gait.targets(float(t)) for t in times]), atol=1e-12)
    np.testing.assert_allclose(gait.command(0.37), single)
    gait.reset()
    period = gait.period_s
    assert period is None or period > 0


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_spec_defaults_are_valid_values(name: str) -> None:
    spec = get_spec(name)
    assert spec.summary and spec.params
    for param in spec.params:
        assert param.doc and coerce_value(name, param, param.default) == param.default


def test_unknown_gait_lists_known_names() -> None:
    with pytest.raises(GaitError, match=r"unknown gait 'serpentine'.*serpenoid.*sidewinding"):
        make_gait("serpentine", 12)
    with pytest.raises(GaitError, match="did you mean 'serpenoid'"):
        get_spec("serpenoidd")


def test_unknown_parameter_is_named_with_the_valid_ones() -> None:
    with pytest.raises(GaitError) as info:
        make_gait("serpenoid", 12, {"omga": 1.0})
    message = str(info.value)
    assert "'omga'" in message and "amplitude, omega, phase_lag, offset" in message
    assert "did you mean 'omega'" in message


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"omega": "abc"}, r"expected a number in rad/s for serpenoid\.omega"),
        ({"omega": [1.0]}, r"serpenoid\.omega"),
        ({"amplitude": math.nan}, r"serpenoid\.amplitude"),
        ({"amplitude": None}, r"serpenoid\.amplitude"),
    ],
)
def test_bad_parameter_values_raise(params: dict[str, object], match: str) -> None:
    with pytest.raises(GaitError, match=match):
        make_gait("serpenoid", 12, params)


def test_list_and_text_parameters_are_type_checked() -> None:
    with pytest.raises(GaitError, match=r"list of numbers in rad for simple\.pose"):
        make_gait("simple", 3, {"pose": 0.1})
    with pytest.raises(GaitError, match=r"simple\.pose: expected 3 values"):
        make_gait("simple", 3, {"pose": (0.1, 0.2)})
    with pytest.raises(GaitError, match=r"keyframes\.interpolation"):
        make_gait("keyframes", 3, {"interpolation": 1.0})


def test_values_may_be_expressions_and_numpy_types() -> None:
    gait = make_gait("serpenoid", 4, {"omega": "pi/2", "amplitude": np.float32(0.25)})
    assert gait.period_s == pytest.approx(4.0)
    pose = make_gait("simple", 3, {"pose": np.array([0.1, -0.2, 0.3])}).targets(0.0)
    np.testing.assert_allclose(pose, [0.1, -0.2, 0.3])


def test_bad_joint_count_and_limits_raise() -> None:
    with pytest.raises(GaitError, match="joint_count"):
        make_gait("serpenoid", 0)
    with pytest.raises(GaitError, match="lower_rad"):
        make_gait("dft", 4, lower_rad=np.zeros(3))
    with pytest.raises(GaitError, match="lower_rad <= upper_rad"):
        make_gait("dft", 2, lower_rad=np.array([0.0, 1.0]), upper_rad=np.array([1.0, 0.0]))


def test_parse_set_options_converts_each_kind() -> None:
    assert parse_set_options("serpenoid", ["omega=pi/4", "amplitude = 0.5*pi"]) == {
        "omega": pytest.approx(math.pi / 4),
        "amplitude": pytest.approx(math.pi / 2),
    }
    assert parse_set_options("simple", ["pose=0.1, -pi/2,radians(90)"]) == {
        "pose": pytest.approx((0.1, -math.pi / 2, math.pi / 2))
    }
    assert parse_set_options("keyframes", ["interpolation=linear", "poses="]) == {
        "interpolation": "linear",
        "poses": (),
    }
    parsed = parse_set_options("serpenoid", ["phase_lag=-tau/8"])
    assert make_gait("serpenoid", 4, parsed).phase_lag == pytest.approx(-math.pi / 4)  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("item", "expected"),
    [
        ("omega", "set: omega: expected key=value"),
        ("=1", "set: =1: expected key=value"),
        ("omega=", "set: omega=: expected a number in rad/s for serpenoid.omega"),
        ("omega=abc", "set: omega=abc: expected a number in rad/s for serpenoid.omega"),
        ("omega=1,2", "set: omega=1,2: expected a number in rad/s for serpenoid.omega"),
        ("nope=1", "set: nope=1: unknown parameter 'nope' for gait 'serpenoid'"),
    ],
)
def test_bad_set_strings_raise_helpful_errors(item: str, expected: str) -> None:
    with pytest.raises(GaitError) as info:
        parse_set_options("serpenoid", [item])
    assert str(info.value).startswith(expected)
    assert isinstance(info.value, ConfigError)  # the keyword ("set") and the text that failed
    assert (info.value.source, info.value.key) == ("set", item)
    if item in ("omega", "nope=1"):
        assert "amplitude, omega, phase_lag, offset" in str(info.value)


def test_bad_choice_in_set_string_lists_choices() -> None:
    with pytest.raises(
        GaitError, match=r"expected one of linear, cubic for keyframes\.interpolation"
    ):
        parse_set_options("keyframes", ["interpolation=spline"])


@pytest.mark.parametrize(
    ("text", "value"),
    [("pi/4", math.pi / 4), ("0.5*pi", math.pi / 2), ("-2e-3", -0.002), ("2**-1", 0.5)],
)
def test_expressions_parse(text: str, value: float) -> None:
    assert parse_number(text) == pytest.approx(value)


@pytest.mark.parametrize(
    "text",
    [
        "__import__('os').system('true')",
        "().__class__",
        "open('x')",
        "pi if 1 else 2",
        "9**9**9",
        "1/0",
        "(-8)**0.5",
        "True",
        "'1'",
        "x" * 300,
    ],
)
def test_unsafe_or_invalid_expressions_are_rejected(text: str) -> None:
    with pytest.raises(ValueError):
        parse_number(text)


def test_resolve_params_fills_defaults() -> None:
    values = resolve_params("serpenoid", {"amplitude": 1})
    assert values == {"amplitude": 1.0, "omega": math.pi, "phase_lag": 0.7, "offset": 0.0}
