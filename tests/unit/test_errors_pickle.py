"""Every snakebot error survives pickling (a worker process, a Ray node) as itself."""

from __future__ import annotations

import inspect
import pickle
from pathlib import Path

import pytest

import snakebot.errors as errors

SAMPLE_ARGS: dict[str, object] = {
    "source": Path("robots/x.toml"),
    "key": "servo.id",
    "message": "bad",
    "time_s": 1.25,
    "detail": "2x",
    "check": "speed",
    "port": "/dev/ttyUSB0",
    "servo_ids": (1, 2),
    "servo_id": 3,
    "flags": ("overload",),
    "path": Path("out.mcap"),
    "reason": "exists",
    "backend": "twin",
    "option": "port",
    "accepted": ("friction",),
    "address": "10.0.0.5:6379",
    "trials": ["dft/seed-1"],
}

CLASSES = [
    c for c in vars(errors).values() if inspect.isclass(c) and issubclass(c, errors.SnakebotError)
]


def _make(kind: type[errors.SnakebotError]) -> errors.SnakebotError:
    params = list(inspect.signature(kind.__init__).parameters.values())[1:]
    if params and params[0].kind is inspect.Parameter.VAR_POSITIONAL:
        return kind("what went wrong")
    return kind(**{p.name: SAMPLE_ARGS[p.name] for p in params if p.default is p.empty})


@pytest.mark.parametrize("kind", CLASSES, ids=lambda c: c.__name__)
def test_an_error_comes_back_from_pickle_with_its_message_and_fields(
    kind: type[errors.SnakebotError],
) -> None:
    error = _make(kind)
    again = pickle.loads(pickle.dumps(error))
    assert type(again) is kind
    assert str(again) == str(error)
    assert vars(again) == vars(error)


def test_every_error_class_is_checked() -> None:
    assert {"ConfigError", "ClusterError", "PhysicsHealthError", "BusError"} <= {
        c.__name__ for c in CLASSES
    }
