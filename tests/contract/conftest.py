"""Backends under the contract: each entry builds a fresh, unconnected backend for a robot.

A backend joins the contract by adding a factory here; every test in this folder then runs on it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import pytest

from snakebot.backends.base import Backend
from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.config import load_robot

BackendFactory = Callable[[str], Backend]


def _twin(robot: str) -> Backend:
    # Frictionless ground: the contract checks the servo loop, not locomotion.
    return TwinBackend(load_robot(robot), friction=GroundFriction(0.0, 0.0))


FACTORIES: dict[str, Callable[[], Iterator[BackendFactory]]] = {}


def _twin_factory() -> Iterator[BackendFactory]:
    yield _twin


FACTORIES["twin"] = _twin_factory


@pytest.fixture(params=sorted(FACTORIES))
def make_backend(request: pytest.FixtureRequest) -> Iterator[BackendFactory]:
    """A factory for the backend under test (one parametrisation per backend)."""
    yield from FACTORIES[request.param]()
