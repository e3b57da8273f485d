"""The MuJoCo digital twin: model built from the robot config, servo model, ground friction."""

from snakebot.backends.twin.backend import TwinBackend
from snakebot.backends.twin.model_builder import GroundFriction, build_model, build_spec

__all__ = ["GroundFriction", "TwinBackend", "build_model", "build_spec"]
