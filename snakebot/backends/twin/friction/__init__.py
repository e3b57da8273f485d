"""Ground friction models of the twin besides MuJoCo's contact pairs: scale friction."""

from snakebot.backends.twin.friction.scale import (
    FRICTION_MODELS,
    ScaleFriction,
    add_scale_friction,
    bind_scale_friction,
)

__all__ = ["FRICTION_MODELS", "ScaleFriction", "add_scale_friction", "bind_scale_friction"]
