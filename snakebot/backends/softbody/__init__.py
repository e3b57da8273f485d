"""Miller's (1988) mass-spring bodies: a second body kind of the twin, behind the Backend contract.

A body file (``firmware_configs/bodies/*.toml``) becomes a lattice of point masses and springs in
MuJoCo; gaits drive its muscles through the same safety layer as a servo chain's joints.
"""

from snakebot.backends.softbody.backend import SoftBodyBackend
from snakebot.backends.softbody.health import BodyHealthLimits
from snakebot.backends.softbody.model import build_body_model, build_body_spec

__all__ = ["BodyHealthLimits", "SoftBodyBackend", "build_body_model", "build_body_spec"]
