"""Backends behind one contract (base.py): the MuJoCo twin and the Dynamixel chain.

What a backend can do beyond the contract is declared by the protocols in capabilities.py,
re-exported here: ask ``isinstance(backend, SensesBody)`` and so on.
"""

from snakebot.backends.offscreen_gl import choose_offscreen_gl

# Before any backend module imports mujoco, which reads MUJOCO_GL only then: headless Linux
# renders offscreen (--video, mujoco.Renderer) with nothing set. Imports nothing heavy.
choose_offscreen_gl()

from snakebot.backends.capabilities import (  # noqa: E402 - after MUJOCO_GL is chosen
    CAPABILITIES,
    ChecksPhysics,
    OnBus,
    ReportsHealth,
    ReportsTravel,
    Resettable,
    SensesBody,
    SensesCurrent,
    SensesImu,
    Simulated,
    claimed,
)

__all__ = [
    "CAPABILITIES",
    "ChecksPhysics",
    "OnBus",
    "ReportsHealth",
    "ReportsTravel",
    "Resettable",
    "SensesBody",
    "SensesCurrent",
    "SensesImu",
    "Simulated",
    "choose_offscreen_gl",
    "claimed",
]
